//! Edge-collapse simplification with a certified two-sided Hausdorff bound
//! (hybrid paper §2.1, §5.2).
//!
//! Paper: J. D. Cohen, D. G. Aliaga, W. Zhang, "Hybrid Simplification:
//! Combining Multi-resolution Polygon and Point Rendering", Proc. IEEE
//! Visualization 2001, §5.2 (the "hybrid paper" in this tree's docs).
//!
//! `collapse` performs the collapses (the step API the hybrid and merge-tree
//! methods build on) and `step_bounds` gives every collapse the guaranteed
//! bound of its new triangles; `bound` certifies a result: every output
//! triangle carries a true upper bound on the two-sided Hausdorff distance
//! between itself and the part of the original surface attributed to it, and
//! `error_bound` is their maximum; `recertify` certifies a state of a
//! collapse from another state's certificate, re-measuring only near what
//! changed, `relay` certifies a coarse state through a finer certified one
//! (an LOD chain's coarser rows through its finest), and `history` keeps
//! every state of one collapse at hand (an error search's probes, an LOD
//! chain's rows). `progressive`
//! records the collapses once as a hierarchy whose every prefix carries a
//! certified bound, for cuts that move with a slider instead of re-running.

mod attribution;
pub mod bound;
pub mod collapse;
mod history;
pub mod progressive;
pub mod projection;
pub mod quadric;
mod queue;
pub mod recertify;
pub mod relay;
pub mod step_bounds;

pub use bound::{
    Ask, BoundOptions, Certificate, Original, Traced, certify, certify_against, certify_traced,
    certify_with_progress,
};
pub use collapse::{
    Candidate, Collapse, CollapseOptions, EdgeCollapser, StarCostFn, quadric_cost, quadric_mean,
};
pub use recertify::Trace;
pub use relay::Relay;

use crate::geom::TriMesh;
use crate::progress::{Cancelled, Progress};
use history::History;

/// When to stop collapsing.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Target {
    /// At most this many triangles.
    Triangles(usize),
    /// At most this fraction of the input's triangles.
    Ratio(f32),
    /// As few triangles as possible with a certified bound of at most this
    /// distance (absolute) ...
    Error(f32),
    /// ... or this fraction of the bounding-box diagonal.
    RelativeError(f32),
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SimplifyOptions {
    pub target: Target,
    pub collapse: CollapseOptions,
    /// Certify every triangle to its own tolerance (for per-triangle inspection),
    /// not only as far as the mesh's bound needs; slower.
    pub per_triangle_bounds: bool,
}

/// A simplified mesh with its certificate.
#[derive(Debug, Clone)]
pub struct Simplified {
    pub mesh: TriMesh,
    pub certificate: Certificate,
    pub collapses: usize,
}

impl Simplified {
    pub fn error_bound(&self) -> f32 {
        self.certificate.error_bound()
    }
}

/// A result with the trace that certifies other states of its collapse.
type Certified = (Simplified, Trace);

/// A probe of an error search: certified, or an exact distance over the
/// error (its certificate would be over too), all a failed probe needs.
// One per probe, moved once: boxing the result buys nothing.
#[allow(clippy::large_enum_variant)]
enum Verdict {
    Certified(Certified),
    Over(f32),
}

impl Verdict {
    /// The certificate of a state certified with no limit to be over.
    fn certified(self) -> Certified {
        match self {
            Verdict::Certified(c) => c,
            Verdict::Over(lower) => unreachable!("{lower} is over no limit"),
        }
    }
}

/// Invalid simplification parameters.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SimplifyError {
    #[error("invalid target: {0}")]
    BadTarget(String),
    #[error("cancelled")]
    Cancelled,
}

impl From<Cancelled> for SimplifyError {
    fn from(_: Cancelled) -> Self {
        SimplifyError::Cancelled
    }
}

