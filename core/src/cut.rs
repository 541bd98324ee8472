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

/// What a ray hit on a cut (the studio's click-to-inspect).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Picked {
    /// Triangle `index` of the cut's mesh, with its error bound when known.
    Triangle {
        index: usize,
        error: Option<f32>,
    },
    Point {
        index: usize,
        radius: f32,
        error: f32,
    },
    Splat {
        index: usize,
        domain: usize,
    },
    Layer {
        layer: usize,
        isodensity: f32,
    },
}

/// Distance along the ray (origin, unit dir) to triangle `t`, if it is hit
/// (Möller–Trumbore, both faces).
fn ray_triangle(origin: Vec3, dir: Vec3, [a, b, c]: [Vec3; 3]) -> Option<f32> {
    let (e1, e2) = (b - a, c - a);
    let p = dir.cross(e2);
    let det = e1.dot(p);
    if det.abs() < 1e-12 {
        return None;
    }
    let s = origin - a;
    let u = s.dot(p) / det;
    let q = s.cross(e1);
    let v = dir.dot(q) / det;
    let t = e2.dot(q) / det;
    (u >= 0.0 && v >= 0.0 && u + v <= 1.0 && t > 0.0).then_some(t)
}

impl DrawSet {
    /// The primitive nearest along the ray from `origin` in direction `dir`.
    pub fn pick(&self, origin: Vec3, dir: Vec3) -> Option<(f32, Picked)> {
        let dir = dir.normalize_or_zero();
        let mut best: Option<(f32, Picked)> = None;
        let mut offer = |t: f32, p: Picked| {
            if best.is_none_or(|(bt, _)| t < bt) {
                best = Some((t, p));
            }
        };
        for i in 0..self.mesh.triangles.len() {
            if let Some(t) = ray_triangle(origin, dir, self.mesh.triangle(i)) {
                let error = self.triangle_errors.get(i).copied();
                offer(t, Picked::Triangle { index: i, error });
            }
        }
        for (i, p) in self.points.iter().enumerate() {
            // Ray against the point's ball.
            let oc = p.center - origin;
            let along = oc.dot(dir);
            let d2 = oc.length_squared() - along * along;
            if along > 0.0 && d2 <= p.radius * p.radius {
                let t = along - (p.radius * p.radius - d2).max(0.0).sqrt();
                offer(
                    t,
                    Picked::Point {
                        index: i,
                        radius: p.radius,
                        error: p.error,
                    },
                );
            }
        }
        for (i, s) in self.splats.iter().enumerate() {
            let [a, b] = s.axes;
            let corners = [
                s.center - a - b,
                s.center + a - b,
                s.center + a + b,
                s.center - a + b,
            ];
            for tri in [
                [corners[0], corners[1], corners[2]],
                [corners[0], corners[2], corners[3]],
            ] {
                if let Some(t) = ray_triangle(origin, dir, tri) {
                    offer(
                        t,
                        Picked::Splat {
                            index: i,
                            domain: s.domain,
                        },
                    );
                }
            }
        }
        for (l, layer) in self.layers.iter().enumerate() {
            for i in 0..layer.mesh.triangles.len() {
                if let Some(t) = ray_triangle(origin, dir, layer.mesh.triangle(i)) {
                    offer(
                        t,
                        Picked::Layer {
                            layer: l,
                            isodensity: layer.isodensity,
                        },
                    );
                }
            }
        }
        best
    }
}

/// A built LOD hierarchy.
pub trait Hierarchy: Send + Sync {
    /// Short name of the method, for logs and the inspector.
    fn method(&self) -> &'static str;
    /// Bounding-box diagonal of the model it was built from (what relative
    /// tolerances and bounds refer to).
    fn diagonal(&self) -> f32;
    /// The primitives to draw for `view` within `tolerance`. Hierarchies that
    /// adapt incrementally keep the previous cut and start from it.
    fn select(&mut self, view: &View, tolerance: Tolerance) -> DrawSet;
    /// Equal keys for two views promise equal cuts at `tolerance`, so a caller
    /// re-selecting every frame can skip the work; `None` (the default) when
    /// any change of the view may change the cut.
    fn view_key(&self, _view: &View, _tolerance: Tolerance) -> Option<u64> {
        None
    }
    /// The finest cut with at most `n` triangles, for methods whose cuts
    /// form one sequence (edge collapse); `None` for the others.
    fn select_triangles(&mut self, _n: usize) -> Option<DrawSet> {
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

/// The finest cut of `hierarchy` with at most `n` triangles: its own where
/// its cuts form one sequence, else the cut at the least relative tolerance
/// that keeps to `n` (bisected to 1e-6 of the diagonal; the coarsest cut if
/// none does).
pub fn select_triangles(hierarchy: &mut dyn Hierarchy, view: &View, n: usize) -> DrawSet {
    if let Some(set) = hierarchy.select_triangles(n) {
        return set;
    }
    let mut cut = |f: f32| hierarchy.select(view, Tolerance::Relative(f));
    let (mut lo, mut hi) = (0.0f32, 1.0f32);
    let mut best = cut(hi);
    if best.mesh.triangles.len() > n {
        return best;
    }
    while hi - lo > 1e-6 {
        let mid = 0.5 * (lo + hi);
        let set = cut(mid);
        if set.mesh.triangles.len() <= n {
            (hi, best) = (mid, set);
        } else {
            lo = mid;
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn picking_finds_the_nearest_primitive_of_each_kind() {
        let mut set = DrawSet {
            mesh: TriMesh::new(
                vec![
                    Vec3::new(-1.0, -1.0, 0.0),
                    Vec3::new(1.0, -1.0, 0.0),
                    Vec3::new(0.0, 1.0, 0.0),
                ],
                vec![[0, 1, 2]],
            ),
            triangle_errors: vec![0.25],
            ..Default::default()
        };
        let down = Vec3::NEG_Z;
        let hit = set.pick(Vec3::new(0.0, 0.0, 5.0), down);
        assert_eq!(
            hit,
            Some((
                5.0,
                Picked::Triangle {
                    index: 0,
                    error: Some(0.25)
                }
            ))
        );
        assert_eq!(set.pick(Vec3::new(3.0, 0.0, 5.0), down), None, "beside it");
        // A point in front of the triangle is nearer.
        set.points.push(CutPoint {
            center: Vec3::new(0.0, 0.0, 1.0),
            radius: 0.5,
            color: Vec3::ONE,
            normal: Vec3::Z,
            error: 0.7,
        });
        let (t, p) = set.pick(Vec3::new(0.0, 0.0, 5.0), down).unwrap();
        assert!((t - 3.5).abs() < 1e-5);
        assert_eq!(
            p,
            Picked::Point {
                index: 0,
                radius: 0.5,
                error: 0.7
            }
        );
        // Behind the eye nothing counts.
        assert_eq!(set.pick(Vec3::new(0.0, 0.0, -5.0), down), None);
    }
}
