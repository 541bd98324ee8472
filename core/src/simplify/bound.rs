//! Certified upper bound on the two-sided Hausdorff distance between an original
//! surface O and its simplification S, per triangle of S.
//!
//! Both directions are bounded by one branch and bound over pieces of a
//! triangle (a piece is split 1→4 at its edge midpoints). For the largest
//! distance from a piece P to a target surface X, two upper bounds hold:
//! - convexity: for any one triangle T of X, y ↦ d(y, T) is convex (distance to
//!   a convex set), so max_{y∈P} d(y, X) ≤ max_{y∈P} d(y, T) = max_i d(p_i, T);
//!   we try the triangles of X nearest to P's vertices;
//! - Lipschitz: y ↦ d(y, X) is 1-Lipschitz and every y ∈ P lies within
//!   ρ(P) ≤ ℓ_max(P)/√3 of a vertex, so max_{y∈P} d(y, X) ≤ max_i d(p_i, X) + ρ(P);
//! - for S → O, Cohen et al.'s planar projection (module `projection`): a
//!   patch of O that lies over all of P without folding bounds d(y, O) by its
//!   height over P's plane. It certifies most triangles whole, so it is tried
//!   on a piece once before the piece is split.
//!
//! The piece with the largest upper value is split until it is within a
//! tolerance of the largest exact d(p, X) seen, which is a lower bound; the
//! result is therefore a true upper bound and close to the truth. Distances are
//! exact (BVH, closest point on triangle).
//!
//! O → S runs over every original triangle (the part of O a triangle of S stands
//! for is the set of original triangles attributed to it), S → O over every
//! triangle of S; a triangle's bound is the larger of the two.

use std::cmp::Ordering;
use std::collections::BinaryHeap;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering as AtomicOrdering};

use glam::Vec3;
use rayon::prelude::*;

use super::projection::Projection;
use super::recertify::{Recertify, RelayCarry, Trace, carry_relayed};
use super::relay::{Beta, Relay};
use crate::distance::MeshDistance;
use crate::geom::{Aabb, TriMesh};
use crate::progress::{Cancelled, Progress};

/// How hard branch and bound works.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BoundOptions {
    /// Stop refining when the upper bound is within this fraction of the lower bound...
    pub rel_tol: f32,
    /// ...or within this absolute distance of it.
    pub abs_tol: f32,
    /// At most this many 1→4 splits per triangle (the bound stays valid, only looser).
    pub max_splits: usize,
    /// Refine every triangle to its own tolerance. Off: a triangle is only refined
    /// while its bound exceeds the mesh's lower bound by `rel_tol` (it cannot raise
    /// the maximum), which is much faster and keeps `error_bound` just as tight.
    pub per_triangle: bool,
}

impl BoundOptions {
    /// Defaults scaled to a model of bounding-box diagonal `diag`.
    pub fn for_diagonal(diag: f32) -> Self {
        Self {
            rel_tol: 0.05,
            abs_tol: 1e-5 * diag,
            max_splits: 256,
            per_triangle: false,
        }
    }
}

/// Per-triangle certified bounds of a simplification.
#[derive(Debug, Clone, PartialEq)]
pub struct Certificate {
    /// Upper bound per triangle of S (see the module doc).
    pub triangle_bounds: Vec<f32>,
    /// For each original triangle, the triangle of S it is attributed to.
    pub attributed: Vec<u32>,
    /// Largest O → S and S → O bounds.
    pub forward: f32,
    pub reverse: f32,
}

impl Certificate {
    /// The guaranteed two-sided Hausdorff bound of the whole simplification.
    pub fn error_bound(&self) -> f32 {
        self.forward.max(self.reverse)
    }
}

const INV_SQRT3: f32 = 0.577_350_3;

/// Relative slack for f32 round-off in the distance computations: a bound that is
/// exact in real arithmetic can come out a few ulps under a measurement.
pub(super) const ROUNDING: f32 = 1e-5;

/// Covering radius bound of a triangle by its vertices.
fn cover_radius(p: &[Vec3; 3]) -> f32 {
    let l = p[0]
        .distance_squared(p[1])
        .max(p[1].distance_squared(p[2]))
        .max(p[2].distance_squared(p[0]));
    l.sqrt() * INV_SQRT3
}

struct Piece {
    upper: f32,
    p: [Vec3; 3],
    d: [f32; 3],
    near: [u32; 3],
    /// The planar projection was tried on it.
    projected: bool,
}

impl PartialEq for Piece {
    fn eq(&self, o: &Self) -> bool {
        self.upper == o.upper
    }
}
impl Eq for Piece {}
impl PartialOrd for Piece {
    fn partial_cmp(&self, o: &Self) -> Option<Ordering> {
        Some(self.cmp(o))
    }
}
impl Ord for Piece {
    fn cmp(&self, o: &Self) -> Ordering {
        self.upper.total_cmp(&o.upper)
    }
}

