//! Certifying a state of an edge collapse from another state's certificate:
//! an error search's probes and an LOD chain's rows (issue 26) would
//! otherwise each pay a pass over the whole original.
//!
//! Collapses never edit a triangle: they retire some and make new ones under
//! new ids (`collapse`), so any state S_B is any other S_A less the triangles
//! only S_A has ("removed") plus those only S_B has ("added"), by the
//! collapser's ids, whichever came first. Then, with O the original:
//! - S → O: a triangle of S_A still in S_B keeps its bound (O is unchanged);
//! - O → S: an original triangle's bound u against S_A used only triangles
//!   of S_A within u of it (convexity and Lipschitz, module `bound`, both use
//!   a tried or nearest triangle at most the bound away). When no removed or
//!   added triangle comes within u of it, every triangle it used is in S_B,
//!   so u bounds it against S_B, and its exact distances stay exact (no added
//!   triangle is nearer): lower bounds and nearest triangles carry too.
//!
//! "Within u" is tested conservatively on a grid of cells marked under the
//! changed triangles' boxes. Nothing is loosened: what carries is a bound
//! the other certificate proved for triangles this state has too;
//! everything else is certified afresh.

use glam::Vec3;
use rayon::prelude::*;

use super::bound::{Bounds, Nearest, Original};
use super::relay::Beta;
use crate::geom::{Aabb, TriMesh};

/// What a certificate keeps for certifying other states of its collapse.
#[derive(Debug, Clone, PartialEq)]
pub struct Trace {
    /// The original's box: a trace of another original carries nothing.
    original: Aabb,
    /// The collapser's id of each triangle of S, ascending.
    ids: Vec<u32>,
    /// Each triangle of S's box.
    boxes: Vec<Aabb>,
    /// S → O per triangle of S: upper and lower bound.
    reverse: Vec<(f32, f32)>,
    /// O → S per original triangle: upper and lower bound, and the triangle
    /// of S that covers it best.
    forward: Vec<Bounds>,
    /// Per original vertex: exact distance to S and its nearest triangle.
    at_vertex: Vec<Nearest>,
    /// A relayed certificate's β per triangle of M (module `relay`).
    beta: Vec<Option<Beta>>,
}

impl Trace {
    pub(super) fn new(
        original: &Original,
        ids: &[u32],
        simplified: &TriMesh,
        reverse: &[Bounds],
        forward: Vec<Bounds>,
        at_vertex: Vec<Nearest>,
        beta: Vec<Option<Beta>>,
    ) -> Self {
        Trace {
            original: original.bounds(),
            ids: ids.to_vec(),
            boxes: (0..simplified.triangles.len())
                .map(|t| triangle_box(&simplified.triangle(t)))
                .collect(),
            reverse: reverse.iter().map(|b| (b.0, b.1)).collect(),
            forward,
            at_vertex,
            beta,
        }
    }
}

/// Another state's trace matched against a state S_B: what
/// carries, by S_B's indices (`None`: certified afresh).
pub(super) struct Recertify {
    /// Per triangle of S_B: its S → O bounds where it was in S_A.
    pub reverse: Vec<Option<Bounds>>,
    /// Per original triangle: its O → S bounds where nothing changed in reach.
    pub forward: Vec<Option<Bounds>>,
    /// Per original vertex: exact distance and nearest triangle, where every
    /// triangle it is in carries (its distance is at most their bounds).
    pub at_vertex: Vec<Option<Nearest>>,
}

/// Cells along the longest side of the original's box: fine enough that an
/// original triangle's reach (its box grown by its bound) touches a few.
const CELLS: f32 = 256.0;

/// A grid over a box: the cells a box overlaps.
struct Cells {
    origin: Vec3,
    inv_cell: f32,
    dims: [usize; 3],
}

