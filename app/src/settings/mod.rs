//! What the studio builds and cuts with: the chosen method, the parameters
//! of each (one module per method, with their ranges) and the cut threshold.
//! No UI here (the controls are in `panels`), so builds depend on settings
//! only. Everything is persisted between sessions except the voxel threshold,
//! which is in the units of one volume's values (see
//! [`voxel::VoxelSettings::threshold`]).

pub mod amg;
pub mod chain;
pub mod hybrid;
pub mod mergetree;
pub mod simplify;
pub mod threshold;
pub mod tiles;
pub mod voxel;

use std::ops::RangeInclusive;

use lodstudio_core::lod::{Knobs, Params};
use serde::{Deserialize, Serialize};

use self::amg::AmgSettings;
use self::hybrid::HybridSettings;
use self::mergetree::MergeTreeSettings;
use self::simplify::EdgeCollapseSettings;
use self::threshold::Threshold;
use self::voxel::{VolumeGrid, VoxelSettings};

/// The LOD methods the studio can build: core's list, written once.
pub use lodstudio_core::lod::Method;

/// The chosen method, the parameters of every method, and how builds start.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct MethodSettings {
    pub method: Method,
    /// Rebuild by itself shortly after a parameter changes.
    pub auto_rebuild: bool,
    pub edge_collapse: EdgeCollapseSettings,
    pub voxel: VoxelSettings,
    pub merge_tree: MergeTreeSettings,
    pub hybrid: HybridSettings,
    pub amg: AmgSettings,
    /// The error threshold of live cuts (hierarchies).
    pub threshold: Threshold,
}

impl Default for MethodSettings {
    fn default() -> Self {
        MethodSettings {
            method: Method::default(),
            auto_rebuild: true,
            edge_collapse: EdgeCollapseSettings::default(),
            voxel: VoxelSettings::default(),
            merge_tree: MergeTreeSettings::default(),
            hybrid: HybridSettings::default(),
            amg: AmgSettings::default(),
            threshold: Threshold::default(),
        }
    }
}

impl MethodSettings {
    /// Settings with any value out of range (a hand-edited or older session)
    /// replaced, so a build never starts from nonsense.
    pub fn sanitized(mut self) -> MethodSettings {
        self.edge_collapse = self.edge_collapse.sanitized();
        self.voxel = self.voxel.sanitized();
        self.threshold = self.threshold.sanitized();
        self.merge_tree = self.merge_tree.sanitized();
        self.hybrid = self.hybrid.sanitized();
        self.amg = self.amg.sanitized();
        self
    }

    /// What a build of the chosen method is made with (a result built with
    /// other parameters is stale); `volume` is the grid of the open model
    /// when it is a volume (voxel builds depend on other values then).
    pub fn params(&self, volume: Option<&VolumeGrid>) -> Params {
        match self.method {
            Method::EdgeCollapse => Params::EdgeCollapse(self.edge_collapse.params()),
            Method::Voxel => Params::Voxel(self.voxel.params(volume)),
            Method::MergeTree => Params::MergeTree(self.merge_tree.options()),
            Method::Hybrid => Params::Hybrid(self.hybrid.options()),
            Method::Amg => Params::Amg(self.amg.params()),
            // Not in the studio's method list: a chain row's kind.
            Method::Impostor => Params::default_for(Method::Impostor),
        }
    }
}

impl MethodSettings {
    /// Shows `params` (a reopened hierarchy's): its method's settings take
    /// its values, in range; run-time settings stay.
    pub fn set_params(&mut self, params: &Params) {
        self.method = params.method();
        match params {
            Params::EdgeCollapse(p) => {
                let ec = &mut self.edge_collapse;
                ec.lock_borders = p.collapse.lock_borders;
                ec.min_quality = p.collapse.min_quality;
                ec.min_normal_cos = p.collapse.min_normal_cos;
                ec.uv_tolerance = p.collapse.uv_tolerance;
                ec.attribute_weights = p.collapse.attribute_weights;
                ec.topology = p.topology;
            }
            Params::Voxel(p) => {
                let v = &mut self.voxel;
                v.resolution = p.resolution;
                v.radius = p.radius;
                v.filter = p.filter;
                v.iso = p.iso;
                v.layers_error = p.layers_error;
                v.simplify = p.post != lodstudio_core::voxel::PostSimplify::Off;
                v.pyramid = p.pyramid;
            }
            Params::Impostor(_) => {}
            Params::MergeTree(p) => {
                self.merge_tree.min_vertices = p.min_vertices;
                self.merge_tree.min_quality = p.collapse.min_quality;
            }
            Params::Hybrid(p) => {
                self.hybrid.kappa = p.kappa;
                self.hybrid.tau = p.tau;
            }
            Params::Amg(p) => {
                self.amg.k = p.k;
                if let lodstudio_core::amg::Texel::Spacings(s) = p.texel {
                    self.amg.texel = s;
                }
            }
        }
        *self = self.sanitized();
    }

    /// What changes a cut at run time, for a model of `input_triangles`.
    pub fn knobs(&self, input_triangles: usize) -> Knobs {
        Knobs {
            criteria: self.merge_tree.criteria(),
            pyramid_position: self.voxel.runtime_position(),
            amg_level: self.amg.runtime_level(),
            collapse: self.edge_collapse.runtime(input_triangles),
        }
    }
}

/// `value` clamped to `range` (an infinity to its end), or `fallback` when it
/// is not a number (a hand-edited or older settings file).
pub fn clamp_or(value: f32, range: RangeInclusive<f32>, fallback: f32) -> f32 {
    if value.is_nan() {
        fallback
    } else {
        value.clamp(*range.start(), *range.end())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn settings_round_trip_and_bad_values_are_replaced() {
        let settings = MethodSettings {
            auto_rebuild: false,
            edge_collapse: EdgeCollapseSettings {
                ratio: 0.3,
                ..Default::default()
            },
            ..Default::default()
        };
        let json = serde_json::to_string(&settings).expect("serialises");
        let back: MethodSettings = serde_json::from_str(&json).expect("parses");
        assert_eq!(back.sanitized(), settings);

        let odd = r#"{"edge_collapse": {"ratio": 7.0, "min_quality": -2.0},
                      "voxel": {"resolution": 9999, "iso": 0.0}}"#;
        let restored = serde_json::from_str::<MethodSettings>(odd)
            .expect("partial settings parse")
            .sanitized();
        assert!(restored.auto_rebuild, "missing fields take their defaults");
        assert_eq!(restored.edge_collapse.ratio, 1.0);
        assert_eq!(restored.edge_collapse.min_quality, 0.0);
        assert_eq!(
            restored.voxel.resolution,
            *lodstudio_core::voxel::RESOLUTION_RANGE.end()
        );
        assert_eq!(restored.voxel.iso, 0.05);
        assert_eq!(restored.voxel.radius, VoxelSettings::default().radius);
    }
}
