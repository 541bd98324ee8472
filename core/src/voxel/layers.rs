//! Multi-layered marching cubes (§3): several iso-surfaces of the filtered
//! density, increasingly translucent outwards, approximate its smooth fall-off
//! and anti-alias the object's edges.
//!
//! Eq. 5: near a planar surface the density depends only on the distance r to
//! it, d(r) = the filter's mass beyond r; we measure that profile by filtering
//! a sampled half-space with the very filter in use. Eq. 6: the layers are the
//! segments of a piecewise-constant p with ∫|p − d| dr ≤ δ and as few segments
//! as that allows; following the paper's heuristic, breakpoints sit at equal
//! steps of density (so more layers where d changes fastest) and each segment's
//! constant is d at its midpoint (the L¹-best constant of a monotone function).
//! Eq. 4: a layer of isodensity d has translucency 1 − d/m, m the innermost
//! (largest) isodensity. §3's order: back to front by walking the volume's
//! slices along the axis closest to the view direction.

use glam::Vec3;

use super::{DENSITY_ISO, Filter, filter, marching_cubes};
use crate::geom::{TriMesh, Volume};
use crate::lod::{DrawSet, Hierarchy, Layer};
use crate::progress::{Cancelled, Progress};
use crate::simplify::{BoundOptions, Original};
use crate::view::{Tolerance, View};

/// Samples of the profile per filter radius.
const PROFILE_STEPS: usize = 16;
/// More layers than this stop helping the eye and cost a full extraction each.
pub const MAX_LAYERS: usize = 12;

/// The density profile across a planar surface (eq. 5): `d[i]` at signed
/// distance r_i = −R + 2R·i/(len−1) (negative inside), for support R = 1.
pub fn profile(kind: Filter) -> Vec<f32> {
    let h = 1.0 / PROFILE_STEPS as f32;
    let r = PROFILE_STEPS;
    // A slab long enough along x for the full transition, and wide enough
    // across for the kernel around the middle line.
    let (nx, nyz) = (4 * r + 1, 2 * r + 3);
    let mut data = vec![0.0f32; nx * nyz * nyz];
    for (i, v) in data.iter_mut().enumerate() {
        // S = 1 inside (x < 0), ½ on the plane, with x = (i − 2r)·h.
        let x = (i % nx) as isize - 2 * r as isize;
        *v = match x.cmp(&0) {
            std::cmp::Ordering::Less => 1.0,
            std::cmp::Ordering::Equal => 0.5,
            std::cmp::Ordering::Greater => 0.0,
        };
    }
    let slab = Volume {
        dims: [nx, nyz, nyz],
        spacing: Vec3::splat(h),
        origin: Vec3::ZERO,
        data,
    };
    // Rows far from the y/z borders see the kernel whole; use the middle one.
    let f = filter::apply(kind, &slab, 1.0, &Progress::new()).expect("never cancelled");
    let mid = nyz / 2;
    (r..=3 * r).map(|x| f.value(x, mid, mid)).collect()
}

/// The layers chosen for an error bound.
#[derive(Debug, Clone, PartialEq)]
pub struct LayerPlan {
    /// Isodensities, innermost (largest) first.
    pub isodensities: Vec<f32>,
    /// Opacity of each layer (eq. 4: 1 − translucency = d/m).
    pub opacities: Vec<f32>,
    /// ∫|p − d| dr over the transition band, divided by its width 2R: the mean
    /// density error, comparable across filters and radii.
    pub error: f32,
}

/// Eq. 6: the fewest layers whose piecewise-constant fit of `profile` has a mean
/// density error at most `delta` (at most [`MAX_LAYERS`]).
pub fn plan(profile: &[f32], delta: f32) -> LayerPlan {
    let delta = if delta.is_nan() { 0.0 } else { delta.max(0.0) };
    let mut best = fit(profile, 1);
    for n in 2..=MAX_LAYERS {
        if best.error <= delta {
            break;
        }
        best = fit(profile, n);
    }
    best
}

