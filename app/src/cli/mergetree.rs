//! `mergetree`: builds the view-dependent merge tree of a mesh and replays a
//! camera path over it, timing the incremental update against a cold start
//! (merge-tree paper Table 1).

use std::sync::Arc;
use std::time::Instant;

use super::*;
use lodstudio_core::mergetree::{Criteria, MergeTreeOptions, MergeTreeView};
use lodstudio_core::view::{Tolerance, View};

#[derive(Args, Debug)]
pub struct MergeTreeArgs {
    /// A mesh file, or builtin:NAME.
    file: PathBuf,
    /// Frames of the camera path.
    #[arg(long, value_name = "F", default_value_t = 100)]
    frames: usize,
    /// Screen-space threshold T in pixels (§5.1).
    #[arg(long, value_name = "P", default_value_t = 1.0)]
    pixels: f32,
    /// Fly in towards the model while orbiting, instead of a fixed-distance orbit.
    #[arg(long)]
    zoom: bool,
    /// Stop building once this few vertices are left (§4.1).
    #[arg(long, value_name = "N", default_value_t = MergeTreeOptions::default().min_vertices)]
    min_vertices: usize,
    /// Sliver guard: minimum quality 4√3·area/Σl² of triangles a merge makes (eq. 3, §6); 0 disables.
    #[arg(long, value_name = "Q", default_value_t = MergeTreeOptions::default().collapse.min_quality)]
    min_quality: f32,
    /// Do not simplify back-facing and off-screen regions harder.
    #[arg(long)]
    no_backface: bool,
    /// Do not refine silhouette regions.
    #[arg(long)]
    no_silhouette: bool,
    /// Do not refine where the shading changes fastest.
    #[arg(long)]
    no_lighting: bool,
    /// Write the last frame's display mesh here (.obj, .ply or .glb).
    #[arg(short = 'o', long = "output", value_name = "OUT")]
    output: Option<PathBuf>,
    #[command(flatten)]
    save: SaveArgs,
    #[command(flatten)]
    report: ReportArgs,
    #[command(flatten)]
    input: InputArgs,
}

/// The camera of frame `i`: an orbit at 2 diagonals, or a spiral flying in
/// from 3 diagonals to 0.75.
fn camera(args: &MergeTreeArgs, center: glam::Vec3, diagonal: f32, i: usize) -> View {
    let s = i as f32 / args.frames.max(1) as f32;
    let distance = if args.zoom {
        diagonal * (3.0 - 2.25 * s)
    } else {
        2.0 * diagonal
    };
    View::orbit(center, distance, s * std::f32::consts::TAU, 0.3)
}

fn mean(v: &[f64]) -> f64 {
    v.iter().sum::<f64>() / v.len().max(1) as f64
}

/// The median, robust to the frames a busy machine preempts.
fn median(v: &[f64]) -> f64 {
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    s.get(s.len() / 2).copied().unwrap_or(0.0)
}

