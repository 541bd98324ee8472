//! Parameters of hybrid simplification (hybrid paper §5): the performance
//! ratio κ of points to triangles and the transition factor τ.

use std::ops::RangeInclusive;

use lodstudio_core::hybrid::HybridOptions;
use serde::{Deserialize, Serialize};

const KAPPA_RANGE: RangeInclusive<f32> = 0.0..=16.0;
const TAU_RANGE: RangeInclusive<f32> = 0.1..=20.0;

const KAPPA_HINT: &str = "κ: how many points render in the time of one triangle (§5.1). \
    The graph counts primitives as triangles + points/κ, and point replacement turns one \
    triangle into at most ⌊κ⌋ points; κ ≤ 1 never replaces triangles by points, larger κ \
    switches to points earlier (Fig. 9).";
const TAU_HINT: &str = "τ: the transition factor that scales the value (cost / benefit) \
    of every triangle operation (§5.1). τ = 1 compares triangles and points on equal \
    terms; larger τ makes edge collapses look worse, so points take over sooner.";

/// Everything the hybrid build needs besides the mesh.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct HybridSettings {
    pub kappa: f32,
    pub tau: f32,
}

impl Default for HybridSettings {
    fn default() -> Self {
        let o = HybridOptions::default();
        HybridSettings {
            kappa: o.kappa,
            tau: o.tau,
        }
    }
}

impl HybridSettings {
    pub fn sanitized(self) -> Self {
        let d = Self::default();
        let clamp = |v: f32, r: RangeInclusive<f32>, f: f32| {
            if v.is_finite() {
                v.clamp(*r.start(), *r.end())
            } else {
                f
            }
        };
        HybridSettings {
            kappa: clamp(self.kappa, KAPPA_RANGE, d.kappa),
            tau: clamp(self.tau, TAU_RANGE, d.tau),
        }
    }

    pub fn options(&self) -> HybridOptions {
        let s = self.sanitized();
        HybridOptions {
            kappa: s.kappa,
            tau: s.tau,
            ..HybridOptions::default()
        }
    }

    /// The controls; true when a value changed.
    pub fn ui(&mut self, ui: &mut egui::Ui) -> bool {
        let before = *self;
        ui.add(egui::Slider::new(&mut self.kappa, KAPPA_RANGE).text("κ (kappa)"))
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