/// Simplifies `mesh` (repaired, as `io::load` returns it) to the target and
/// certifies the result.
pub fn simplify(
    mesh: &TriMesh,
    opts: &SimplifyOptions,
    progress: &Progress,
) -> Result<Simplified, SimplifyError> {
    let mut out = simplify_chain(
        mesh,
        &[opts.target],
        opts.collapse,
        opts.per_triangle_bounds,
        progress,
    )?;
    Ok(out.pop().expect("one result per target"))
}

/// Simplifies `mesh` to every target of an LOD chain in one progressive
/// collapse, run forward once with every state at hand (`history`):
/// collapses are deterministic, so each count target equals a fresh run to
/// its count, and the error targets (smallest first) each search on from the
/// state the previous one reached, each probe certified from the nearest
/// certified state's trace (`recertify`); one original's search structures
/// certify them all. An error target's result meets its error and is as
/// deterministic as the rest, but its count may differ by the search's 2 %
/// from a lone `simplify` to that error (its probes start elsewhere).
/// Results come in the order of `targets`.
pub fn simplify_chain(
    mesh: &TriMesh,
    targets: &[Target],
    collapse_opts: CollapseOptions,
    per_triangle_bounds: bool,
    progress: &Progress,
) -> Result<Vec<Simplified>, SimplifyError> {
    let n = mesh.triangles.len();
    let diag = mesh.bounds().diagonal();
    let valid_fraction = |r: f32| r.is_finite() && (0.0..=1.0).contains(&r);
    let valid_error = |e: f32| e.is_finite() && e >= 0.0;
    // A triangle count to run to (Ok), or an error bound to search for (Err).
    let goal = |target: Target| -> Result<Result<usize, f32>, SimplifyError> {
        match target {
            Target::Triangles(t) => Ok(Ok(t)),
            Target::Ratio(r) if valid_fraction(r) => Ok(Ok((r as f64 * n as f64).round() as usize)),
            Target::Error(e) if valid_error(e) => Ok(Err(e)),
            Target::RelativeError(e) if valid_error(e) => Ok(Err(e * diag)),
            Target::Ratio(r) => Err(SimplifyError::BadTarget(format!(
                "ratio {r} is not in 0..=1"
            ))),
            Target::Error(e) | Target::RelativeError(e) => Err(SimplifyError::BadTarget(format!(
                "error {e} is not a finite distance >= 0"
            ))),
        }
    };
    let goals = targets
        .iter()
        .map(|t| goal(*t))
        .collect::<Result<Vec<_>, _>>()?;
    let bound_opts = BoundOptions {
        per_triangle: per_triangle_bounds,
        ..BoundOptions::for_diagonal(diag)
    };
    // Count goals by decreasing count, error goals by increasing error.
    let mut counts: Vec<(usize, usize)> = goals
        .iter()
        .enumerate()
        .filter_map(|(i, g)| g.ok().map(|c| (i, c)))
        .collect();
    counts.sort_by(|a, b| b.1.cmp(&a.1).then(a.0.cmp(&b.0)));
    let mut errors: Vec<(usize, f32)> = goals
        .iter()
        .enumerate()
        .filter_map(|(i, g)| g.err().map(|e| (i, e)))
        .collect();
    errors.sort_by(|a, b| a.1.total_cmp(&b.1).then(a.0.cmp(&b.0)));
    let mut results: Vec<Option<Simplified>> = vec![None; targets.len()];
    std::thread::scope(|scope| {
        // The original's search structures are built beside the first
        // collapses (which run on one thread), for every certificate.
        let mut building = Some(scope.spawn(|| Original::new(mesh)));
        let mut original = None;
        // A state's certificate, carrying what another state's trace
        // proved that still holds (module `recertify`), or an exact distance
        // over the limit asked about that ends it early.
        let mut certify = |h: &History, k: usize, earlier: Option<&Trace>, ask: Ask| {
            let original = original.get_or_insert_with(|| {
                let handle = building.take().expect("joined once");
                handle
                    .join()
                    .unwrap_or_else(|p| std::panic::resume_unwind(p))
            });
            let (out, ids) = h.mesh_at(k);
            progress.stage("certifying the error bound");
            let traced = certify_traced(original, &out, &ids, earlier, &bound_opts, ask, progress)?;
            Ok(match traced {
                Traced::Certified(certificate, trace) => {
                    let r = Simplified {
                        mesh: out,
                        certificate,
                        collapses: k,
                    };
                    Verdict::Certified((r, *trace))
                }
                Traced::Over(lower) => Verdict::Over(lower),
            })
        };
        let mut history = History::new(EdgeCollapser::new(mesh, collapse_opts));
        for (i, count) in counts {
            let k = history.reach(count, progress)?;
            results[i] = Some(certify(&history, k, None, Ask::Tight)?.certified().0);
        }
        let (mut from, mut certified, mut probed) = (0, None, Vec::new());
        // The finest error row relays the coarser rows' probes (module
        // `relay`): they lie far from every certified state.
        let finest = std::cell::OnceCell::new();
        let mut relay = None;
        let coarser = errors.len().saturating_sub(1);
        for (row, (i, max_error)) in errors.into_iter().enumerate() {
            let search = Search {
                from,
                certified,
                max_error,
                relay: relay.as_ref(),
            };
            let (r, k) = to_error(&mut history, search, &mut probed, progress, &mut certify)?;
            if relay.is_none() && row < coarser {
                let m: &Simplified = finest.get_or_init(|| r.0.clone());
                relay = Relay::new(mesh, &m.mesh, &m.certificate);
            }
            results[i] = Some(r.0.clone());
            (from, certified) = (k, Some(r));
        }
        Ok::<(), SimplifyError>(())
    })?;
    Ok(results
        .into_iter()
        .map(|r| r.expect("every target simplified"))
        .collect())
}

