//! What every hierarchy answers: given a view and a tolerance, which primitives
//! to draw (DESIGN.md). The GUI, the exporter and the tests treat all five
//! methods through [`Hierarchy`] and the [`DrawSet`] of a cut.

use glam::Vec3;

use crate::geom::TriMesh;
use crate::view::{Tolerance, View};

/// A point primitive: a disc/sphere of `radius` (hybrid paper §5.3).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CutPoint {
    pub center: Vec3,
    pub radius: f32,
    pub color: Vec3,
    pub normal: Vec3,
    /// Error bound of the node it came from (object space).
    pub error: f32,
}

/// An RGBA8 texture (colour, and Ψ in alpha for AMG domain primitives).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Texture {
    pub width: u32,
    pub height: u32,
    pub rgba: Vec<[u8; 4]>,
}

/// A textured, alpha-blended quad (AMG paper §3): `center ± axes[0] ± axes[1]`.
#[derive(Debug, Clone, PartialEq)]
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

/// A translucent layer mesh (voxel paper §3) with its opacity.
#[derive(Debug, Clone, PartialEq)]
pub struct Layer {
    pub mesh: TriMesh,
    pub alpha: f32,
    pub isodensity: f32,
}

/// The primitives on a cut.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct DrawSet {
    pub mesh: TriMesh,
    /// Per-triangle error bound of `mesh` (object space), when the method has one.
    pub triangle_errors: Vec<f32>,
    pub points: Vec<CutPoint>,
    pub splats: Vec<Splat>,
    pub textures: Vec<Texture>,
    pub layers: Vec<Layer>,
    /// The layers' triangles as (layer, triangle), back to front for the view
    /// of the cut (voxel paper §3); empty draws them layer by layer.
    pub layer_order: Vec<[u32; 2]>,
    /// The cut's error bound in object space (max over its primitives).
    pub error_bound: f32,
}

impl DrawSet {
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

/// A built LOD hierarchy.
pub trait Hierarchy: Send + Sync {
    /// Short name of the method, for logs and the inspector.
    fn method(&self) -> &'static str;
    /// The primitives to draw for `view` within `tolerance`. Hierarchies that
    /// adapt incrementally keep the previous cut and start from it.
    fn select(&mut self, view: &View, tolerance: Tolerance) -> DrawSet;
    /// Equal keys for two views promise equal cuts at `tolerance`, so a caller
    /// re-selecting every frame can skip the work; `None` (the default) when
    /// any change of the view may change the cut.
    fn view_key(&self, _view: &View, _tolerance: Tolerance) -> Option<u64> {
        None
    }
    /// Run-time parameters that change the cut without a rebuild (the merge
    /// tree's criteria, say), as JSON; unknown keys are ignored.
    fn set_runtime(&mut self, _params: &serde_json::Value) {}
    /// The built hierarchy in a saved-hierarchy file with `params` (see
    /// [`crate::io::hierarchy_file`]); `None` for hierarchies that do not save.
    fn save(&self, _params: &serde_json::Value) -> Option<Vec<u8>> {
        None
    }
}
