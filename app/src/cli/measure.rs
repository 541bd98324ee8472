//! `measure`: sampled two-sided Hausdorff distance between two meshes, B's
//! UV error against A when both are textured, and the share of B's area whose
//! normals point against its winding (what renders dark in a client).

use super::*;

#[derive(Args, Debug)]
pub struct MeasureArgs {
    /// The reference mesh.
    a: PathBuf,
    /// The mesh compared with it.
    b: PathBuf,
    /// Area samples per surface (vertices and edge midpoints are added).
    #[arg(long, default_value_t = 1_000_000)]
    samples: usize,
    /// Print one JSON object.
    #[arg(long)]
    json: bool,
    #[command(flatten)]
    input: InputArgs,
}

pub fn run(args: MeasureArgs) -> Result<(), CliError> {
    use lodstudio_core::distance::{SamplingOptions, hausdorff_mesh_mesh};
    // Each sample is a point and its distance, on both sides.
    io::limits::check_items("samples (--samples)", args.samples, 2 * 32)
        .map_err(|e| CliError::BadInput(e.expected))?;
    if args.samples == 0 {
        return Err(CliError::BadInput("--samples must be at least 1".into()));
    }
    let a = load_mesh(&args.a, &args.input)?;
    let b = load_mesh(&args.b, &args.input)?;
    let start = std::time::Instant::now();
    let opts = SamplingOptions {
        samples: args.samples,
        seed: 1,
    };
    let r = hausdorff_mesh_mesh(&a, &b, &opts);
    let diag = a.bounds().diagonal();
    // UVs count as carried where the measured distance allows.
    let uv = lodstudio_core::distance::uv_error(&a, &b, r.two_sided());
    let against = normals_against_winding(&args.b, &args.input)?;
    if args.json {
        println!(
            "{}",
            serde_json::json!({
                "hausdorff": r.two_sided(),
                "hausdorff_relative": r.two_sided() / diag,
                "a_to_b": r.a_to_b,
                "b_to_a": r.b_to_a,
                "mean_a_to_b": r.mean_a_to_b,
                "mean_b_to_a": r.mean_b_to_a,
                "samples_a": r.samples_a,
                "samples_b": r.samples_b,
                "uv_error": uv,
                "normals_against_winding": against,
                "seconds": start.elapsed().as_secs_f64(),
            })
        );
    } else {
        println!(
            "two-sided Hausdorff {:.6} ({:.4}% of the diagonal): A->B {:.6}, B->A {:.6} ({} + {} samples)",
            r.two_sided(),
            100.0 * r.two_sided() / diag,
            r.a_to_b,
            r.b_to_a,
            r.samples_a,
            r.samples_b
        );
        println!(
            "normals of B against its winding on {:.2}% of its area",
            100.0 * against
        );
        if let Some(uv) = uv {
            println!(
                "UV error of B: mean {:.5}, max {:.5}, {:.2}% of its area off by more than {}",
                uv.mean,
                uv.max,
                100.0 * uv.area_over_threshold,
                lodstudio_core::distance::UV_ERROR_THRESHOLD
            );
        }
    }
    Ok(())
}

/// The share of `file`'s area with normals against its winding, read as a
/// client reads it: unwelded, each vertex with the normal the file gives it
/// (welding would give a fold's two sides one normal).
fn normals_against_winding(file: &std::path::Path, input: &InputArgs) -> Result<f64, CliError> {
    let mut opts = input.load_options()?;
    opts.repair.weld = Weld::Off;
    match lodstudio_core::open::open(file, &opts, &Progress::new())?.model {
        Model::Mesh(m) => Ok(m.area_with_normals_against_winding()),
        _ => Ok(0.0),
    }
}