/// The n-segment fit with breakpoints at density levels k/n.
fn fit(profile: &[f32], n: usize) -> LayerPlan {
    let len = profile.len();
    // Index where the (decreasing) profile crosses each level k/n.
    let crossing = |level: f32| profile.iter().position(|&d| d < level).unwrap_or(len);
    let mut bounds: Vec<usize> = (1..n)
        .rev()
        .map(|k| crossing(k as f32 / n as f32))
        .collect();
    bounds.insert(0, 0);
    bounds.push(len);
    bounds.dedup();
    let (mut iso, mut error) = (Vec::new(), 0.0);
    for seg in bounds.windows(2) {
        let (a, b) = (seg[0], seg[1]);
        if a == b {
            continue;
        }
        let c = profile[(a + b - 1) / 2];
        error += profile[a..b].iter().map(|d| (d - c).abs()).sum::<f32>();
        iso.push(c);
    }
    iso.retain(|&d| d > 0.0 && d < 1.0);
    if iso.is_empty() {
        iso.push(super::DENSITY_ISO);
    }
    let m = iso.iter().cloned().fold(0.0f32, f32::max);
    LayerPlan {
        opacities: iso.iter().map(|d| d / m).collect(),
        isodensities: iso,
        error: error / len as f32,
    }
}

/// Extracts one mesh per planned layer from the filtered `density`.
pub fn extract(
    density: &Volume,
    plan: &LayerPlan,
    progress: &Progress,
) -> Result<Vec<Layer>, Cancelled> {
    plan.isodensities
        .iter()
        .zip(&plan.opacities)
        .map(|(&iso, &alpha)| {
            Ok(Layer {
                mesh: marching_cubes(density, iso, progress)?,
                alpha,
                isodensity: iso,
            })
        })
        .collect()
}

/// §3: all layers' triangles as (layer, triangle), back to front for `view`:
/// the cells of the volume grid (`origin`, `spacing`) are walked slice by slice
/// along the axis closest to the view direction, farthest slice first; inside a
/// slice inner layers go before outer ones. A marching-cubes triangle's centroid
/// lies in its own cell, which names the slice.
pub fn back_to_front(layers: &[Layer], origin: Vec3, spacing: Vec3, view: &View) -> Vec<[u32; 2]> {
    let fwd = view.forward();
    let axis = fwd.abs().max_position();
    let slice = |l: &Layer, t: usize| {
        let c = l.mesh.triangle(t).iter().sum::<Vec3>() / 3.0;
        ((c[axis] - origin[axis]) / spacing[axis]).floor().max(0.0) as usize
    };
    let mut items: Vec<(usize, [u32; 2])> = layers
        .iter()
        .enumerate()
        .flat_map(|(li, l)| {
            (0..l.mesh.triangles.len()).map(move |t| (slice(l, t), [li as u32, t as u32]))
        })
        .collect();
    // Stable: within a slice the layer order (innermost first) is kept.
    if fwd[axis] > 0.0 {
        items.sort_by_key(|(s, _)| std::cmp::Reverse(*s));
    } else {
        items.sort_by_key(|(s, _)| *s);
    }
    items.into_iter().map(|(_, id)| id).collect()
}

/// One level of §2 from its filtered density, with §3's translucent layers
/// when the layers error `delta` asks for more than one surface (else the
/// one surface at `iso`, a layer of its own, simplified further as `post`
/// says; translucent layers stay as extracted, their back-to-front order
/// follows the grid): the pipeline the CLI and the studio share.
pub struct LayeredLevel {
    /// The level proper: the layer nearest the 0.5 isodensity, its topology measured.
    pub level: super::VoxelLevel,
    pub plan: LayerPlan,
    pub layers: Vec<Layer>,
}

pub fn layered_level(
    density: &Volume,
    (resolution, radius): (usize, f32),
    filter: Filter,
    delta: f32,
    iso: f32,
    post: super::PostSimplify,
    progress: &Progress,
) -> Result<LayeredLevel, Cancelled> {
    let plan = plan(&profile(filter), delta);
    let layers = if plan.isodensities.len() > 1 {
        extract(density, &plan, progress)?
    } else {
        let raw = marching_cubes(density, iso, progress)?;
        let voxel = density.spacing.max_element();
        vec![Layer {
            mesh: super::post_simplify(raw, voxel, post, progress)?,
            alpha: plan.opacities.first().copied().unwrap_or(1.0),
            isodensity: iso,
        }]
    };
    let main = layers
        .iter()
        .min_by(|a, b| {
            (a.isodensity - DENSITY_ISO)
                .abs()
                .total_cmp(&(b.isodensity - DENSITY_ISO).abs())
        })
        .map(|l| l.mesh.clone())
        .unwrap_or_default();
    Ok(LayeredLevel {
        level: super::level(main, resolution, radius),
        plan,
        layers,
    })
}

