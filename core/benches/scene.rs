//! Issue 49's figure: an instanced scene costs what its unique meshes cost.
//! The engine (82 nodes, 29 meshes, 67 instances) exported as a scene
//! (`io::scene::read` → `scene::build` → `SceneChains::write`, what
//! `lodstudio export` runs) against:
//!
//! - the same scene with each mesh drawn once (its unique meshes alone);
//! - the same scene with every instance drawn 2× and 4× (cost against
//!   instances: it should not grow, the meshes are simplified once);
//! - the flattened export it replaced (every instance in world space, one
//!   mesh: `io::gltf::read` → `build_chain` → `Chain::glb`);
//! - the peer: meshoptimizer's `simplify` of each unique mesh to the
//!   triangle counts of the scene's LODs.
//!
//! Each the median of three runs. Run with
//! `cargo bench -p lodstudio-core --bench scene`; it prints a Markdown
//! table. BENCHMARKS.md holds a recorded run.

#[path = "common/meshopt_peer.rs"]
#[allow(
    dead_code,
    reason = "the shared peer module's n/4, n/2 reduction is for single meshes"
)]
mod meshopt_peer;

use std::path::PathBuf;
use std::time::Instant;

use lodstudio_core::geom::RepairOptions;
use lodstudio_core::io::gltf_writer::PointsAs;
use lodstudio_core::io::{gltf, scene};
use lodstudio_core::recipe::{Recipe, build_chain, parse_lods};
use lodstudio_core::scene::Layout;
use lodstudio_core::{Model, Progress};

const LODS: &str = "source,simplify:0.5%,simplify:2%,simplify:8%";

fn median(mut runs: Vec<f64>) -> f64 {
    runs.sort_by(f64::total_cmp);
    runs[runs.len() / 2]
}

/// Seconds of three runs of `f`, their median.
fn timed(mut f: impl FnMut()) -> f64 {
    median(
        (0..3)
            .map(|_| {
                let t = Instant::now();
                f();
                t.elapsed().as_secs_f64()
            })
            .collect(),
    )
}

/// Builds and writes `scene`'s chains; the seconds writing took.
fn export(scene: &scene::Scene, recipe: &Recipe) -> f64 {
    let p = Progress::new();
    let chains = lodstudio_core::scene::build(scene, recipe, &[], &RepairOptions::default(), &p)
        .expect("the engine's chains");
    let t = Instant::now();
    let written = chains.write(scene, Layout::MsftLod, PointsAs::Points);
    assert!(!written.is_empty());
    t.elapsed().as_secs_f64()
}

fn main() {
    let path =
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../shared/models/2CylinderEngine.gltf");
    let bytes = std::fs::read(&path).expect("the engine");
    let base = path.parent();
    let recipe = Recipe::new(parse_lods(LODS, None).expect("rows"));
    let engine = scene::read(&bytes, base).expect("the engine reads");
    let instances = |s: &scene::Scene| s.meshes.iter().map(|m| m.instances.len()).sum::<usize>();
    let with_instances = |k: usize| {
        let mut s = engine.clone();
        for m in &mut s.meshes {
            match k {
                1 => m.instances.truncate(1),
                k => {
                    m.instances = m
                        .instances
                        .iter()
                        .cycle()
                        .take(k * m.instances.len())
                        .copied()
                        .collect()
                }
            }
        }
        s
    };
    println!(
        "| export of the engine, `{LODS}` | meshes | instances | seconds | of which writing | vs unique meshes |"
    );
    println!("|---|---|---|---|---|---|");
    let unique = with_instances(1);
    // A warm-up: the first build of a process pays for its page faults.
    export(&unique, &recipe);
    let mut writing = 0.0;
    let t_unique = timed(|| writing = export(&unique, &recipe));
    let row = |what: &str, s: &scene::Scene, t: f64, w: f64| {
        println!(
            "| {what} | {} | {} | {t:.2} | {w:.3} | {:.2}× |",
            s.meshes.len(),
            instances(s),
            t / t_unique
        );
    };
    row(
        "unique meshes alone (each drawn once)",
        &unique,
        t_unique,
        writing,
    );
    let t_read = timed(|| {
        scene::read(&bytes, base).expect("reads");
    });
    let t_scene = timed(|| {
        let s = scene::read(&bytes, base).expect("reads");
        writing = export(&s, &recipe);
    });
    row(
        "the engine as a scene (read + build + write)",
        &engine,
        t_scene,
        writing,
    );
    for k in [2, 4] {
        let s = with_instances(k);
        let t = timed(|| writing = export(&s, &recipe));
        row(&format!("every instance drawn {k}×"), &s, t, writing);
    }
    let t_flat = timed(|| {
        let (mesh, _) = gltf::read(&bytes, base).expect("reads");
        let (mesh, _) = lodstudio_core::geom::repair::repair_mesh(mesh, &RepairOptions::default());
        let chain = build_chain(&Model::Mesh(mesh), &recipe, &Progress::new()).expect("chain");
        chain.glb();
    });
    println!(
        "| flattened (the export before: {} instances baked into one mesh) | 1 | {} | {t_flat:.2} | — | {:.2}× |",
        instances(&engine),
        instances(&engine),
        t_flat / t_unique
    );
    // The peer on the unique meshes, to the counts the scene's LODs have.
    let chains = lodstudio_core::scene::build(
        &unique,
        &recipe,
        &[],
        &RepairOptions::default(),
        &Progress::new(),
    )
    .expect("chains");
    let t_peer = timed(|| {
        for (m, chain) in unique.meshes.iter().zip(&chains.chains) {
            for l in &chain.lods[1..] {
                meshopt_peer::meshopt_to(&m.mesh, l.set.mesh.triangles.len());
            }
        }
    });
    println!(
        "| peer: meshoptimizer `simplify` of the unique meshes to the same counts (no bound, no writing) | {} | — | {t_peer:.3} | — | {:.2}× |",
        unique.meshes.len(),
        t_peer / t_unique
    );
    println!();
    println!("Reading the engine as a scene alone: {t_read:.3} s.");
}
