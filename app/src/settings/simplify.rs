//! Parameters of edge-collapse simplification (hybrid paper §5.2). The build records the collapses
//! once, down to a floor (`simplify::progressive`); the target only chooses
//! a prefix, live.

use std::ops::RangeInclusive;

use lodstudio_core::lod::PrefixTarget;
use lodstudio_core::simplify::CollapseOptions;
pub use lodstudio_core::simplify::collapse::{
    ATTRIBUTE_WEIGHT_RANGE, AttributeWeights, GUARD_RANGE, UV_TOLERANCE_RANGE,
};
use lodstudio_core::simplify::progressive::{FLOOR_RATIO, ProgressiveOptions};
pub use lodstudio_core::simplify::prune::TopologyMode;
use serde::{Deserialize, Serialize};

use super::clamp_or;

/// Which prefix of the recorded collapses is shown: the cut section's unit
/// (a budget of triangles, or the error threshold in pixels or % of the
/// diagonal); each keeps its own value so switching back restores it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub enum TargetMode {
    #[default]
    Ratio,
    Triangles,
    /// The view's error threshold, as for every other hierarchy (an older
    /// session's error target is the threshold in % of the diagonal).
    #[serde(alias = "Error")]
    Threshold,
}

/// Down to the floor a build records.
pub const RATIO_RANGE: RangeInclusive<f32> = FLOOR_RATIO..=1.0;
/// DragValue needs a finite upper end; no model comes close.
pub const MAX_TRIANGLES: usize = 1_000_000_000;

/// Everything edge collapse needs besides the mesh.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct EdgeCollapseSettings {
    pub mode: TargetMode,
    /// Fraction of the input's triangles to keep.
    pub ratio: f32,
    pub triangles: usize,
    pub lock_borders: bool,
    /// Smallest triangle quality a collapse may create (0 disables the guard).
    pub min_quality: f32,
    /// Smallest cosine between a triangle's normals before and after a collapse.
    pub min_normal_cos: f32,
    /// Texels a seam crossing may move a texture coordinate (0 keeps seams).
    pub uv_tolerance: f32,
    /// Appearance in the collapse order.
    pub attribute_weights: AttributeWeights,
    /// Whether the record may prune pieces and contract pairs where the
    /// collapse stops short of the floor.
    pub topology: TopologyMode,
}

impl Default for EdgeCollapseSettings {
    fn default() -> Self {
        let collapse = CollapseOptions::default();
        EdgeCollapseSettings {
            mode: TargetMode::Ratio,
            ratio: 0.1,
            triangles: 1000,
            lock_borders: collapse.lock_borders,
            min_quality: collapse.min_quality,
            min_normal_cos: collapse.min_normal_cos,
            uv_tolerance: collapse.uv_tolerance,
            attribute_weights: collapse.attribute_weights,
            topology: TopologyMode::Keep,
        }
    }
}

impl EdgeCollapseSettings {
    /// The same settings with every value inside the range its control offers.
    pub fn sanitized(self) -> Self {
        let d = Self::default();
        EdgeCollapseSettings {
            mode: self.mode,
            ratio: clamp_or(self.ratio, RATIO_RANGE, d.ratio),
            triangles: self.triangles.clamp(1, MAX_TRIANGLES),
            lock_borders: self.lock_borders,
            min_quality: clamp_or(self.min_quality, GUARD_RANGE, d.min_quality),
            min_normal_cos: clamp_or(self.min_normal_cos, GUARD_RANGE, d.min_normal_cos),
            uv_tolerance: clamp_or(self.uv_tolerance, UV_TOLERANCE_RANGE, d.uv_tolerance),
            attribute_weights: {
                let (w, dw) = (self.attribute_weights, d.attribute_weights);
                AttributeWeights {
                    normal: clamp_or(w.normal, ATTRIBUTE_WEIGHT_RANGE, dw.normal),
                    uv: clamp_or(w.uv, ATTRIBUTE_WEIGHT_RANGE, dw.uv),
                    color: clamp_or(w.color, ATTRIBUTE_WEIGHT_RANGE, dw.color),
                }
            },
            topology: self.topology,
        }
    }

    /// What the build depends on: the collapses' legality rules.
    pub fn collapse(&self) -> CollapseOptions {
        let s = self.sanitized();
        CollapseOptions {
            lock_borders: s.lock_borders,
            min_quality: s.min_quality,
            min_normal_cos: s.min_normal_cos,
            uv_tolerance: s.uv_tolerance,
            attribute_weights: s.attribute_weights,
            free_seams: false,
        }
    }

    /// What a build is made with: the legality rules, recorded down to the
    /// default floor (the ratio slider's low end).
    pub fn params(&self) -> ProgressiveOptions {
        ProgressiveOptions {
            collapse: self.collapse(),
            floor: None,
            topology: self.topology,
        }
    }

    /// The run-time choice of a recorded collapse's prefix (the live cut's
    /// knob): `None` follows the view's threshold.
    pub fn runtime(&self, input_triangles: usize) -> Option<PrefixTarget> {
        let s = self.sanitized();
        match s.mode {
            TargetMode::Ratio => {
                let n = (f64::from(s.ratio) * input_triangles as f64).round();
                Some(PrefixTarget::Triangles(n as usize))
            }
            TargetMode::Triangles => Some(PrefixTarget::Triangles(s.triangles)),
            TargetMode::Threshold => None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_mode_chooses_the_prefix_and_only_legality_rebuilds() {
        let mut s = EdgeCollapseSettings {
            ratio: 0.25,
            triangles: 500,
            ..Default::default()
        };
        assert_eq!(s.runtime(1000), Some(PrefixTarget::Triangles(250)));
        s.mode = TargetMode::Triangles;
        assert_eq!(s.runtime(1000), Some(PrefixTarget::Triangles(500)));
        s.mode = TargetMode::Threshold;
        assert_eq!(s.runtime(1000), None);
        let moved = EdgeCollapseSettings { ratio: 0.5, ..s };
        assert_eq!(moved.collapse(), s.collapse(), "a target is no rebuild");
        let free = EdgeCollapseSettings {
            topology: TopologyMode::Free,
            ..s
        };
        assert_ne!(free.params(), s.params(), "free topology rebuilds");
        assert_eq!(free.params().topology, TopologyMode::Free);
        s.min_normal_cos = f32::NAN;
        assert_eq!(
            s.collapse().min_normal_cos,
            CollapseOptions::default().min_normal_cos
        );
        assert_eq!(s.params().floor(100_000), 100, "the ratio slider's low end");
        // An older session's error target is the threshold now.
        let old: EdgeCollapseSettings = serde_json::from_str(r#"{"mode": "Error"}"#).unwrap();
        assert_eq!(old.mode, TargetMode::Threshold);
    }
}
