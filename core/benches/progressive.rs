//! Issue 25's figure: moving the edge-collapse slider is incremental. The
//! collapses are recorded once (down to 0.1 % of the triangles, every step
//! with its certified bound); then the slider walks its range in 10 % steps
//! (100 % → 10 % and back), one step a frame, and each step is timed:
//!
//! - incremental: `ProgressiveCut::move_to` (replay / undo the collapses in
//!   between) and `draw_set` (gather the alive triangles into the mesh the
//!   viewport and exports get), separately;
//! - fresh: a new cut from the input replayed to the step, then gathered;
//! - a re-run, as the studio did before: our collapse from the input to the
//!   step's count (uncertified), and meshoptimizer's `simplify` to it (the
//!   `meshopt` crate, dev-dependency) as the peer.
//!
//! Run with `cargo bench -p lodstudio-core --bench progressive` (the dragon
//! at n/4, n/2 and n, reduced by meshopt as in the simplify bench); it
//! prints Markdown tables. BENCHMARKS.md holds a recorded run.

mod common;
#[path = "common/meshopt_peer.rs"]
mod meshopt_peer;

use std::sync::Arc;
use std::time::Instant;

use lodstudio_core::Progress;
use lodstudio_core::simplify::progressive::{ProgressiveCut, record};
use lodstudio_core::simplify::{CollapseOptions, EdgeCollapser};
use meshopt_peer::{meshopt_to, quarters_of};

const DRAGON: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../../shared/models/dragon_vrip.ply.gz"
);

fn ms(t: Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1e3
}

/// Median and maximum.
fn spread(v: &[f64]) -> String {
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    format!("{:.2} / {:.2}", s[s.len() / 2], s[s.len() - 1])
}

fn main() {
    let dragon = common::load_mesh(DRAGON);
    println!("## Progressive edge collapse: the slider in 10 % steps\n");
    println!(
        "| input tris | record to 0.1 % (s) | steps | incremental move ms (median / max) | \
         incremental gather ms | incremental total ms | fresh total ms | \
         re-run ours ms | re-run meshopt ms |"
    );
    println!("|---|---|---|---|---|---|---|---|---|");
    for quarter in [1usize, 2, 4] {
        let input = quarters_of(&dragon, quarter);
        let m = input.triangles.len();
        eprintln!("recording {m} triangles");
        let start = Instant::now();
        let floor = m / 1000;
        let p =
            Arc::new(record(&input, CollapseOptions::default(), floor, &Progress::new()).unwrap());
        let record_s = start.elapsed().as_secs_f64();
        // 100 %, 90 %, ..., 10 %, then back up to 100 %.
        let down = (0..10).map(|i| 1.0 - 0.1 * i as f64);
        let up = (1..10).rev().map(|i| 1.0 - 0.1 * i as f64);
        let steps: Vec<usize> = down
            .chain(up)
            .map(|r| (r * m as f64).round() as usize)
            .collect();
        let mut cut = ProgressiveCut::new(Arc::clone(&p));
        let (mut moves, mut gathers, mut totals, mut fresh) = (vec![], vec![], vec![], vec![]);
        let (mut rerun, mut peer) = (vec![], vec![]);
        for (i, &target) in steps.iter().enumerate() {
            let k = p.prefix_for_triangles(target);
            let t = Instant::now();
            cut.move_to(k);
            let moved = ms(t);
            let g = Instant::now();
            let set = cut.draw_set();
            let (gathered, total) = (ms(g), ms(t));
            assert_eq!(set.mesh.triangles.len(), p.triangles_at(k));
            if i == 0 {
                continue; // the first frame moves nowhere
            }
            moves.push(moved);
            gathers.push(gathered);
            totals.push(total);
            let t = Instant::now();
            let mut new = ProgressiveCut::new(Arc::clone(&p));
            let again = new.select_prefix(k);
            fresh.push(ms(t));
            assert_eq!(again.mesh, set.mesh, "fresh and incremental agree");
            if i < 10 {
                // The re-runs only once per count (down the range).
                let t = Instant::now();
                let mut s = EdgeCollapser::new(&input, CollapseOptions::default());
                s.run(target, |_, _| true);
                let _ = s.mesh();
                rerun.push(ms(t));
                let t = Instant::now();
                let _ = meshopt_to(&input, target);
                peer.push(ms(t));
            }
        }
        println!(
            "| {m} | {record_s:.1} | {} | {} | {} | {} | {} | {} | {} |",
            moves.len(),
            spread(&moves),
            spread(&gathers),
            spread(&totals),
            spread(&fresh),
            spread(&rerun),
            spread(&peer),
        );
    }
}
