//! Certified pruning of small components (issue 48, item 2: "small
//! components are pruned when their removal is within the target"). A far
//! LOD of a scan of many pieces spends most of its triangles keeping specks
//! that no longer show; meshoptimizer's `Prune` drops them by size and says
//! nothing of what it cost. Here what it costs is certified.
//!
//! **The bound.** Let R be the mesh less the pruned components P. R ⊆ O, so
//! every point of R is on O (distance 0), and a point x of a pruned
//! component is within d(x, R) of R: d_H(O, R) = max over P of d(x, R).
//! Each pruned triangle's max d(x, R) is bounded by the branch and bound of
//! `bound` (convexity and Lipschitz, exact distances), so the pruning's
//! bound is certified. Simplifying R then adds its own certificate by the
//! triangle inequality on the O → S side only: a point of S is within its
//! bound of R ⊆ O, while a pruned point is within the pruning's bound of R
//! and R within the collapse's of S.
//!
//! **Which components.** Never the largest (by area). The others are
//! ranked by the exact distance of their farthest vertex from the rest of
//! the mesh (a lower bound on their cost; over the budget, never pruned).
//! The k cheapest are certified together against the mesh without them,
//! and the largest k within the budget is found by bisection; what is
//! pruned is certified as it is, whatever the search assumed.

use rayon::prelude::*;

use super::bound::{
    Ask, BoundOptions, Original, Traced, certify_against, certify_traced, max_distance_bound,
};
use super::collapse::CollapseOptions;
use super::progressive::{Progressive, record};
use super::{Simplified, SimplifyError, SimplifyOptions, Target};
use crate::distance::{Bvh, MeshDistance, closest_point_on_triangle};
use crate::geom::{Aabb, Topology, TriMesh};
use crate::progress::{Cancelled, Progress};

/// A mesh less its pruned components.
#[derive(Debug, Clone)]
pub struct Pruned {
    /// The triangles kept, with their attributes and materials.
    pub mesh: TriMesh,
    /// Components removed, and their triangles (indices into the input).
    pub components: usize,
    pub removed: Vec<u32>,
    /// Certified two-sided Hausdorff distance between the input and `mesh`.
    pub bound: f32,
}

impl Pruned {
    /// `mesh` itself, nothing pruned.
    fn nothing(mesh: &TriMesh) -> Pruned {
        Pruned {
            mesh: mesh.clone(),
            components: 0,
            removed: Vec::new(),
            bound: 0.0,
        }
    }
}

