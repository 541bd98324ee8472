//! `export`: LOD chains as glTF (MSFT_lod + MSFT_screencoverage).

use super::*;
use lodstudio_core::simplify;

/// The LOD methods `export` can use (the others are not built yet).
#[derive(clap::ValueEnum, Debug, Clone, Copy)]
enum ExportMethod {
    /// Edge collapse with a certified two-sided Hausdorff bound; every LOD is
    /// simplified from the original mesh.
    Simplify,
}

#[derive(Args, Debug)]
pub struct ExportArgs {
    /// A mesh file, or builtin:NAME.
    file: PathBuf,
    /// How the LODs are built.
    #[arg(long, value_enum)]
    method: ExportMethod,
    /// Comma-separated LOD tolerances: "1%" (error relative to the bounding-box
    /// diagonal), "8px" (pixels on a --viewport-height screen when the object
    /// covers --coverage of its height), or a bare number in (0,1] (a triangle
    /// ratio). LODs are written in decreasing quality, whatever the order here.
    #[arg(long, value_name = "LIST", allow_hyphen_values = true)]
    lods: String,
    /// Output GLB.
    #[arg(short = 'o', long = "output", value_name = "OUT.glb")]
    output: PathBuf,
    /// Pixel tolerance for the MSFT_screencoverage thresholds: a LOD is shown
    /// only where its error bound projects to at most this many pixels.
    #[arg(long, value_name = "P", default_value_t = 1.0)]
    pixels: f32,
    /// Viewport height in pixels, for the thresholds and for "px" tolerances.
    #[arg(long, value_name = "H", default_value_t = 1080.0)]
    viewport_height: f32,
    /// Screen coverage (object height / viewport height) at which "px" tolerances
    /// are converted to object space: e = px · diagonal / (H · coverage).
    #[arg(long, value_name = "C", default_value_t = 1.0)]
    coverage: f32,
    /// Border, seam and non-manifold vertices never move.
    #[arg(long)]
    lock_borders: bool,
    #[command(flatten)]
    report: ReportArgs,
    #[command(flatten)]
    input: InputArgs,
}

/// One item of `export --lods`.
#[derive(Debug, Clone, Copy, PartialEq)]
enum LodTolerance {
    /// Error bound as a fraction of the bounding-box diagonal ("1%").
    Relative(f32),
    /// Error bound in pixels ("8px"), converted through the bounding sphere.
    Pixels(f32),
    /// Fraction of the input's triangles ("0.25").
    Ratio(f32),
}

/// Parses `export --lods`: `1%`, `8px` or a triangle ratio in (0,1], comma-separated.
fn parse_lods(list: &str) -> Result<Vec<(String, LodTolerance)>, CliError> {
    let bad = |item: &str, why: &str| {
        CliError::BadInput(format!(
            "--lods: {item:?} {why} (expected items like 1%, 8px or a triangle ratio 0.25)"
        ))
    };
    let mut out = Vec::new();
    for item in list.split(',').map(str::trim) {
        if item.is_empty() {
            return Err(bad(list, "has an empty item"));
        }
        let number = |s: &str| {
            s.trim()
                .parse::<f32>()
                .ok()
                .filter(|v| v.is_finite() && *v >= 0.0)
                .ok_or_else(|| bad(item, "is not a number >= 0"))
        };
        let tol = if let Some(p) = item.strip_suffix('%') {
            LodTolerance::Relative(number(p)? / 100.0)
        } else if let Some(p) = item.strip_suffix("px") {
            LodTolerance::Pixels(number(p)?)
        } else {
            let r = number(item)?;
            if !(r > 0.0 && r <= 1.0) {
                return Err(bad(item, "is not a triangle ratio in (0,1]"));
            }
            LodTolerance::Ratio(r)
        };
        out.push((item.to_string(), tol));
    }
    Ok(out)
}

