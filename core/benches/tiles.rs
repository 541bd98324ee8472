//! Benchmark of issue 47 (3D Tiles): `tiles::build` on the dragon at n/4,
//! n/2 and n (meshoptimizer reduces it beforehand, untimed) against
//! meshoptimizer simplifying the very same parents in the same run: each
//! parent's children welded (`tiles::hlod::union`, untimed), to half,
//! borders locked (`LockBorder`). Ours includes writing each tile to its
//! work folder (a temporary folder). One thread each (rayon's pool is one
//! thread, one tile worker), so the ratio is per thread.
//!
//! Run with `cargo bench -p lodstudio-core --bench tiles`; it prints a
//! Markdown table. `LODSTUDIO_BENCH_MODEL=PATH` replaces the dragon.

mod common;
#[path = "common/meshopt_peer.rs"]
mod meshopt_peer;

use std::time::Instant;

use lodstudio_core::Progress;
use lodstudio_core::tiles::{self, Store, hlod::union};
use meshopt_peer::{meshopt_with, quarters_of};

/// Leaf tiles of this many triangles at most (the CLI's default).
const TILE_TRIANGLES: usize = 65_536;

fn main() {
    rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build_global()
        .expect("the bench's pool is the first");
    let path = std::env::var("LODSTUDIO_BENCH_MODEL").unwrap_or_else(|_| {
        concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../shared/models/dragon_vrip.ply.gz"
        )
        .into()
    });
    let full = common::load_mesh(&path);
    println!("## 3D Tiles against meshoptimizer on the same parents ({path}, one thread)\n");
    println!(
        "| input triangles | tiles | levels | ours: tiles::build s | triangles/s | meshopt on the same parents s | ours / meshopt | root triangles (ours) |"
    );
    println!("|---:|---:|---:|---:|---:|---:|---:|---:|");
    for quarters in [1, 2, 4] {
        let mesh = quarters_of(&full, quarters);
        let dir = tempfile::tempdir().expect("a scratch folder");
        let store = Store::open(dir.path()).expect("a work folder");
        let start = Instant::now();
        let plan = tiles::build(&store, &mesh, TILE_TRIANGLES, 1, &Progress::new()).unwrap();
        let ours = start.elapsed().as_secs_f64();
        let mut peer = 0.0;
        for kids in plan.children.iter().filter(|k| !k.is_empty()) {
            let [a, b] = [kids[0], kids[1]].map(|k| store.mesh(k).expect("a made tile"));
            let joined = union(&a, &b);
            let start = Instant::now();
            let out = meshopt_with(
                &joined,
                joined.triangles.len() / 2,
                meshopt::SimplifyOptions::LockBorder,
            );
            peer += start.elapsed().as_secs_f64();
            std::hint::black_box(out);
        }
        let n = mesh.triangles.len();
        println!(
            "| {n} | {} | {} | {ours:.2} | {:.0} | {peer:.2} | {:.1}× | {} |",
            plan.children.len(),
            plan.levels(),
            n as f64 / ours,
            ours / peer.max(1e-9),
            store.made(0).expect("the root").triangles
        );
    }
}