/// `mesh` less every component but the largest whose removal costs at most
/// `budget` (module doc); the input itself (bound 0) when none does.
pub fn prune(mesh: &TriMesh, budget: f32, opts: &BoundOptions) -> Pruned {
    let unchanged = || Pruned::nothing(mesh);
    let topology = Topology::of(mesh);
    let count = topology.components.len();
    if count < 2 || budget.is_nan() || budget <= 0.0 {
        return unchanged();
    }
    let component = |t: usize| topology.vertex_component[mesh.triangles[t][0] as usize] as usize;
    let mut area = vec![0.0f64; count];
    for t in 0..mesh.triangles.len() {
        area[component(t)] += mesh.triangle_area(t) as f64;
    }
    let largest = (0..count)
        .max_by(|&a, &b| area[a].total_cmp(&area[b]).then(b.cmp(&a)))
        .expect("two components or more");
    // Screen: a component whose vertex lies farther than the budget from
    // every other component cannot be pruned.
    let boxes: Vec<Aabb> = (0..mesh.triangles.len())
        .map(|t| Aabb::from_points(&mesh.triangle(t)))
        .collect();
    let bvh = Bvh::build(&boxes);
    let mut vertices_of: Vec<Vec<u32>> = vec![Vec::new(); count];
    for (v, &c) in topology.vertex_component.iter().enumerate() {
        if c != u32::MAX {
            vertices_of[c as usize].push(v as u32);
        }
    }
    // Each component's largest vertex distance to the others: a lower
    // bound on what it costs.
    let estimate: Vec<f32> = (0..count)
        .into_par_iter()
        .map(|c| match c == largest {
            true => f32::INFINITY,
            false => vertices_of[c]
                .iter()
                .map(|&v| {
                    let p = mesh.positions[v as usize];
                    let others = |t: u32| match component(t as usize) == c {
                        true => f32::INFINITY,
                        false => {
                            let [a, b, d] = mesh.triangle(t as usize);
                            closest_point_on_triangle(p, a, b, d).distance(p)
                        }
                    };
                    bvh.nearest(p, others).map_or(f32::INFINITY, |(d, _)| d)
                })
                .fold(0.0, f32::max),
        })
        .collect();
    let mut candidates: Vec<usize> = (0..count).filter(|&c| estimate[c] <= budget).collect();
    candidates.sort_by(|&a, &b| estimate[a].total_cmp(&estimate[b]).then(a.cmp(&b)));
    let mut triangles_of: Vec<Vec<usize>> = vec![Vec::new(); count];
    for t in 0..mesh.triangles.len() {
        triangles_of[component(t)].push(t);
    }
    // The k cheapest candidates, certified against the mesh without them:
    // the largest cost among them.
    let certified = |k: usize| -> f32 {
        let mut out = vec![false; count];
        for &c in &candidates[..k] {
            out[c] = true;
        }
        let rest: Vec<u32> = (0..mesh.triangles.len() as u32)
            .filter(|&t| !out[component(t as usize)])
            .collect();
        let rest = mesh.arrays().gather(rest);
        let target = MeshDistance::new(&rest);
        candidates[..k]
            .par_iter()
            .flat_map_iter(|&c| &triangles_of[c])
            .map(|&t| {
                let tri = mesh.triangle(t);
                let at = tri.map(|p| target.nearest(p));
                max_distance_bound(tri, at, (&target, None), opts, 0.0, 0.0).0
            })
            .reduce(|| 0.0, f32::max)
    };
    // The longest prefix within the budget, by bisection (cost mostly grows
    // with the prefix; whatever is chosen is certified as it is).
    let (mut lo, mut hi, mut bound) = (0, candidates.len(), 0.0);
    while lo < hi {
        let mid = (lo + hi).div_ceil(2);
        let cost = certified(mid);
        match cost <= budget {
            true => (lo, bound) = (mid, cost),
            false => hi = mid - 1,
        }
    }
    if lo == 0 {
        return unchanged();
    }
    let mut pruned = vec![false; count];
    for &c in &candidates[..lo] {
        pruned[c] = true;
    }
    let (removed, kept): (Vec<u32>, Vec<u32>) =
        (0..mesh.triangles.len() as u32).partition(|&t| pruned[component(t as usize)]);
    Pruned {
        mesh: mesh.arrays().gather(kept),
        components: lo,
        removed,
        bound,
    }
}

/// Whether a simplification may change the mesh's topology.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum TopologyMode {
    /// Every component and handle stays.
    #[default]
    Keep,
    /// Components may be pruned, and pieces merged and holes closed by pair
    /// contraction, where that is certified ([`simplify_free`]).
    Free,
}

impl TopologyMode {
    pub fn is_keep(&self) -> bool {
        *self == TopologyMode::Keep
    }
}

impl std::str::FromStr for TopologyMode {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "keep" => Ok(TopologyMode::Keep),
            "free" => Ok(TopologyMode::Free),
            _ => Err(format!("expected keep or free, got {s:?}")),
        }
    }
}

/// What a simplification free to change topology did.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct TopologyReport {
    pub components_before: usize,
    pub components_after: usize,
    /// Summed over components from their Euler characteristics: negative
    /// where a contraction joined pieces at one vertex (not a manifold).
    pub genus_before: i64,
    pub genus_after: i64,
    pub pruned_components: usize,
    pub pruned_triangles: usize,
    /// The pruning's certified share of the bound (0 when none went).
    pub prune_bound: f32,
    /// The grid spacing of the pair contraction across gaps (module
    /// `pairs`) and the vertices it contracted into another; 0 when none.
    pub pair_cell: f32,
    pub contracted_vertices: usize,
}