impl Cells {
    fn new(bounds: Aabb, along_longest: f32) -> Self {
        let extent = bounds.extent().max(Vec3::splat(f32::MIN_POSITIVE));
        let cell = (extent.max_element() / along_longest).max(f32::MIN_POSITIVE);
        let dims = (extent / cell)
            .ceil()
            .to_array()
            .map(|d| (d as usize).clamp(1, along_longest as usize));
        Cells {
            origin: bounds.min,
            inv_cell: 1.0 / cell,
            dims,
        }
    }

    fn len(&self) -> usize {
        self.dims[0] * self.dims[1] * self.dims[2]
    }

    /// The cells a box overlaps, clamped to the grid (overlapping boxes
    /// keep overlapping ranges, so the tests stay conservative outside it).
    fn ranges(&self, b: &Aabb) -> [std::ops::RangeInclusive<usize>; 3] {
        let lo = ((b.min - self.origin) * self.inv_cell).floor().to_array();
        let hi = ((b.max - self.origin) * self.inv_cell).floor().to_array();
        [0, 1, 2].map(|k| {
            let top = self.dims[k] - 1;
            // NaN and ±∞ clamp to the grid's ends (`as` saturates).
            let c = |x: f32| (x.max(0.0) as usize).min(top);
            c(lo[k])..=c(hi[k])
        })
    }

    /// Calls `f` on each cell a box overlaps while it returns true; false
    /// where it stopped.
    fn each(&self, b: &Aabb, mut f: impl FnMut(usize) -> bool) -> bool {
        let [xs, ys, zs] = self.ranges(b);
        for z in zs {
            for y in ys.clone() {
                for x in xs.clone() {
                    if !f((z * self.dims[1] + y) * self.dims[0] + x) {
                        return false;
                    }
                }
            }
        }
        true
    }
}

/// One grid's cells marked under boxes.
struct Bits {
    cells: Cells,
    bits: Vec<u64>,
}

impl Bits {
    fn new(bounds: Aabb, along_longest: f32) -> Self {
        let cells = Cells::new(bounds, along_longest);
        let bits = vec![0; cells.len().div_ceil(64)];
        Bits { cells, bits }
    }

    fn mark(&mut self, b: &Aabb) {
        let bits = &mut self.bits;
        self.cells.each(b, |i| {
            bits[i / 64] |= 1 << (i % 64);
            true
        });
    }

    /// Whether a box overlaps a marked cell; `None` where it spans more than
    /// [`MOST_CELLS`] (too many to read).
    fn touches(&self, b: &Aabb) -> Option<bool> {
        let spans = self.cells.ranges(b).into_iter().map(|r| r.count());
        if spans.product::<usize>() > MOST_CELLS {
            return None;
        }
        Some(
            !self
                .cells
                .each(b, |i| self.bits[i / 64] & (1 << (i % 64)) == 0),
        )
    }
}

/// Cells marked under boxes, on the grid and on one [`COARSER`] times
/// coarser: most reaches miss every change, and a few coarse cells say so
/// (a reach over a coarse row's bound spans a hundred fine cells).
struct Marks {
    fine: Bits,
    coarse: Bits,
    any: bool,
}

/// Cells a reach may span before it counts as touching a change unread: a
/// large bound over few changes would otherwise read a large block of the
/// grid per original triangle.
const MOST_CELLS: usize = 512;

/// Fine cells per coarse cell, along each side.
const COARSER: f32 = 8.0;

impl Marks {
    fn new(bounds: Aabb) -> Self {
        Marks {
            fine: Bits::new(bounds, CELLS),
            coarse: Bits::new(bounds, CELLS / COARSER),
            any: false,
        }
    }

    fn mark(&mut self, b: &Aabb) {
        self.any = true;
        self.fine.mark(b);
        self.coarse.mark(b);
    }

    /// Whether a box overlaps a marked cell (or spans too many to read).
    fn touches(&self, b: &Aabb) -> bool {
        self.any && self.coarse.touches(b) != Some(false) && self.fine.touches(b) != Some(false)
    }
}

fn triangle_box(p: &[Vec3; 3]) -> Aabb {
    Aabb::from_points(p)
}

