//! Benchmark of issue 3: our edge collapse (with and without its certified
//! two-sided Hausdorff bound) against meshoptimizer's `simplify` (the `meshopt`
//! crate, a dev-dependency only), and how our time grows with the input size.
//!
//! Run with `cargo bench -p lodstudio-core --bench simplify`; it prints
//! Markdown tables on stdout (progress goes to stderr). BENCHMARKS.md at the
//! repository root holds a recorded run.
//!
//! Environment:
//! - `LODSTUDIO_BENCH_REPS=N` (default 1): time each simplification N times
//!   and report the fastest (the meshes and errors are the same every time).
//! - `LODSTUDIO_BENCH_SAMPLES=N` (default 1,000,000): area samples per surface
//!   for the measured Hausdorff distance.
//!
//! How the comparison is made, per model and ratio:
//! 1. meshopt runs first with `target_index_count = 3 × round(ratio × n)`, a
//!    target error of 1.0 (relative, so the count decides) and default options
//!    (`SimplifyOptions::None`: borders not locked);
//! 2. ours runs to exactly meshopt's achieved triangle count, so both results
//!    are compared at (nearly) equal counts; both counts are printed;
//! 3. both results are measured against the input with the same sampled
//!    two-sided Hausdorff (same samples count and seed).
//!
//! Timed: meshopt = the `meshopt::simplify` call only (its index buffer is
//! built before, its output compacted after, both untimed). Ours "collapse" =
//! `EdgeCollapser::new` + `run` + `mesh()` (a compacted `TriMesh`); ours
//! "certify" = `simplify::certify`. The collapse and meshopt are
//! single-threaded; `certify` uses rayon on all cores (its single-threaded time
//! is also given in the scaling table).
//!
//! Also: `simplify::simplify` to an error target (0.5% of the diagonal), the
//! whole search, against one run to the count it finds (both certified).

mod common;

use std::time::Instant;

use lodstudio_core::distance::{SamplingOptions, hausdorff_mesh_mesh};
use lodstudio_core::geom::{RepairOptions, repair::repair_mesh};
use lodstudio_core::simplify::{
    self, BoundOptions, Certificate, CollapseOptions, EdgeCollapser, Simplified, SimplifyOptions,
    Target, certify,
};
use lodstudio_core::{Progress, TriMesh};

const MODELS: [(&str, &str); 3] = [
    (
        "dragon",
        concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../shared/models/dragon_vrip.ply.gz"
        ),
    ),
    (
        "horse",
        concat!(env!("CARGO_MANIFEST_DIR"), "/../../shared/models/horse.ply"),
    ),
    (
        "bunny",
        concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../shared/models/stanford-bunny.obj"
        ),
    ),
];

const RATIOS: [f64; 2] = [0.10, 0.01];

fn env_usize(name: &str, default: usize) -> usize {
    std::env::var(name)
        .ok()
        .and_then(|s| s.replace([',', '_'], "").parse().ok())
        .unwrap_or(default)
        .max(1)
}

/// Runs `f` `reps` times; the fastest time (seconds) and the last result.
fn timed<T>(reps: usize, mut f: impl FnMut() -> T) -> (f64, T) {
    let mut best = f64::INFINITY;
    let mut out = None;
    for _ in 0..reps {
        let start = Instant::now();
        let r = f();
        best = best.min(start.elapsed().as_secs_f64());
        out = Some(r);
    }
    (best, out.expect("reps >= 1"))
}

/// meshoptimizer's result, compacted to the vertices it uses.
struct Meshopt {
    mesh: TriMesh,
    seconds: f64,
    /// Its own error estimate, relative to its scale (the largest box extent).
    error_relative: f32,
    scale: f32,
}

fn meshopt_simplify(mesh: &TriMesh, target_triangles: usize, reps: usize) -> Meshopt {
    let flat: Vec<f32> = mesh.positions.iter().flat_map(|p| p.to_array()).collect();
    let bytes: Vec<u8> = flat.iter().flat_map(|x| x.to_ne_bytes()).collect();
    let vertices = meshopt::VertexDataAdapter::new(&bytes, 12, 0).expect("vertex adapter");
    let indices: Vec<u32> = mesh.triangles.iter().flatten().copied().collect();
    let mut error = 0f32;
    let (seconds, out) = timed(reps, || {
        meshopt::simplify(
            &indices,
            &vertices,
            3 * target_triangles,
            1.0,
            meshopt::SimplifyOptions::None,
            Some(&mut error),
        )
    });
    let scale = meshopt::simplify_scale(&vertices);
    let mut remap = vec![u32::MAX; mesh.positions.len()];
    let mut positions = Vec::new();
    let triangles = out
        .chunks_exact(3)
        .map(|t| {
            [t[0], t[1], t[2]].map(|v| {
                if remap[v as usize] == u32::MAX {
                    remap[v as usize] = positions.len() as u32;
                    positions.push(mesh.positions[v as usize]);
                }
                remap[v as usize]
            })
        })
        .collect();
    Meshopt {
        mesh: TriMesh::new(positions, triangles),
        seconds,
        error_relative: error,
        scale,
    }
}