/// The best of the convexity and Lipschitz bounds for a piece, and the target
/// triangle that achieved the best convexity bound. Convexity is tried with
/// each vertex's nearest triangle alone and, for a piece that straddles two of
/// them, with both: a straight cut where their distances cross leaves two
/// convex parts, each within its triangle's distance at its corners.
fn piece_bound(p: &[Vec3; 3], d: &[f32; 3], near: &[u32; 3], target: &MeshDistance) -> (f32, u32) {
    let mut cands = [(u32::MAX, [0.0f32; 3]); 3];
    let mut n = 0;
    for &t in near {
        if cands[..n].iter().all(|c| c.0 != t) {
            // A vertex's distance to its own nearest triangle is known.
            let ds = [0, 1, 2].map(|i| {
                if near[i] == t {
                    d[i]
                } else {
                    target.triangle_distance(p[i], t)
                }
            });
            cands[n] = (t, ds);
            n += 1;
        }
    }
    let mut best = (f32::INFINITY, near[0]);
    for (t, ds) in &cands[..n] {
        let b = ds[0].max(ds[1]).max(ds[2]);
        if b < best.0 {
            best = (b, *t);
        }
    }
    for i in 0..n {
        for j in i + 1..n {
            let ((tx, dx), (ty, dy)) = (cands[i], cands[j]);
            let f = |k: usize| dx[k] - dy[k];
            let side_x = [0, 1, 2].map(|k| f(k) <= 0.0);
            if side_x.iter().all(|s| *s) || side_x.iter().all(|s| !*s) {
                continue;
            }
            let (mut bx, mut by) = (0.0f32, 0.0f32);
            for k in 0..3 {
                if side_x[k] {
                    bx = bx.max(dx[k]);
                } else {
                    by = by.max(dy[k]);
                }
                let l = (k + 1) % 3;
                if side_x[k] != side_x[l] {
                    let s = (f(k) / (f(k) - f(l))).clamp(0.0, 1.0);
                    let c = p[k] + (p[l] - p[k]) * s;
                    bx = bx.max(target.triangle_distance(c, tx));
                    by = by.max(target.triangle_distance(c, ty));
                }
            }
            if bx.max(by) < best.0 {
                best = (bx.max(by), if bx >= by { tx } else { ty });
            }
        }
    }
    let lipschitz = d[0].max(d[1]).max(d[2]) + cover_radius(p);
    (best.0.min(lipschitz), best.1)
}

fn piece(p: [Vec3; 3], d: [f32; 3], near: [u32; 3], target: &MeshDistance) -> Piece {
    Piece {
        upper: piece_bound(&p, &d, &near, target).0,
        p,
        d,
        near,
        projected: false,
    }
}

/// Largest patch of O a planar projection grows over one piece: beyond it,
/// splitting is cheaper.
pub const PATCH_CAP: usize = 4096;

/// Upper bound of max_{y ∈ tri} d(y, X) for the surface X behind `target`;
/// `at` holds (d(tri_i, X), nearest triangle of X) for the three vertices.
/// With `projection` (of X), a piece that stays above the tolerance also
/// tries the planar projection (module `projection`) once before it is split:
/// most triangles of a simplification are certified whole that way.
/// Refinement also stops once the bound is at most `enough`, and, while the
/// exact distances found stay under `aim` (0: none), once it is at most
/// `aim` and not before: past the tolerance if need be, so a search's
/// question (is the bound within it?) is decided, up to the split budget.
/// Returns the upper bound, the largest exact distance found (a lower bound)
/// and the triangle of X that covers `tri` best as a whole.
pub fn max_distance_bound(
    tri: [Vec3; 3],
    at: [(f32, u32); 3],
    (target, projection): (&MeshDistance, Option<&Projection>),
    opts: &BoundOptions,
    enough: f32,
    aim: f32,
) -> (f32, f32, u32) {
    let (d, near) = (at.map(|x| x.0), at.map(|x| x.1));
    let mut lower = d[0].max(d[1]).max(d[2]);
    let threshold = |lower: f32| {
        if lower < aim {
            enough.max(aim)
        } else {
            enough.max(lower * (1.0 + opts.rel_tol) + opts.abs_tol)
        }
    };
    let (upper, owner) = piece_bound(&tri, &d, &near, target);
    let mut top = Piece {
        upper,
        p: tri,
        d,
        near,
        projected: false,
    };
    // Most triangles need no split: no heap for them.
    let mut heap = BinaryHeap::new();
    let mut splits = 0;
    // `top` is always the piece with the largest upper value.
    loop {
        if top.upper <= threshold(lower) {
            break;
        }
        if let Some(projection) = projection.filter(|_| !top.projected) {
            let limit = 2.0 * threshold(lower);
            if let Some(b) = projection.bound(top.p, top.near, PATCH_CAP, limit) {
                top.upper = top.upper.min(b.max(lower));
            }
            top.projected = true;
            heap.push(top);
        } else if splits < opts.max_splits {
            splits += 1;
            // A part is within any bound of the whole.
            let Piece {
                p, d, near, upper, ..
            } = top;
            let m = [
                (p[0] + p[1]) * 0.5,
                (p[1] + p[2]) * 0.5,
                (p[2] + p[0]) * 0.5,
            ];
            let am = [
                target.nearest_near(m[0], near[0]),
                target.nearest_near(m[1], near[1]),
                target.nearest_near(m[2], near[2]),
            ];
            let (dm, nm) = (am.map(|x| x.0), am.map(|x| x.1));
            lower = lower.max(dm[0]).max(dm[1]).max(dm[2]);
            for (p, d, near) in [
                (
                    [p[0], m[0], m[2]],
                    [d[0], dm[0], dm[2]],
                    [near[0], nm[0], nm[2]],
                ),
                (
                    [m[0], p[1], m[1]],
                    [dm[0], d[1], dm[1]],
                    [nm[0], near[1], nm[1]],
                ),
                (
                    [m[2], m[1], p[2]],
                    [dm[2], dm[1], d[2]],
                    [nm[2], nm[1], near[2]],
                ),
                (m, dm, nm),
            ] {
                let part = piece(p, d, near, target);
                heap.push(Piece {
                    upper: part.upper.min(upper),
                    ..part
                });
            }
        } else {
            break;
        }
        top = heap.pop().expect("a piece was just pushed");
    }
    (top.upper.max(lower) * (1.0 + ROUNDING), lower, owner)
}