pub fn run(args: ExportArgs) -> Result<(), CliError> {
    use lodstudio_core::io::gltf::{lod_screen_coverages, write_lod_chain_glb};
    let is_glb = args
        .output
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("glb"));
    if !is_glb {
        return Err(CliError::BadInput(format!(
            "{}: export writes GLB; name the output *.glb",
            args.output.display()
        )));
    }
    check_output(&args.output, args.report.force)?;
    let items = parse_lods(&args.lods)?;
    for (name, v) in [
        ("--pixels", args.pixels),
        ("--viewport-height", args.viewport_height),
        ("--coverage", args.coverage),
    ] {
        if !(v.is_finite() && v > 0.0) {
            return Err(CliError::BadInput(format!(
                "{name} must be a finite number > 0, got {v}"
            )));
        }
    }
    let ExportMethod::Simplify = args.method;
    let mesh = load_mesh(&args.file, &args.input)?;
    let start = std::time::Instant::now();
    let diag = mesh.bounds().diagonal();
    // The bounding box's circumscribed sphere bounds the object.
    let radius = 0.5 * diag;
    let targets: Vec<(String, Target)> = items
        .into_iter()
        .map(|(label, tol)| {
            let target = match tol {
                LodTolerance::Relative(e) => Target::RelativeError(e),
                // p pixels at coverage C: e = p · 2r / (H · C).
                LodTolerance::Pixels(p) => {
                    Target::Error(p * 2.0 * radius / (args.viewport_height * args.coverage))
                }
                LodTolerance::Ratio(r) => Target::Ratio(r),
            };
            (label, target)
        })
        .collect();
    let collapse = CollapseOptions {
        lock_borders: args.lock_borders,
        ..Default::default()
    };
    // Every LOD is simplified from the original, independently: one thread each.
    let results: Vec<Result<simplify::Simplified, simplify::SimplifyError>> =
        std::thread::scope(|scope| {
            let handles: Vec<_> = targets
                .iter()
                .map(|(_, target)| {
                    let opts = SimplifyOptions {
                        per_triangle_bounds: false,
                        target: *target,
                        collapse,
                    };
                    let mesh = &mesh;
                    scope.spawn(move || simplify::simplify(mesh, &opts, &Progress::new()))
                })
                .collect();
            handles
                .into_iter()
                .map(|h| h.join().unwrap_or_else(|p| std::panic::resume_unwind(p)))
                .collect()
        });
    let mut lods = Vec::with_capacity(targets.len());
    for ((label, _), result) in targets.into_iter().zip(results) {
        let result = result.map_err(|e| match e {
            simplify::SimplifyError::BadTarget(m) => {
                CliError::BadInput(format!("--lods {label}: {m}"))
            }
            simplify::SimplifyError::Cancelled => CliError::Failure(e.to_string()),
        })?;
        lods.push((label, result));
    }
    // Decreasing quality: increasing bound, then decreasing triangle count.
    lods.sort_by(|(_, a), (_, b)| {
        a.error_bound()
            .total_cmp(&b.error_bound())
            .then(b.mesh.triangles.len().cmp(&a.mesh.triangles.len()))
    });
    let bounds: Vec<f32> = lods.iter().map(|(_, r)| r.error_bound()).collect();
    let coverages = lod_screen_coverages(&bounds, radius, args.pixels, args.viewport_height);
    let meshes: Vec<lodstudio_core::TriMesh> = lods.iter().map(|(_, r)| r.mesh.clone()).collect();
    let bytes = write_lod_chain_glb(&meshes, &coverages);
    io::write_atomic(&args.output, &bytes)
        .map_err(|e| CliError::BadInput(format!("{}: cannot write: {e}", args.output.display())))?;
    let seconds = start.elapsed().as_secs_f64();
    let per_lod: Vec<serde_json::Value> = lods
        .iter()
        .zip(&coverages)
        .map(|((label, r), c)| {
            let e = r.error_bound();
            serde_json::json!({
                "tolerance": label,
                "triangles": r.mesh.triangles.len(),
                "points": 0,
                "splats": 0,
                "vertices": r.mesh.positions.len(),
                "error_bound": e,
                "error_bound_relative": e / diag,
                "screen_coverage": c,
            })
        })
        .collect();
    if args.report.json {
        println!(
            "{}",
            serde_json::json!({
                "method": "simplify",
                "lods": per_lod,
                "bytes": bytes.len(),
                "input_triangles": mesh.triangles.len(),
                "bbox_diagonal": diag,
                "pixels": args.pixels,
                "viewport_height": args.viewport_height,
                "seconds": seconds,
                "output": args.output.display().to_string(),
            })
        );
    } else {
        println!(
            "{} -> {}: {} LODs, {} bytes, {:.2} s (MSFT_lod; thresholds for {} px on {} px)",
            args.file.display(),
            args.output.display(),
            lods.len(),
            bytes.len(),
            seconds,
            args.pixels,
            args.viewport_height
        );
        for (i, ((label, r), c)) in lods.iter().zip(&coverages).enumerate() {
            println!(
                "  lod{i} {label:>8}: {:>8} triangles, bound {:.6} ({:.4}% of the diagonal), shown from coverage {c:.4}",
                r.mesh.triangles.len(),
                r.error_bound(),
                100.0 * r.error_bound() / diag,
            );
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lod_lists_parse_percentages_pixels_and_ratios() {
        let l = parse_lods(" 1%, 8px ,0.25,1").unwrap();
        let tols: Vec<LodTolerance> = l.iter().map(|(_, t)| *t).collect();
        assert_eq!(
            tols,
            [
                LodTolerance::Relative(0.01),
                LodTolerance::Pixels(8.0),
                LodTolerance::Ratio(0.25),
                LodTolerance::Ratio(1.0)
            ]
        );
        assert_eq!(l[1].0, "8px");
        for bad in ["", "1%,", "abc", "-1%", "2", "0", "xpx", "nan%", "1%%"] {
            assert!(parse_lods(bad).is_err(), "{bad:?}");
        }
    }
}
