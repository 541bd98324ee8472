//! What a voxel build is made with (§2–§5): the grid, the filter, the
//! surface extracted and whether the whole pyramid is kept, with each
//! value's default and range written once, here.

use std::ops::RangeInclusive;

use serde::{Deserialize, Serialize};

use super::layers::{self, Layered};
use super::pyramid::PyramidCut;
use super::{DENSITY_ISO, Filter, PostSimplify, Pyramid, RADIUS_RANGE, RESOLUTION_RANGE, Source};
use crate::lod::{Hierarchy, ParamError, in_range};
use crate::progress::{Cancelled, Progress};

/// Densities an implicit solid's surface may be extracted at.
pub const ISO_RANGE: RangeInclusive<f32> = 0.05..=0.95;
/// Layers error δ (§3, eq. 6): the mean density error one surface leaves is
/// at most 0.5, so 0.5 is one surface and smaller values add layers.
pub const LAYERS_RANGE: RangeInclusive<f32> = 0.0..=0.5;

/// Everything a voxel build needs besides its source.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct VoxelParams {
    /// Voxels along the longest side of a solid's bounds (volumes keep
    /// their own grid).
    pub resolution: usize,
    /// Filter support radius R, in voxels of that grid.
    pub radius: f32,
    pub filter: Filter,
    /// Density of the extracted surface of a solid (a volume's is always
    /// the density 0.5 of its filtered S).
    pub iso: f32,
    /// Volumes: samples at or above this value form S; `None`, the middle
    /// of the volume's value range.
    pub threshold: Option<f32>,
    /// Layers error δ of §3 (0.5: one surface).
    pub layers_error: f32,
    /// How each extracted level is simplified further (§5: the method is
    /// "the first stage").
    pub post: PostSimplify,
    /// The whole pyramid (Tables 1–3), browsed at any position (§5),
    /// instead of one level.
    pub pyramid: bool,
}

impl Default for VoxelParams {
    fn default() -> Self {
        VoxelParams {
            resolution: 64,
            radius: 2.0,
            filter: Filter::Gaussian,
            iso: DENSITY_ISO,
            threshold: None,
            layers_error: *LAYERS_RANGE.end(),
            post: PostSimplify::HALF_VOXEL,
            pyramid: false,
        }
    }
}

impl VoxelParams {
    pub fn validate(&self) -> Result<(), ParamError> {
        in_range("resolution", self.resolution, &RESOLUTION_RANGE)?;
        super::check_resolution_budget(self.resolution)
            .map_err(|m| ParamError::new("resolution", m))?;
        in_range("radius", self.radius, &RADIUS_RANGE)?;
        in_range("iso", self.iso, &ISO_RANGE)?;
        in_range("layers_error", self.layers_error, &LAYERS_RANGE)?;
        if let Some(t) = self.threshold
            && !t.is_finite()
        {
            return Err(ParamError::new("threshold", "must be a finite value"));
        }
        self.post.check().map_err(|m| ParamError::new("post", m))
    }

    /// Samples, filters and extracts `source`: the pyramid cut live, or one
    /// level (its layers when δ asks for several), each certified against a
    /// mesh's surface.
    pub fn build(
        &self,
        source: Source,
        progress: &Progress,
    ) -> Result<Box<dyn Hierarchy>, Cancelled> {
        if self.pyramid {
            let mut pyramid =
                Pyramid::build(source, self.resolution, self.radius, self.filter, progress)?;
            pyramid.post = self.post;
            pyramid.certify(source.surface(), progress)?;
            return Ok(Box::new(PyramidCut::new(pyramid, None)));
        }
        let (resolution, iso) = match source {
            Source::Solid(_) => (self.resolution, self.iso),
            Source::Volume(v, _) => (v.dims.into_iter().max().unwrap_or(0), DENSITY_ISO),
        };
        let f = super::density(source, resolution, 1, self.radius, self.filter, progress)?;
        let built = layers::layered_level(
            &f,
            (resolution, self.radius),
            self.filter,
            self.layers_error,
            iso,
            self.post,
            progress,
        )?;
        let mut level = Layered::of(built, &f);
        if let Some(surface) = source.surface() {
            level.certify(surface, progress)?;
        }
        Ok(Box::new(level))
    }
}