/// The nearest triangle of a point left unsearched ([`nearest_points`]).
pub(super) const UNKNOWN: u32 = u32::MAX;

/// What ends [`nearest_points`] early: a watched point farther than the
/// distance sets the flag.
type Watch<'w> = (&'w [bool], f32, &'w AtomicBool);

/// Each point's exact distance and nearest triangle of `to`: `known` where
/// another certificate carries it, `(0, UNKNOWN)` where `need` leaves it
/// out. Fixed chunks of points are searched in order, each from its
/// predecessor's nearest triangle (files list neighbours together): a good
/// first guess prunes the search, and chunks keep the result the same on
/// any number of threads. A watched point farther than the watch's distance
/// ends the search: which one a worker met first depends on timing, that
/// one exists does not.
pub(super) fn nearest_points(
    to: &MeshDistance,
    p: &[Vec3],
    known: Option<&[Option<Nearest>]>,
    need: Option<&[bool]>,
    watch: Option<Watch>,
) -> Vec<Nearest> {
    const CHUNK: usize = 256;
    let mut at = vec![(0.0, UNKNOWN); p.len()];
    let stopped = || watch.is_some_and(|w| w.2.load(AtomicOrdering::Relaxed));
    at.par_chunks_mut(CHUNK).enumerate().for_each(|(c, chunk)| {
        if stopped() {
            return;
        }
        let mut hint = UNKNOWN;
        for (k, a) in chunk.iter_mut().enumerate() {
            let v = c * CHUNK + k;
            if let Some(known) = known.and_then(|known| known[v]) {
                *a = known;
            } else if need.is_none_or(|need| need[v]) {
                *a = to.nearest_near(p[v], hint);
            } else {
                continue;
            }
            hint = a.1;
            if let Some((watched, over, beyond)) = watch
                && a.0 > over
                && watched[v]
            {
                beyond.store(true, AtomicOrdering::Relaxed);
            }
        }
    });
    at
}

/// Per vertex of `mesh`: whether a triangle `open` names has it (the points
/// [`nearest_points`] needs for those triangles' bounds).
pub(super) fn corners_of(mesh: &TriMesh, open: impl Fn(usize) -> bool) -> Vec<bool> {
    let mut need = vec![false; mesh.positions.len()];
    for t in (0..mesh.triangles.len()).filter(|&t| open(t)) {
        for v in mesh.triangles[t] {
            need[v as usize] = true;
        }
    }
    need
}

/// A triangle's bound, lower bound and best covering triangle of the other surface.
pub(super) type Bounds = (f32, f32, u32);
/// A point's exact distance to a surface and its nearest triangle.
pub(super) type Nearest = (f32, u32);

/// [`Bounds`] per triangle of `from`.
type SideBounds = Vec<Bounds>;

/// One direction of the certificate: the triangles of `from` against the surface `to`.
struct Side<'a> {
    from: &'a TriMesh,
    to: &'a MeshDistance<'a>,
    /// Exact distance and nearest triangle of `to` per vertex of `from`.
    at_vertex: Vec<(f32, u32)>,
    /// For S → O: the original's planar projection, tried first.
    projection: Option<&'a Projection<'a>>,
}

