//! `cut`: reopen a saved hierarchy and write its cut, without rebuilding.

use super::*;
use lodstudio_core::lod::select_triangles;
use lodstudio_core::view::{Tolerance, View};

#[derive(Args, Debug)]
pub struct CutArgs {
    /// A saved hierarchy (.lodh) from `simplify`, `hybrid`, `mergetree` or
    /// `voxel --pyramid` with --save.
    file: PathBuf,
    /// Object-space error of the cut: a distance, or a percentage of the
    /// bounding-box diagonal ("1%").
    #[arg(
        long,
        value_name = "E",
        default_value = "1%",
        conflicts_with = "triangles"
    )]
    error: String,
    /// The finest cut with at most N triangles instead (a saved edge collapse:
    /// exactly what `simplify FILE --triangles N` makes).
    #[arg(long, value_name = "N")]
    triangles: Option<usize>,
    /// Voxel pyramids: extract this continuous position (0 = finest, §5)
    /// instead of the coarsest level within the error.
    #[arg(long, value_name = "T")]
    at: Option<f32>,
    /// The cut as glTF (.glb: triangles, points, layers, splats) or a mesh file.
    #[arg(short = 'o', long = "output", value_name = "OUT")]
    output: Option<PathBuf>,
    #[command(flatten)]
    report: ReportArgs,
}

pub fn run(args: CutArgs) -> Result<(), CliError> {
    let error = super::simplify::parse_error_target(&args.error)?;
    if let Some(t) = args.at
        && !(t.is_finite() && t >= 0.0)
    {
        return Err(CliError::BadInput(format!("--at must be >= 0, got {t}")));
    }
    if let Some(out) = &args.output {
        check_output(out, args.report.force)?;
    }
    super::outputs::input(&args.file)?;
    let bytes = io::read_file(&args.file, &Progress::new())?;
    let start = std::time::Instant::now();
    let (header, mut hierarchy) = lodstudio_core::open::reopen(&bytes)
        .map_err(|e| CliError::BadInput(format!("{}: {e}", args.file.display())))?;
    hierarchy.set_knobs(&lodstudio_core::lod::Knobs {
        pyramid_position: args.at,
        ..Default::default()
    });
    let view = View::orbit(glam::Vec3::ZERO, 1.0, 0.0, 0.0);
    let diagonal = hierarchy.diagonal();
    let set = match args.triangles {
        Some(n) => select_triangles(hierarchy.as_mut(), &view, n),
        None => {
            let fraction = match error {
                Target::RelativeError(f) => f,
                Target::Error(e) => e / diagonal.max(f32::MIN_POSITIVE),
                Target::Triangles(_) | Target::Ratio(_) => unreachable!("an error target"),
            };
            hierarchy.select(&view, Tolerance::Relative(fraction))
        }
    };
    if let Some(out) = &args.output {
        write_cut(out, &set)?;
    }
    let j = serde_json::json!({
        "method": header.method,
        "version": header.version,
        "params": header.params,
        "triangles": set.mesh.triangles.len(),
        "points": set.points.len(),
        "splats": set.splats.len(),
        "error_bound": set.error_bound,
        "error_bound_kind": set.error_bound_kind.name(),
        "error_bound_relative": set.error_bound / diagonal.max(f32::MIN_POSITIVE),
        "bbox_diagonal": diagonal,
        "seconds": start.elapsed().as_secs_f64(),
    });
    if args.report.json {
        println!("{j}");
    } else {
        println!(
            "{} ({} hierarchy): {} triangles, {} points, {} splats, bound {}",
            args.file.display(),
            j["method"].as_str().unwrap_or_default(),
            j["triangles"],
            j["points"],
            j["splats"],
            set.error_bound
        );
    }
    Ok(())
}