/// A box grown by `d` (and a hair for round-off: the tests must be conservative).
fn grown(b: Aabb, d: f32) -> Aabb {
    let g = Vec3::splat(d * (1.0 + 1e-4) + 1e-6 * (b.max - b.min).length());
    Aabb {
        min: b.min - g,
        max: b.max + g,
    }
}

/// Two states of one collapse matched by id: which of S_A's triangles
/// stayed (their index in S_B), the S → O bounds S_B keeps by them, and the
/// cells under what changed.
struct Matched {
    stayed: Vec<Option<u32>>,
    reverse: Vec<Option<Bounds>>,
    changes: Marks,
}

impl Matched {
    /// `None` where `earlier` is of another original.
    fn new(earlier: &Trace, original: &Original, later: &TriMesh, ids: &[u32]) -> Option<Self> {
        let bounds = original.bounds();
        if earlier.original != bounds {
            return None;
        }
        // Both id lists ascend: one merge finds what stayed, went and came.
        // A triangle stays where its id and its box agree (a trace of another
        // collapse of the same original shares ids, not triangles).
        let mut stayed = vec![None; earlier.ids.len()];
        let mut reverse = vec![None; ids.len()];
        let mut changes = Marks::new(bounds);
        let (mut i, mut j) = (0, 0);
        while i < earlier.ids.len() || j < ids.len() {
            match (earlier.ids.get(i), ids.get(j)) {
                (Some(a), Some(b))
                    if a == b && earlier.boxes[i] == triangle_box(&later.triangle(j)) =>
                {
                    let (u, l) = earlier.reverse[i];
                    reverse[j] = Some((u, l, 0));
                    stayed[i] = Some(j as u32);
                    i += 1;
                    j += 1;
                }
                (Some(a), b) if b.is_none_or(|b| a <= b) => {
                    changes.mark(&earlier.boxes[i]);
                    i += 1;
                }
                _ => {
                    changes.mark(&triangle_box(&later.triangle(j)));
                    j += 1;
                }
            }
        }
        Some(Matched {
            stayed,
            reverse,
            changes,
        })
    }

    /// S_B's index of S_A's triangle `i`, where it stayed.
    fn index(&self, i: u32) -> Option<u32> {
        self.stayed.get(i as usize).copied().flatten()
    }

    /// Whether a bound `u` that held for a box against S_A holds against
    /// S_B: no changed triangle comes within it (module doc).
    fn holds(&self, b: Aabb, u: f32) -> bool {
        u.is_finite() && !self.changes.touches(&grown(b, u))
    }
}

/// S → O bounds per triangle of S, and β per triangle of M.
pub(super) type RelayCarry = (Vec<Option<Bounds>>, Vec<Option<Beta>>);

/// What a relayed probe (module `relay`) carries from another state's
/// trace: S → O bounds by id, and the relay's β of each triangle of M
/// (`m_boxes`) where nothing changed within it (the argument of the module
/// doc, for M's triangles instead of the original's). `None` where
/// `earlier` is of another original.
pub(super) fn carry_relayed(
    earlier: &Trace,
    original: &Original,
    later: &TriMesh,
    ids: &[u32],
    m_boxes: &[Aabb],
) -> Option<RelayCarry> {
    let matched = Matched::new(earlier, original, later, ids)?;
    let beta = if earlier.beta.len() == m_boxes.len() {
        (earlier.beta.par_iter().zip(m_boxes))
            .map(|(b, &m)| {
                let (u, owner) = (*b)?;
                matched
                    .holds(m, u)
                    .then(|| matched.index(owner).map(|k| (u, k)))
                    .flatten()
            })
            .collect()
    } else {
        vec![None; m_boxes.len()]
    };
    Some((matched.reverse, beta))
}

