//! AMG method cost: decomposition and primitive construction at n, 2n, 4n
//! points (goal: near-linear), and Ruge–Stüben setup time on the stiffness
//! matrices given in AMG_MATRICES (MatrixMarket files, comma-separated), to be
//! compared with PyAMG on the same files (scripts/amg_pyamg.sh).

use std::time::Instant;

use lodstudio_core::Progress;
use lodstudio_core::amg::{self, AmgOptions, coarsening};
use lodstudio_core::builtins::octahedron_points;

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
