//! An error limit on the edge collapse (issue 48): before each collapse, the
//! certified bound of the triangles it would make is checked against the
//! limit, both directions as `step_bounds` bounds a finished collapse (new
//! triangle → original O by branch and bound, O → new triangle by the
//! attribution of O's pieces). A collapse over the limit is refused and the
//! collapse goes on with the others, as meshoptimizer's `target_error` and
//! CGAL's bounded-distance placement do, instead of an error target ending
//! at the first prefix that one early, expensive collapse puts over it.
//!
//! Far under the limit the triangle inequality is enough and nothing is
//! measured: a collapse moves each point of a star triangle at most δ (its
//! moved end's distance to the new vertex) onto the triangle's image, so
//! the image is within its source's bound plus δ of O, and the source's
//! pieces of O within their bound plus δ of the image (a removed
//! triangle's fold onto the edge to its third vertex, in a new triangle).
//! Only where that passes the limit is the collapse measured, which also
//! tightens its triangles' bounds for the collapses after it.
//!
//! Every triangle alive is then within the limit (O's own are exact), so
//! every state of the run is: the two-sided Hausdorff distance of a state to
//! O is at most the largest bound of its triangles (module `attribution`).
//! The result is still certified afresh, as every other one.
//!
//! Raising the limit readmits the refused edges. An LOD chain's error rows,
//! smallest first, run as phases of one forward collapse, each to where
//! nothing more collapses within its error: every row is a prefix of one
//! sequence, so a recorded sequence still cuts exactly. A refused collapse
//! is recorded nowhere until a larger limit admits it; it is then recorded
//! where it is performed.

use glam::Vec3;
use rayon::prelude::*;

use super::attribution::{Attribution, Handover};
use super::bound::{BoundOptions, Original, max_distance_bound};
use super::collapse::{Candidate, Collapse, EdgeCollapser, Veto};

/// A collapse's new triangles must be within `max_error` of O, and O's
/// pieces within it of them.
pub(super) struct Limit<'a> {
    original: &'a Original<'a>,
    opts: BoundOptions,
    max_error: f32,
    attribution: Attribution<'a>,
    /// Per triangle id: a bound of its distance to O (new triangle → O; 0
    /// for O's own).
    reverse: Vec<f32>,
    /// Nearest original distance (and triangle) of every collapser vertex.
    nearest: Vec<(f32, u32)>,
    /// The collapse `allows` let through last: its edge, its new vertex's
    /// nearest original point, and how its triangles got their bounds.
    allowed: Option<([u32; 2], (f32, u32), Allowed)>,
    /// Scratch: the star, its new triangles, their corners' nearest, the
    /// star triangle each comes from and how far that one's points move.
    star: Vec<u32>,
    made: Vec<[Vec3; 3]>,
    corners: Vec<[(f32, u32); 3]>,
    from: Vec<(u32, f32)>,
    /// Scratch: per new triangle, its bounds by the triangle inequality.
    carried: Vec<(f32, f32)>,
}

/// How an allowed collapse's new triangles are bounded.
enum Allowed {
    /// By the triangle inequality: every point of a star triangle moves at
    /// most δ (the moved end's distance to the new vertex) to its image,
    /// so an image's bounds are its source's plus δ, and the source's
    /// pieces go to it whole; a removed triangle's go to a new triangle on
    /// the edge it folds onto. Per new triangle: (reverse, forward), and
    /// (removed, new triangle index) for the removed ones.
    Carried(Vec<(f32, f32)>, Vec<(u32, usize)>),
    /// Measured: each new triangle's reverse bound, and the pieces handed
    /// over afresh (module `attribution`).
    Measured(Vec<f32>, Handover),
}

impl<'a> Limit<'a> {
    /// A limit of 0 for `col`, which has made no collapse, over its input
    /// `original`.
    pub fn new(original: &'a Original<'a>, col: &EdgeCollapser) -> Self {
        debug_assert_eq!(col.collapses(), 0);
        let distance = original.distance();
        let nearest = col
            .arrays()
            .positions
            .par_iter()
            .map(|p| distance.nearest(*p))
            .collect();
        let mut attribution = Attribution::new(original.mesh());
        attribution.grow(col.triangle_total());
        Limit {
            original,
            // As loose as the step bounds' (about a dozen checks per
            // collapse): still true upper bounds, so a refusal may be
            // needless but an acceptance is sound.
            opts: BoundOptions {
                rel_tol: 0.25,
                max_splits: 8,
                ..BoundOptions::for_diagonal(original.mesh().bounds().diagonal())
            },
            max_error: 0.0,
            attribution,
            reverse: vec![0.0; col.triangle_total()],
            nearest,
            allowed: None,
            star: Vec::new(),
            made: Vec::new(),
            corners: Vec::new(),
            from: Vec::new(),
            carried: Vec::new(),
        }
    }

    /// The limit from now on; never lowered (the triangles alive were
    /// checked against the old one).
    pub fn raise(&mut self, max_error: f32) {
        debug_assert!(max_error >= self.max_error);
        self.max_error = self.max_error.max(max_error);
    }

