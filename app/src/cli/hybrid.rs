//! `hybrid`: the multi-resolution graph of triangles and points (hybrid paper).

use super::*;
use lodstudio_core::hybrid::{HybridCut, HybridOptions, Mrg, NodeKind, curve};
use lodstudio_core::lod::Hierarchy;
use lodstudio_core::view::{Tolerance, View};
use std::sync::Arc;

#[derive(Args, Debug)]
pub struct HybridArgs {
    /// A mesh file, or builtin:NAME.
    file: PathBuf,
    /// Performance ratio κ of points to triangles (κ ≤ 1: no points).
    #[arg(long, value_name = "K", default_value_t = HybridOptions::default().kappa)]
    kappa: f32,
    /// Transition factor τ (> 0; larger introduces points sooner).
    #[arg(long, value_name = "T", default_value_t = HybridOptions::default().tau)]
    tau: f32,
    /// Write the primitives-versus-error curves (hybrid and triangle-only) as CSV.
    #[arg(long, value_name = "CSV")]
    curve: Option<PathBuf>,
    /// Take the cut at this error: a distance, or a percentage of the diagonal ("1%").
    #[arg(long, value_name = "E", requires = "output")]
    cut_error: Option<String>,
    /// Cut output: triangles to OUT, points to OUT with extension .points.ply
    /// (and both in OUT when it is .glb).
    #[arg(
        short = 'o',
        long = "output",
        value_name = "OUT",
        requires = "cut_error"
    )]
    output: Option<PathBuf>,
    #[command(flatten)]
    save: SaveArgs,
    #[command(flatten)]
    report: ReportArgs,
    #[command(flatten)]
    input: InputArgs,
}

/// Builds the MRG of `file`'s mesh through `lod::build`.
pub fn build(
    mesh: &lodstudio_core::TriMesh,
    opts: &HybridOptions,
    file: &std::path::Path,
) -> Result<Arc<Mrg>, CliError> {
    let cut: Box<HybridCut> = super::build(&Params::Hybrid(*opts), mesh, file)?;
    Ok(Arc::clone(cut.mrg()))
}

pub fn run(args: HybridArgs) -> Result<(), CliError> {
    let opts = HybridOptions {
        kappa: args.kappa,
        tau: args.tau,
        ..Default::default()
    };
    opts.validate()?;
    let tolerance = args
        .cut_error
        .as_deref()
        .map(super::simplify::parse_error_target)
        .transpose()?;
    for out in [
        args.curve.clone(),
        args.output.clone(),
        args.output.as_deref().map(io::cut_writer::points_path),
    ]
    .into_iter()
    .flatten()
    {
        check_output(&out, args.report.force)?;
    }
    args.save.check(args.report.force)?;
    let mesh = load_mesh(&args.file, &args.input)?;
    // The triangle-only twin first, kept as its curve alone: the two graphs
    // are never in memory together (the dragon's peak: 2.06 GB -> see
    // BENCHMARKS.md).
    let triangle_curve = curve::curve(build(&mesh, &opts.triangles_only(), &args.file)?.as_ref());
    let start = std::time::Instant::now();
    let mrg = build(&mesh, &opts, &args.file)?;
    args.save.write(
        &HybridCut::new(Arc::clone(&mrg)),
        serde_json::json!({"kappa": args.kappa, "tau": args.tau, "file": args.file.display().to_string()}),
    )?;
    let seconds = start.elapsed().as_secs_f64();
    let input = mesh.triangles.len() as f64;
    let hybrid_curve = curve::curve(&mrg);
    if let Some(path) = &args.curve {
        let mut csv = String::from("curve,error,primitives\n");
        for (name, c) in [("hybrid", &hybrid_curve), ("triangles", &triangle_curve)] {
            for p in c {
                csv.push_str(&format!("{name},{},{}\n", p.0, p.1));
            }
        }
        write_output(path, csv.as_bytes())?;
    }
    let diag = mrg.diagonal;
    let cut = match (tolerance, &args.output) {
        (Some(t), Some(out)) => {
            let fraction = match t {
                Target::Error(e) => e / diag.max(f32::MIN_POSITIVE),
                Target::RelativeError(f) => f,
                _ => unreachable!("parse_error_target gives errors"),
            };
            let mut cut = HybridCut::new(Arc::clone(&mrg));
            let view = View::orbit(mesh.bounds().center(), diag, 0.0, 0.0);
            let set = cut.select(&view, Tolerance::Relative(fraction));
            write_cut(out, &set)?;
            Some((set, fraction))
        }
        _ => None,
    };
    let mrg_points = mrg.points.len();
    let mrg_triangles = mrg.triangles.len();
    if args.report.json {
        let mut json = serde_json::json!({
            "nodes": mrg.nodes.len(),
            "triangles": mrg_triangles,
            "points": mrg_points,
            "node_kinds": {
                "triangle_simplification": mrg.count(NodeKind::TriangleSimplification),
                "point_replacement": mrg.count(NodeKind::PointReplacement),
                "point_simplification": mrg.count(NodeKind::PointSimplification),
            },
            "input_triangles": mesh.triangles.len(),
            "bbox_diagonal": diag,
            "curve": curve::thin(&hybrid_curve, 200),
            "triangle_curve": curve::thin(&triangle_curve, 200),
            "worst_ratio_to_triangle_curve": curve::worst_ratio(&hybrid_curve, &triangle_curve, input),
            "seconds": seconds,
        });
        if let Some((set, fraction)) = &cut {
            json["cut"] = serde_json::json!({
                "tolerance_relative": fraction,
                "triangles": set.mesh.triangles.len(),
                "points": set.points.len(),
                "error_bound": set.error_bound,
                "error_bound_relative": set.error_bound / diag,
            });
        }
        println!("{json}");
    } else {
        println!(
            "{}: MRG of {} nodes ({} edge collapses, {} point replacements, {} point merges), {} triangles and {} points, {:.2} s",
            args.file.display(),
            mrg.nodes.len(),
            mrg.count(NodeKind::TriangleSimplification),
            mrg.count(NodeKind::PointReplacement),
            mrg.count(NodeKind::PointSimplification),
            mrg_triangles,
            mrg_points,
            seconds
        );
        if let Some((set, _)) = &cut {
            println!(
                "cut: {} triangles and {} points, error bound {:.6} ({:.4}% of the diagonal)",
                set.mesh.triangles.len(),
                set.points.len(),
                set.error_bound,
                100.0 * set.error_bound / diag
            );
        }
    }
    Ok(())
}