/// Progress over the first pass, and the cancel flag checked per triangle;
/// the pass also ends once a triangle's exact distance exceeds `over`.
struct Tracker<'a> {
    progress: &'a Progress,
    done: AtomicUsize,
    total: usize,
    over: f32,
    exceeded: AtomicBool,
}

/// Triangles a worker counts before it adds them to the shared count: one
/// shared counter bumped per triangle costs the two cores a cache line each
/// time (30 ms per pass over the dragon).
const TICKS: u32 = 256;

impl Tracker<'_> {
    /// Counts one triangle on a worker's `local` count; false once cancelled
    /// or over.
    fn tick(&self, local: &mut u32) -> bool {
        *local += 1;
        if *local == TICKS {
            *local = 0;
            let d = self.done.fetch_add(TICKS as usize, AtomicOrdering::Relaxed);
            self.progress
                .set_fraction((d + TICKS as usize) as f32 / self.total.max(1) as f32);
        }
        !self.progress.is_cancelled() && !self.exceeded.load(AtomicOrdering::Relaxed)
    }

    /// Notes a triangle's lower bound.
    fn found(&self, lower: f32) {
        if lower > self.over {
            self.exceeded.store(true, AtomicOrdering::Relaxed);
        }
    }
}

impl<'a> Side<'a> {
    /// Its corners' exact distances and nearest triangles (searched here
    /// where [`nearest_points`] left them out).
    fn at(&self, t: usize) -> [(f32, u32); 3] {
        self.from.triangles[t].map(|v| match self.at_vertex[v as usize] {
            (_, UNKNOWN) => self.to.nearest(self.from.positions[v as usize]),
            at => at,
        })
    }

    /// The largest distance of a vertex of a triangle.
    fn corner_lower(&self) -> f32 {
        (0..self.from.triangles.len())
            .into_par_iter()
            .map(|t| self.at(t).iter().fold(0.0, |m, a| a.0.max(m)))
            .reduce(|| 0.0, f32::max)
    }

    /// For every triangle: its bound, the largest exact distance found, and the
    /// triangle of `to` that covers it best as a whole; `known` where an
    /// earlier certificate carries it.
    fn bounds(
        &self,
        opts: &BoundOptions,
        (enough, aim): (f32, f32),
        track: &Tracker,
        known: Option<&[Option<Bounds>]>,
    ) -> SideBounds {
        (0..self.from.triangles.len())
            .into_par_iter()
            .map_init(
                || 0,
                |local, t| {
                    if let Some(b) = known.and_then(|k| k[t]) {
                        return b;
                    }
                    if !track.tick(local) {
                        return (f32::INFINITY, 0.0, 0);
                    }
                    let at = self.at(t);
                    let tri = self.from.triangle(t);
                    let to = (self.to, self.projection);
                    let b = max_distance_bound(tri, at, to, opts, enough, aim);
                    track.found(b.1);
                    b
                },
            )
            .collect()
    }

    /// Second pass: triangles still above `enough` and `aim` get a larger
    /// split budget (only they can decide the maximum, or the question).
    fn refine(
        &self,
        bounds: &mut SideBounds,
        opts: &BoundOptions,
        (enough, aim): (f32, f32),
        track: &Tracker,
    ) {
        let deep = BoundOptions {
            max_splits: opts.max_splits * 4,
            ..*opts
        };
        bounds.par_iter_mut().enumerate().for_each(|(t, b)| {
            if b.0 > enough.max(aim) && !track.progress.is_cancelled() {
                let (tri, to) = (self.from.triangle(t), (self.to, self.projection));
                let (upper, lower, _) = max_distance_bound(tri, self.at(t), to, &deep, enough, aim);
                *b = (upper.min(b.0), lower.max(b.1), b.2);
            }
        });
    }
}

/// The original's search structures (its nearest-triangle BVH and planar
/// projection), built once for every certificate against it: an error
/// target certifies a dozen probes, and the dragon's take 0.3 s to build.
pub struct Original<'a> {
    mesh: &'a TriMesh,
    bounds: Aabb,
    distance: MeshDistance<'a>,
    projection: Projection<'a>,
    /// Per vertex: whether a triangle has it (a point of the input has none,
    /// and no triangle's bound covers it).
    on_surface: Vec<bool>,
}

impl<'a> Original<'a> {
    pub fn new(mesh: &'a TriMesh) -> Self {
        let mut on_surface = vec![false; mesh.positions.len()];
        for &v in mesh.triangles.iter().flatten() {
            on_surface[v as usize] = true;
        }
        Original {
            mesh,
            bounds: mesh.bounds(),
            distance: MeshDistance::new(mesh),
            projection: Projection::new(mesh),
            on_surface,
        }
    }

