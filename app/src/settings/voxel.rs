//! Parameters of voxel-based simplification (voxel paper §2): sample the solid (or threshold a volume model) into a volume buffer
//! S, low-pass filter it into a density f = h ∗ S, and extract the iso-density
//! surface by marching cubes.

use std::ops::RangeInclusive;

use lodstudio_core::geom::Volume;
pub use lodstudio_core::voxel::params::{ISO_RANGE, LAYERS_RANGE};
use lodstudio_core::voxel::{Filter, PostSimplify, RADIUS_RANGE, RESOLUTION_RANGE, VoxelParams};
use serde::{Deserialize, Serialize};

use super::clamp_or;

/// Pyramid positions the slider offers (levels beyond the pyramid clamp).
pub const POSITION_RANGE: RangeInclusive<f32> = 0.0..=6.0;

/// Everything voxel simplification needs besides the solid.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct VoxelSettings {
    pub filter: Filter,
    /// Voxels along the longest side of the object's bounds.
    pub resolution: usize,
    /// Filter support radius, in voxels of that grid.
    pub radius: f32,
    /// Density of the extracted surface (0..1); implicit solids only (a volume's
    /// surface is always the density 0.5 of its filtered S).
    pub iso: f32,
    /// Volumes only: samples at or above this value, in the volume's own units,
    /// form the solid S. It is model-specific, so it is not persisted: `None`
    /// stands for the middle of the open volume's value range, and the studio
    /// resets it to `None` whenever a different volume opens.
    #[serde(skip)]
    pub threshold: Option<f32>,
    /// Multi-layered surfaces (§3): the mean density error δ of eq. 6 the
    /// layers may leave; 0.5 or more gives the single surface.
    pub layers_error: f32,
    /// Collapse each extracted level's edges to half a voxel (§5: the
    /// method is "the first stage"), certified; off keeps the raw extraction.
    pub simplify: bool,
    /// Build the whole pyramid (Tables 1–3) and browse it continuously.
    pub pyramid: bool,
    /// Run time: the continuous pyramid position shown (0 = finest, §5) ...
    pub position: f32,
    /// ... unless the pyramid follows the error threshold: the coarsest
    /// level whose certified bound is within it.
    pub follow_threshold: bool,
}

/// What the voxel controls and a volume build need to know of a volume,
/// computed once when it opens (its value range takes a pass over the data).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VolumeGrid {
    pub dims: [usize; 3],
    /// (min, max) of the finite samples; (0, 0) when there are none.
    pub range: (f32, f32),
}

impl VolumeGrid {
    pub fn of(volume: &Volume) -> Self {
        let (lo, hi) = volume.value_range();
        VolumeGrid {
            dims: volume.dims,
            range: if lo <= hi { (lo, hi) } else { (0.0, 0.0) },
        }
    }

    /// The default threshold: the middle of the value range.
    pub fn middle(&self) -> f32 {
        0.5 * (self.range.0 + self.range.1)
    }

    /// `threshold` inside the value range (the middle for `None` or NaN).
    pub fn threshold(&self, threshold: Option<f32>) -> f32 {
        match threshold {
            Some(t) if !t.is_nan() => t.clamp(self.range.0, self.range.1),
            _ => self.middle(),
        }
    }
}

impl Default for VoxelSettings {
    fn default() -> Self {
        let d = VoxelParams::default();
        VoxelSettings {
            filter: d.filter,
            resolution: d.resolution,
            radius: d.radius,
            iso: d.iso,
            threshold: d.threshold,
            layers_error: d.layers_error,
            simplify: d.post != PostSimplify::Off,
            pyramid: d.pyramid,
            position: 0.0,
            follow_threshold: true,
        }
    }
}

