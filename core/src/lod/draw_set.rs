//! The primitives on a cut: triangles, points, textured splats and
//! translucent layers, with each primitive's error bound where the method
//! has one.

use glam::Vec3;
use serde::{Deserialize, Serialize};

use crate::geom::TriMesh;

/// A point primitive: a disc/sphere of `radius` (hybrid paper §5.3).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct CutPoint {
    pub center: Vec3,
    pub radius: f32,
    pub color: Vec3,
    pub normal: Vec3,
    /// Error bound of the node it came from (object space).
    pub error: f32,
}

/// An RGBA8 texture (colour, and Ψ in alpha for AMG domain primitives).
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct Texture {
    pub width: u32,
    pub height: u32,
    pub rgba: Vec<[u8; 4]>,
}

/// A textured, alpha-blended quad (AMG paper §3): `center ± axes[0] ± axes[1]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Splat {
    pub center: Vec3,
    /// Half-extent vectors along the quad's principal axes.
    pub axes: [Vec3; 2],
    pub normal: Vec3,
    /// Index into [`DrawSet::textures`].
    pub texture: usize,
    /// Domain id (AMG level, index) for inspection.
    pub domain: usize,
    /// Splats (indices into [`DrawSet::splats`]) whose domains overlap this
    /// one's; AMG §4 blends a primitive with these before locking its depth.
    pub neighbours: Vec<usize>,
}

impl Splat {
    /// The quad's corners, counter-clockwise about its normal: `center -
    /// a - b`, `+ a - b`, `+ a + b`, `- a + b` (texture corners (0, 0),
    /// (1, 0), (1, 1), (0, 1)).
    pub fn corners(&self) -> [Vec3; 4] {
        let [a, b] = self.axes;
        [
            self.center - a - b,
            self.center + a - b,
            self.center + a + b,
            self.center - a + b,
        ]
    }
}

/// A translucent layer mesh (voxel paper §3) with its opacity.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Layer {
    pub mesh: TriMesh,
    pub alpha: f32,
    pub isodensity: f32,
}

/// What a cut's `error_bound` is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub enum BoundKind {
    /// A guarantee: no dense measurement of the two-sided Hausdorff distance
    /// to the original exceeds it (points as balls, splats as their quads).
    #[default]
    Certified,
    /// A measure of the method's own (AMG: the largest distance of a domain's
    /// points to its splat's plane), not a bound on the distance to the original.
    Estimate,
}

impl BoundKind {
    /// The JSON and inspector word.
    pub fn name(self) -> &'static str {
        match self {
            BoundKind::Certified => "certified",
            BoundKind::Estimate => "estimate",
        }
    }
}

/// The primitives on a cut.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct DrawSet {
    pub mesh: TriMesh,
    /// Per-triangle error bound of `mesh` (object space), when the method has one.
    pub triangle_errors: Vec<f32>,
    /// Per-triangle hierarchy level of `mesh`, for inspection, when the method
    /// has levels (merge tree: the highest tree level among the nodes of its
    /// display vertices, 0 for original vertices only).
    pub triangle_levels: Vec<u32>,
    pub points: Vec<CutPoint>,
    pub splats: Vec<Splat>,
    pub textures: Vec<Texture>,
    pub layers: Vec<Layer>,
    /// The layers' triangles as (layer, triangle), back to front for the view
    /// of the cut (voxel paper §3); empty draws them layer by layer.
    pub layer_order: Vec<[u32; 2]>,
    /// The cut's error bound in object space (max over its primitives).
    pub error_bound: f32,
    pub error_bound_kind: BoundKind,
    /// A triangle budget the method could not reach, and why.
    pub unmet: Option<super::Unmet>,
}

impl DrawSet {
    /// What the studio's "colour by region" colours in this set (merge-tree
    /// levels, AMG domains, voxel layers); `None` when it has none.
    pub fn regions(&self) -> Option<&'static str> {
        if !self.triangle_levels.is_empty() {
            Some("merge-tree level")
        } else if !self.splats.is_empty() {
            Some("AMG domain")
        } else if !self.layers.is_empty() {
            Some("voxel layer")
        } else {
            None
        }
    }

    pub fn primitive_count(&self) -> usize {
        self.mesh.triangles.len()
            + self.points.len()
            + self.splats.len()
            + self
                .layers
                .iter()
                .map(|l| l.mesh.triangles.len())
                .sum::<usize>()
    }
}