/// The certified largest distance from the input's `removed` triangles to
/// `result`: the O → S side of what pruning left out, measured directly.
fn removed_to(mesh: &TriMesh, removed: &[u32], result: &TriMesh, opts: &BoundOptions) -> f32 {
    if result.triangles.is_empty() {
        return f32::INFINITY;
    }
    let target = MeshDistance::new(result);
    removed
        .par_iter()
        .map(|&t| {
            let tri = mesh.triangle(t as usize);
            let at = tri.map(|p| target.nearest(p));
            max_distance_bound(tri, at, (&target, None), opts, 0.0, 0.0).0
        })
        .reduce(|| 0.0, f32::max)
}

/// `pruned`'s mesh simplified by `opts`, certified against the whole input:
/// its O → S side also covers the pruned triangles, by the lesser of two
/// certified bounds, their own distance to the result and the pruning's
/// bound plus the collapse's (triangle inequality). They are attributed to
/// no triangle of the result.
fn simplify_pruned(
    mesh: &TriMesh,
    pruned: &Pruned,
    opts: &SimplifyOptions,
    bound_opts: &BoundOptions,
    progress: &Progress,
) -> Result<Simplified, SimplifyError> {
    let mut result = super::simplify(&pruned.mesh, opts, progress)?;
    let c = &mut result.certificate;
    let direct = removed_to(mesh, &pruned.removed, &result.mesh, bound_opts);
    c.forward = c.forward.max(direct.min(pruned.bound + c.forward));
    c.attributed.clear();
    Ok(result)
}

/// Pair contraction (module `pairs`) of a certified result of `mesh`, with
/// the collapse going on from it, certified against `mesh` directly.
struct Contracting<'a> {
    original: Original<'a>,
    opts: SimplifyOptions,
    certifying: BoundOptions,
}

impl<'a> Contracting<'a> {
    fn new(mesh: &'a TriMesh, opts: &SimplifyOptions, bound_opts: &BoundOptions) -> Self {
        Contracting {
            original: Original::new(mesh),
            opts: *opts,
            certifying: BoundOptions {
                per_triangle: opts.per_triangle_bounds,
                ..*bound_opts
            },
        }
    }

    /// `base`'s pairs within one cell of spacing `cell` (the grid offset by
    /// `shift` cells) contracted, then collapsed to the options' target;
    /// with an `error`, to what is left of it after the contraction's own
    /// certified cost. A result not certified `below` is [`Attempt::Over`]:
    /// an exact distance past it ends its certificate early.
    fn run(
        &self,
        base: &TriMesh,
        cell: f32,
        shift: f32,
        error: Option<f32>,
        below: Option<f32>,
        progress: &Progress,
    ) -> Result<Attempt, SimplifyError> {
        let (contracted, pairs) = super::pairs::contract(base, cell, shift);
        if pairs == 0 || contracted.triangles.is_empty() {
            return Ok(Attempt::Nothing);
        }
        // A count is collapsed to uncertified (the result is certified
        // against the input below, not against the contracted mesh); an
        // error needs the collapse's limit, which certifies as it goes.
        let (mesh, collapses, unmet) = match (error, self.opts.target) {
            (Some(e), _) => {
                let cost =
                    certify_against(&self.original, &contracted, &self.certifying, progress)?
                        .error_bound();
                if cost >= e {
                    return Ok(Attempt::Over);
                }
                let opts = SimplifyOptions {
                    target: Target::Error(e - cost),
                    ..self.opts
                };
                let r = super::simplify(&contracted, &opts, progress)?;
                (r.mesh, r.collapses, r.unmet)
            }
            (None, Target::Triangles(count)) => {
                super::collapse_to(&contracted, self.opts.collapse, count, progress)?
            }
            (None, target) => {
                unreachable!("contraction runs to a count or an error, not {target:?}")
            }
        };
        if let Some(limit) = below {
            let ids: Vec<u32> = (0..mesh.triangles.len() as u32).collect();
            let within = Ask::Within(limit, None);
            let o = &self.original;
            let traced = certify_traced(o, &mesh, &ids, None, &self.certifying, within, progress)?;
            if let Traced::Over(_) = traced {
                return Ok(Attempt::Over);
            }
        }
        let result = Simplified {
            certificate: certify_against(&self.original, &mesh, &self.certifying, progress)?,
            mesh,
            collapses,
            unmet,
        };
        let contraction = Contraction {
            cell,
            pairs,
            from: base.triangles.len(),
            mesh: contracted,
        };
        Ok(Attempt::Done(result, contraction))
    }
}

