//! Parameters of extreme point-set simplification with algebraic multigrid
//! (AMG paper): the neighbourhood size k (§2.1), the level drawn (§2.3) and
//! the texel size of the domain primitives' textures (§3.2).

use std::ops::RangeInclusive;

use serde::{Deserialize, Serialize};

const K_RANGE: RangeInclusive<usize> = 8..=100;
const TEXEL_RANGE: RangeInclusive<f32> = 0.25..=8.0;
const LEVEL_RANGE: RangeInclusive<usize> = 0..=24;

const K_HINT: &str = "§2.1: each point's neighbourhood is its k nearest neighbours (grown to \
    the minimal feature size where points are dense); the paper uses 50 to 100. Larger k \
    smooths the classifier and the local finite elements.";
const LEVEL_HINT: &str = "§2.3: the level of the Ruge–Stüben hierarchy whose domains are \
    drawn (0 = every point its own domain; each level has 2–3× fewer). No rebuild.";
const AUTO_HINT: &str = "Let the error threshold choose the level: the coarsest whose every \
    domain primitive's plane error passes it.";
const TEXEL_HINT: &str = "§3.2: texel size of the primitives' textures, in units of the \
    median point spacing: smaller gives sharper colour and Ψ, and more texels.";

/// Everything the AMG decomposition needs besides the points.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct AmgSettings {
    pub k: usize,
    /// Texel size in median point spacings.
    pub texel: f32,
    /// Run time: the level drawn, unless the threshold chooses it.
    pub level: usize,
    pub auto_level: bool,
}

impl Default for AmgSettings {
    fn default() -> Self {
        AmgSettings {
            k: lodstudio_core::amg::AmgOptions::default().k,
            texel: 1.0,
            level: 3,
            auto_level: false,
        }
    }
}

impl AmgSettings {
    pub fn sanitized(self) -> Self {
        let d = Self::default();
        AmgSettings {
            k: self.k.clamp(*K_RANGE.start(), *K_RANGE.end()),
            texel: if self.texel.is_finite() {
                self.texel.clamp(*TEXEL_RANGE.start(), *TEXEL_RANGE.end())
            } else {
                d.texel
            },
            level: self.level.min(*LEVEL_RANGE.end()),
            auto_level: self.auto_level,
        }
    }

    /// What a build depends on (the level is chosen at run time).
    pub fn build_params(self) -> Self {
        AmgSettings {
            level: 0,
            auto_level: false,
            ..self.sanitized()
        }
    }

    /// The level to draw (`None`: the threshold chooses), the live cut's knob.
    pub fn runtime_level(&self) -> Option<usize> {
        (!self.auto_level).then_some(self.level)
    }

    /// The controls; true when a build parameter changed.
    pub fn ui(&mut self, ui: &mut egui::Ui, levels: Option<usize>) -> bool {
        let before = self.build_params();
        ui.add(egui::Slider::new(&mut self.k, K_RANGE).text("k (neighbours)"))
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
        self.build_params() != before
    }
}