/// One extracted level on its volume grid, as a hierarchy of one: a single
/// surface is drawn opaque; several layers (§3) are translucent and
/// re-ordered back to front for every view.
#[derive(Debug, Clone)]
pub struct Layered {
    pub layers: Vec<Layer>,
    pub origin: Vec3,
    pub spacing: Vec3,
    /// Certified two-sided Hausdorff bound of the layers against the input
    /// surface ([`Layered::certify`]); infinite while there is none (an
    /// implicit solid or a volume has no surface to measure against).
    pub error_bound: f32,
    /// The level proper and the plan of its layers, when built from them
    /// ([`Layered::of`]): what reports show of the build.
    pub level: Option<Box<super::VoxelLevel>>,
    pub plan: Option<LayerPlan>,
}

impl Layered {
    /// `layers` on the grid of `density`, not certified yet.
    pub fn new(layers: Vec<Layer>, density: &Volume) -> Layered {
        Layered {
            layers,
            origin: density.origin,
            spacing: density.spacing,
            error_bound: f32::INFINITY,
            level: None,
            plan: None,
        }
    }

    /// A built level's layers on the grid of `density`, keeping the level and
    /// its plan; not certified yet.
    pub fn of(built: LayeredLevel, density: &Volume) -> Layered {
        Layered {
            level: Some(Box::new(built.level)),
            plan: Some(built.plan),
            ..Layered::new(built.layers, density)
        }
    }

    /// Certifies the level against the input surface `reference` with the
    /// simplifier's machinery (as the pyramid's levels are): every layer is
    /// drawn, so the bound covers all of them.
    pub fn certify(&mut self, reference: &TriMesh, progress: &Progress) -> Result<(), Cancelled> {
        let mut all = TriMesh::default();
        for layer in &self.layers {
            all.append(&layer.mesh);
        }
        progress.stage("certifying the level's bound");
        let original = Original::new(reference);
        let opts = BoundOptions::for_diagonal(reference.bounds().diagonal());
        self.error_bound = super::pyramid::level_bound(&original, &all, &opts, progress)?;
        Ok(())
    }
}

impl Hierarchy for Layered {
    fn method(&self) -> crate::lod::Method {
        crate::lod::Method::Voxel
    }

    /// The layers' own extent (they are what the level keeps of the object).
    fn diagonal(&self) -> f32 {
        let points = self.layers.iter().flat_map(|l| &l.mesh.positions);
        let b = crate::geom::Aabb::from_points(points);
        if b.is_empty() { 0.0 } else { b.diagonal() }
    }

    /// The level is the only one: the tolerance does not change it, the view
    /// orders its layers.
    fn select(&mut self, view: &View, _tolerance: Tolerance) -> DrawSet {
        let bound = |set: DrawSet| DrawSet {
            error_bound: self.error_bound,
            ..set
        };
        match &self.layers[..] {
            [one] => bound(DrawSet {
                mesh: one.mesh.clone(),
                ..Default::default()
            }),
            layers => bound(DrawSet {
                layer_order: back_to_front(layers, self.origin, self.spacing, view),
                layers: layers.to_vec(),
                ..Default::default()
            }),
        }
    }

    /// The order changes only with the slicing axis and its direction (one
    /// surface: never).
    fn view_key(&self, view: &View, _tolerance: Tolerance) -> Option<u64> {
        if self.layers.len() == 1 {
            return Some(0);
        }
        let f = view.forward();
        let axis = f.abs().max_position();
        Some(2 * axis as u64 + u64::from(f[axis] > 0.0))
    }

