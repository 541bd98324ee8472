//! Issue 26's figure: a five-row edge-collapse chain is one progressive
//! collapse (`recipe::build_chain` → `simplify::simplify_chain`), so it
//! costs little more than its finest row alone. For the dragon at n/4, n/2
//! and n (reduced by meshopt as in the other benches), with error rows
//! (certified bounds) and ratio rows:
//!
//! - the chain through `build_chain` (what the studio and `export` run);
//! - its finest row alone (a one-row recipe); both the median of three
//!   alternating runs;
//! - the five rows as five fresh runs one after another (the export before);
//! - the peer: meshoptimizer's `simplify` to the five counts the chain made.
//!
//! A second table says where a chain's time goes (n/4): the collapses and
//! each row's certificate (an O(input) pass over the original), which is
//! why a chain of k rows costs more than one row.
//!
//! Run with `cargo bench -p lodstudio-core --bench chain`; it prints
//! Markdown tables. BENCHMARKS.md holds a recorded run.

mod common;
#[path = "common/meshopt_peer.rs"]
mod meshopt_peer;

use std::time::Instant;

use lodstudio_core::recipe::{Recipe, build_chain, parse_lods};
use lodstudio_core::simplify::{
    BoundOptions, CollapseOptions, EdgeCollapser, Original, certify_against,
};
use lodstudio_core::{Model, Progress, TriMesh};
use meshopt_peer::{meshopt_to, quarters_of};

const DRAGON: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../../shared/models/dragon_vrip.ply.gz"
);

/// Runs of the chain and of its finest row, alternating: this machine's
/// times vary by a quarter from run to run, the median much less.
const RUNS: usize = 3;

fn median(mut runs: Vec<f64>) -> f64 {
    runs.sort_by(f64::total_cmp);
    runs[runs.len() / 2]
}

fn seconds(f: impl FnOnce()) -> f64 {
    let t = Instant::now();
    f();
    t.elapsed().as_secs_f64()
}

/// Where the time of a chain of ratio rows goes: one collapser run on
/// from row to row, each row certified against the original.
fn profile(input: &TriMesh) {
    let m = input.triangles.len();
    println!("\n### Where a chain's time goes ({m} triangles, ratio rows)\n");
    println!("| stage | seconds | certified bound |");
    println!("|---|---|---|");
    let mut collapser = None;
    let new = seconds(|| collapser = Some(EdgeCollapser::new(input, CollapseOptions::default())));
    let mut collapser = collapser.unwrap();
    let mut original = None;
    let search = seconds(|| original = Some(Original::new(input)));
    let original = original.unwrap();
    println!("| collapser set-up (quadrics, queue) | {new:.2} | |");
    println!("| original's search structures | {search:.2} | |");
    let opts = BoundOptions {
        per_triangle: false,
        ..BoundOptions::for_diagonal(input.bounds().diagonal())
    };
    for f in [2, 4, 8, 16, 32] {
        let run = seconds(|| collapser.run(m / f, |_, _| true));
        let (out, _) = collapser.mesh();
        let mut bound = 0.0;
        let certify = seconds(|| {
            bound = certify_against(&original, &out, &opts, &Progress::new())
                .unwrap()
                .error_bound()
        });
        println!("| collapse on to m/{f} | {run:.2} | |");
        println!("| certify m/{f} against the original | {certify:.2} | {bound:.3e} |");
    }
}

fn main() {
    let dragon = common::load_mesh(DRAGON);
    println!("## LOD chains: five edge-collapse rows in one progressive collapse\n");
    println!(
        "| input tris | rows | chain s | finest row alone s | chain / finest | \
         five fresh runs s | meshopt, five counts s | triangles per LOD |"
    );
    println!("|---|---|---|---|---|---|---|---|");
    for quarter in [1usize, 2, 4] {
        let input = quarters_of(&dragon, quarter);
        let m = input.triangles.len();
        let model = Model::Mesh(input.clone());
        for rows in ["0.1%,0.2%,0.4%,0.8%,1.6%", "0.5,0.25,0.125,0.0625,0.03125"] {
            let items = parse_lods(rows, Some(lodstudio_core::lod::Method::EdgeCollapse)).unwrap();
            let recipe = Recipe::new(items.clone());
            eprintln!("{m} triangles, rows {rows}");
            let finest = Recipe::new(items[..1].to_vec());
            let mut chain = None;
            let (mut chain_s, mut finest_s) = (Vec::new(), Vec::new());
            for _ in 0..RUNS {
                chain_s.push(seconds(|| {
                    chain = Some(build_chain(&model, &recipe, &Progress::new()).unwrap())
                }));
                finest_s.push(seconds(|| {
                    build_chain(&model, &finest, &Progress::new()).unwrap();
                }));
            }
            let (chain_s, finest_s) = (median(chain_s), median(finest_s));
            let chain = chain.unwrap();
            let fresh_s: f64 = items
                .iter()
                .map(|row| {
                    let one = Recipe::new(vec![row.clone()]);
                    seconds(|| {
                        build_chain(&model, &one, &Progress::new()).unwrap();
                    })
                })
                .sum();
            let counts: Vec<usize> = chain
                .lods
                .iter()
                .map(|l| l.set.mesh.triangles.len())
                .collect();
            let peer_s = seconds(|| {
                for &c in &counts {
                    let _ = meshopt_to(&input, c);
                }
            });
            println!(
                "| {m} | {rows} | {chain_s:.2} | {finest_s:.2} | {:.2} | {fresh_s:.2} | {peer_s:.2} | {} |",
                chain_s / finest_s,
                counts
                    .iter()
                    .map(usize::to_string)
                    .collect::<Vec<_>>()
                    .join(" / ")
            );
        }
    }
    profile(&quarters_of(&dragon, 1));
}