/// Our collapse to at most `target` triangles: the result and the seconds.
fn ours_collapse(mesh: &TriMesh, target: usize, reps: usize) -> (f64, TriMesh) {
    timed(reps, || {
        let mut s = EdgeCollapser::new(mesh, CollapseOptions::default());
        s.run(target, |_, _| true);
        s.mesh().0
    })
}

fn ours_certify(original: &TriMesh, simplified: &TriMesh, reps: usize) -> (f64, Certificate) {
    let opts = BoundOptions::for_diagonal(original.bounds().diagonal());
    timed(reps, || certify(original, simplified, &opts))
}

/// `simplify::simplify` as the CLI runs it, certificate included.
fn simplify_to(mesh: &TriMesh, target: Target) -> Simplified {
    let opts = SimplifyOptions {
        target,
        collapse: CollapseOptions::default(),
        per_triangle_bounds: false,
    };
    simplify::simplify(mesh, &opts, &Progress::new()).expect("a valid target")
}

fn measure(original: &TriMesh, simplified: &TriMesh, samples: usize) -> f32 {
    let opts = SamplingOptions { samples, seed: 7 };
    hausdorff_mesh_mesh(original, simplified, &opts).two_sided()
}

fn pct(x: f32, diag: f32) -> String {
    format!("{:.4}%", 100.0 * x / diag)
}

