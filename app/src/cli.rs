//! Command-line interface: subcommands print a human summary, or exactly one
//! JSON object with `--json` (the contract in DESIGN.md).

use std::path::PathBuf;

use clap::{Args, Parser, Subcommand};
use lodstudio_core::geom::{RepairOptions, Weld};
use lodstudio_core::io::{self, LoadError, LoadOptions, Model, RawSpec, ScalarType};
use lodstudio_core::simplify::{self, CollapseOptions, SimplifyOptions, Target};
use lodstudio_core::stats::ModelSummary;
use lodstudio_core::{Progress, builtins};

#[derive(Parser, Debug)]
#[command(
    name = "lodstudio",
    version,
    about = "Build, inspect and export level-of-detail hierarchies. With no subcommand, opens the studio."
)]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Open the studio on FILE (or a builtin:NAME).
    Open { file: PathBuf },
    /// Print counts, topology and the repairs made on load.
    Info(InfoArgs),
    /// Simplify a mesh by edge collapse with a certified two-sided Hausdorff bound.
    Simplify(SimplifyArgs),
    /// Measure the two-sided Hausdorff distance between two meshes by dense sampling.
    Measure(MeasureArgs),
    /// Voxel simplification: low-pass filter the solid's volume and extract its
    /// iso-surface; lower genus as the filter widens (voxel paper §2).
    Voxel(VoxelArgs),
    /// Export an LOD chain as one GLB: the MSFT_lod node extension with
    /// MSFT_screencoverage thresholds from each LOD's guaranteed error bound.
    Export(ExportArgs),
}

/// The LOD methods `export` can use (the others are not built yet).
#[derive(clap::ValueEnum, Debug, Clone, Copy)]
enum ExportMethod {
    /// Edge collapse with a certified two-sided Hausdorff bound; every LOD is
    /// simplified from the original mesh.
    Simplify,
}