impl VoxelSettings {
    /// The same settings with every value inside the range its control offers.
    pub fn sanitized(self) -> Self {
        let d = Self::default();
        VoxelSettings {
            filter: self.filter,
            resolution: self
                .resolution
                .clamp(*RESOLUTION_RANGE.start(), *RESOLUTION_RANGE.end()),
            radius: clamp_or(self.radius, RADIUS_RANGE, d.radius),
            iso: clamp_or(self.iso, ISO_RANGE, d.iso),
            threshold: self.threshold.filter(|t| !t.is_nan()),
            layers_error: clamp_or(self.layers_error, LAYERS_RANGE, d.layers_error),
            simplify: self.simplify,
            pyramid: self.pyramid,
            position: clamp_or(self.position, POSITION_RANGE, d.position),
            follow_threshold: self.follow_threshold,
        }
    }

    /// How each extracted level is simplified further: the default
    /// collapse, or none.
    pub fn post(&self) -> PostSimplify {
        match self.simplify {
            true => VoxelParams::default().post,
            false => PostSimplify::Off,
        }
    }

    /// The pyramid position a cut shows: `None` follows the threshold.
    pub fn runtime_position(&self) -> Option<f32> {
        (!self.follow_threshold).then_some(self.sanitized().position)
    }

    /// What a build is made with. Of a volume (`volume` its grid) the
    /// threshold is resolved, and the resolution and iso, which have no
    /// effect on it, keep their defaults, so changing them does not make its
    /// result stale.
    pub fn params(&self, volume: Option<&VolumeGrid>) -> VoxelParams {
        let s = self.sanitized();
        let d = VoxelParams::default();
        let (resolution, iso, threshold) = match volume {
            Some(grid) => (d.resolution, d.iso, Some(grid.threshold(s.threshold))),
            None => (s.resolution, s.iso, None),
        };
        VoxelParams {
            resolution,
            radius: s.radius,
            filter: s.filter,
            iso,
            threshold,
            layers_error: s.layers_error,
            post: s.post(),
            pyramid: s.pyramid,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn out_of_range_values_are_replaced() {
        let odd = VoxelSettings {
            filter: Filter::Cone,
            resolution: 4,
            radius: f32::NAN,
            iso: 3.0,
            threshold: Some(f32::NAN),
            layers_error: 7.0,
            simplify: false,
            pyramid: true,
            position: f32::INFINITY,
            follow_threshold: false,
        }
        .sanitized();
        assert_eq!((odd.pyramid, odd.position), (true, 6.0));
        assert_eq!(odd.runtime_position(), Some(6.0));
        assert_eq!(VoxelSettings::default().runtime_position(), None);
        assert_eq!(odd.layers_error, 0.5);
        assert_eq!(odd.threshold, None);
        assert_eq!(odd.filter, Filter::Cone);
        assert_eq!(odd.resolution, *RESOLUTION_RANGE.start());
        assert_eq!(odd.radius, VoxelSettings::default().radius);
        assert_eq!(odd.iso, 0.95);
        assert_eq!(
            VoxelSettings::default().sanitized(),
            VoxelSettings::default()
        );
    }

    #[test]
    fn volume_builds_depend_only_on_what_has_an_effect() {
        let volume = Volume {
            dims: [2, 1, 1],
            spacing: glam::Vec3::ONE,
            origin: glam::Vec3::ZERO,
            data: vec![-4.0, 10.0],
        };
        let grid = VolumeGrid::of(&volume);
        assert_eq!(
            (grid.dims, grid.range, grid.middle()),
            ([2, 1, 1], (-4.0, 10.0), 3.0)
        );
        let settings = VoxelSettings::default();
        assert_eq!(settings.params(Some(&grid)).threshold, Some(3.0));
        let moved = VoxelSettings {
            resolution: 200,
            iso: 0.3,
            threshold: Some(3.0),
            ..settings
        };
        assert_eq!(moved.params(Some(&grid)), settings.params(Some(&grid)));
        assert_ne!(moved.params(None), settings.params(None), "a solid's do");
        let clamped = VoxelSettings {
            threshold: Some(99.0),
            ..settings
        };
        assert_eq!(clamped.params(Some(&grid)).threshold, Some(10.0));
        assert_eq!(clamped.params(None), settings.params(None));
        assert_eq!(
            settings.params(None),
            VoxelParams::default(),
            "the studio starts from the one default"
        );
    }
}
