//! An error limit on the edge collapse (issue 48): before each collapse, the
//! certified bound of the triangles it would make is checked against the
//! limit, both directions as `step_bounds` bounds a finished collapse (new
//! triangle → original O by branch and bound, O → new triangle by the
//! attribution of O's pieces). A collapse over the limit is refused and the
//! collapse goes on with the others, as meshoptimizer's `target_error` and
//! CGAL's bounded-distance placement do, instead of an error target ending
//! at the first prefix that one early, expensive collapse puts over it.
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
    /// Nearest original distance (and triangle) of every collapser vertex.
    nearest: Vec<(f32, u32)>,
    /// The collapse `allows` let through last: its edge, its new vertex's
    /// nearest original point and the pieces' new owners.
    allowed: Option<([u32; 2], (f32, u32), Handover)>,
    /// Scratch: the star, its new triangles and their corners' nearest.
    star: Vec<u32>,
    made: Vec<[Vec3; 3]>,
    corners: Vec<[(f32, u32); 3]>,
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
            nearest,
            allowed: None,
            star: Vec::new(),
            made: Vec::new(),
            corners: Vec::new(),
        }
    }

    /// The limit from now on; never lowered (the triangles alive were
    /// checked against the old one).
    pub fn raise(&mut self, max_error: f32) {
        debug_assert!(max_error >= self.max_error);
        self.max_error = self.max_error.max(max_error);
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
        let at_new = self.original.distance().nearest(cand.position);
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
        }
        // New triangle → O first: no piece is cut for a collapse refused here.
        let to = (self.original.distance(), Some(self.original.projection()));
        for (p, at) in self.made.iter().zip(&self.corners) {
            let (upper, _, _) = max_distance_bound(*p, *at, to, &self.opts, max_error, max_error);
            if upper + round_off(p) > max_error {
                return false;
            }
        }
        let mut handover = self.attribution.peek(&self.star);
        let tolerance = (self.opts.rel_tol, self.opts.abs_tol, max_error);
        self.attribution
            .hand_over(&mut handover, &self.made, tolerance);
        let slack = self.made.iter().map(round_off).fold(0.0, f32::max);
        if handover.forward() + slack > max_error {
            return false;
        }
        self.allowed = Some((cand.edge, at_new, handover));
        true
    }

    fn collapsed(&mut self, col: &EdgeCollapser, c: &Collapse) {
        let (edge, at_new, handover) = self.allowed.take().expect("allowed before collapsing");
        debug_assert_eq!(edge, c.edge);
        self.attribution.take(&c.removed);
        self.attribution.grow(col.triangle_total());
        self.attribution.give(handover, &c.added);
        self.nearest.push(at_new);
        debug_assert_eq!(self.nearest.len(), col.vertex_count());
    }
}