#[derive(Args, Debug)]
struct ExportArgs {
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

#[derive(clap::ValueEnum, Debug, Clone, Copy)]
enum FilterArg {
    Gaussian,
    Cone,
}

#[derive(Args, Debug)]
struct VoxelArgs {
    /// builtin:sphereflake, builtin:csg-part, or a volume (NRRD, NIfTI, INR, raw).
    file: PathBuf,
    /// Voxels along the longest side of an implicit solid's bounds (volumes keep their grid).
    #[arg(long, default_value_t = 128)]
    resolution: usize,
    /// Filter support radius R in voxels of that grid.
    #[arg(long, default_value_t = 2.0)]
    radius: f32,
    /// Low-pass filter: the Gaussian or the hyper-cone of eq. 3.
    #[arg(long, value_enum, default_value = "gaussian")]
    filter: FilterArg,
    /// Volumes: samples at or above this value are inside (default: the middle of the value range).
    #[arg(long)]
    iso: Option<f32>,
    /// The whole chain: resolution halves and the radius (in finest voxels) doubles per level (Tables 1–3).
    #[arg(long)]
    pyramid: bool,
    /// Output mesh (.obj, .ply, .glb); with --pyramid, a folder for one .ply per level.
    #[arg(short = 'o', long = "output", value_name = "OUT")]
    output: Option<PathBuf>,
    #[command(flatten)]
    report: ReportArgs,
    #[command(flatten)]
    input: InputArgs,
}

#[derive(Args, Debug)]
struct MeasureArgs {
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

#[derive(Args, Debug)]
#[command(group(clap::ArgGroup::new("target").required(true).args(["triangles", "ratio", "error"])))]
struct SimplifyArgs {
    /// A mesh file, or builtin:NAME.
    file: PathBuf,
    /// Output mesh (.obj, .ply or .glb).
    #[arg(short = 'o', long = "output", value_name = "OUT")]
    output: PathBuf,
    /// Keep at most N triangles.
    #[arg(long, value_name = "N")]
    triangles: Option<usize>,
    /// Keep at most this fraction of the triangles (0..1).
    #[arg(long, value_name = "R")]
    ratio: Option<f32>,
    /// Largest certified error: a distance, or a percentage of the bounding-box diagonal ("0.5%").
    #[arg(long, value_name = "E")]
    error: Option<String>,
    /// Border, seam and non-manifold vertices never move.
    #[arg(long)]
    lock_borders: bool,
    /// Keep UV/normal seams: vertices are not welded across attribute seams, and
    /// seam (and border) vertices never move, so both sides stay crack-free.
    #[arg(long, conflicts_with_all = ["weld_tolerance", "no_weld"])]
    keep_seams: bool,
    /// Sliver guard: minimum triangle quality 4√3·area/Σl² (merge-tree paper eq. 3); 0 disables.
    #[arg(long, value_name = "Q", default_value_t = 0.0)]
    min_quality: f32,
    #[command(flatten)]
    report: ReportArgs,
    #[command(flatten)]
    input: InputArgs,
}

/// How results are reported and written.
#[derive(Args, Debug)]
struct ReportArgs {
    /// Overwrite output files that exist.
    #[arg(long)]
    force: bool,
    /// Print one JSON object.
    #[arg(long)]
    json: bool,
}

#[derive(Args, Debug)]
struct InputArgs {
    /// Merge vertices closer than this distance (default: only identical ones).
    #[arg(long, value_name = "DISTANCE")]
    weld_tolerance: Option<f32>,
    /// Keep vertex records as they are (no welding).
    #[arg(long, conflicts_with = "weld_tolerance")]
    no_weld: bool,
    /// Raw volume: grid size X,Y,Z.
    #[arg(long, value_name = "X,Y,Z", value_parser = parse_triple::<usize>)]
    raw_dims: Option<[usize; 3]>,
    /// Raw volume: scalar type (u8, i8, u16, i16, u32, i32, f32, f64).
    #[arg(long, value_name = "TYPE", requires = "raw_dims")]
    raw_type: Option<String>,
    /// Raw volume: voxel spacing X,Y,Z.
    #[arg(long, value_name = "X,Y,Z", value_parser = parse_triple::<f32>, requires = "raw_dims")]
    raw_spacing: Option<[f32; 3]>,
    /// Raw volume: bytes to skip before the samples.
    #[arg(long, value_name = "BYTES", default_value_t = 0, requires = "raw_dims")]
    raw_header: usize,
    /// Raw volume: samples are big-endian.
    #[arg(long, requires = "raw_dims")]
    raw_big_endian: bool,
}

#[derive(Args, Debug)]
struct InfoArgs {
    /// A model file, or builtin:NAME.
    #[arg(required_unless_present = "builtins")]
    file: Option<PathBuf>,
    /// List the built-in models.
    #[arg(long)]
    builtins: bool,
    /// Print one JSON object.
    #[arg(long)]
    json: bool,
    #[command(flatten)]
    input: InputArgs,
}

/// A CLI failure: bad input (exit 2) or anything else (exit 1).
#[derive(Debug)]
pub enum CliError {
    BadInput(String),
    Failure(String),
}

impl CliError {
    pub fn code(&self) -> u8 {
        match self {
            CliError::BadInput(_) => 2,
            CliError::Failure(_) => 1,
        }
    }
    pub fn message(&self) -> &str {
        match self {
            CliError::BadInput(m) | CliError::Failure(m) => m,
        }
    }
}

impl From<LoadError> for CliError {
    fn from(e: LoadError) -> Self {
        match e {
            LoadError::Cancelled => CliError::Failure(e.to_string()),
            _ => CliError::BadInput(e.to_string()),
        }
    }
}

pub fn run() -> Result<(), CliError> {
    let cli = match Cli::try_parse() {
        Ok(c) => c,
        Err(e) => {
            use clap::error::ErrorKind;
            if matches!(e.kind(), ErrorKind::DisplayHelp | ErrorKind::DisplayVersion) {
                let _ = e.print();
                return Ok(());
            }
            let text = e.to_string();
            let line = text
                .lines()
                .find(|l| l.starts_with("error:"))
                .unwrap_or("bad arguments")
                .trim_start_matches("error: ");
            return Err(CliError::BadInput(format!("{line} (see --help)")));
        }
    };
    match cli.command {
        None => studio(None),
        Some(Command::Open { file }) => studio(Some(file)),
        Some(Command::Info(args)) => info(args),
        Some(Command::Simplify(args)) => simplify(args),
        Some(Command::Measure(args)) => measure(args),
        Some(Command::Voxel(args)) => voxel(args),
        Some(Command::Export(args)) => export(args),
    }
}

fn studio(file: Option<PathBuf>) -> Result<(), CliError> {
    lodstudio::run_studio(file).map_err(CliError::Failure)
}

impl InputArgs {
    fn load_options(&self) -> Result<LoadOptions, CliError> {
        let weld = match (self.no_weld, self.weld_tolerance) {
            (true, _) => Weld::Off,
            (false, Some(t)) if t.is_finite() && t >= 0.0 => Weld::Tolerance(t),
            (false, Some(t)) => {
                return Err(CliError::BadInput(format!(
                    "--weld-tolerance must be a finite distance >= 0, got {t}"
                )));
            }
            (false, None) => Weld::Exact,
        };
        let raw = match &self.raw_dims {
            None => None,
            Some(d) => {
                let scalar = self
                    .raw_type
                    .as_deref()
                    .map(ScalarType::parse)
                    .unwrap_or(Some(ScalarType::U8))
                    .ok_or_else(|| {
                        CliError::BadInput(format!(
                            "--raw-type: unknown scalar type {:?}",
                            self.raw_type.as_deref().unwrap_or_default()
                        ))
                    })?;
                let s = self.raw_spacing.unwrap_or([1.0; 3]);
                if s.iter().any(|v| !(v.is_finite() && *v > 0.0)) {
                    return Err(CliError::BadInput(
                        "--raw-spacing values must be finite and > 0".into(),
                    ));
                }
                Some(RawSpec {
                    dims: *d,
                    scalar,
                    big_endian: self.raw_big_endian,
                    spacing: glam::Vec3::new(s[0], s[1], s[2]),
                    header_bytes: self.raw_header,
                })
            }
        };
        Ok(LoadOptions {
            repair: RepairOptions { weld },
            raw,
        })
    }
}

/// Parses `X,Y,Z` into three values.
fn parse_triple<T: std::str::FromStr + Copy + Default>(s: &str) -> Result<[T; 3], String> {
    let parts: Vec<&str> = s.split(',').map(str::trim).collect();
    let mut out = [T::default(); 3];
    if parts.len() != 3 {
        return Err(format!("expected three comma-separated values, got {s:?}"));
    }
    for (o, p) in out.iter_mut().zip(parts) {
        *o = p
            .parse()
            .map_err(|_| format!("{p:?} is not a valid number"))?;
    }
    Ok(out)
}

fn info(args: InfoArgs) -> Result<(), CliError> {
    if args.builtins {
        if args.json {
            let list: Vec<_> = builtins::NAMES
                .iter()
                .map(|(n, d)| serde_json::json!({"name": format!("builtin:{n}"), "description": d}))
                .collect();
            println!("{}", serde_json::json!({ "builtins": list }));
        } else {
            for (n, d) in builtins::NAMES {
                println!("builtin:{n:<20} {d}");
            }
        }
        return Ok(());
    }
    let file = args.file.expect("clap requires FILE without --builtins");
    let opts = args.input.load_options()?;
    let loaded = io::load(&file, &opts, &Progress::new())?;
    let summary = ModelSummary::of(&loaded);
    if args.json {
        let mut v = summary.to_json();
        v["file"] = serde_json::json!(file.display().to_string());
        println!("{v}");
    } else {
        println!("{}", file.display());
        for (label, value) in summary.lines() {
            println!("  {label:<22} {value}");
        }
    }
    Ok(())
}

/// Loads FILE and insists on a triangle mesh.
fn load_mesh(
    file: &std::path::Path,
    input: &InputArgs,
) -> Result<lodstudio_core::TriMesh, CliError> {
    let loaded = io::load(file, &input.load_options()?, &Progress::new())?;
    match loaded.model {
        Model::Mesh(m) => Ok(m),
        other => Err(CliError::BadInput(format!(
            "{}: this command needs a triangle mesh, not a {}",
            file.display(),
            other.kind()
        ))),
    }
}

/// Refuses to replace an existing file unless `--force` was given.
fn check_output(out: &std::path::Path, force: bool) -> Result<(), CliError> {
    if out.exists() && !force {
        return Err(CliError::BadInput(format!(
            "{} exists (use --force to overwrite)",
            out.display()
        )));
    }
    Ok(())
}

fn write_mesh(out: &std::path::Path, mesh: &lodstudio_core::TriMesh) -> Result<(), CliError> {
    let bytes = io::encode_mesh(out, mesh).map_err(CliError::BadInput)?;
    io::write_atomic(out, &bytes)
        .map_err(|e| CliError::BadInput(format!("{}: cannot write: {e}", out.display())))
}

fn parse_error_target(e: &str) -> Result<Target, CliError> {
    let bad = || {
        CliError::BadInput(format!(
            "--error: expected a distance or a percentage, got {e:?}"
        ))
    };
    let (value, relative) = match e.trim().strip_suffix('%') {
        Some(p) => (p.trim().parse::<f32>().map_err(|_| bad())? / 100.0, true),
        None => (e.trim().parse::<f32>().map_err(|_| bad())?, false),
    };
    if !(value.is_finite() && value >= 0.0) {
        return Err(bad());
    }
    Ok(if relative {
        Target::RelativeError(value)
    } else {
        Target::Error(value)
    })
}

fn simplify(args: SimplifyArgs) -> Result<(), CliError> {
    check_output(&args.output, args.report.force)?;
    let target = match (args.triangles, args.ratio, &args.error) {
        (Some(n), _, _) => Target::Triangles(n),
        (_, Some(r), _) => Target::Ratio(r),
        (_, _, Some(e)) => parse_error_target(e)?,
        _ => unreachable!("clap requires one target"),
    };
    if !(args.min_quality.is_finite() && (0.0..=1.0).contains(&args.min_quality)) {
        return Err(CliError::BadInput(format!(
            "--min-quality must be in 0..=1, got {}",
            args.min_quality
        )));
    }
    let mut input = args.input;
    input.no_weld |= args.keep_seams;
    let mesh = load_mesh(&args.file, &input)?;
    let start = std::time::Instant::now();
    let opts = SimplifyOptions {
        per_triangle_bounds: false,
        target,
        collapse: CollapseOptions {
            lock_borders: args.lock_borders || args.keep_seams,
            min_quality: args.min_quality,
            ..Default::default()
        },
    };
    let result = simplify::simplify(&mesh, &opts, &Progress::new()).map_err(|e| match e {
        simplify::SimplifyError::BadTarget(m) => CliError::BadInput(m),
        simplify::SimplifyError::Cancelled => CliError::Failure(e.to_string()),
    })?;
    let seconds = start.elapsed().as_secs_f64();
    write_mesh(&args.output, &result.mesh)?;
    let diag = mesh.bounds().diagonal();
    let bound = result.error_bound();
    if args.report.json {
        println!(
            "{}",
            serde_json::json!({
                "input_triangles": mesh.triangles.len(),
                "output_triangles": result.mesh.triangles.len(),
                "error_bound": bound,
                "error_bound_relative": bound / diag,
                "seconds": seconds,
                "forward_bound": result.certificate.forward,
                "reverse_bound": result.certificate.reverse,
                "collapses": result.collapses,
                "bbox_diagonal": diag,
                "output": args.output.display().to_string(),
            })
        );
    } else {
        println!(
            "{} -> {}: {} -> {} triangles, certified two-sided Hausdorff bound {:.6} ({:.4}% of the diagonal), {:.2} s",
            args.file.display(),
            args.output.display(),
            mesh.triangles.len(),
            result.mesh.triangles.len(),
            bound,
            100.0 * bound / diag,
            seconds
        );
    }
    Ok(())
}

fn measure(args: MeasureArgs) -> Result<(), CliError> {
    use lodstudio_core::distance::{SamplingOptions, hausdorff_mesh_mesh};
    let a = load_mesh(&args.a, &args.input)?;
    let b = load_mesh(&args.b, &args.input)?;
    let start = std::time::Instant::now();
    let opts = SamplingOptions {
        samples: args.samples,
        seed: 1,
    };
    let r = hausdorff_mesh_mesh(&a, &b, &opts);
    let diag = a.bounds().diagonal();
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
    }
    Ok(())
}

/// What the voxel method samples: an implicit solid or a scalar volume.
enum VoxelInput {
    Solid(Box<dyn lodstudio_core::implicit::Implicit>),
    Volume(lodstudio_core::Volume, f32),
}

fn voxel_input(args: &VoxelArgs) -> Result<VoxelInput, CliError> {
    if let Some(name) = args.file.to_str().and_then(|s| s.strip_prefix("builtin:")) {
        return builtins::implicit(name).map(VoxelInput::Solid).ok_or_else(|| {
            CliError::BadInput(format!(
                "builtin:{name}: the voxel method needs a solid: builtin:sphereflake or builtin:csg-part"
            ))
        });
    }
    let loaded = io::load(&args.file, &args.input.load_options()?, &Progress::new())?;
    match loaded.model {
        Model::Volume(v) => {
            let (lo, hi) = v.value_range();
            let iso = args.iso.unwrap_or(0.5 * (lo + hi));
            if !iso.is_finite() {
                return Err(CliError::BadInput("--iso must be a finite value".into()));
            }
            Ok(VoxelInput::Volume(v, iso))
        }
        other => Err(CliError::BadInput(format!(
            "{}: the voxel method takes implicit solids and volumes; {} input needs an inside test that is not built yet",
            args.file.display(),
            other.kind()
        ))),
    }
}

fn voxel(args: VoxelArgs) -> Result<(), CliError> {
    use lodstudio_core::voxel::{self, DENSITY_ISO, Filter};
    if !(8..=1024).contains(&args.resolution) {
        return Err(CliError::BadInput(format!(
            "--resolution must be in 8..=1024, got {}",
            args.resolution
        )));
    }
    if !(args.radius.is_finite() && (0.0..=64.0).contains(&args.radius)) {
        return Err(CliError::BadInput(format!(
            "--radius must be in 0..=64 voxels, got {}",
            args.radius
        )));
    }
    let filter = match args.filter {
        FilterArg::Gaussian => Filter::Gaussian,
        FilterArg::Cone => Filter::Cone,
    };
    let input = voxel_input(&args)?;
    if let Some(out) = &args.output {
        check_output(out, args.report.force || (args.pyramid && out.is_dir()))?;
    }
    let progress = Progress::new();
    let run = |resolution: usize, radius: f32| match &input {
        VoxelInput::Solid(solid) => voxel::simplify_implicit(
            solid.as_ref(),
            resolution,
            radius,
            filter,
            DENSITY_ISO,
            &progress,
        ),
        VoxelInput::Volume(v, iso) => voxel::simplify_volume(v, *iso, radius, filter, &progress),
    };
    let level_json = |l: &voxel::VoxelLevel, finest: usize| {
        serde_json::json!({
            "resolution": l.resolution,
            "radius": l.radius * finest as f32 / l.resolution.max(1) as f32,
            "triangles": l.mesh.triangles.len(),
            "components": l.components,
            "genus": l.genus,
        })
    };
    let start = std::time::Instant::now();
    let failed = |_| CliError::Failure("cancelled".into());
    if !args.pyramid {
        let l = run(args.resolution, args.radius).map_err(failed)?;
        if let Some(out) = &args.output {
            write_mesh(out, &l.mesh)?;
        }
        let mut j = level_json(&l, l.resolution);
        j["layers"] = 1.into();
        j["seconds"] = start.elapsed().as_secs_f64().into();
        if args.report.json {
            println!("{j}");
        } else {
            println!(
                "{}: resolution {}, radius {} voxels -> {} triangles, {} components, genus {}",
                args.file.display(),
                l.resolution,
                l.radius,
                l.mesh.triangles.len(),
                l.components,
                l.genus
            );
        }
        return Ok(());
    }
    if matches!(input, VoxelInput::Volume(..)) {
        return Err(CliError::BadInput(
            "--pyramid needs an implicit solid (volumes keep their own grid)".into(),
        ));
    }
    if let Some(dir) = &args.output {
        std::fs::create_dir_all(dir)
            .map_err(|e| CliError::BadInput(format!("{}: cannot create: {e}", dir.display())))?;
    }
    let mut levels = Vec::new();
    let mut resolution = args.resolution;
    while resolution >= 8 {
        let l = run(resolution, args.radius).map_err(failed)?;
        if let Some(dir) = &args.output {
            let path = dir.join(format!("level{}_{}.ply", levels.len(), resolution));
            check_output(&path, args.report.force)?;
            write_mesh(&path, &l.mesh)?;
        }
        let j = level_json(&l, args.resolution);
        if !args.report.json {
            println!(
                "resolution {:>5}  radius {:>7.2}  triangles {:>8}  components {:>4}  genus {:>4}",
                j["resolution"],
                j["radius"].as_f64().unwrap_or(0.0),
                j["triangles"],
                j["components"],
                j["genus"]
            );
        }
        levels.push(j);
        resolution /= 2;
    }
    if args.report.json {
        println!(
            "{}",
            serde_json::json!({ "levels": levels, "seconds": start.elapsed().as_secs_f64() })
        );
    }
    Ok(())
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

fn export(args: ExportArgs) -> Result<(), CliError> {
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