    fn has_levels(&self) -> bool {
        false
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_level_of_one_surface_is_opaque_and_its_bound_holds() {
        let torus = crate::builtins::torus(1.0, 0.4, 48, 24);
        let solid = crate::implicit::MeshSolid::new(&torus);
        let source = super::super::Source::Solid(&solid);
        let progress = Progress::new();
        let f = super::super::density(source, 32, 1, 1.5, Filter::Gaussian, &progress)
            .expect("not cancelled");
        let post = super::super::PostSimplify::HALF_VOXEL;
        let built = layered_level(
            &f,
            (32, 1.5),
            Filter::Gaussian,
            0.5,
            DENSITY_ISO,
            post,
            &progress,
        )
        .expect("not cancelled");
        let mut level = Layered::new(built.layers, &f);
        let view = View::orbit(Vec3::ZERO, 4.0, 0.3, 0.2);
        let tolerance = Tolerance::Pixels(1.0);
        assert!(
            level.select(&view, tolerance).error_bound.is_infinite(),
            "not certified yet"
        );
        level.certify(&torus, &progress).expect("not cancelled");
        let set = level.select(&view, tolerance);
        assert!(
            set.layers.is_empty() && !set.mesh.triangles.is_empty(),
            "opaque"
        );
        assert!(!level.has_levels());
        assert_eq!(level.view_key(&view, tolerance), Some(0));
        // The certified bound is at least a dense two-sided measurement.
        let opts = crate::distance::SamplingOptions {
            samples: 40_000,
            ..Default::default()
        };
        let measured = crate::distance::hausdorff_mesh_mesh(&torus, &set.mesh, &opts).two_sided();
        assert!(
            set.error_bound >= measured && set.error_bound < 0.25,
            "bound {} vs measured {measured}",
            set.error_bound
        );
    }

    #[test]
    fn profiles_fall_from_one_to_zero_through_a_half() {
        for kind in [Filter::Gaussian, Filter::Cone] {
            let d = profile(kind);
            assert_eq!(d.len(), 2 * PROFILE_STEPS + 1);
            assert!(
                d.windows(2).all(|w| w[1] <= w[0] + 1e-5),
                "{kind:?} decreasing"
            );
            assert!(d[0] > 0.97 && *d.last().unwrap() < 0.03, "{kind:?}: {d:?}");
            assert!((d[PROFILE_STEPS] - 0.5).abs() < 0.02, "{kind:?} symmetric");
        }
    }

    #[test]
    fn tighter_bounds_take_more_layers_and_meet_the_bound() {
        let d = profile(Filter::Gaussian);
        let one = plan(&d, 1.0);
        assert_eq!(one.isodensities.len(), 1);
        assert!((one.isodensities[0] - 0.5).abs() < 0.05);
        let mut last = 1;
        for delta in [0.08, 0.04, 0.02, 0.01] {
            let p = plan(&d, delta);
            assert!(
                p.error <= delta || p.isodensities.len() == MAX_LAYERS,
                "{delta}"
            );
            assert!(p.isodensities.len() >= last, "{delta}");
            last = p.isodensities.len();
            assert!(
                p.isodensities.windows(2).all(|w| w[1] < w[0]),
                "innermost first"
            );
            assert_eq!(p.opacities[0], 1.0, "the innermost layer is opaque");
            assert!(
                p.opacities.windows(2).all(|w| w[1] < w[0]),
                "translucent outwards"
            );
        }
        assert!(last > 2);
    }

    #[test]
    fn layers_are_nested_and_drawn_back_to_front() {
        let sphere = crate::implicit::Sphere {
            center: Vec3::ZERO,
            radius: 1.0,
        };
        let p = Progress::new();
        let s = super::super::sampling::sample_implicit(&sphere, 24, 0.25, 2, &p).unwrap();
        let f = filter::apply(Filter::Gaussian, &s, 0.25, &p).unwrap();
        let plan = plan(&profile(Filter::Gaussian), 0.03);
        let layers = extract(&f, &plan, &p).unwrap();
        assert!(layers.len() >= 2);
        // Higher isodensity = nearer the solid's core: smaller mean radius.
        let radius = |l: &Layer| {
            l.mesh.positions.iter().map(|q| q.length()).sum::<f32>() / l.mesh.positions.len() as f32
        };
        assert!(layers.windows(2).all(|w| radius(&w[0]) < radius(&w[1])));
        let view = View::orbit(Vec3::ZERO, 5.0, 0.3, 0.2);
        let order = back_to_front(&layers, f.origin, f.spacing, &view);
        let total: usize = layers.iter().map(|l| l.mesh.triangles.len()).sum();
        assert_eq!(order.len(), total);
        // Distance along the view never grows by more than one slice (plus the
        // cell's own extent) from one triangle to the next.
        let fwd = view.forward();
        let axis = fwd.abs().max_position();
        let depth = |[l, t]: [u32; 2]| {
            let c = layers[l as usize]
                .mesh
                .triangle(t as usize)
                .iter()
                .sum::<Vec3>()
                / 3.0;
            c[axis] * fwd[axis].signum()
        };
        for w in order.windows(2) {
            assert!(depth(w[1]) <= depth(w[0]) + f.spacing[axis] * 1.001);
        }
    }
}
