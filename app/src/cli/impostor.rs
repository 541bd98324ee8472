//! `lodstudio impostor`: an octahedral impostor of a mesh as a GLB of
//! alpha-masked cards on one atlas (`core::impostor`).

use std::path::PathBuf;

use clap::Args;
use lodstudio_core::impostor::{self, DEFAULT_VIEWS, ImpostorOptions};

use super::{CliError, InputArgs, ReportArgs, check_output, load_mesh, write_mesh};

#[derive(Args, Debug)]
pub struct ImpostorArgs {
    /// A mesh file, or builtin:NAME.
    file: PathBuf,
    /// Output GLB.
    #[arg(short, long = "output", value_name = "OUT.glb")]
    output: PathBuf,
    /// Frames per side of the octahedral map (views² directions).
    #[arg(long, value_name = "N", default_value_t = DEFAULT_VIEWS)]
    views: u32,
    /// The atlas's side in texels.
    #[arg(long, value_name = "N", default_value_t = lodstudio_core::bake::DEFAULT_TEXTURE_SIZE)]
    texture_size: u32,
    #[command(flatten)]
    report: ReportArgs,
    #[command(flatten)]
    input: InputArgs,
}

pub fn run(args: ImpostorArgs) -> Result<(), CliError> {
    check_output(&args.output, args.report.force)?;
    if !args
        .output
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("glb"))
    {
        return Err(CliError::BadInput(
            "an impostor is textured cards: give a .glb output".into(),
        ));
    }
    let mesh = load_mesh(&args.file, &args.input)?;
    let opts = ImpostorOptions {
        views: args.views,
        texture: args.texture_size,
    };
    let built =
        impostor::build(&mesh, &opts, &lodstudio_core::Progress::new()).map_err(|e| match e {
            lodstudio_core::lod::BuildError::Cancelled => CliError::Failure(e.to_string()),
            e => CliError::BadInput(e.to_string()),
        })?;
    write_mesh(&args.output, &built.mesh)?;
    let diag = mesh.bounds().diagonal();
    let r = &built.report;
    if args.report.json {
        let mut report = serde_json::json!(r);
        report["silhouette_error_relative"] = serde_json::json!(r.silhouette_error / diag);
        report["triangles"] = serde_json::json!(built.mesh.triangles.len());
        report["output"] = serde_json::json!(args.output.display().to_string());
        println!("{report}");
    } else {
        println!(
            "{} -> {}: {} cards of {}² frames ({}² views), silhouette error {:.6} ({:.3}% of the diagonal), {:.2} s",
            args.file.display(),
            args.output.display(),
            r.cards,
            r.frame,
            r.views,
            r.silhouette_error,
            100.0 * r.silhouette_error / diag,
            r.seconds
        );
    }
    Ok(())
}