fn main() {
    // `cargo bench` passes `--bench`; a filter argument picks models by name.
    let filter: Vec<String> = std::env::args()
        .skip(1)
        .filter(|a| !a.starts_with('-'))
        .collect();
    let reps = env_usize("LODSTUDIO_BENCH_REPS", 1);
    let samples = env_usize("LODSTUDIO_BENCH_SAMPLES", 1_000_000);
    let threads = rayon::current_num_threads();
    println!(
        "lodstudio simplify benchmark: meshopt crate 0.7.0 (meshoptimizer 1.3), \
         {threads} rayon threads, best of {reps} run(s) per timing, \
         {samples} area samples per surface for the measured Hausdorff\n"
    );

    let mut loaded = Vec::new();
    let (mut time_rows, mut error_rows) = (Vec::new(), Vec::new());
    for (name, path) in MODELS {
        if !filter.is_empty() && !filter.iter().any(|f| name.contains(f.as_str())) {
            continue;
        }
        eprintln!("loading {name}");
        let mesh = common::load_mesh(path);
        let n = mesh.triangles.len();
        let diag = mesh.bounds().diagonal();
        for ratio in RATIOS {
            let target = (ratio * n as f64).round() as usize;
            let label = format!("| {name} | {:.0}% |", ratio * 100.0);
            eprintln!("{label} meshopt");
            let mo = meshopt_simplify(&mesh, target, reps);
            let mo_tris = mo.mesh.triangles.len();
            eprintln!("{label} ours");
            let (t_collapse, ours) = ours_collapse(&mesh, mo_tris, reps);
            let (t_certify, cert) = ours_certify(&mesh, &ours, reps);
            eprintln!("{label} measuring");
            let h_ours = measure(&mesh, &ours, samples);
            let h_mo = measure(&mesh, &mo.mesh, samples);
            let bound = cert.error_bound();
            assert!(
                h_ours <= bound,
                "{name}: measured {h_ours} above the certified bound {bound}"
            );
            let t_both = t_collapse + t_certify;
            let mo_err = mo.error_relative * mo.scale;
            time_rows.push(format!(
                "{label} {n} | {mo_tris} | {} | {t_collapse:.3} | {t_certify:.3} | {t_both:.3} | \
                 {:.3} | {:.1}× | {:.1}× | {:.1}× |",
                ours.triangles.len(),
                mo.seconds,
                t_collapse / mo.seconds,
                t_certify / mo.seconds,
                t_both / mo.seconds,
            ));
            error_rows.push(format!(
                "{label} {} / {mo_tris} | {h_ours:.3e} ({}) | {h_mo:.3e} ({}) | {:.2} | \
                 {bound:.3e} ({}) | {mo_err:.3e} ({}) |",
                ours.triangles.len(),
                pct(h_ours, diag),
                pct(h_mo, diag),
                h_ours / h_mo,
                pct(bound, diag),
                pct(mo_err, diag),
            ));
            eprintln!("{}", time_rows.last().expect("a row"));
            eprintln!("{}", error_rows.last().expect("a row"));
        }
        loaded.push((name, mesh));
    }
    println!("## Time, ours against meshoptimizer at equal triangle counts\n");
    println!(
        "| model | ratio | tris in | tris out meshopt | tris out ours | ours collapse (s) | \
         ours certify (s) | ours collapse+certify (s) | meshopt (s) | \
         collapse / meshopt | certify / meshopt | (collapse+certify) / meshopt |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|---|---|");
    for r in &time_rows {
        println!("{r}");
    }
    println!("\n## Error at equal triangle counts (absolute, and % of the bbox diagonal)\n");
    println!(
        "| model | ratio | tris out ours / meshopt | measured Hausdorff, ours | \
         measured Hausdorff, meshopt | ours / meshopt | our certified bound | \
         meshopt's reported error |"
    );
    println!("|---|---|---|---|---|---|---|---|");
    for r in &error_rows {
        println!("{r}");
    }
    println!();

    // The error target: the run under its limit (every collapse's bound
    // checked, those over it skipped) with its certificate, against an
    // unlimited run to the count it finds, with its certificate.
    println!("## Error target: the limited run against an unlimited run to its count\n");
    println!(
        "| model | target (% of diagonal) | tris out | certified bound | limited run (s) | \
         one run + certificate (s) | limited / one run |"
    );
    println!("|---|---|---|---|---|---|---|");
    for (name, mesh) in &loaded {
        let tolerance = 0.005;
        eprintln!("error target: {name}");
        let (t_search, found) = timed(reps, || simplify_to(mesh, Target::RelativeError(tolerance)));
        let tris = found.mesh.triangles.len();
        let (t_one, _) = timed(reps, || simplify_to(mesh, Target::Triangles(tris)));
        println!(
            "| {name} | {:.1}% | {tris} | {} | {t_search:.3} | {t_one:.3} | {:.1}× |",
            100.0 * tolerance,
            pct(found.error_bound(), mesh.bounds().diagonal()),
            t_search / t_one,
        );
    }
    println!();

    let Some((_, dragon)) = loaded.into_iter().find(|(name, _)| *name == "dragon") else {
        return;
    };
    // Scaling: the dragon at n/4, n/2 (reduced by meshopt, then repaired as a
    // loaded model would be) and n, each simplified by us to 10%.
    println!("## Scaling: ours on the dragon at n/4, n/2, n triangles, each to 10%\n");
    println!(
        "| input tris | output tris | collapse (s) | collapse s / M tris in | \
         certify, {threads} threads (s) | certify s / M tris in | \
         certify, 1 thread (s) | collapse+certify s / M tris in |"
    );
    println!("|---|---|---|---|---|---|---|---|");
    let n = dragon.triangles.len();
    let one_thread = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("a one-thread pool");
    for quarter in [1usize, 2, 4] {
        let input = if quarter == 4 {
            dragon.clone()
        } else {
            let reduced = meshopt_simplify(&dragon, n * quarter / 4, 1).mesh;
            repair_mesh(reduced, &RepairOptions::default()).0
        };
        let m = input.triangles.len();
        let target = (0.1 * m as f64).round() as usize;
        eprintln!("scaling: {m} triangles");
        let (t_collapse, out) = ours_collapse(&input, target, reps);
        let (t_certify, _) = ours_certify(&input, &out, reps);
        let (t_certify_1, _) = one_thread.install(|| ours_certify(&input, &out, reps));
        let mtris = m as f64 / 1e6;
        println!(
            "| {m} | {} | {t_collapse:.3} | {:.3} | {t_certify:.3} | {:.3} | {t_certify_1:.3} | {:.3} |",
            out.triangles.len(),
            t_collapse / mtris,
            t_certify / mtris,
            (t_collapse + t_certify) / mtris,
        );
    }
}