    /// The new triangles' bounds by the triangle inequality, and where the
    /// removed triangles' pieces go; `None` unless all are within the limit.
    fn carry(&mut self, col: &EdgeCollapser, cand: &Candidate) -> Option<Vec<(u32, usize)>> {
        let [a, b] = cand.edge;
        let max_error = self.max_error;
        self.carried.clear();
        for (k, &(t, delta)) in self.from.iter().enumerate() {
            let slack = round_off(&self.made[k]);
            let reverse = self.reverse[t as usize] + delta + slack;
            let forward = self.attribution.forward(t) + delta + slack;
            if reverse > max_error || forward > max_error {
                return None;
            }
            self.carried.push((reverse, forward));
        }
        let delta = [a, b]
            .map(|v| col.position(v).distance(cand.position))
            .into_iter()
            .fold(0.0, f32::max);
        let mut folded = Vec::new();
        for &t in &self.star {
            let tri = col.triangle(t);
            if !(tri.contains(&a) && tri.contains(&b)) {
                continue;
            }
            // Its points fold onto the edge from the new vertex to `o`.
            let o = tri.iter().copied().find(|w| *w != a && *w != b)?;
            let k = self
                .from
                .iter()
                .position(|&(s, _)| col.triangle(s).contains(&o))?;
            let forward = self.attribution.forward(t) + delta + round_off(&self.made[k]);
            if forward > max_error {
                return None;
            }
            self.carried[k].1 = self.carried[k].1.max(forward);
            folded.push((t, k));
        }
        Some(folded)
    }
}

/// f32 round-off of a triangle's coordinates (flat collapses bound to 0),
/// as `step_bounds` adds it.
fn round_off(p: &[Vec3; 3]) -> f32 {
    8.0 * f32::EPSILON * p.iter().map(|v| v.abs().max_element()).fold(0.0, f32::max)
}

impl Veto for Limit<'_> {
    fn allows(&mut self, cand: &Candidate, col: &EdgeCollapser) -> bool {
        let [a, b] = cand.edge;
        let max_error = self.max_error;
        // The new triangles in the order the collapse makes them.
        col.star_into(cand.edge, &mut self.star);
        self.star.sort_unstable();
        self.made.clear();
        self.corners.clear();
        self.from.clear();
        let at_new = self.original.distance().nearest(cand.position);
        let moves = [a, b].map(|v| col.position(v).distance(cand.position));
        for &t in &self.star {
            let tri = col.triangle(t);
            if tri.contains(&a) && tri.contains(&b) {
                continue;
            }
            let moved = |w: u32| w == a || w == b;
            self.made.push(tri.map(|w| {
                if moved(w) {
                    cand.position
                } else {
                    col.position(w)
                }
            }));
            self.corners.push(tri.map(|w| {
                if moved(w) {
                    at_new
                } else {
                    self.nearest[w as usize]
                }
            }));
            self.from.push((t, moves[usize::from(tri.contains(&b))]));
        }
        // Far under the limit, the triangle inequality is enough.
        if let Some(folded) = self.carry(col, cand) {
            let carried = std::mem::take(&mut self.carried);
            self.allowed = Some((cand.edge, at_new, Allowed::Carried(carried, folded)));
            return true;
        }
        // Measured, each bound refined towards half the limit where it can
        // be: headroom for the carried bounds of the collapses after it
        // (the dragon at 0.5 %: 3,164 triangles against 3,706 refined only
        // to the limit, 10 % slower). New triangle → O first: no piece is
        // cut for a collapse refused here.
        let aim = 0.5 * max_error;
        let to = (self.original.distance(), Some(self.original.projection()));
        let mut reverse = Vec::with_capacity(self.made.len());
        for (p, at) in self.made.iter().zip(&self.corners) {
            let (upper, _, _) = max_distance_bound(*p, *at, to, &self.opts, aim, aim);
            let upper = upper + round_off(p);
            if upper > max_error {
                return false;
            }
            reverse.push(upper);
        }
        let mut handover = self.attribution.peek(&self.star);
        let tolerance = (self.opts.rel_tol, self.opts.abs_tol, aim);
        self.attribution
            .hand_over(&mut handover, &self.made, tolerance);
        let slack = self.made.iter().map(round_off).fold(0.0, f32::max);
        if handover.forward() + slack > max_error {
            return false;
        }
        self.allowed = Some((cand.edge, at_new, Allowed::Measured(reverse, handover)));
        true
    }

    fn collapsed(&mut self, col: &EdgeCollapser, c: &Collapse) {
        let (edge, at_new, allowed) = self.allowed.take().expect("allowed before collapsing");
        debug_assert_eq!(edge, c.edge);
        self.attribution.grow(col.triangle_total());
        match allowed {
            Allowed::Carried(bounds, folded) => {
                for (k, &(t, _)) in self.from.iter().enumerate() {
                    self.attribution.carry(t, c.added[k], bounds[k].1);
                }
                for (t, k) in folded {
                    self.attribution.carry(t, c.added[k], bounds[k].1);
                }
                self.reverse.extend(bounds.iter().map(|b| b.0));
                self.carried = bounds;
            }
            Allowed::Measured(reverse, handover) => {
                self.attribution.take(&c.removed);
                self.attribution.give(handover, &c.added);
                self.reverse.extend(reverse);
            }
        }
        debug_assert_eq!(self.reverse.len(), col.triangle_total());
        self.nearest.push(at_new);
        debug_assert_eq!(self.nearest.len(), col.vertex_count());
    }
}
