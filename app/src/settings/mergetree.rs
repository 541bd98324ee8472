//! Parameters of view-dependent simplification with merge trees (merge-tree
//! paper): how the tree is built (§4, §6) and which
//! criteria refine or coarsen it while the camera moves (§3, §5).

use std::ops::RangeInclusive;

pub use lodstudio_core::mergetree::MIN_VERTICES_RANGE;
use lodstudio_core::mergetree::{Criteria, MergeTreeOptions};
pub use lodstudio_core::simplify::collapse::GUARD_RANGE as QUALITY_RANGE;
use serde::{Deserialize, Serialize};

use super::clamp_or;

/// The light's direction for the illumination criterion, in degrees.
pub const AZIMUTH_RANGE: RangeInclusive<f32> = -180.0..=180.0;
pub const ELEVATION_RANGE: RangeInclusive<f32> = -90.0..=90.0;

/// Everything the merge tree needs besides the mesh.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct MergeTreeSettings {
    pub min_vertices: usize,
    pub min_quality: f32,
    pub backface: bool,
    pub silhouette: bool,
    pub lighting: bool,
    /// The light comes from the eye (else from azimuth/elevation).
    pub light_from_eye: bool,
    /// Degrees.
    pub light_azimuth: f32,
    pub light_elevation: f32,
}

impl Default for MergeTreeSettings {
    fn default() -> Self {
        let o = MergeTreeOptions::default();
        let c = Criteria::default();
        MergeTreeSettings {
            min_vertices: o.min_vertices,
            min_quality: o.collapse.min_quality,
            backface: c.backface,
            silhouette: c.silhouette,
            lighting: c.lighting,
            light_from_eye: true,
            light_azimuth: 45.0,
            light_elevation: 45.0,
        }
    }
}

impl MergeTreeSettings {
    pub fn sanitized(self) -> Self {
        let d = Self::default();
        MergeTreeSettings {
            min_vertices: self
                .min_vertices
                .clamp(*MIN_VERTICES_RANGE.start(), *MIN_VERTICES_RANGE.end()),
            min_quality: clamp_or(self.min_quality, QUALITY_RANGE, d.min_quality),
            light_azimuth: clamp_or(self.light_azimuth, AZIMUTH_RANGE, d.light_azimuth),
            light_elevation: clamp_or(self.light_elevation, ELEVATION_RANGE, d.light_elevation),
            ..self
        }
    }

    /// What the tree's build depends on (the criteria apply at run time).
    pub fn options(&self) -> MergeTreeOptions {
        let s = self.sanitized();
        let mut options = MergeTreeOptions {
            min_vertices: s.min_vertices,
            ..Default::default()
        };
        options.collapse.min_quality = s.min_quality;
        options
    }

    pub fn criteria(&self) -> Criteria {
        Criteria {
            backface: self.backface,
            silhouette: self.silhouette,
            lighting: self.lighting,
        }
    }

    /// Direction towards the light, or `None` when it follows the eye.
    pub fn light(&self) -> Option<glam::Vec3> {
        if self.light_from_eye {
            return None;
        }
        let (a, e) = (
            self.light_azimuth.to_radians(),
            self.light_elevation.to_radians(),
        );
        Some(glam::Vec3::new(
            e.cos() * a.sin(),
            e.sin(),
            e.cos() * a.cos(),
        ))
    }
}
