//! Issue 26's figure: a five-row edge-collapse chain is one progressive
//! collapse (`recipe::build_chain` → `simplify::simplify_chain`), so it
//! costs little more than its finest row alone. For the dragon at n/4, n/2
//! and n (reduced by meshopt as in the other benches), with error rows
//! (certified bounds) and ratio rows:
//!
//! - the chain through `build_chain` (what the studio and `export` run);
//! - its finest row alone (a one-row recipe);
//! - the five rows as five fresh runs one after another (the export before);
//! - the peer: meshoptimizer's `simplify` to the five counts the chain made.
//!
//! Run with `cargo bench -p lodstudio-core --bench chain`; it prints a
//! Markdown table. BENCHMARKS.md holds a recorded run.

mod common;

use std::time::Instant;

use lodstudio_core::geom::{RepairOptions, repair::repair_mesh};
use lodstudio_core::recipe::{Recipe, build_chain, parse_lods};
use lodstudio_core::{Model, Progress, TriMesh};

const DRAGON: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../../shared/models/dragon_vrip.ply.gz"
);

/// meshoptimizer's simplification of `mesh` to `target` triangles (indices).
fn meshopt_to(mesh: &TriMesh, target: usize) -> Vec<u32> {
    let bytes: Vec<u8> = mesh
        .positions
        .iter()
        .flat_map(|p| p.to_array())
        .flat_map(f32::to_ne_bytes)
        .collect();
    let vertices = meshopt::VertexDataAdapter::new(&bytes, 12, 0).expect("vertex adapter");
    let indices: Vec<u32> = mesh.triangles.iter().flatten().copied().collect();
    meshopt::simplify(
        &indices,
        &vertices,
        3 * target,
        1.0,
        meshopt::SimplifyOptions::None,
        None,
    )
}

fn seconds(f: impl FnOnce()) -> f64 {
    let t = Instant::now();
    f();
    t.elapsed().as_secs_f64()
}

fn main() {
    let dragon = common::load_mesh(DRAGON);
    let n = dragon.triangles.len();
    println!("## LOD chains: five edge-collapse rows in one progressive collapse\n");
    println!(
        "| input tris | rows | chain s | finest row alone s | chain / finest | \
         five fresh runs s | meshopt, five counts s | triangles per LOD |"
    );
    println!("|---|---|---|---|---|---|---|---|");
    for quarter in [1usize, 2, 4] {
        let input = if quarter == 4 {
            dragon.clone()
        } else {
            let reduced = meshopt_to(&dragon, n * quarter / 4);
            let mut mesh = TriMesh::new(dragon.positions.clone(), Vec::new());
            mesh.triangles = reduced
                .chunks_exact(3)
                .map(|t| [t[0], t[1], t[2]])
                .collect();
            repair_mesh(mesh, &RepairOptions::default()).0
        };
        let m = input.triangles.len();
        let model = Model::Mesh(input.clone());
        for rows in ["0.1%,0.2%,0.4%,0.8%,1.6%", "0.5,0.25,0.125,0.0625,0.03125"] {
            let items = parse_lods(rows, Some(lodstudio_core::lod::Method::EdgeCollapse)).unwrap();
            let recipe = Recipe::new(items.clone());
            eprintln!("{m} triangles, rows {rows}");
            let mut chain = None;
            let chain_s =
                seconds(|| chain = Some(build_chain(&model, &recipe, &Progress::new()).unwrap()));
            let chain = chain.unwrap();
            let finest = Recipe::new(items[..1].to_vec());
            let finest_s = seconds(|| {
                build_chain(&model, &finest, &Progress::new()).unwrap();
            });
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
}
