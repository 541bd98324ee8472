//! `compare`: how different two models look, rendered through the studio's
//! own pipelines from the same views around A: the share of pixels that only
//! one of them covers, and the PSNR of the shaded images, per view and on
//! average. `FILE.glb#lodN` names one level of an exported LOD chain.

use lodstudio::render::{Camera, Offscreen, Scene};

use super::*;

#[derive(Args, Debug)]
pub struct CompareArgs {
    /// The reference model: a file, builtin:NAME, or FILE.glb#lodN.
    a: PathBuf,
    /// The model compared with it (FILE.glb#lodN: level N of an exported LOD chain).
    b: PathBuf,
    /// Views evenly spaced around A's bounding sphere.
    #[arg(long, default_value_t = 8, value_parser = clap::value_parser!(u32).range(1..=64))]
    views: u32,
    /// Width and height of each render in pixels.
    #[arg(long, default_value_t = 256, value_parser = clap::value_parser!(u32).range(16..=2048))]
    size: u32,
    /// Write each view's difference image to DIR/viewK.png (only A covers:
    /// red, only B: green, elsewhere the colour difference ×4).
    #[arg(long, value_name = "DIR")]
    save_diff: Option<PathBuf>,
    /// Write each view to DIR/viewK.png as A's render, B's and their
    /// difference side by side.
    #[arg(long, value_name = "DIR")]
    save_views: Option<PathBuf>,
    /// Replace images that exist in --save-diff's or --save-views' folder.
    #[arg(long)]
    force: bool,
    /// Print one JSON object.
    #[arg(long)]
    json: bool,
    #[command(flatten)]
    input: InputArgs,
}

/// Where view `i`'s difference image goes.
fn diff_path(dir: &std::path::Path, i: usize) -> PathBuf {
    dir.join(format!("view{i}.png"))
}

pub fn run(args: CompareArgs) -> Result<(), CliError> {
    let opts = args.input.load_options()?;
    let folders = [&args.save_diff, &args.save_views];
    for dir in folders.into_iter().flatten() {
        for i in 0..args.views as usize {
            check_output(&diff_path(dir, i), args.force)?;
        }
    }
    let scene = |file: &std::path::Path| -> Result<Scene, CliError> {
        let loaded = open_input(file, &opts)?;
        Ok(Scene::from_model(&loaded.model))
    };
    let (a, b) = (scene(&args.a)?, scene(&args.b)?);
    for dir in folders.into_iter().flatten() {
        std::fs::create_dir_all(dir)
            .map_err(|e| CliError::BadInput(format!("{}: cannot create: {e}", dir.display())))?;
    }
    let start = std::time::Instant::now();
    let fail = |e: lodstudio::render::offscreen::RenderError| CliError::Failure(e.to_string());
    let mut offscreen = Offscreen::headless().map_err(fail)?;
    let cameras = Camera::views_around(a.sphere(), args.views as usize, 1.0);
    let views = offscreen
        .compare(&a, &b, &cameras, [args.size; 2])
        .map_err(fail)?;
    if let Some(dir) = &args.save_diff {
        for (i, view) in views.iter().enumerate() {
            write_output(&diff_path(dir, i), &io::image::encode_png(&view.image))?;
        }
    }
    if let Some(dir) = &args.save_views {
        for (i, view) in views.iter().enumerate() {
            write_output(
                &diff_path(dir, i),
                &io::image::encode_png(&view.side_by_side),
            )?;
        }
    }
    let n = views.len() as f64;
    let silhouette = views.iter().map(|v| v.difference.silhouette).sum::<f64>() / n;
    let psnr = views.iter().map(|v| v.difference.psnr).sum::<f64>() / n;
    let wrong = views.iter().map(|v| v.difference.wrong_colour).sum::<f64>() / n;
    if args.json {
        let per_view: Vec<_> = views
            .iter()
            .enumerate()
            .map(|(i, v)| {
                serde_json::json!({
                    "view": i,
                    "silhouette_difference": v.difference.silhouette,
                    "psnr": v.difference.psnr,
                    "wrong_colour": v.difference.wrong_colour,
                })
            })
            .collect();
        println!(
            "{}",
            serde_json::json!({
                "views": per_view,
                "silhouette_difference": silhouette,
                "psnr": psnr,
                "wrong_colour": wrong,
                "size": args.size,
                "seconds": start.elapsed().as_secs_f64(),
            })
        );
    } else {
        for (i, v) in views.iter().enumerate() {
            println!(
                "view {i}: {:.3}% of pixels covered by one model only, PSNR {:.2} dB",
                100.0 * v.difference.silhouette,
                v.difference.psnr
            );
        }
        println!(
            "mean over {} views of {}x{} px: silhouette difference {:.3}%, PSNR {:.2} dB (identical: 0%, {} dB)",
            views.len(),
            args.size,
            args.size,
            100.0 * silhouette,
            psnr,
            lodstudio_core::distance::visual::PSNR_CAP_DB
        );
    }
    Ok(())
}