impl Recertify {
    /// `None` where `earlier` is of another original.
    pub fn new(earlier: &Trace, original: &Original, later: &TriMesh, ids: &[u32]) -> Option<Self> {
        let corners = original.distance().corners();
        let mesh = original.mesh();
        if earlier.forward.len() != mesh.triangles.len()
            || earlier.at_vertex.len() != mesh.positions.len()
        {
            return None;
        }
        let matched = Matched::new(earlier, original, later, ids)?;
        let original = mesh;
        let forward: Vec<Option<Bounds>> = earlier
            .forward
            .par_iter()
            .enumerate()
            .map(|(t, &(u, l, owner))| {
                let owner = matched.index(owner)?;
                matched
                    .holds(triangle_box(&corners[t]), u)
                    .then_some((u, l, owner))
            })
            .collect();
        let mut exact = vec![false; original.positions.len()];
        for (t, f) in forward.iter().enumerate() {
            if f.is_some() {
                for v in original.triangles[t] {
                    exact[v as usize] = true;
                }
            }
        }
        for (t, f) in forward.iter().enumerate() {
            if f.is_none() {
                for v in original.triangles[t] {
                    exact[v as usize] = false;
                }
            }
        }
        let at_vertex = earlier
            .at_vertex
            .par_iter()
            .zip(&exact)
            .map(|(&(d, near), &exact)| {
                if exact {
                    matched.index(near).map(|k| (d, k))
                } else {
                    None
                }
            })
            .collect();
        Some(Recertify {
            reverse: matched.reverse,
            forward,
            at_vertex,
        })
    }