    pub fn mesh(&self) -> &'a TriMesh {
        self.mesh
    }

    pub fn bounds(&self) -> Aabb {
        self.bounds
    }

    /// Nearest-triangle distances to the original.
    pub fn distance(&self) -> &MeshDistance<'a> {
        &self.distance
    }

    /// The original's planar projection (module `projection`).
    pub fn projection(&self) -> &Projection<'a> {
        &self.projection
    }
}

/// Certifies `simplified` against `original` (see the module doc).
pub fn certify(original: &TriMesh, simplified: &TriMesh, opts: &BoundOptions) -> Certificate {
    match certify_with_progress(original, simplified, opts, &Progress::new()) {
        Ok(c) => c,
        Err(Cancelled) => unreachable!("a fresh progress handle is never cancelled"),
    }
}

/// [`certify`], publishing its fraction done on `progress` and stopping as soon
/// as it is cancelled.
pub fn certify_with_progress(
    original: &TriMesh,
    simplified: &TriMesh,
    opts: &BoundOptions,
    progress: &Progress,
) -> Result<Certificate, Cancelled> {
    certify_against(&Original::new(original), simplified, opts, progress)
}

/// [`certify_with_progress`] against an original whose structures are built.
pub fn certify_against(
    original: &Original,
    simplified: &TriMesh,
    opts: &BoundOptions,
    progress: &Progress,
) -> Result<Certificate, Cancelled> {
    if let Some(c) = empty(original.mesh, simplified) {
        return Ok(c);
    }
    match certify_sides(
        original,
        simplified,
        Earlier::default(),
        opts,
        Ask::Tight,
        progress,
    ) {
        Ok((rev, fwd, ..)) => Ok(certificate(&rev, &fwd)),
        Err(Stop::Cancelled) => Err(Cancelled),
        Err(Stop::Over(_)) => unreachable!("no distance exceeds infinity"),
    }
}

/// The certificate where either surface is empty: nothing of S leaves the
/// original unbounded; no original leaves nothing to be far from.
fn empty(original: &TriMesh, simplified: &TriMesh) -> Option<Certificate> {
    let n = simplified.triangles.len();
    (n == 0 || original.triangles.is_empty()).then(|| Certificate {
        triangle_bounds: vec![0.0; n],
        attributed: Vec::new(),
        forward: if original.triangles.is_empty() {
            0.0
        } else {
            f32::INFINITY
        },
        reverse: 0.0,
    })
}

/// What a certificate is asked: an error search's probe only whether its
/// bound is within the error, a result its tightest bound.
#[derive(Clone, Copy)]
pub enum Ask<'r> {
    /// The tightest bound the options' tolerance gives.
    Tight,
    /// Whether the bound is within this limit. A piece is refined until its
    /// bound is within it, not to the tolerance: the certificate lands
    /// anywhere up to the limit (so it is not the tight one), far fewer
    /// pieces are refined or projected, and a state whose distances stay
    /// under the limit is not failed for a bound the tolerance left above
    /// it. An exact distance over the limit ends it early
    /// ([`Traced::Over`]). With a relay (a finer certified state, module
    /// `relay`), what it bounds within the limit is not measured directly.
    Within(f32, Option<&'r Relay<'r>>),
}

impl<'r> Ask<'r> {
    /// An exact distance over this ends the certificate.
    fn over(self) -> f32 {
        match self {
            Ask::Tight => f32::INFINITY,
            Ask::Within(limit, _) => limit,
        }
    }

    /// The relay, where it serves the limit.
    fn relay(self) -> Option<&'r Relay<'r>> {
        match self {
            Ask::Tight => None,
            Ask::Within(limit, relay) => relay.filter(|r| r.serves(limit)),
        }
    }

    /// What refinement aims under: the limit less the rounding slack every
    /// bound gets, so a piece that reaches it is within the limit.
    fn aim(self) -> f32 {
        match self {
            Ask::Tight => 0.0,
            Ask::Within(limit, _) => limit * (1.0 - 4.0 * ROUNDING),
        }
    }
}

/// What certifying a state of a collapse found.
#[derive(Debug, Clone, PartialEq)]
pub enum Traced {
    /// Its certificate, and the trace that certifies other states.
    Certified(Certificate, Box<Trace>),
    /// Over the limit it was asked about ([`Ask::Within`]): an exact
    /// distance beyond it was found (the certificate would exceed it too, so
    /// an error search needs no more); the largest such distance where S's
    /// vertices or carried bounds told, else the limit.
    Over(f32),
}