/// What one contraction gave.
// One per attempt, matched at once: boxing the result buys nothing.
#[allow(clippy::large_enum_variant)]
enum Attempt {
    /// No pair within a cell, or no triangle left.
    Nothing,
    /// The contraction alone costs the error, or the result is not below
    /// the bound asked.
    Over,
    /// The result and the contraction it went on from.
    Done(Simplified, Contraction),
}

/// A state of the collapse with its pairs contracted (module `pairs`).
#[derive(Debug, Clone)]
struct Contraction {
    cell: f32,
    /// Vertices contracted into another.
    pairs: usize,
    /// The state's triangles, and the mesh the contraction made of it.
    from: usize,
    mesh: TriMesh,
}

/// [`simplify`](super::simplify) free to drop components (`--topology
/// free`). For an error E, components costing at most E/2 are pruned and
/// the rest simplified to E less what they cost (or not, where the plain
/// collapse to E keeps fewer triangles); the collapse to E/2 is
/// also contracted across gaps and holes (module `pairs`) and collapsed to
/// E less the contraction's certified cost, and the fewest triangles win. For a triangle count, the
/// plain result's bound e is the yardstick: the mesh is pruned at a
/// quarter, half and all of e, and at √2·e, 2e, … while the count is unmet,
/// each simplified to the count. Where the plain result stops short of the
/// count, its vertices are also contracted across gaps and holes (module
/// `pairs`) and collapsed to the count, certified against the input. Of all
/// these and the plain result the one nearest the count wins, then the one
/// with the lowest certified bound.
///
/// # Errors
/// As [`simplify`](super::simplify).
pub fn simplify_free(
    mesh: &TriMesh,
    opts: &SimplifyOptions,
    progress: &Progress,
) -> Result<Free, SimplifyError> {
    let diag = mesh.bounds().diagonal();
    // A grid spacing to contract pairs at: none past the diagonal, and none
    // at 0 (an error of 0) or at infinity, where √2 steps never end.
    let spacing = |cell: f32| cell > 0.0 && cell.is_finite() && cell <= diag;
    let bound_opts = BoundOptions::for_diagonal(diag);
    let error = match opts.target {
        Target::Error(e) => Some(e),
        Target::RelativeError(e) => Some(e * diag),
        Target::Triangles(_) | Target::Ratio(_) => None,
    };
    let (pruned, result, pairs) = match error {
        Some(e) => {
            let pruned = prune(mesh, e * 0.5, &bound_opts);
            let rest = SimplifyOptions {
                target: Target::Error((e - pruned.bound).max(0.0)),
                ..*opts
            };
            let result = simplify_pruned(mesh, &pruned, &rest, &bound_opts, progress)?;
            let mut best = (pruned, result, None);
            // The plain collapse to E too: pruning at E/2 leaves the rest
            // less room, which can cost more triangles than it saves.
            let plain = super::simplify(mesh, opts, progress)?;
            if plain.mesh.triangles.len() < best.1.mesh.triangles.len() {
                best = (Pruned::nothing(mesh), plain, None);
            }
            // Pairs contracted in the collapse at half the error, where what
            // contraction costs leaves room within E for the collapse to go
            // on: cells from E/4 up by √2, two grid offsets each, until
            // both cost the error or the cell is the diagonal.
            let half = SimplifyOptions {
                target: Target::Error(0.5 * e),
                ..*opts
            };
            let base = super::simplify(mesh, &half, progress)?.mesh;
            let contracting = Contracting::new(mesh, opts, &bound_opts);
            let mut cell = 0.25 * e;
            while spacing(cell) {
                let mut over = true;
                for shift in [0.0, 0.5] {
                    match contracting.run(&base, cell, shift, Some(e), None, progress)? {
                        Attempt::Over => {}
                        Attempt::Nothing => over = false,
                        Attempt::Done(r, contraction) => {
                            over = false;
                            let fewer = r.mesh.triangles.len() < best.1.mesh.triangles.len();
                            if fewer && r.error_bound() <= e {
                                best = (Pruned::nothing(mesh), r, Some(contraction));
                            }
                        }
                    }
                }
                if over {
                    break;
                }
                cell *= std::f32::consts::SQRT_2;
            }
            best
        }
        None => {
            let plain = super::simplify(mesh, opts, progress)?;
            let asked = match opts.target {
                Target::Ratio(r) => (r as f64 * mesh.triangles.len() as f64).round() as usize,
                Target::Triangles(n) => n,
                Target::Error(_) | Target::RelativeError(_) => unreachable!("a count"),
            };
            let rest = SimplifyOptions {
                target: Target::Triangles(asked),
                ..*opts
            };
            let key = |r: &Simplified| (r.mesh.triangles.len().max(asked), r.error_bound());
            let yardstick = plain.error_bound();
            let floor = (plain.mesh.triangles.len() > asked).then(|| plain.mesh.clone());
            let mut best = (Pruned::nothing(mesh), plain, None);
            let mut tried: Vec<Vec<u32>> = Vec::new();
            // A quarter, half and all of the yardstick; then, while the
            // count is still unmet, √2 times as much each time, up to the
            // diagonal (a count past the pieces' floor is reached, at the
            // certified price of what goes).
            let mut share = 0.25;
            while share <= 1.0 || (best.1.mesh.triangles.len() > asked && share * yardstick <= diag)
            {
                let pruned = prune(mesh, share * yardstick, &bound_opts);
                share *= match share < 1.0 {
                    true => 2.0,
                    false => std::f32::consts::SQRT_2,
                };
                if pruned.components == 0 || tried.contains(&pruned.removed) {
                    continue;
                }
                tried.push(pruned.removed.clone());
                let result = simplify_pruned(mesh, &pruned, &rest, &bound_opts, progress)?;
                let (new, old) = (key(&result), key(&best.1));
                if new.0 < old.0 || (new.0 == old.0 && new.1 < old.1) {
                    best = (pruned, result, None);
                }
            }
            // Where the collapse stopped short of the count, pairs closer
            // than a cell are contracted across gaps and holes (module
            // `pairs`) and the collapse goes on, certified against the
            // input directly: cells from the yardstick up by √2, up to the
            // diagonal, until three have reached the count.
            let contracting = Contracting::new(mesh, &rest, &bound_opts);
            if let Some(floor) = floor {
                let (mut cell, mut reached) = (yardstick.max(1e-4 * diag), 0);
                while spacing(cell) && reached < 3 {
                    let mut any = false;
                    for shift in [0.0, 0.25, 0.5, 0.75] {
                        let Attempt::Done(result, contraction) =
                            contracting.run(&floor, cell, shift, None, None, progress)?
                        else {
                            continue;
                        };
                        any |= result.mesh.triangles.len() <= asked;
                        let (new, old) = (key(&result), key(&best.1));
                        if new.0 < old.0 || (new.0 == old.0 && new.1 < old.1) {
                            best = (Pruned::nothing(mesh), result, Some(contraction));
                        }
                    }
                    reached += usize::from(any);
                    cell *= std::f32::consts::SQRT_2;
                }
            } else {
                // The count is reached, every piece and handle kept; at a
                // coarse count they can cost more than they show (the rocker
                // arm at 50 triangles keeps its hole at 7.9 % of the
                // diagonal; a state of 200 with its pairs contracted gets
                // there at 5.4 %). Finer states of the collapse (2, 4 and 8
                // times the count) are contracted at cells from e/4 up by √2
                // to √2·e and collapsed to the count; a result certified
                // below the best so far wins. Each attempt collapses its
                // base again: bases are at most an eighth of the input (or
                // 2¹⁶ triangles), so a far count's search costs about what
                // the plain collapse did, and a near count's none (the
                // dragon at 10 %: 120 s for no gain, against 7.5 s).
                let n = mesh.triangles.len();
                let finer: Vec<usize> = [2, 4, 8]
                    .map(|m| m * asked)
                    .into_iter()
                    .filter(|&b| b < n && b <= (n / 8).max(1 << 16))
                    .collect();
                for base in super::states(mesh, opts.collapse, &finer, progress)? {
                    let mut cell = 0.25 * yardstick;
                    while spacing(cell) && cell <= 1.5 * yardstick {
                        for shift in [0.0, 0.5] {
                            let below = Some(best.1.error_bound());
                            let Attempt::Done(result, contraction) =
                                contracting.run(&base, cell, shift, None, below, progress)?
                            else {
                                continue;
                            };
                            if key(&result) < key(&best.1) {
                                best = (Pruned::nothing(mesh), result, Some(contraction));
                            }
                        }
                        cell *= std::f32::consts::SQRT_2;
                    }
                }
            }
            best
        }
    };
    let (before, after) = (Topology::of(mesh), Topology::of(&result.mesh));
    let report = TopologyReport {
        components_before: before.components.len(),
        components_after: after.components.len(),
        genus_before: before.genus,
        genus_after: after.genus,
        pruned_components: pruned.components,
        pruned_triangles: pruned.removed.len(),
        prune_bound: pruned.bound,
        pair_cell: pairs.as_ref().map_or(0.0, |p| p.cell),
        contracted_vertices: pairs.as_ref().map_or(0, |p| p.pairs),
    };
    let route = match pairs {
        Some(c) => Route::Changed {
            from: c.from,
            to: Box::new(c.mesh),
        },
        None if pruned.components > 0 => Route::Changed {
            from: mesh.triangles.len(),
            to: Box::new(pruned.mesh),
        },
        None => Route::Collapse,
    };
    Ok(Free {
        result,
        report,
        route,
    })
}

