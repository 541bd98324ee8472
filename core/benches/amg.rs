//! AMG method cost: decomposition and primitive construction at n, 2n, 4n
//! points (goal: near-linear), each stage of the decomposition on the mug
//! scan (every 4th, every 2nd, every point; `LODSTUDIO_BENCH_MODEL` picks
//! another point set), and Ruge–Stüben setup time on the stiffness
//! matrices given in AMG_MATRICES (MatrixMarket files, comma-separated), to be
//! compared with PyAMG on the same files (scripts/amg_pyamg.sh).

use std::time::Instant;

use lodstudio_core::Progress;
use lodstudio_core::amg::{self, AmgOptions, classifier, coarsening, neighbourhood, stiffness};
use lodstudio_core::builtins::octahedron_points;
use lodstudio_core::geom::PointSet;

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() {
    let opts = AmgOptions::default();
    println!("| points | levels | decomposition s | primitives (level L-5) | primitive s |");
    println!("|---|---|---|---|---|");
    for n in [25_000, 50_000, 100_000] {
        let pts = octahedron_points(n, 1);
        let (mut td, mut tp) = (Vec::new(), Vec::new());
        let mut last = (0, 0);
        for _ in 0..3 {
            let t = Instant::now();
            let ms = amg::decompose(&pts, &opts, &Progress::new()).unwrap();
            td.push(t.elapsed().as_secs_f64());
            let level = ms.default_level();
            let t = Instant::now();
            let p = amg::primitives(&ms, level, 0.02, &Progress::new()).unwrap();
            tp.push(t.elapsed().as_secs_f64());
            last = (ms.levels(), p.splats.len());
        }
        println!(
            "| {n} | {} | {:.3} | {} | {:.3} |",
            last.0,
            median(td),
            last.1,
            median(tp)
        );
    }
    stages(&opts);
    let Ok(files) = std::env::var("AMG_MATRICES") else {
        return;
    };
    println!(
        "\n| matrix | rows | level sizes | RS setup s (median of 5) | level sizes with PyAMG's zero rows |"
    );
    println!("|---|---|---|---|---|");
    for f in files.split(',') {
        let a: sprs::CsMat<f64> = sprs::io::read_matrix_market(f).unwrap().to_csr();
        let mut times = Vec::new();
        let mut sizes = Vec::new();
        for _ in 0..5 {
            let t = Instant::now();
            let c = coarsening::coarsen(a.clone(), &opts.coarsening, &Progress::new()).unwrap();
            times.push(t.elapsed().as_secs_f64());
            sizes = c.level_sizes();
        }
        let zero = coarsening::RugeStuben {
            orphans: coarsening::Orphans::Zero,
            ..opts.coarsening
        };
        let pyamg_like = coarsening::coarsen(a.clone(), &zero, &Progress::new()).unwrap();
        println!(
            "| {f} | {} | {sizes:?} | {:.3} | {:?} |",
            a.rows(),
            median(times),
            pyamg_like.level_sizes()
        );
    }
}

/// Seconds of `f` (best of three) and its last result.
fn best_of_3<T>(mut f: impl FnMut() -> T) -> (f64, T) {
    let mut best = f64::INFINITY;
    let mut out = None;
    for _ in 0..3 {
        let t = Instant::now();
        out = Some(f());
        best = best.min(t.elapsed().as_secs_f64());
    }
    (best, out.expect("three runs"))
}

/// The decomposition's stages (§2.1–2.3) on a scan at n/4, n/2, n points.
fn stages(opts: &AmgOptions) {
    let path = std::env::var("LODSTUDIO_BENCH_MODEL").unwrap_or_else(|_| {
        concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../shared/models/table_scene_mug_stereo_textured.ply"
        )
        .into()
    });
    let loaded = lodstudio_core::io::load(path.as_ref(), &Default::default(), &Progress::new())
        .unwrap_or_else(|e| panic!("cannot load {path}: {e}"));
    let full = amg::point_set(&loaded.model).expect("a point set or a mesh");
    println!(
        "\n## Decomposition stages ({path}, best of 3, {} threads)\n",
        rayon::current_num_threads()
    );
    println!("| points | neighbourhoods s | classifier s | stiffness s | coarsening s | total s |");
    println!("|---|---|---|---|---|---|");
    for step in [4, 2, 1] {
        let pos: Vec<_> = full.positions.iter().step_by(step).copied().collect();
        let points = PointSet {
            positions: pos,
            ..Default::default()
        };
        let p = &points.positions;
        let progress = Progress::new();
        let (tn, nb) = best_of_3(|| neighbourhood::neighbourhoods(p, opts.k, opts.epsilon));
        let (tc, class) = best_of_3(|| classifier::classify(p, &nb));
        let (ts, a) =
            best_of_3(|| stiffness::stiffness(p, &nb, &class, opts.contrast, &progress).unwrap());
        let (tr, _) =
            best_of_3(|| coarsening::coarsen(a.clone(), &opts.coarsening, &progress).unwrap());
        println!(
            "| {} | {tn:.3} | {tc:.3} | {ts:.3} | {tr:.3} | {:.3} |",
            p.len(),
            tn + tc + ts + tr
        );
    }
}