/// Certifies a state of an edge collapse (`ids`: the collapser's id of each
/// triangle of `simplified`, ascending) and keeps the trace that certifies
/// other states of the same collapse; with `earlier`, the trace of another
/// state, what it proved that still holds carries (module `recertify`).
/// Asked [`Ask::Within`] a limit, it stops as soon as an exact distance
/// exceeds it: an error search's failed probe mostly costs the vertices'
/// distances alone.
pub fn certify_traced(
    original: &Original,
    simplified: &TriMesh,
    ids: &[u32],
    earlier: Option<&Trace>,
    opts: &BoundOptions,
    ask: Ask,
    progress: &Progress,
) -> Result<Traced, Cancelled> {
    if let Some(c) = empty(original.mesh, simplified) {
        if c.error_bound() > ask.over() {
            return Ok(Traced::Over(c.error_bound()));
        }
        let rev = vec![(0.0, 0.0, 0); ids.len()];
        let trace = Trace::new(
            original,
            ids,
            simplified,
            &rev,
            Vec::new(),
            Vec::new(),
            Vec::new(),
        );
        return Ok(Traced::Certified(c, Box::new(trace)));
    }
    // A relayed probe carries only S → O bounds and β (module `relay`): the
    // relay bounds the original's triangles for less than finding which of
    // their bounds carry (a pass over them).
    let (recertify, relayed) = match ask.relay() {
        Some(relay) => {
            let carry = |e| carry_relayed(e, original, simplified, ids, relay.boxes());
            (None, earlier.and_then(carry))
        }
        None => {
            let carry = |e| Recertify::new(e, original, simplified, ids);
            (earlier.and_then(carry), None)
        }
    };
    let earlier = Earlier { recertify, relayed };
    match certify_sides(original, simplified, earlier, opts, ask, progress) {
        Ok((rev, fwd, at_vertex, beta)) => {
            let certificate = certificate(&rev, &fwd);
            let trace = Trace::new(original, ids, simplified, &rev, fwd, at_vertex, beta);
            Ok(Traced::Certified(certificate, Box::new(trace)))
        }
        Err(Stop::Over(lower)) => Ok(Traced::Over(lower)),
        Err(Stop::Cancelled) => Err(Cancelled),
    }
}

/// Why certifying stopped early.
enum Stop {
    Cancelled,
    /// An exact distance (a lower bound of the result) over the limit.
    Over(f32),
}

impl From<Cancelled> for Stop {
    fn from(_: Cancelled) -> Self {
        Stop::Cancelled
    }
}

/// Both directions' bounds, the original's vertices' nearest triangles of
/// S, and a relayed certificate's β (what a trace keeps).
type Sides = (SideBounds, SideBounds, Vec<Nearest>, Vec<Option<Beta>>);

/// What another state's trace carries to a certificate: for a direct one,
/// what `recertify` finds; for a relayed one, S → O bounds by id and β.
#[derive(Default)]
struct Earlier {
    recertify: Option<Recertify>,
    relayed: Option<RelayCarry>,
}