/// What [`simplify_free`] made, and how.
#[derive(Debug, Clone)]
pub struct Free {
    pub result: Simplified,
    pub report: TopologyReport,
    pub route: Route,
}

/// How [`simplify_free`] reached its result, for its progressive record
/// ([`record_free`]).
#[derive(Debug, Clone)]
pub enum Route {
    /// The plain collapse.
    Collapse,
    /// The plain collapse down to `from` triangles, then `to` in its place
    /// (the input less pruned pieces, or that state's pairs contracted),
    /// and the collapse of `to`.
    Changed { from: usize, to: Box<TriMesh> },
}

/// The progressive record of [`simplify_free`] run to `floor` triangles
/// (`--save` with `--topology free`, and the studio's free-topology
/// build): the plain collapse down to where the topology changed, the
/// change as one step certified against the input directly, then the
/// collapse of the changed mesh, each step bound raised by the change's
/// (triangle inequality, `Progressive::then`); the floor is certified
/// directly once more, a last step where that is lower. Each prefix is
/// what `simplify_free` makes run to its count: the same collapses, on the
/// same meshes.
///
/// # Errors
/// Cancelled through `progress`.
pub fn record_free(
    mesh: &TriMesh,
    collapse: CollapseOptions,
    floor: usize,
    progress: &Progress,
) -> Result<Progressive, Cancelled> {
    let opts = SimplifyOptions {
        target: Target::Triangles(floor.max(1)),
        collapse,
        per_triangle_bounds: false,
    };
    let free = simplify_free(mesh, &opts, progress).map_err(|e| match e {
        SimplifyError::Cancelled => Cancelled,
        SimplifyError::BadTarget(m) => unreachable!("a count of at least 1 is a target: {m}"),
    })?;
    let Route::Changed { from, to } = free.route else {
        return record(mesh, collapse, floor, progress);
    };
    let original = Original::new(mesh);
    let certifying = BoundOptions::for_diagonal(mesh.bounds().diagonal());
    let certify =
        |m: &TriMesh| certify_against(&original, m, &certifying, progress).map(|c| c.error_bound());
    let before = record(mesh, collapse, from, progress)?;
    let jump = certify(&to)?;
    let joined = before.then(jump, record(&to, collapse, floor, progress)?);
    let last = joined.mesh_at(joined.collapses());
    let direct = certify(&last)?;
    Ok(match direct < joined.bound_at(joined.collapses()) {
        true => joined.then(direct, Progressive::of(&last)),
        false => joined,
    })
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;
    use crate::distance::{SamplingOptions, hausdorff_mesh_mesh};

    /// A unit sphere and a small one `gap` beyond its surface.
    fn two_spheres(gap: f32) -> TriMesh {
        let big = crate::builtins::icosphere(Vec3::ZERO, 1.0, 4);
        let small = crate::builtins::icosphere(Vec3::new(1.05 + gap, 0.0, 0.0), 0.05, 1);
        TriMesh::concat(&[big, small])
    }

    /// The small sphere goes when its cost is within the budget, and the
    /// certified bound holds against an independent dense measurement
    /// between the input and what is left; under a budget shorter than its
    /// nearest point's distance it stays.
    #[test]
    fn a_small_component_is_pruned_within_a_certified_bound() {
        let mesh = two_spheres(0.02);
        let opts = BoundOptions::for_diagonal(mesh.bounds().diagonal());
        let pruned = prune(&mesh, 0.5, &opts);
        assert_eq!((pruned.components, pruned.removed.len()), (1, 80));
        let measured = hausdorff_mesh_mesh(&mesh, &pruned.mesh, &SamplingOptions::default());
        assert!(
            measured.two_sided() <= pruned.bound,
            "{measured:?} > {}",
            pruned.bound
        );
        // Its far side is 0.12 from the big sphere: the bound is near that.
        assert!(pruned.bound < 0.13, "{}", pruned.bound);
        let kept = prune(&mesh, 0.01, &opts);
        assert_eq!((kept.components, kept.bound), (0, 0.0));
        assert_eq!(kept.mesh.triangles.len(), mesh.triangles.len());
    }

    /// A count for which the edge collapse alone must keep a piece or a
    /// handle of four triangles or more, asked with `simplify_free`.
    fn free_to(mesh: &TriMesh, count: usize) -> (Simplified, TopologyReport) {
        let opts = SimplifyOptions {
            target: Target::Triangles(count),
            collapse: Default::default(),
            per_triangle_bounds: false,
        };
        let Free {
            result: r,
            report: t,
            ..
        } = simplify_free(mesh, &opts, &Progress::new()).unwrap();
        eprintln!(
            "{} triangles, bound {}, {t:?}",
            r.mesh.triangles.len(),
            r.error_bound()
        );
        (r, t)
    }

    /// Two unit spheres 0.02 apart.
    fn touching_spheres() -> TriMesh {
        let a = crate::builtins::icosphere(Vec3::ZERO, 1.0, 3);
        let b = crate::builtins::icosphere(Vec3::new(2.02, 0.0, 0.0), 1.0, 3);
        TriMesh::concat(&[a, b])
    }

    /// The certified bound holds against an independent dense measurement.
    fn assert_certified(mesh: &TriMesh, r: &Simplified) {
        let sampling = SamplingOptions {
            samples: 400_000,
            seed: 5,
        };
        let measured = hausdorff_mesh_mesh(mesh, &r.mesh, &sampling).two_sided();
        assert!(
            measured <= r.error_bound(),
            "{measured} > {}",
            r.error_bound()
        );
    }

    /// Two spheres nearly touching, asked for fewer triangles than two
    /// tetrahedra: pruning either costs its whole size, while contracting
    /// the pair across the gap merges them into one piece for much less.
    #[test]
    fn nearly_touching_pieces_merge_by_a_virtual_edge() {
        let mesh = touching_spheres();
        let (r, t) = free_to(&mesh, 6);
        assert!(r.mesh.triangles.len() <= 6 && r.unmet.is_none());
        assert_eq!((t.components_before, t.components_after), (2, 1));
        assert!(t.contracted_vertices > 0 && t.pair_cell > 0.0);
        assert_eq!(t.pruned_components, 0);
        assert_certified(&mesh, &r);
        // Pruning a sphere leaves its far side 2 from the other.
        assert!(r.error_bound() < 1.5, "{}", r.error_bound());
    }

    /// The same spheres within an error the collapse reaches with two
    /// tetrahedra: contracting across the gap keeps fewer triangles, within
    /// the error and its certified bound.
    #[test]
    fn an_error_target_merges_pieces_where_that_keeps_fewer_triangles() {
        let mesh = touching_spheres();
        let opts = SimplifyOptions {
            target: Target::Error(1.5),
            collapse: Default::default(),
            per_triangle_bounds: false,
        };
        let kept = super::super::simplify(&mesh, &opts, &Progress::new()).unwrap();
        let Free {
            result: r,
            report: t,
            ..
        } = simplify_free(&mesh, &opts, &Progress::new()).unwrap();
        eprintln!(
            "keep {} at {}, free {} at {}, {t:?}",
            kept.mesh.triangles.len(),
            kept.error_bound(),
            r.mesh.triangles.len(),
            r.error_bound()
        );
        assert_eq!(kept.mesh.triangles.len(), 8);
        assert!(r.mesh.triangles.len() < 8 && r.error_bound() <= 1.5);
        assert_eq!((t.components_after, t.pruned_components), (1, 0));
        assert!(t.pair_cell > 0.0);
        assert_certified(&mesh, &r);
        // An error of 0 contracts nothing (a spacing of 0 never grows).
        let exact = SimplifyOptions {
            target: Target::Error(0.0),
            ..opts
        };
        let Free {
            result: r,
            report: t,
            ..
        } = simplify_free(&mesh, &exact, &Progress::new()).unwrap();
        assert_eq!(t.pair_cell, 0.0);
        assert_eq!(r.mesh.triangles.len(), mesh.triangles.len());
    }

    /// The record of a free run to a count (`--save`, the studio's free
    /// build): the plain collapse down to where it stopped, one step that
    /// closes the hole, the collapse on; its prefix at the count is the
    /// run's mesh with the run's bound, and the prefixes on both sides of
    /// the step hold against an independent dense measurement.
    #[test]
    fn a_free_record_steps_through_the_topology_change() {
        let mesh = crate::builtins::torus(1.0, 0.3, 32, 16);
        let (r, _) = free_to(&mesh, 8);
        let p = record_free(&mesh, CollapseOptions::default(), 8, &Progress::new()).unwrap();
        let floor = p.prefix_for_triangles(8);
        assert_eq!(p.mesh_at(floor), r.mesh);
        assert_eq!(p.bound_at(floor), r.error_bound());
        let genus = |k: usize| Topology::of(&p.mesh_at(k)).genus;
        let step = (0..=p.collapses()).position(|k| genus(k) != 1).unwrap();
        assert!(p.triangles_at(step - 1) > 8 && step < floor);
        let sampling = SamplingOptions {
            samples: 200_000,
            seed: 3,
        };
        for k in [step - 1, step, step + 1, floor] {
            let measured = hausdorff_mesh_mesh(&mesh, &p.mesh_at(k), &sampling).two_sided();
            assert!(
                measured <= p.bound_at(k),
                "{k}: {measured} > {}",
                p.bound_at(k)
            );
        }
    }

    /// A fat torus at counts the collapse reaches: a finer state with its
    /// pairs contracted, collapsed to the count, is certified lower than
    /// the plain result (pairs across the tube give the greedy collapse
    /// another start; the hole stays), and wins, its bound holding against
    /// an independent dense measurement.
    #[test]
    fn a_reached_count_contracts_where_that_certifies_lower() {
        let mesh = crate::builtins::torus(1.0, 0.7, 48, 24);
        for count in [24, 48] {
            let opts = SimplifyOptions {
                target: Target::Triangles(count),
                collapse: Default::default(),
                per_triangle_bounds: false,
            };
            let plain = super::super::simplify(&mesh, &opts, &Progress::new()).unwrap();
            assert!(plain.unmet.is_none());
            let (r, t) = free_to(&mesh, count);
            assert_eq!(r.mesh.triangles.len(), count);
            assert!(r.error_bound() < 0.85 * plain.error_bound(), "{count}");
            assert!(t.pair_cell > 0.0 && t.contracted_vertices > 0);
            assert_certified(&mesh, &r);
        }
    }

    /// A torus at a count under its handle's floor: the hole closes.
    #[test]
    fn a_torus_hole_closes_at_a_coarse_count() {
        let mesh = crate::builtins::torus(1.0, 0.3, 32, 16);
        let (r, t) = free_to(&mesh, 8);
        assert!(r.mesh.triangles.len() <= 8 && r.unmet.is_none());
        assert_eq!((t.genus_before, t.genus_after), (1, 0));
        assert_eq!(t.components_after, 1);
        assert!(t.contracted_vertices > 0);
        assert_certified(&mesh, &r);
    }
}
