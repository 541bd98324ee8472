//! Controls of hybrid simplification: κ and τ, explained in the paper's terms.

use lodstudio_core::hybrid::{KAPPA_RANGE, TAU_RANGE};

use crate::settings::hybrid::HybridSettings;

const KAPPA_HINT: &str = "κ: how many points render in the time of one triangle (§5.1). \
    The graph counts primitives as triangles + points/κ, and point replacement turns one \
    triangle into at most ⌊κ⌋ points; κ ≤ 1 never replaces triangles by points, larger κ \
    switches to points earlier (Fig. 9).";

const TAU_HINT: &str = "τ: the transition factor that scales the value (cost / benefit) \
    of every triangle operation (§5.1). τ = 1 compares triangles and points on equal \
    terms; larger τ makes edge collapses look worse, so points take over sooner.";

impl HybridSettings {
    /// The controls; true when a value changed.
    pub fn ui(&mut self, ui: &mut egui::Ui) -> bool {
        let before = *self;
        ui.add(
            egui::Slider::new(&mut self.kappa, KAPPA_RANGE)
                .logarithmic(true)
                .text("κ (kappa)"),
        )
        .on_hover_text(KAPPA_HINT);
        ui.add(
            egui::Slider::new(&mut self.tau, TAU_RANGE)
                .logarithmic(true)
                .text("τ (tau)"),
        )
        .on_hover_text(TAU_HINT);
        *self != before
    }
}
