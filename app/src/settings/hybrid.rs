//! Parameters of hybrid simplification (hybrid paper §5): the performance
//! ratio κ of points to triangles and the transition factor τ, in the ranges
//! the build accepts.

use lodstudio_core::hybrid::{HybridOptions, KAPPA_RANGE, TAU_RANGE};
use serde::{Deserialize, Serialize};

use super::clamp_or;

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
        HybridSettings {
            kappa: clamp_or(self.kappa, KAPPA_RANGE, d.kappa),
            tau: clamp_or(self.tau, TAU_RANGE, d.tau),
        }
    }

    /// What a build is made with.
    pub fn options(&self) -> HybridOptions {
        let s = self.sanitized();
        HybridOptions {
            kappa: s.kappa,
            tau: s.tau,
            ..HybridOptions::default()
        }
    }
}
