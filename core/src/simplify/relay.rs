//! Certifying a coarse state S through a finer certified state M of the
//! same original O (an LOD chain's finest row), one triangle at a time: the
//! triangle inequality bounds
//! - S → O: d(y, O) ≤ d(y, M) + ρ for every y, with ρ M's certified S → O
//!   bound, so a triangle of S within `aim − ρ` of M is within `aim` of O;
//! - O → S: an original triangle o attributed to M's triangle T lies within
//!   c(o), the largest distance of its corners to T, of T (convexity), and
//!   every point of T within β(T) of S, so o lies within c(o) + β(T) of S.
//!
//! M has a fraction of O's triangles, so these bounds cost a fraction of a
//! direct pass over O (the dragon's finest row has 1/37 of its triangles).
//! They are looser by ρ and c(o), so they only answer whether a triangle is
//! within an error search's limit (`Ask::Within`); a triangle they leave
//! above it is measured directly, so a probe's verdict is as decisive as a
//! direct one's. A coarser row's probes lie far from every certified state
//! and carry little of the original's bounds (module `recertify`): the
//! relay spares them most of the pass. A relayed probe carries S → O bounds
//! by id and β where nothing changed within reach of M's triangle from the
//! nearer trace (recertify's argument on M's triangles), and relays the
//! original's triangles again, for less than finding which of theirs carry.

use rayon::prelude::*;

use super::bound::{
    BoundOptions, Bounds, Certificate, Nearest, Original, ROUNDING, corners_of, max_distance_bound,
    nearest_points,
};
use super::recertify::RelayCarry;
use crate::distance::MeshDistance;
use crate::geom::{Aabb, TriMesh};

/// β(T) of a triangle T of M, and the triangle of S that covers it best.
pub(super) type Beta = (f32, u32);

/// What [`Relay::bounds`] gives: S → O and O → S bounds (`None`: to be
/// measured directly), and β per triangle of M.
pub(super) type Relayed = (Vec<Option<Bounds>>, Vec<Option<Bounds>>, Vec<Option<Beta>>);

/// Splits a relayed bound may take: a triangle the relay cannot bound
/// quickly is measured directly.
const SPLITS: usize = 16;

/// A finer certified state that bounds coarser ones (module doc).
pub struct Relay<'m> {
    m: Original<'m>,
    /// ρ: M's certified S → O bound.
    rho: f32,
    /// Per original triangle: M's triangle it is attributed to, and c(o).
    through: Vec<(u32, f32)>,
    /// Per triangle of M: the largest c(o) of the original triangles
    /// attributed to it (negative: none).
    widest: Vec<f32>,
    /// Per triangle of M: its box (what β(T) carries by, module `recertify`).
    boxes: Vec<Aabb>,
}

impl<'m> Relay<'m> {
    /// M (`m`) with its certificate against `original`; `None` where the
    /// certificate attributes no original triangle (an empty M).
    pub fn new(original: &TriMesh, m: &'m TriMesh, certificate: &Certificate) -> Option<Self> {
        if certificate.attributed.len() != original.triangles.len() || m.triangles.is_empty() {
            return None;
        }
        let m = Original::new(m);
        let through: Vec<(u32, f32)> = (0..original.triangles.len())
            .into_par_iter()
            .map(|o| {
                let t = certificate.attributed[o];
                let far = original
                    .triangle(o)
                    .iter()
                    .map(|&p| m.distance().triangle_distance(p, t))
                    .fold(0.0, f32::max);
                (t, far * (1.0 + ROUNDING))
            })
            .collect();
        let mut widest = vec![-1.0f32; m.mesh().triangles.len()];
        for &(t, c) in &through {
            widest[t as usize] = widest[t as usize].max(c);
        }
        let boxes = (0..m.mesh().triangles.len())
            .map(|t| Aabb::from_points(&m.mesh().triangle(t)))
            .collect();
        Some(Relay {
            m,
            rho: certificate.reverse,
            through,
            widest,
            boxes,
        })
    }

    /// Whether it is worth asking about `limit`: ρ under half of it (else a
    /// relayed bound is rarely within it).
    pub fn serves(&self, limit: f32) -> bool {
        self.rho < 0.5 * limit
    }

    /// Each triangle of M's box.
    pub(super) fn boxes(&self) -> &[Aabb] {
        &self.boxes
    }

