//! `cut`: reopen a saved hierarchy and write its cut, without rebuilding.

use std::path::Path;

use super::*;
use lodstudio_core::io::hierarchy_file;
use lodstudio_core::view::{Tolerance, View};

#[derive(Args, Debug)]
pub struct CutArgs {
    /// A saved hierarchy (.lodh) from `hybrid`, `mergetree` or `voxel --pyramid` with --save.
    file: PathBuf,
    /// Object-space error of the cut, as a fraction of the diagonal ("1%" or 0.01).
    #[arg(long, value_name = "E", default_value = "1%")]
    error: String,
    /// Voxel pyramids: the continuous position to extract (0 = finest, §5).
    #[arg(long, value_name = "T", default_value_t = 0.0)]
    at: f32,
    /// The cut as glTF (.glb: triangles, points, layers, splats) or a mesh file.
    #[arg(short = 'o', long = "output", value_name = "OUT")]
    output: Option<PathBuf>,
    #[command(flatten)]
    report: ReportArgs,
}

fn parse_fraction(e: &str) -> Option<f32> {
    let v = match e.trim().strip_suffix('%') {
        Some(p) => p.trim().parse::<f32>().ok()? / 100.0,
        None => e.trim().parse::<f32>().ok()?,
    };
    (v.is_finite() && v >= 0.0).then_some(v)
}

pub fn run(args: CutArgs) -> Result<(), CliError> {
    let fraction = parse_fraction(&args.error).ok_or_else(|| {
        CliError::BadInput(format!(
            "--error: expected a fraction or a percentage, got {:?}",
            args.error
        ))
    })?;
    if !(args.at.is_finite() && args.at >= 0.0) {
        return Err(CliError::BadInput(format!(
            "--at must be >= 0, got {}",
            args.at
        )));
    }
    if let Some(out) = &args.output {
        check_output(out, args.report.force)?;
    }
    let bytes = std::fs::read(&args.file)
        .map_err(|e| CliError::BadInput(format!("{}: cannot read: {e}", args.file.display())))?;
    let start = std::time::Instant::now();
    let (header, mut hierarchy) = hierarchy_file::reopen(&bytes)
        .map_err(|e| CliError::BadInput(format!("{}: {e}", args.file.display())))?;
    hierarchy.set_runtime(&serde_json::json!({"position": args.at}));
    let view = View::orbit(glam::Vec3::ZERO, 1.0, 0.0, 0.0);
    let set = hierarchy.select(&view, Tolerance::Relative(fraction));
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

/// A cut as GLB (everything) or as a mesh file (its triangles).
fn write_cut(out: &Path, set: &lodstudio_core::cut::DrawSet) -> Result<(), CliError> {
    if io::extension(out) == "glb" {
        let bytes = io::gltf_writer::write_draw_set_glb(set);
        return io::write_atomic(out, &bytes)
            .map_err(|e| CliError::BadInput(format!("{}: cannot write: {e}", out.display())));
    }
    write_mesh(out, &set.mesh)
}