/// Where an error search starts: state `from` of the collapse, with its
/// certificate where a smaller error's search made it (a chain's previous
/// row, within every smaller error), and the finer state that relays its
/// probes (a chain's finest row).
struct Search<'r> {
    from: usize,
    certified: Option<Certified>,
    max_error: f32,
    relay: Option<&'r Relay<'r>>,
}

/// The smallest triangle count whose certified bound is within `max_error`:
/// halve the count while the bound holds, then bisect. Every probe is a state
/// of the one collapse `history` holds, certified from the nearest certified
/// state's trace (`recertify`) and asked only whether it is within
/// `max_error` (`Ask::Within`): a probe that fails stops at the first exact
/// distance over it, one that holds is refined no further than it, so the
/// result is certified again, tight, from its own trace (everything
/// carries: only what is above the tolerance is refined). `probed` holds
/// the (count, bound) of every probe so far (a failed one's: a lower bound of it) and gains this
/// search's: a count below the start that a
/// smaller error's search found over this error starts the bisection without
/// halving (a chain's rows double their errors, and the halving's first
/// probe, far from any certified state, is the dearest). Returns the result
/// and its state, where a coarser error's search may start.
fn to_error(
    history: &mut History,
    search: Search,
    probed: &mut Vec<(usize, f32)>,
    progress: &Progress,
    mut certify: impl FnMut(&History, usize, Option<&Trace>, Ask) -> Result<Verdict, SimplifyError>,
) -> Result<(Certified, usize), SimplifyError> {
    let Search {
        from,
        certified,
        max_error,
        relay,
    } = search;
    let n = history.count(from);
    // The good state's certificate (within `max_error` once `good`; tight
    // until a probe replaces it), and the last failed probe's: either may be
    // the nearer to a probe.
    let (mut known, mut good_k, mut good_n, mut tight) = (certified, from, n, true);
    let mut good = known
        .as_ref()
        .is_some_and(|(r, _)| r.error_bound() <= max_error);
    let mut failed: Option<(usize, Trace)> = None;
    // Halving until a probe fails (or reaches 0), then bisecting from there.
    let known_bad = probed
        .iter()
        .filter(|&&(c, b)| c < n && b > max_error)
        .map(|p| p.0)
        .max();
    let (mut probe, mut bad_n, mut bisecting) = match known_bad {
        Some(bad) => (n / 2, bad, true),
        None => (n / 2, 0usize, false),
    };
    loop {
        if bisecting {
            if good_n <= bad_n + 1 || good_n - bad_n <= good_n / 50 {
                break;
            }
            probe = (good_n + bad_n) / 2;
        } else if probe == 0 {
            bisecting = true;
            continue;
        }
        let k = history.reach(probe, progress)?;
        if k == good_k && good {
            // Nothing more can collapse: every smaller count gives this mesh.
            break;
        }
        let nearer = match (&known, &failed) {
            (_, Some((fk, t))) if fk.abs_diff(k) < good_k.abs_diff(k) => Some(t),
            (Some((_, t)), _) => Some(t),
            _ => failed.as_ref().map(|f| &f.1),
        };
        match certify(history, k, nearer, Ask::Within(max_error, relay))? {
            Verdict::Certified((r, trace)) if r.error_bound() <= max_error => {
                probed.push((probe, r.error_bound()));
                good_n = r.mesh.triangles.len().min(probe);
                (known, good, good_k, tight) = (Some((r, trace)), true, k, false);
                if !bisecting {
                    probe /= 2;
                }
            }
            over => {
                let lower = match over {
                    Verdict::Certified((r, trace)) => {
                        failed = Some((k, trace));
                        r.error_bound()
                    }
                    Verdict::Over(lower) => lower,
                };
                probed.push((probe, lower));
                bad_n = probe;
                bisecting = true;
            }
        }
    }
    let earlier = match known {
        Some(c) if good && tight => return Ok((c, good_k)),
        Some((_, trace)) if good => Some(trace),
        _ => None,
    };
    let tight = certify(history, good_k, earlier.as_ref(), Ask::Tight)?;
    Ok((tight.certified(), good_k))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::builtins::torus;
    use crate::distance::{SamplingOptions, hausdorff_mesh_mesh};

    /// A chain's coarser error rows, relayed through its finest (module
    /// `relay`), meet their errors with certificates that hold against
    /// sampling and are as tight as a fresh certificate of the same mesh
    /// (within its tolerance); the same on one thread as on many.
    #[test]
    fn relayed_error_rows_are_sound_and_tight() {
        let mesh = torus(1.0, 0.35, 96, 40);
        let diag = mesh.bounds().diagonal();
        let errors = [0.002, 0.008, 0.016, 0.032];
        let targets = errors.map(Target::RelativeError);
        let run = || {
            simplify_chain(
                &mesh,
                &targets,
                CollapseOptions::default(),
                false,
                &Progress::new(),
            )
            .unwrap()
        };
        let rows = run();
        let one_thread = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap();
        let again = one_thread.install(run);
        // The finest row's ρ is under half of each coarser error: it relays them.
        assert!(rows[0].certificate.reverse < 0.5 * errors[1] * diag);
        for ((row, e), same) in rows.iter().zip(errors).zip(&again) {
            assert_eq!(
                (&row.mesh, &row.certificate),
                (&same.mesh, &same.certificate)
            );
            let b = row.error_bound();
            assert!(b <= e * diag, "{b} over {e}");
            let fresh = certify(&mesh, &row.mesh, &BoundOptions::for_diagonal(diag)).error_bound();
            // Tighter where a probe refined past the tolerance.
            assert!(b <= 1.05 * fresh, "{e}: {b} vs fresh {fresh}");
            let measured = hausdorff_mesh_mesh(&mesh, &row.mesh, &SamplingOptions::default());
            assert!(measured.two_sided() <= b, "{e}: {b} < {measured:?}");
        }
        assert!(
            rows.windows(2)
                .all(|w| w[0].mesh.triangles.len() > w[1].mesh.triangles.len())
        );
    }

    /// A watched build publishes what it has collapsed so far; an unwatched one
    /// publishes nothing.
    #[test]
    fn watched_builds_publish_intermediate_meshes() {
        let mesh = torus(1.0, 0.3, 64, 32);
        let opts = SimplifyOptions {
            target: Target::Ratio(0.1),
            collapse: CollapseOptions::default(),
            per_triangle_bounds: false,
        };
        let quiet = Progress::new();
        simplify(&mesh, &opts, &quiet).unwrap();
        assert!(quiet.take_preview().is_none());
        let watched = Progress::new();
        watched.watch();
        let done = simplify(&mesh, &opts, &watched).unwrap();
        let state = watched.take_preview().expect("an intermediate mesh");
        let n = state.mesh.triangles.len();
        assert!(
            done.mesh.triangles.len() < n && n < mesh.triangles.len(),
            "{n}"
        );
        assert!(watched.take_preview().is_none(), "taken once");
    }

    /// Cancelling while the bound is being certified stops the build.
    #[test]
    fn cancel_during_certification_stops() {
        let mesh = crate::builtins::icosphere(glam::Vec3::ZERO, 1.0, 6);
        let progress = std::sync::Arc::new(Progress::new());
        let watcher = {
            let p = progress.clone();
            std::thread::spawn(move || {
                while p.stage_name() != "certifying the error bound" {
                    std::thread::sleep(std::time::Duration::from_micros(200));
                }
                p.cancel();
            })
        };
        let opts = SimplifyOptions {
            per_triangle_bounds: false,
            target: Target::Ratio(0.5),
            collapse: CollapseOptions::default(),
        };
        let r = simplify(&mesh, &opts, &progress);
        watcher.join().unwrap();
        assert!(matches!(r, Err(SimplifyError::Cancelled)));
    }

    /// The error search looks its states up along one collapse; what it
    /// returns is what a fresh run to its triangle count makes, with a bound
    /// as tight.
    #[test]
    fn an_error_search_ends_where_a_fresh_run_to_its_count_does() {
        let mesh = crate::builtins::icosphere(glam::Vec3::ZERO, 1.0, 4);
        let run = |target| {
            let opts = SimplifyOptions {
                per_triangle_bounds: false,
                target,
                collapse: CollapseOptions::default(),
            };
            simplify(&mesh, &opts, &Progress::new()).unwrap()
        };
        // 0.5: the search ends where nothing more collapses, far under it
        // (its probes' certificates, asked only about the limit, are not
        // the result's).
        for e in [0.002, 0.02, 0.5] {
            let searched = run(Target::RelativeError(e));
            let fresh = run(Target::Triangles(searched.mesh.triangles.len()));
            assert!(searched.mesh.triangles.len() < mesh.triangles.len() / 4);
            assert_eq!(searched.mesh, fresh.mesh);
            assert_eq!(searched.collapses, fresh.collapses);
            // Its probes are certified from one another (`recertify`): as
            // tight as a fresh certificate, within its relative tolerance.
            let (s, f) = (searched.error_bound(), fresh.error_bound());
            assert!(s <= e * mesh.bounds().diagonal(), "{s}");
            assert!((s - f).abs() <= 0.05 * f.max(s), "{s} vs {f}");
        }
    }

    #[test]
    fn error_target_is_met_with_a_certified_bound() {
        let mesh = torus(1.0, 0.35, 64, 32);
        let opts = SimplifyOptions {
            per_triangle_bounds: false,
            target: Target::RelativeError(0.005),
            collapse: CollapseOptions::default(),
        };
        let r = simplify(&mesh, &opts, &Progress::new()).unwrap();
        let limit = 0.005 * mesh.bounds().diagonal();
        assert!(r.error_bound() <= limit);
        assert!(r.mesh.triangles.len() < mesh.triangles.len() / 2);
        let measured = hausdorff_mesh_mesh(&mesh, &r.mesh, &SamplingOptions::default()).two_sided();
        assert!(measured <= r.error_bound());
        // One step coarser would break the limit, or the search stopped within 2%.
        let bad = SimplifyOptions {
            per_triangle_bounds: false,
            target: Target::Ratio(2.0),
            ..opts
        };
        assert!(matches!(
            simplify(&mesh, &bad, &Progress::new()),
            Err(SimplifyError::BadTarget(_))
        ));
    }
}