    /// The bounds of the triangles of S (`s`, searched by `to_s`;
    /// `corner(t)` its triangle t's largest exact corner distance to O) and
    /// of the original's that are relayed within `aim` or carried from
    /// another relayed state (`carried`: S → O bounds, β by triangle of M),
    /// and every β, for this state's trace: S → O, O → S, β.
    pub(super) fn bounds(
        &self,
        (s, to_s): (&TriMesh, &MeshDistance),
        corner: impl Fn(usize) -> f32 + Sync,
        opts: &BoundOptions,
        aim: f32,
        carried: Option<&RelayCarry>,
    ) -> Relayed {
        let quick = BoundOptions {
            max_splits: SPLITS,
            ..*opts
        };
        // A relayed bound u within `aim` once rounded up: u ≤ cap(slack).
        let cap = |slack: f32| aim / (1.0 + ROUNDING) - slack;
        let at_m = nearest_points(self.m.distance(), &s.positions, None, None, None);
        let to_m = (self.m.distance(), Some(self.m.projection()));
        let reverse = (0..s.triangles.len())
            .into_par_iter()
            .map(|t| {
                let c = cap(self.rho);
                if let Some(b) = carried.and_then(|k| k.0[t]) {
                    return Some(b);
                }
                if c <= 0.0 {
                    return None;
                }
                let at = s.triangles[t].map(|v| at_m[v as usize]);
                let (u, _, _) = max_distance_bound(s.triangle(t), at, to_m, &quick, c, c);
                let u = (u + self.rho) * (1.0 + ROUNDING);
                (u <= aim).then(|| (u, corner(t), 0))
            })
            .collect();
        // β(T) for M's triangles some original triangle is attributed to.
        let m = self.m.mesh();
        let open = |t: usize| self.widest[t] >= 0.0 && carried.is_none_or(|k| k.1[t].is_none());
        let need = corners_of(m, open);
        let at_s: Vec<Nearest> = nearest_points(to_s, &m.positions, None, Some(&need), None);
        let beta: Vec<Option<Beta>> = (0..m.triangles.len())
            .into_par_iter()
            .map(|t| {
                if self.widest[t] < 0.0 {
                    return None;
                }
                if let Some(b) = carried.and_then(|k| k.1[t]) {
                    return Some(b);
                }
                let c = cap(self.widest[t]).max(0.0);
                let at = m.triangles[t].map(|v| at_s[v as usize]);
                let (b, _, owner) =
                    max_distance_bound(m.triangle(t), at, (to_s, None), &quick, c, c);
                Some((b, owner))
            })
            .collect();
        let forward = (0..self.through.len())
            .into_par_iter()
            .map(|o| {
                let (t, c) = self.through[o];
                let (b, owner) = beta[t as usize]?;
                let u = (c + b) * (1.0 + ROUNDING);
                (u <= aim).then_some((u, 0.0, owner))
            })
            .collect();
        (reverse, forward, beta)
    }
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;
    use crate::distance::{SamplingOptions, hausdorff_mesh_mesh};
    use crate::progress::Progress;
    use crate::simplify::Certificate;
    use crate::simplify::recertify::carry_relayed;
    use crate::simplify::{
        Ask, CollapseOptions, EdgeCollapser, Traced, certify_against, certify_traced,
    };

    fn state(mesh: &TriMesh, count: usize) -> (TriMesh, Vec<u32>) {
        let mut collapser = EdgeCollapser::new(mesh, CollapseOptions::default());
        collapser.run(count, |_, _| true);
        collapser.mesh()
    }

    /// A torus (`around` × `across` quads), the state of its collapse at
    /// 1/`finer` of its triangles (M) with M's certificate, and the options.
    fn torus_and_finer(around: u32, across: u32, finer: usize) -> Fixture {
        let o = crate::builtins::torus(1.0, 0.35, around, across);
        let opts = BoundOptions::for_diagonal(o.bounds().diagonal());
        let (m, _) = state(&o, o.triangles.len() / finer);
        let certificate = certify_against(&Original::new(&o), &m, &opts, &Progress::new()).unwrap();
        (o, m, certificate, opts)
    }

    type Fixture = (TriMesh, TriMesh, Certificate, BoundOptions);

    /// Points of a triangle on a barycentric grid (corners, edges, inside).
    fn samples(p: [Vec3; 3]) -> impl Iterator<Item = Vec3> {
        const N: usize = 6;
        (0..=N).flat_map(move |i| {
            (0..=N - i).map(move |j| {
                let (a, b) = (i as f32 / N as f32, j as f32 / N as f32);
                p[0] * (1.0 - a - b) + p[1] * a + p[2] * b
            })
        })
    }