    /// The largest lower bound of the later state's distance it carries.
    pub fn lower(&self) -> f32 {
        let bounds = self.reverse.iter().chain(&self.forward).flatten();
        let vertices = self.at_vertex.iter().flatten().map(|a| a.0);
        bounds.map(|b| b.1).chain(vertices).fold(0.0, f32::max)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::distance::{MeshDistance, SamplingOptions, hausdorff_mesh_mesh};
    use crate::progress::Progress;
    use crate::simplify::{
        Ask, BoundOptions, Certificate, CollapseOptions, EdgeCollapser, Original, Traced,
        certify_against, certify_traced,
    };

    /// A certificate asked about no limit, and its trace.
    fn certified(
        original: &Original,
        s: &TriMesh,
        ids: &[u32],
        earlier: Option<&Trace>,
        opts: &BoundOptions,
    ) -> (Certificate, Trace) {
        match certify_traced(
            original,
            s,
            ids,
            earlier,
            opts,
            Ask::Tight,
            &Progress::new(),
        ) {
            Ok(Traced::Certified(c, t)) => (c, *t),
            other => panic!("{other:?}"),
        }
    }

    /// Along one collapse, between a certified state and one 4 %, 20 % or
    /// 50 % further, either way: what carries is what a fresh measurement of
    /// the other state says (vertices' distances equal, triangles' bounds
    /// hold on samples), and its re-certified bound holds against sampling
    /// and is as tight as a fresh certificate's (within the relative
    /// tolerance).
    #[test]
    fn what_carries_holds_for_the_other_state() {
        let mesh = crate::builtins::torus(1.0, 0.35, 120, 48);
        let original = Original::new(&mesh);
        let opts = BoundOptions::for_diagonal(mesh.bounds().diagonal());
        let state = |count: usize| {
            let mut collapser = EdgeCollapser::new(&mesh, CollapseOptions::default());
            collapser.run(count, |_, _| true);
            let (s, ids) = collapser.mesh();
            let (_, trace) = certified(&original, &s, &ids, None, &opts);
            (s, ids, trace)
        };
        let n = mesh.triangles.len();
        // Coarse states' bounds span cells of the grid; fine ones' do not.
        for (first, step) in [(n / 8, 0.96), (n / 8, 0.5), (n / 100, 0.96), (n / 100, 0.8)] {
            let (a, b) = (state(first), state((first as f32 * step) as usize));
            for ((_, _, trace), (s, ids, _)) in [(&a, &b), (&b, &a)] {
                let re = Recertify::new(trace, &original, s, ids).expect("same original");
                let to_s = MeshDistance::new(s);
                let carried = re.forward.iter().flatten().count();
                if step > 0.9 && first == n / 8 {
                    assert!(carried > n / 2, "{carried} carried");
                    assert!(re.reverse.iter().flatten().count() > s.triangles.len() / 2);
                }
                assert!(carried > 0, "{first} {step}");
                for (v, a) in re.at_vertex.iter().enumerate() {
                    if let Some((d, near)) = a {
                        let (exact, _) = to_s.nearest(mesh.positions[v]);
                        assert_eq!(*d, exact, "vertex {v}");
                        assert_eq!(*d, to_s.triangle_distance(mesh.positions[v], *near));
                    }
                }
                for (t, f) in re.forward.iter().enumerate() {
                    if let Some((u, l, _)) = f {
                        let [p, q, r] = mesh.triangle(t);
                        for (i, j) in [(0, 0), (4, 0), (0, 4), (1, 1), (2, 1), (1, 2)] {
                            let y = p + (q - p) * (i as f32 / 4.0) + (r - p) * (j as f32 / 4.0);
                            // A sample's own coordinates round (|y| < 1.4: 1e-6 covers it).
                            assert!(to_s.distance(y) <= *u + 1e-6, "{step}: triangle {t}");
                        }
                        assert!(*l <= *u);
                    }
                }
                let (recertified, traced) = certified(&original, s, ids, Some(trace), &opts);
                // Every vertex's distance, carried or searched afresh, is exact.
                for (v, (d, near)) in traced.at_vertex.iter().enumerate() {
                    assert_eq!(*d, to_s.nearest(mesh.positions[v]).0, "vertex {v}");
                    assert_eq!(*d, to_s.triangle_distance(mesh.positions[v], *near));
                }
                let fresh = certify_against(&original, s, &opts, &Progress::new()).unwrap();
                let sampled =
                    hausdorff_mesh_mesh(&mesh, s, &SamplingOptions::default()).two_sided();
                let (r, f) = (recertified.error_bound(), fresh.error_bound());
                assert!(r >= sampled, "{step}: {r} < sampled {sampled}");
                assert!(r <= f * (1.0 + opts.rel_tol) + opts.abs_tol, "{r} vs {f}");
                assert_eq!(recertified.attributed.len(), n);
            }
        }
    }

    /// A box marks the cells it overlaps and no others, boxes outside the
    /// grid clamp to its border cells, and a box over more fine cells than
    /// are read is answered by the coarse grid (unless nothing is marked).
    #[test]
    fn marked_cells_are_the_ones_under_the_box() {
        let cube = |a: f32, b: f32| Aabb {
            min: Vec3::splat(a),
            max: Vec3::splat(b),
        };
        let everything = cube(0.0, 256.0);
        let mut g = Marks::new(everything);
        assert!(!g.touches(&everything));
        assert_eq!(g.fine.cells.dims, [256, 256, 256]);
        assert_eq!(g.coarse.cells.dims, [32, 32, 32]);
        g.mark(&Aabb {
            min: Vec3::new(10.5, 10.5, 10.5),
            max: Vec3::new(11.5, 10.6, 10.6),
        });
        let probe = |x: f32| Aabb {
            min: Vec3::new(x, 10.2, 10.2),
            max: Vec3::new(x + 0.1, 10.3, 10.3),
        };
        assert!(g.touches(&probe(10.0)));
        assert!(g.touches(&probe(11.8)));
        assert!(!g.touches(&probe(12.1)));
        assert!(!g.touches(&probe(9.5)));
        g.mark(&cube(300.0, 400.0));
        assert!(g.touches(&cube(255.5, 500.0)));
        assert!(!g.touches(&cube(248.0, 254.0)));
        // Over more fine cells than are read: the coarse grid answers where
        // it has no mark, and a mark under it counts as touching.
        assert!(!g.touches(&cube(100.0, 120.0)));
        assert!(g.touches(&cube(0.0, 30.0)));
        // A box beside a mark in the same coarse cell: the fine grid answers.
        assert!(!g.touches(&cube(13.5, 14.5)));
    }
}