/// Both directions' per-triangle bounds, the original's vertices' exact
/// distances and nearest triangles of S, and a relayed certificate's β.
fn certify_sides(
    original: &Original,
    simplified: &TriMesh,
    Earlier {
        recertify,
        relayed: by_relay,
    }: Earlier,
    opts: &BoundOptions,
    ask: Ask,
    progress: &Progress,
) -> Result<Sides, Stop> {
    let (over, aim) = (ask.over(), ask.aim());
    let Original {
        mesh: original,
        distance: to_o,
        projection,
        on_surface,
        ..
    } = original;
    let n = simplified.triangles.len();
    let enough_above = |l: f32| {
        if opts.per_triangle {
            0.0
        } else {
            l * (1.0 + opts.rel_tol)
        }
    };
    let to_s = MeshDistance::new(simplified);
    let rev = Side {
        from: simplified,
        to: to_o,
        at_vertex: nearest_points(to_o, &simplified.positions, None, None, None),
        projection: Some(projection),
    };
    // S's corners (a point of the input lies in no triangle, so only a
    // vertex of a triangle counts) and what carried are exact distances: one
    // over `over` ends it before the original's vertices are searched (those
    // are watched during their search).
    let carried = recertify.as_ref().map_or(0.0, |r| r.lower());
    let reached = rev.corner_lower().max(carried);
    if reached > over {
        return Err(Stop::Over(reached));
    }
    let known = |side: fn(&Recertify) -> &Vec<Option<Bounds>>| {
        recertify.as_ref().map(|r| side(r).as_slice())
    };
    let (mut rev_known, mut fwd_known) = (known(|r| &r.reverse), known(|r| &r.forward));
    // What carries, or what a finer certified state bounds within the
    // limit (module `relay`), is not measured again.
    let (relayed, beta);
    if let Some(relay) = ask.relay() {
        let corner = |t: usize| rev.at(t).iter().fold(0.0, |m, a| a.0.max(m));
        let (r, f, b) = relay.bounds((simplified, &to_s), corner, opts, aim, by_relay.as_ref());
        (relayed, beta) = ((r, f), b);
        (rev_known, fwd_known) = (Some(relayed.0.as_slice()), Some(relayed.1.as_slice()));
    } else {
        beta = Vec::new();
    }
    // Only the vertices of the original's triangles still open are searched
    // (a triangle's direct bound needs its corners'; those of a triangle
    // that carried or relayed are searched only if it is refined).
    let need = fwd_known.map(|known| corners_of(original, |t| known[t].is_none()));
    let beyond = AtomicBool::new(false);
    let fwd_at = nearest_points(
        &to_s,
        &original.positions,
        recertify.as_ref().map(|r| r.at_vertex.as_slice()),
        need.as_deref(),
        Some((on_surface, over, &beyond)),
    );
    if beyond.into_inner() {
        return Err(Stop::Over(over));
    }
    let fwd = Side {
        from: original,
        to: &to_s,
        at_vertex: fwd_at,
        projection: None,
    };
    progress.check()?;
    // The largest exact vertex distance is a lower bound of the result: refining a
    // triangle far below it cannot change the maximum, so the absolute tolerance
    // follows it and the work goes where the maximum is.
    let lower = rev
        .at_vertex
        .iter()
        .chain(&fwd.at_vertex)
        .map(|x| x.0)
        .fold(carried, f32::max);
    let opts = BoundOptions {
        abs_tol: opts.abs_tol.max(opts.rel_tol * lower),
        ..*opts
    };
    // Pass one measures what does not carry (the refinement is short).
    let fresh = |k: Option<&[Option<_>]>, all: usize| {
        k.map_or(all, |k| k.iter().filter(|b| b.is_none()).count())
    };
    let track = Tracker {
        progress,
        done: AtomicUsize::new(0),
        total: fresh(rev_known, n) + fresh(fwd_known, original.triangles.len()),
        over,
        exceeded: AtomicBool::new(false),
    };
    let mut reverse = rev.bounds(&opts, (enough_above(lower), aim), &track, rev_known);
    let mut forward = fwd.bounds(&opts, (enough_above(lower), aim), &track, fwd_known);
    progress.check()?;
    // Pass one raised the lower bound; refine what is still above it.
    let found = reverse
        .iter()
        .chain(&forward)
        .map(|x| x.1)
        .fold(lower, f32::max);
    if found > over {
        // Which triangle stopped the pass depends on the workers' timing:
        // only "over `over`" is the same on any number of threads.
        return Err(Stop::Over(over));
    }
    rev.refine(&mut reverse, &opts, (enough_above(found), aim), &track);
    fwd.refine(&mut forward, &opts, (enough_above(found), aim), &track);
    progress.check()?;
    Ok((reverse, forward, fwd.at_vertex, beta))
}