pub fn run(args: MergeTreeArgs) -> Result<(), CliError> {
    if let Some(out) = &args.output {
        check_output(out, args.report.force)?;
    }
    if args.frames == 0 || args.frames > 1_000_000 {
        return Err(CliError::BadInput(format!(
            "--frames must be in 1..=1000000, got {}",
            args.frames
        )));
    }
    if !(args.pixels.is_finite() && args.pixels > 0.0) {
        return Err(CliError::BadInput(format!(
            "--pixels must be a finite number > 0, got {}",
            args.pixels
        )));
    }
    let mut opts = MergeTreeOptions {
        min_vertices: args.min_vertices,
        ..Default::default()
    };
    opts.collapse.min_quality = args.min_quality;
    let params = Params::MergeTree(opts);
    params.validate()?;
    let mesh = load_mesh(&args.file, &args.input)?;
    args.save.check(args.report.force)?;
    let start = Instant::now();
    let built: Box<MergeTreeView> = super::build(&params, &mesh, &args.file)?;
    let tree = Arc::clone(built.tree());
    let build_seconds = start.elapsed().as_secs_f64();
    let criteria = Criteria {
        backface: !args.no_backface,
        silhouette: !args.no_silhouette,
        lighting: !args.no_lighting,
    };
    args.save.write(
        &MergeTreeView::new(tree.clone(), criteria),
        serde_json::json!({"min_vertices": args.min_vertices, "min_quality": args.min_quality, "file": args.file.display().to_string()}),
    )?;
    let bounds = mesh.bounds();
    let (center, diagonal) = (bounds.center(), bounds.diagonal());
    let tolerance = Tolerance::Pixels(args.pixels);
    // Incremental (frame to frame), cold start (every frame from all vertices),
    // and a uniform cut of the same tree with the same screen-space error.
    let mut warm = MergeTreeView::new(tree.clone(), criteria);
    let mut cold = MergeTreeView::new(tree.clone(), criteria);
    let mut uniform = MergeTreeView::new(tree.clone(), criteria);
    let (mut update_ms, mut rebuild_ms) = (Vec::new(), Vec::new());
    let (mut adaptive, mut uniform_tris) = (Vec::new(), Vec::new());
    let (mut folds, mut mismatches, mut differing_frames) = (0usize, 0usize, 0usize);
    let (mut evaluated, mut changes) = (Vec::new(), Vec::new());
    for i in 0..args.frames {
        let view = camera(&args, center, diagonal, i);
        let t = Instant::now();
        let stats = warm.update(&view, tolerance);
        // Frame 0 starts from all vertices: a cold start, not an update.
        if i > 0 {
            update_ms.push(t.elapsed().as_secs_f64() * 1e3);
            evaluated.push(stats.evaluated as f64);
            changes.push((stats.splits + stats.merges) as f64);
        }
        let t = Instant::now();
        cold.reset();
        let cold_stats = cold.update(&view, tolerance);
        rebuild_ms.push(t.elapsed().as_secs_f64() * 1e3);
        mismatches += stats.fan_mismatches + cold_stats.fan_mismatches;
        if (0..tree.merges().len()).any(|k| warm.is_merged(k) != cold.is_merged(k)) {
            differing_frames += 1;
        }
        folds += warm.folds();
        adaptive.push(warm.display_count() as f64);
        // Uniform: one object-space error everywhere, the largest whose
        // projection is within P pixels at the model's nearest point.
        let scale = view.pixels(1.0, center, 0.5 * diagonal);
        uniform.update(&view, Tolerance::Relative(args.pixels / scale / diagonal));
        uniform_tris.push(uniform.display_count() as f64);
    }
    if let Some(out) = &args.output {
        write_cut(out, &warm.draw_set())?;
    }
    let levels = tree.levels();
    let json = serde_json::json!({
        "levels": levels,
        "tree_levels": levels.len(),
        "vertices": mesh.positions.len(),
        "original_triangles": mesh.triangles.len(),
        "uniform_triangles": mean(&uniform_tris),
        "adaptive_triangles_mean": mean(&adaptive),
        "adaptive_triangles_min": adaptive.iter().copied().fold(f64::INFINITY, f64::min),
        "adaptive_triangles_max": adaptive.iter().copied().fold(0.0, f64::max),
        "update_ms_mean": mean(&update_ms),
        "update_nodes_evaluated_mean": mean(&evaluated),
        "update_changes_mean": mean(&changes),
        "rebuild_ms_mean": mean(&rebuild_ms),
        "update_ms_median": median(&update_ms),
        "rebuild_ms_median": median(&rebuild_ms),
        "folds": folds,
        "incremental_equals_cold": differing_frames == 0 && mismatches == 0,
        // Counted frame by frame against a cold start from all vertices.
        "frames_differing_from_cold": differing_frames,
        "fan_mismatches": mismatches,
        "adaptive_triangles": &adaptive,
        "dependencies": tree.dependency_count(),
        "build_seconds": build_seconds,
        "frames": args.frames,
        "pixels": args.pixels,
        "zoom": args.zoom,
    });
    if args.report.json {
        println!("{json}");
    } else {
        println!(
            "{}: {} vertices, {} triangles; merge tree of {} levels ({} -> {} vertices) in {:.2} s",
            args.file.display(),
            mesh.positions.len(),
            mesh.triangles.len(),
            levels.len(),
            levels.first().copied().unwrap_or(0),
            levels.last().copied().unwrap_or(0),
            build_seconds
        );
        println!(
            "{} frames at {} px: adaptive {:.0} triangles (uniform of equal error {:.0}); update {:.3} ms (median {:.3}), from scratch {:.3} ms (median {:.3}); {} folds",
            args.frames,
            args.pixels,
            mean(&adaptive),
            mean(&uniform_tris),
            mean(&update_ms),
            median(&update_ms),
            mean(&rebuild_ms),
            median(&rebuild_ms),
            folds
        );
    }
    // Reported first (the comparison is the check), then failed on.
    if mismatches > 0 || differing_frames > 0 {
        return Err(CliError::Failure(format!(
            "internal error: {mismatches} fan mismatches, {differing_frames} frames where the incremental cut differs from a cold start"
        )));
    }
    Ok(())
}
