//! `flythrough`: primitive counts of triangle-only and hybrid cuts along a
//! camera path through a scene of instances (hybrid paper Fig. 10–11).

use super::*;
use lodstudio_core::hybrid::{HybridOptions, flythrough};

#[derive(Args, Debug)]
pub struct FlythroughArgs {
    /// A mesh file, or builtin:NAME.
    file: PathBuf,
    /// Instances of the model laid out over the ground.
    #[arg(long, value_name = "N")]
    instances: usize,
    /// Screen-space tolerance in pixels (1024×768, 60° vertical field of view).
    #[arg(long, value_name = "P", default_value_t = 3.0)]
    pixels: f32,
    /// Performance ratio κ of the hybrid configurations.
    #[arg(long, value_name = "K", default_value_t = HybridOptions::default().kappa)]
    kappa: f32,
    /// Transition factors τ of the hybrid configurations.
    #[arg(
        long,
        value_name = "T,...",
        value_delimiter = ',',
        default_value = "1,5"
    )]
    taus: Vec<f32>,
    /// Frames along the camera path.
    #[arg(long, value_name = "F", default_value_t = 60)]
    frames: usize,
    /// Print one JSON object.
    #[arg(long)]
    json: bool,
    #[command(flatten)]
    input: InputArgs,
}

pub fn run(args: FlythroughArgs) -> Result<(), CliError> {
    if !(1..=100_000).contains(&args.instances) {
        return Err(CliError::BadInput(format!(
            "--instances must be in 1..=100000, got {}",
            args.instances
        )));
    }
    if !(2..=100_000).contains(&args.frames) {
        return Err(CliError::BadInput(format!(
            "--frames must be in 2..=100000, got {}",
            args.frames
        )));
    }
    if !(args.pixels.is_finite() && args.pixels > 0.0) {
        return Err(CliError::BadInput(format!(
            "--pixels must be finite and > 0, got {}",
            args.pixels
        )));
    }
    if args.taus.is_empty() {
        return Err(CliError::BadInput("--taus needs at least one value".into()));
    }
    let base = HybridOptions {
        kappa: args.kappa,
        ..Default::default()
    };
    for tau in &args.taus {
        HybridOptions { tau: *tau, ..base }.validate()?;
    }
    let mesh = load_mesh(&args.file, &args.input)?;
    let start = std::time::Instant::now();
    let mut configs = vec![(
        "triangles",
        1.0,
        1.0,
        super::hybrid::build(&mesh, &base.triangles_only(), &args.file)?,
    )];
    for tau in &args.taus {
        let mrg = super::hybrid::build(&mesh, &HybridOptions { tau: *tau, ..base }, &args.file)?;
        configs.push(("hybrid", args.kappa, *tau, mrg));
    }
    let seconds_build = start.elapsed().as_secs_f64();
    let bounds = mesh.bounds();
    let offsets = flythrough::layout(&bounds, args.instances);
    let views = flythrough::camera_path(&bounds, &offsets, args.frames);
    let start = std::time::Instant::now();
    let counts: Vec<Vec<flythrough::FrameCount>> = configs
        .iter()
        .map(|(_, _, _, mrg)| flythrough::frame_counts(mrg, &offsets, &views, args.pixels))
        .collect();
    let ms_per_frame = 1e3 * start.elapsed().as_secs_f64() / (args.frames * configs.len()) as f64;
    let ratios: Vec<(f32, (f64, f64, f64))> = args
        .taus
        .iter()
        .zip(&counts[1..])
        .map(|(tau, c)| (*tau, flythrough::ratios(&counts[0], c)))
        .collect();
    let (mean, min, max) = ratios[0].1;
    if args.json {
        let configurations: Vec<serde_json::Value> = configs
            .iter()
            .zip(&counts)
            .map(|((name, kappa, tau, _), c)| {
                serde_json::json!({
                    "name": name,
                    "kappa": kappa,
                    "tau": tau,
                    "primitives": c.iter().map(|f| f.primitives).collect::<Vec<_>>(),
                    "triangles": c.iter().map(|f| f.triangles).collect::<Vec<_>>(),
                    "points": c.iter().map(|f| f.points).collect::<Vec<_>>(),
                })
            })
            .collect();
        let per_tau: Vec<serde_json::Value> = ratios
            .iter()
            .map(|(tau, (mean, min, max))| serde_json::json!({"tau": tau, "mean": mean, "min": min, "max": max}))
            .collect();
        println!(
            "{}",
            serde_json::json!({
                "frames": args.frames,
                "instances": args.instances,
                "pixels": args.pixels,
                "configurations": configurations,
                "ratio_mean": mean,
                "ratio_min": min,
                "ratio_max": max,
                "ratios": per_tau,
                "seconds_build": seconds_build,
                "ms_per_frame": ms_per_frame,
            })
        );
    } else {
        for (tau, (mean, min, max)) in &ratios {
            println!(
                "{}: {} instances, {} frames at {} px: triangle-only / hybrid (κ={}, τ={tau}) primitives: mean {mean:.2}, min {min:.2}, max {max:.2}",
                args.file.display(),
                args.instances,
                args.frames,
                args.pixels,
                args.kappa
            );
        }
    }
    Ok(())
}