/// A triangle's bound is the larger of its S → O bound and the O → S
/// bounds of the original triangles attributed to it.
fn certificate(reverse: &SideBounds, forward: &SideBounds) -> Certificate {
    let mut triangle_bounds: Vec<f32> = reverse.iter().map(|x| x.0).collect();
    for (b, _, owner) in forward {
        let tb = &mut triangle_bounds[*owner as usize];
        *tb = tb.max(*b);
    }
    Certificate {
        triangle_bounds,
        attributed: forward.iter().map(|x| x.2).collect(),
        forward: forward.iter().map(|x| x.0).fold(0.0, f32::max),
        reverse: reverse.iter().map(|x| x.0).fold(0.0, f32::max),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::builtins::icosphere;
    use crate::distance::{SamplingOptions, hausdorff_mesh_mesh};

    /// A triangle over a roof of two faces: its vertices are nearest to
    /// different faces, so the unsplit bound comes from the cut between them;
    /// it must hold against dense sampling and beat either face alone.
    #[test]
    fn straddling_piece_bound_holds() {
        let roof = TriMesh::new(
            vec![
                Vec3::new(0.0, -1.0, 0.0),
                Vec3::new(0.0, 1.0, 0.0),
                Vec3::new(-1.0, 0.0, -0.4),
                Vec3::new(1.0, 0.0, -0.4),
            ],
            vec![[0, 1, 2], [1, 0, 3]],
        );
        let target = MeshDistance::new(&roof);
        let tri = [
            Vec3::new(-0.8, -0.2, -0.1),
            Vec3::new(0.8, -0.2, -0.1),
            Vec3::new(0.0, 0.6, 0.1),
        ];
        let at = tri.map(|p| target.nearest(p));
        assert_ne!(at[0].1, at[1].1, "the piece must straddle the ridge");
        let opts = BoundOptions {
            max_splits: 0,
            ..BoundOptions::for_diagonal(2.0)
        };
        let (upper, _, _) = max_distance_bound(tri, at, (&target, None), &opts, 0.0, 0.0);
        let mut sampled = 0.0f32;
        let n = 200;
        for i in 0..=n {
            for j in 0..=n - i {
                let (u, v) = (i as f32 / n as f32, j as f32 / n as f32);
                let y = tri[0] + (tri[1] - tri[0]) * u + (tri[2] - tri[0]) * v;
                sampled = sampled.max(target.distance(y));
            }
        }
        let single = [0u32, 1].map(|t| {
            tri.iter()
                .map(|p| target.triangle_distance(*p, t))
                .fold(0.0, f32::max)
        });
        assert!(upper >= sampled, "bound {upper} < sampled {sampled}");
        assert!(
            upper < single[0].min(single[1]),
            "cut {upper} vs single {single:?}"
        );
    }

    /// Asked whether a state is within a limit, certifying stops early only
    /// where an exact distance proves the state over it (so its certificate
    /// is over it too); a certificate it gives is within the limit and holds
    /// against sampling, though it is looser than the tight one; a limit the
    /// tight bound meets is always met; a limit the tolerance left the tight
    /// bound above is met where the distance is under it (refinement goes
    /// past the tolerance); and every verdict is the same on one thread as
    /// on many.
    #[test]
    fn a_limit_is_decided_and_an_early_stop_is_proven_over() {
        use crate::simplify::{CollapseOptions, EdgeCollapser};
        let mesh = crate::builtins::torus(1.0, 0.35, 96, 40);
        let original = Original::new(&mesh);
        let opts = BoundOptions::for_diagonal(mesh.bounds().diagonal());
        let n = mesh.triangles.len();
        let one_thread = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap();
        let (mut stopped, mut past_tolerance) = (0, 0);
        for count in [n / 10, n / 40, 120] {
            let mut collapser = EdgeCollapser::new(&mesh, CollapseOptions::default());
            collapser.run(count, |_, _| true);
            let (s, ids) = collapser.mesh();
            let p = Progress::new();
            let certify = |ask| certify_traced(&original, &s, &ids, None, &opts, ask, &p);
            let Ok(Traced::Certified(tight, _)) = certify(Ask::Tight) else {
                panic!("no limit, no stop")
            };
            let b = tight.error_bound();
            let sampled = hausdorff_mesh_mesh(
                &mesh,
                &s,
                &SamplingOptions {
                    samples: 50_000,
                    seed: 5,
                },
            )
            .two_sided();
            for limit in [0.3 * b, 0.9 * b, 0.97 * b, 0.99 * b, 1.5 * b] {
                let verdict = certify(Ask::Within(limit, None)).unwrap();
                // The same on any number of threads (a search's next probe
                // and a chain's later rows depend on it).
                assert_eq!(
                    one_thread
                        .install(|| certify(Ask::Within(limit, None)))
                        .unwrap(),
                    verdict
                );
                match verdict {
                    Traced::Over(lower) => {
                        assert!(
                            limit < b && limit <= lower && lower <= b,
                            "{limit} {lower} {b}"
                        );
                        stopped += 1;
                    }
                    Traced::Certified(c, _) => {
                        let within = c.error_bound();
                        assert!(sampled <= within, "{count}: {within} < sampled {sampled}");
                        if within <= limit && limit < b {
                            past_tolerance += 1;
                        }
                    }
                }
            }
            let Ok(Traced::Certified(c, _)) = certify(Ask::Within(1.5 * b, None)) else {
                panic!("{count}: a limit above the tight bound must be met")
            };
            assert!(c.error_bound() <= 1.5 * b);
        }
        assert!(stopped >= 3, "{stopped} early stops");
        assert!(
            past_tolerance >= 1,
            "no limit under the tight bound was met"
        );
    }

    /// A coarse sphere against a fine one: the bound holds against dense
    /// sampling and is within a small factor of it; the original's structures,
    /// built once, certify each level as a fresh certificate does.
    #[test]
    fn bound_holds_and_is_tight_on_spheres() {
        let fine = icosphere(Vec3::ZERO, 1.0, 4);
        let original = Original::new(&fine);
        for level in [0, 1, 2] {
            let coarse = icosphere(Vec3::new(0.01, 0.0, 0.0), 1.0, level);
            let opts = BoundOptions::for_diagonal(3.4);
            let cert = certify(&fine, &coarse, &opts);
            let reused = certify_against(&original, &coarse, &opts, &Progress::new());
            assert_eq!(reused.as_ref(), Ok(&cert));
            let measured = hausdorff_mesh_mesh(
                &fine,
                &coarse,
                &SamplingOptions {
                    samples: 100_000,
                    seed: 2,
                },
            )
            .two_sided();
            let bound = cert.error_bound();
            eprintln!(
                "level {level}: fwd {} rev {} measured {measured}",
                cert.forward, cert.reverse
            );
            assert!(
                bound >= measured,
                "level {level}: bound {bound} < measured {measured}"
            );
            assert!(
                bound <= 1.3 * measured,
                "level {level}: bound {bound} vs {measured}"
            );
            assert_eq!(cert.attributed.len(), fine.triangles.len());
        }
    }
}