    /// Through a finer certified state, a coarser state's triangles get
    /// bounds that hold at sampled points of each (S → O and O → S), and
    /// with the aim a little above its direct bound most triangles of both
    /// get one (else the relay spares nothing).
    #[test]
    fn relayed_bounds_hold_and_cover_most_triangles() {
        let (o, m, certificate, opts) = torus_and_finer(120, 48, 6);
        let original = Original::new(&o);
        let n = o.triangles.len();
        let relay = Relay::new(&o, &m, &certificate).unwrap();
        let (s, _) = state(&o, n / 60);
        let direct = certify_against(&original, &s, &opts, &Progress::new()).unwrap();
        let aim = 1.2 * direct.error_bound();
        assert!(relay.serves(aim), "ρ {} against {aim}", relay.rho);
        let to_s = MeshDistance::new(&s);
        let to_o = original.distance();
        let corner = |t: usize| {
            s.triangle(t)
                .iter()
                .map(|&p| to_o.distance(p))
                .fold(0.0, f32::max)
        };
        let (reverse, forward, _) = relay.bounds((&s, &to_s), corner, &opts, aim, None);
        let (r, f) = (
            reverse.iter().flatten().count(),
            forward.iter().flatten().count(),
        );
        assert!(
            2 * r > s.triangles.len(),
            "{r} of {} relayed",
            s.triangles.len()
        );
        assert!(2 * f > n, "{f} of {n} relayed");
        for (t, b) in reverse.iter().enumerate() {
            if let Some((u, lower, _)) = *b {
                assert!(lower <= u && u <= aim);
                for p in samples(s.triangle(t)) {
                    assert!(
                        to_o.distance(p) <= u,
                        "S triangle {t}: {} > {u}",
                        to_o.distance(p)
                    );
                }
            }
        }
        for (t, b) in forward.iter().enumerate() {
            if let Some((u, _, owner)) = *b {
                assert!(u <= aim && (owner as usize) < s.triangles.len());
                for p in samples(o.triangle(t)) {
                    assert!(
                        to_s.distance(p) <= u,
                        "O triangle {t}: {} > {u}",
                        to_s.distance(p)
                    );
                }
            }
        }
    }

    /// A relayed state's trace carries its β to a nearby state of the same
    /// collapse, more or fewer collapses on: what carries holds against the
    /// later state at sampled points of M's triangles, and most of it
    /// carries; the S → O bounds carried by id hold too.
    #[test]
    fn carried_beta_holds_for_a_nearby_state() {
        let (o, m, certificate, opts) = torus_and_finer(96, 40, 5);
        let original = Original::new(&o);
        let n = o.triangles.len();
        let relay = Relay::new(&o, &m, &certificate).unwrap();
        let count = n / 40;
        let (s, ids) = state(&o, count);
        let b = certify_against(&original, &s, &opts, &Progress::new())
            .unwrap()
            .error_bound();
        let ask = Ask::Within(2.0 * b, Some(&relay));
        let Ok(Traced::Certified(_, trace)) =
            certify_traced(&original, &s, &ids, None, &opts, ask, &Progress::new())
        else {
            panic!("a limit twice the bound is met")
        };
        for later in [count + count / 25, count - count / 25] {
            let (s, ids) = state(&o, later);
            let (reverse, beta) =
                carry_relayed(&trace, &original, &s, &ids, relay.boxes()).unwrap();
            let carried = beta.iter().flatten().count();
            let open = relay.widest.iter().filter(|w| **w >= 0.0).count();
            assert!(2 * carried > open, "{later}: {carried} of {open} carried");
            let to_s = MeshDistance::new(&s);
            for (t, b) in beta.iter().enumerate() {
                if let Some((u, owner)) = *b {
                    assert!((owner as usize) < s.triangles.len());
                    for p in samples(m.triangle(t)) {
                        assert!(to_s.distance(p) <= u, "T {t}: {} > {u}", to_s.distance(p));
                    }
                }
            }
            for (t, b) in reverse.iter().enumerate() {
                if let Some((u, _, _)) = *b {
                    for p in samples(s.triangle(t)) {
                        assert!(original.distance().distance(p) <= u);
                    }
                }
            }
        }
    }

    /// Asked through a relay whether a state is within a limit: a limit
    /// over its direct bound is met, a certificate is within its limit and
    /// holds against sampling, an early stop lies under the direct
    /// bound, and every verdict is the same on one thread as on many.
    #[test]
    fn relayed_verdicts_agree_with_direct_ones() {
        let (o, m, certificate, opts) = torus_and_finer(96, 40, 5);
        let original = Original::new(&o);
        let n = o.triangles.len();
        let relay = Relay::new(&o, &m, &certificate).unwrap();
        let one_thread = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap();
        let mut relayed = 0;
        for count in [n / 20, n / 50, n / 120] {
            let (s, ids) = state(&o, count);
            let b = certify_against(&original, &s, &opts, &Progress::new())
                .unwrap()
                .error_bound();
            let sampled = hausdorff_mesh_mesh(
                &o,
                &s,
                &SamplingOptions {
                    samples: 20_000,
                    seed: 3,
                },
            )
            .two_sided();
            let p = Progress::new();
            for limit in [0.5 * b, 0.95 * b, 1.1 * b, 2.0 * b] {
                let ask = Ask::Within(limit, Some(&relay));
                relayed += usize::from(relay.serves(limit));
                let certify = || certify_traced(&original, &s, &ids, None, &opts, ask, &p);
                let verdict = certify().unwrap();
                assert_eq!(one_thread.install(certify).unwrap(), verdict);
                match verdict {
                    Traced::Over(lower) => assert!(limit <= lower && lower <= b, "{limit} {b}"),
                    Traced::Certified(c, _) => {
                        assert!(
                            c.error_bound() >= sampled,
                            "{} < {sampled}",
                            c.error_bound()
                        );
                        if limit > b {
                            assert!(c.error_bound() <= limit, "{count}: {limit} not met");
                        }
                    }
                }
            }
        }
        assert!(relayed >= 6, "the relay served {relayed} questions");
    }
}
