//! Controls of the AMG decomposition: k, the texel size and the level drawn.

use lodstudio_core::amg::K_RANGE;

use crate::settings::amg::{AmgSettings, LEVEL_RANGE, TEXEL_RANGE};

const K_HINT: &str = "§2.1: each point's neighbourhood is its k nearest neighbours (grown to \
    the minimal feature size where points are dense); the paper uses 50 to 100. Larger k \
    smooths the classifier and the local finite elements.";

const LEVEL_HINT: &str = "§2.3: the level of the Ruge–Stüben hierarchy whose domains are \
    drawn (0 = every point its own domain; each level has 2–3× fewer). No rebuild.";

const AUTO_HINT: &str = "Let the error threshold choose the level: the coarsest whose every \
    domain primitive's plane error passes it.";

const TEXEL_HINT: &str = "§3.2: texel size of the primitives' textures, in units of the \
    median point spacing: smaller gives sharper colour and Ψ, and more texels.";

impl AmgSettings {
    /// The controls; true when a build parameter changed.
    pub fn ui(&mut self, ui: &mut egui::Ui, levels: Option<usize>) -> bool {
        let before = self.params();
        ui.add(
            egui::Slider::new(&mut self.k, K_RANGE)
                .logarithmic(true)
                .text("k (neighbours)"),
        )
        .on_hover_text(K_HINT);
        ui.add(
            egui::Slider::new(&mut self.texel, TEXEL_RANGE)
                .logarithmic(true)
                .text("texel size"),
        )
        .on_hover_text(TEXEL_HINT);
        ui.checkbox(&mut self.auto_level, "level from the threshold")
            .on_hover_text(AUTO_HINT);
        if !self.auto_level {
            let top = levels.map_or(*LEVEL_RANGE.end(), |n| n.saturating_sub(1));
            ui.add(egui::Slider::new(&mut self.level, 0..=top).text("AMG level"))
                .on_hover_text(LEVEL_HINT);
        }
        self.params() != before
    }
}
