//! Benchmark of issue 5 (merge-tree paper Table 1): per-frame incremental
//! update of the display vertices and triangles against a selection from
//! scratch (all vertices, as the paper's frame 0), display triangles against a
//! uniform cut of equal screen-space error, and how build and selection grow
//! with the input size (tori of n, 2n, 4n vertices).
//!
//! Run with `cargo bench -p lodstudio-core --bench mergetree`; it prints
//! Markdown tables on stdout. `LODSTUDIO_SHARED_MODELS` overrides the models'
//! folder (default `../shared/models` beside the checkout);
//! `LODSTUDIO_BENCH_FRAMES` (default 200) sets the orbit's length; arguments
//! pick models by name (`-- bunny horse`; the tori run when none is given).
//!
//! Timed per frame: "update" = `MergeTreeView::update` from the previous
//! frame's cut; "scratch" = `reset` + `update` (every vertex and triangle back,
//! then the same walk). Both produce the same cut (checked). Single-threaded;
//! medians over the frames, since a shared machine preempts some of them.

mod common;

use std::path::PathBuf;
use std::sync::Arc;
use std::time::Instant;

use lodstudio_core::builtins::torus;
use lodstudio_core::mergetree::{self, Criteria, MergeTree, MergeTreeOptions, MergeTreeView};
use lodstudio_core::view::{Tolerance, View};
use lodstudio_core::{Progress, TriMesh};

fn models_dir() -> PathBuf {
    std::env::var_os("LODSTUDIO_SHARED_MODELS")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../shared/models"))
}

struct Replay {
    adaptive: f64,
    uniform: f64,
    /// Medians over the frames (robust to a busy machine's preemptions).
    update_ms: f64,
    scratch_ms: f64,
    evaluated: f64,
    changes: f64,
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v.get(v.len() / 2).copied().unwrap_or(0.0)
}

/// An orbit at 2 diagonals (1024×768, 60° field of view, light from the eye).
fn replay(tree: &Arc<MergeTree>, criteria: Criteria, pixels: f32, frames: usize) -> Replay {
    let b = tree.mesh().bounds();
    let (center, diagonal) = (b.center(), b.diagonal());
    let mut warm = MergeTreeView::new(tree.clone(), criteria);
    let mut cold = MergeTreeView::new(tree.clone(), criteria);
    let mut uniform = MergeTreeView::new(tree.clone(), criteria);
    let mut r = Replay {
        adaptive: 0.0,
        uniform: 0.0,
        update_ms: 0.0,
        scratch_ms: 0.0,
        evaluated: 0.0,
        changes: 0.0,
    };
    let tolerance = Tolerance::Pixels(pixels);
    let (mut updates, mut scratches) = (Vec::new(), Vec::new());
    for i in 0..=frames {
        let a = i as f32 / frames as f32 * std::f32::consts::TAU;
        let view = View::orbit(center, 2.0 * diagonal, a, 0.3);
        let t = Instant::now();
        let stats = warm.update(&view, tolerance);
        let update = t.elapsed().as_secs_f64() * 1e3;
        let t = Instant::now();
        cold.reset();
        cold.update(&view, tolerance);
        let scratch = t.elapsed().as_secs_f64() * 1e3;
        assert!(
            warm.display_triangles().eq(cold.display_triangles()),
            "frame {i}: cuts differ"
        );
        let scale = view.pixels(1.0, center, 0.5 * diagonal);
        uniform.update(&view, Tolerance::Relative(pixels / scale / diagonal));
        if i == 0 {
            continue; // frame 0 is itself a start from all vertices
        }
        updates.push(update);
        scratches.push(scratch);
        r.evaluated += stats.evaluated as f64;
        r.changes += (stats.splits + stats.merges) as f64;
        r.adaptive += warm.display_count() as f64;
        r.uniform += uniform.display_count() as f64;
    }
    let f = frames as f64;
    Replay {
        adaptive: r.adaptive / f,
        uniform: r.uniform / f,
        update_ms: median(updates),
        scratch_ms: median(scratches),
        evaluated: r.evaluated / f,
        changes: r.changes / f,
    }
}

fn build(mesh: &TriMesh) -> (Arc<MergeTree>, f64) {
    let t = Instant::now();
    let tree = mergetree::build(mesh, &MergeTreeOptions::default(), &Progress::new()).unwrap();
    (Arc::new(tree), t.elapsed().as_secs_f64())
}

fn main() {
    // `cargo bench` passes `--bench`; a filter argument picks models by name.
    let filter: Vec<String> = std::env::args()
        .skip(1)
        .filter(|a| !a.starts_with('-'))
        .collect();
    let frames: usize = std::env::var("LODSTUDIO_BENCH_FRAMES")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(200);
    let screen_only = Criteria {
        backface: true,
        silhouette: false,
        lighting: false,
    };
    println!("### Table 1: {frames}-frame orbit at 2 diagonals, 1024×768\n");
    println!(
        "| model | vertices | triangles | levels | build s | criteria | T px | uniform tris | adaptive tris | update ms | scratch ms | scratch/update | nodes evaluated | splits+merges |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|");
    for (name, file) in [
        ("bunny", "stanford-bunny.obj"),
        ("horse", "horse.ply"),
        ("dragon", "dragon_vrip.ply.gz"),
    ] {
        if !filter.is_empty() && !filter.iter().any(|f| name.contains(f.as_str())) {
            continue;
        }
        let mesh = common::load_mesh(models_dir().join(file));
        let (tree, secs) = build(&mesh);
        for (label, criteria) in [
            ("all", Criteria::default()),
            ("screen+backface", screen_only),
        ] {
            for pixels in [8.0, 32.0] {
                let r = replay(&tree, criteria, pixels, frames);
                println!(
                    "| {name} | {} | {} | {} | {secs:.2} | {label} | {pixels} | {:.0} | {:.0} | {:.3} | {:.2} | {:.1} | {:.0} | {:.0} |",
                    mesh.positions.len(),
                    mesh.triangles.len(),
                    tree.levels().len(),
                    r.uniform,
                    r.adaptive,
                    r.update_ms,
                    r.scratch_ms,
                    r.scratch_ms / r.update_ms,
                    r.evaluated,
                    r.changes
                );
            }
        }
        println!("\n{name} vertices per level: {:?}\n", tree.levels());
    }
    if !filter.is_empty() {
        return;
    }
    println!("### Scaling: tori of n, 2n, 4n vertices, T = 8 px, all criteria\n");
    println!("| vertices | levels | build s | update ms | scratch ms | scratch/update |");
    println!("|---|---|---|---|---|---|");
    for (major, minor) in [(200, 100), (283, 141), (400, 200)] {
        let mesh = torus(1.0, 0.3, major, minor);
        let (tree, secs) = build(&mesh);
        let r = replay(&tree, Criteria::default(), 8.0, frames);
        println!(
            "| {} | {} | {secs:.2} | {:.3} | {:.2} | {:.1} |",
            mesh.positions.len(),
            tree.levels().len(),
            r.update_ms,
            r.scratch_ms,
            r.scratch_ms / r.update_ms
        );
    }
}
