//! Command-line interface: subcommands print a human summary, or exactly one
//! JSON object with `--json` (the contract in DESIGN.md).

use std::path::PathBuf;

use clap::{Args, CommandFactory, FromArgMatches, Parser, Subcommand};
use lodstudio_core::geom::{RepairOptions, Weld};
use lodstudio_core::io::{self, LoadError, LoadOptions, Model, RawSpec, ScalarType};
use lodstudio_core::lod::{BuildError, Hierarchy, Params};
use lodstudio_core::simplify::{CollapseOptions, SimplifyOptions, Target};
use lodstudio_core::stats::ModelSummary;
use lodstudio_core::{Progress, builtins};

mod amg;
mod compare;
mod cut;
mod export;
mod flythrough;
mod hybrid;
mod impostor;
mod info;
mod measure;
mod mergetree;
mod outputs;
mod shard;
mod simplify;
mod tiles;
mod voxel;

#[derive(Parser, Debug)]
#[command(
    name = "lodstudio",
    version,
    about = "Build, inspect and export level-of-detail hierarchies. With no subcommand, opens the studio."
)]
struct Cli {
    #[command(subcommand)]
    pub command: Option<Command>,
    #[command(flatten)]
    limits: LimitArgs,
    #[command(flatten)]
    confine: ConfineArgs,
}

/// Where the files a model names may be (io::confine; README, "Running on
/// untrusted input").
#[derive(Args, Debug)]
struct ConfineArgs {
    /// The folder that the files a model or manifest names (glTF buffers and
    /// images, manifest lines) must lie in [default: the folder of the file
    /// that names them].
    #[arg(long, global = true, value_name = "DIR")]
    asset_root: Option<PathBuf>,
    /// Follow references anywhere: absolute paths, `..`, links out of the
    /// folder and file: URIs (trusted local files only; off by default,
    /// batch included).
    #[arg(long, global = true)]
    allow_outside_uris: bool,
}

impl ConfineArgs {
    fn apply(&self) -> Result<(), CliError> {
        if let Some(root) = &self.asset_root
            && !root.is_dir()
        {
            return Err(CliError::BadInput(format!(
                "--asset-root {}: not a folder",
                root.display()
            )));
        }
        io::confine::set(io::confine::Policy {
            asset_root: self.asset_root.clone(),
            allow_outside: self.allow_outside_uris,
        });
        Ok(())
    }
}

/// Hard limits on what an input may make lodstudio allocate (io::limits).
#[derive(Args, Debug)]
struct LimitArgs {
    /// Most bytes a gzip input may inflate to, e.g. 512M (default: a quarter
    /// of the machine's memory; env LODSTUDIO_MAX_DECOMPRESSED).
    #[arg(long, global = true, value_name = "SIZE", value_parser = io::limits::parse_size)]
    max_decompressed: Option<u64>,
    /// Memory budget that counts read from file headers are checked against
    /// before anything is reserved, e.g. 8G (default: half the machine's
    /// memory; env LODSTUDIO_MAX_MEMORY).
    #[arg(long, global = true, value_name = "SIZE", value_parser = io::limits::parse_size)]
    max_memory: Option<u64>,
}

impl LimitArgs {
    /// Puts the limits in force: the options, else the environment, else the machine's.
    fn apply(&self) -> Result<(), CliError> {
        let mut limits = io::limits::Limits::from_env().map_err(CliError::BadInput)?;
        if let Some(v) = self.max_decompressed {
            limits.max_decompressed = v;
            limits.ratio_limited = false;
        }
        if let Some(v) = self.max_memory {
            limits.memory_budget = v;
        }
        io::limits::set(limits);
        Ok(())
    }
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Open the studio on FILE (or a builtin:NAME).
    Open { file: PathBuf },
    /// Print counts, topology and the repairs made on load.
    Info(info::InfoArgs),
    /// Simplify a mesh by edge collapse with a certified two-sided Hausdorff bound.
    Simplify(simplify::SimplifyArgs),
    /// An octahedral impostor: the mesh rendered from views² directions into
    /// one atlas (colour, normal, depth), shown as alpha-masked cards.
    Impostor(impostor::ImpostorArgs),
    /// Measure the two-sided Hausdorff distance between two meshes by dense sampling.
    Measure(measure::MeasureArgs),
    /// How different two models look: rendered from the same views around A,
    /// the share of pixels only one covers and the PSNR of the images.
    Compare(compare::CompareArgs),
    /// Voxel simplification: low-pass filter the solid's volume and extract its
    /// iso-surface; lower genus as the filter widens (voxel paper §2).
    Voxel(voxel::VoxelArgs),
    /// Export an LOD chain as one GLB: the MSFT_lod node extension with
    /// MSFT_screencoverage thresholds from each LOD's guaranteed error bound.
    Export(Box<export::ExportArgs>),
    /// Reopen a saved hierarchy (simplify, hybrid, mergetree, voxel --pyramid
    /// --save) and write its cut at an object-space error or a triangle count,
    /// without rebuilding.
    Cut(cut::CutArgs),
    /// View-dependent merge tree: build it, replay a camera orbit (or zoom) and
    /// time the incremental update against a cold start (merge-tree paper Table 1).
    Mergetree(mergetree::MergeTreeArgs),
    /// Hybrid simplification: a multi-resolution graph of triangles and points
    /// (edge collapse, point replacement, point merging), its curve and a cut.
    Hybrid(hybrid::HybridArgs),
    /// Primitive counts of triangle-only and hybrid cuts along a fly-through.
    Flythrough(flythrough::FlythroughArgs),
    /// AMG extreme simplification of a point set: quasi-flat domains drawn as
    /// textured, alpha-blended quads (domain primitives).
    Amg(amg::AmgArgs),
    /// An OGC 3D Tiles 1.1 tileset: a hierarchical LOD of spatial tiles
    /// (parents simplified with their borders locked, so every cut is
    /// crack-free), each tile's geometricError a certified bound.
    Tiles(tiles::TilesArgs),
}

/// Where a built hierarchy is saved (reopen it with `cut`, or in the studio).
#[derive(Args, Debug)]
pub struct SaveArgs {
    /// Save the built hierarchy (versioned, checksummed) to FILE.lodh.
    #[arg(long, value_name = "FILE.lodh")]
    pub save: Option<PathBuf>,
}

impl SaveArgs {
    /// Refuses an existing file (without --force) before anything is built.
    pub fn check(&self, force: bool) -> Result<(), CliError> {
        self.save
            .as_deref()
            .map_or(Ok(()), |p| check_output(p, force))
    }

    /// Writes `hierarchy` with its `params` when --save was given.
    pub fn write(
        &self,
        hierarchy: &dyn lodstudio_core::lod::Hierarchy,
        params: serde_json::Value,
    ) -> Result<(), CliError> {
        let Some(path) = &self.save else {
            return Ok(());
        };
        let bytes = hierarchy
            .save(&params)
            .ok_or_else(|| CliError::Failure("this hierarchy cannot be saved".into()))?;
        outputs::write(path, &bytes)
    }
}

/// How each extracted voxel level is simplified further (voxel paper §5),
/// for `voxel` and `export --method voxel`.
#[derive(Args, Debug, Clone, Copy)]
pub struct PostArgs {
    /// Voxel: keep the raw marching-cubes extraction (no edge collapse after it).
    #[arg(long, conflicts_with_all = ["post_error", "post_triangles"])]
    pub no_simplify: bool,
    /// Voxel: collapse each level's edges while its certified distance to the
    /// extraction stays within V voxels [default: 0.5].
    #[arg(long, value_name = "V")]
    pub post_error: Option<f32>,
    /// Voxel: collapse each level down to at most N triangles.
    #[arg(long, value_name = "N", conflicts_with = "post_error")]
    pub post_triangles: Option<usize>,
}

impl PostArgs {
    pub fn post(&self) -> Result<lodstudio_core::voxel::PostSimplify, CliError> {
        use lodstudio_core::voxel::PostSimplify;
        let post = match (self.no_simplify, self.post_error, self.post_triangles) {
            (true, ..) => PostSimplify::Off,
            (_, Some(v), _) => PostSimplify::Voxels(v),
            (_, _, Some(n)) => PostSimplify::Triangles(n),
            _ => lodstudio_core::voxel::VoxelParams::default().post,
        };
        post.check().map_err(CliError::BadInput)?;
        Ok(post)
    }
}

/// How results are reported and written.
/// Baked textures (`core::bake`): always, never, or (neither flag) where
/// seams keep a textured model's LOD short of its triangle budget.
#[derive(Args, Debug)]
pub struct BakeArgs {
    /// Give each LOD (but a source row) its own texture: a new UV atlas, the
    /// original's base colour and a normal map of its shading transferred
    /// onto it (GLB output); part, UV and colour seams then stop nothing.
    /// Without it, a textured model's LOD bakes where its seams keep it
    /// short of its triangle budget, or where at a triangle count it
    /// measures closer to the model baked (`baked.measured`).
    #[arg(long)]
    pub bake: bool,
    /// Never bake, even where seams keep a textured model short of its budget.
    #[arg(long, conflicts_with = "bake")]
    pub no_bake: bool,
    /// The baked textures' side in texels (default: the model's texels per
    /// triangle kept, 1024 to 4096).
    #[arg(long, value_name = "N", conflicts_with = "no_bake")]
    pub texture_size: Option<u32>,
}

impl BakeArgs {
    /// A row's `bake`: always, never, or `None` (when short of its budget).
    pub fn choice(&self) -> Option<bool> {
        match (self.bake, self.no_bake) {
            (true, _) => Some(true),
            (_, true) => Some(false),
            _ => None,
        }
    }

    /// The side a LOD of `original` with `triangles` bakes at.
    pub fn texture_size(&self, original: &lodstudio_core::TriMesh, triangles: usize) -> u32 {
        self.texture_size
            .unwrap_or_else(|| lodstudio_core::bake::default_size(original, triangles))
    }
}

#[derive(Args, Debug)]
pub struct ReportArgs {
    /// Overwrite output files that exist.
    #[arg(long)]
    pub force: bool,
    /// Print one JSON object.
    #[arg(long)]
    pub json: bool,
}

#[derive(Args, Debug)]
pub struct InputArgs {
    /// Merge vertices closer than this distance (default: only identical ones).
    #[arg(long, value_name = "DISTANCE")]
    pub weld_tolerance: Option<f32>,
    /// Keep vertex records as they are (no welding).
    #[arg(long, conflicts_with = "weld_tolerance")]
    pub no_weld: bool,
    /// Raw volume: grid size X,Y,Z.
    #[arg(long, value_name = "X,Y,Z", value_parser = parse_triple::<usize>)]
    pub raw_dims: Option<[usize; 3]>,
    /// Raw volume: scalar type (u8, i8, u16, i16, u32, i32, f32, f64).
    #[arg(long, value_name = "TYPE", requires = "raw_dims")]
    pub raw_type: Option<String>,
    /// Raw volume: voxel spacing X,Y,Z.
    #[arg(long, value_name = "X,Y,Z", value_parser = parse_triple::<f32>, requires = "raw_dims")]
    pub raw_spacing: Option<[f32; 3]>,
    /// Raw volume: bytes to skip before the samples.
    #[arg(long, value_name = "BYTES", default_value_t = 0, requires = "raw_dims")]
    pub raw_header: usize,
    /// Raw volume: samples are big-endian.
    #[arg(long, requires = "raw_dims")]
    pub raw_big_endian: bool,
}

#[derive(Args, Debug)]
struct InfoArgs {
    /// A model file, or builtin:NAME.
    #[arg(required_unless_present = "builtins")]
    pub file: Option<PathBuf>,
    /// List the built-in models.
    #[arg(long)]
    pub builtins: bool,
    /// Print one JSON object.
    #[arg(long)]
    pub json: bool,
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

impl From<io::confine::Refused> for CliError {
    fn from(e: io::confine::Refused) -> Self {
        match e {
            io::confine::Refused::Input(m) => CliError::BadInput(m),
            io::confine::Refused::Io(m) => CliError::Failure(m),
        }
    }
}

impl From<lodstudio_core::lod::ParamError> for CliError {
    /// Named as its flag: `--kappa: must be in 1..=16, got 40`.
    fn from(e: lodstudio_core::lod::ParamError) -> Self {
        CliError::BadInput(format!("{}: {}", e.flag(), e.message))
    }
}

impl From<BuildError> for CliError {
    fn from(e: BuildError) -> Self {
        match e {
            BuildError::Param(p) => p.into(),
            BuildError::BadInput(m) => CliError::BadInput(m),
            BuildError::Cancelled => CliError::Failure(e.to_string()),
        }
    }
}

/// Builds `params` on `input`, opened from `file`, through `lod::build`
/// (every subcommand's one build path) and hands back the method's own
/// structure, which the subcommand reports on.
pub fn build<'a, T: Hierarchy>(
    params: &Params,
    input: impl Into<lodstudio_core::lod::Input<'a>>,
    file: &std::path::Path,
) -> Result<Box<T>, CliError> {
    let built =
        lodstudio_core::lod::build(params, input, &Progress::new()).map_err(|e| match e {
            BuildError::BadInput(m) => CliError::BadInput(format!("{}: {m}", file.display())),
            e => e.into(),
        })?;
    let method = built.method();
    (built as Box<dyn std::any::Any>)
        .downcast()
        .map_err(|_| CliError::Failure(format!("internal error: {method:?} built another type")))
}

pub fn run() -> Result<(), CliError> {
    // `--kappa -1` is a value to refuse with its range, not an unknown option.
    let parsed = Cli::command()
        .mut_subcommands(|s| s.allow_negative_numbers(true))
        .try_get_matches()
        .and_then(|m| Cli::from_arg_matches(&m));
    let cli = match parsed {
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
    cli.limits.apply()?;
    cli.confine.apply()?;
    let result = dispatch(cli.command);
    match result {
        Ok(()) => outputs::commit(),
        Err(e) => {
            outputs::discard();
            Err(e)
        }
    }
}

fn dispatch(command: Option<Command>) -> Result<(), CliError> {
    match command {
        None => studio(None),
        Some(Command::Open { file }) => studio(Some(file)),
        Some(Command::Info(args)) => info::run(args),
        Some(Command::Simplify(args)) => simplify::run(args),
        Some(Command::Impostor(args)) => impostor::run(args),
        Some(Command::Measure(args)) => measure::run(args),
        Some(Command::Compare(args)) => compare::run(args),
        Some(Command::Voxel(args)) => voxel::run(args),
        Some(Command::Export(args)) => export::run(*args),
        Some(Command::Cut(args)) => cut::run(args),
        Some(Command::Mergetree(args)) => mergetree::run(args),
        Some(Command::Hybrid(args)) => hybrid::run(args),
        Some(Command::Flythrough(args)) => flythrough::run(args),
        Some(Command::Amg(args)) => amg::run(args),
        Some(Command::Tiles(args)) => tiles::run(args),
    }
}

fn studio(file: Option<PathBuf>) -> Result<(), CliError> {
    lodstudio::run_studio(file)
        .map_err(|e| CliError::Failure(format!("cannot open the studio window: {e}")))
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
pub fn parse_triple<T: std::str::FromStr + Copy + Default>(s: &str) -> Result<[T; 3], String> {
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

/// Opens FILE (a model, builtin:NAME, FILE#lodN or a saved hierarchy) as
/// an input of this run: no output of it may be written over the file.
pub fn open_input(
    file: &std::path::Path,
    opts: &LoadOptions,
) -> Result<lodstudio_core::io::Loaded, CliError> {
    // `FILE.glb#lodN` reads FILE.glb.
    let read = file
        .to_str()
        .and_then(|f| f.rsplit_once("#lod"))
        .map_or(file, |(f, _)| std::path::Path::new(f));
    outputs::input(read)?;
    let loaded = lodstudio_core::open::open(file, opts, &Progress::new())?;
    // Nothing is dropped silently: what the outputs leave out is said.
    for d in &loaded.asset.dropped {
        eprintln!(
            "lodstudio: {}: not carried: {} ({})",
            file.display(),
            d.what,
            d.place
        );
    }
    Ok(loaded)
}

/// Loads FILE and insists on a triangle mesh.
pub fn load_mesh(
    file: &std::path::Path,
    input: &InputArgs,
) -> Result<lodstudio_core::TriMesh, CliError> {
    let loaded = open_input(file, &input.load_options()?)?;
    match loaded.model {
        Model::Mesh(m) => Ok(m),
        other => Err(CliError::BadInput(format!(
            "{}: this command needs a triangle mesh, not a {}",
            file.display(),
            other.kind()
        ))),
    }
}

/// Claims an output of this run: an existing file is replaced only with
/// `--force`, and no two outputs, nor an output and an input, share a path.
pub fn check_output(out: &std::path::Path, force: bool) -> Result<(), CliError> {
    outputs::claim(out, force)
}

/// Writes one output file (put in place when the command succeeds).
pub fn write_output(out: &std::path::Path, bytes: &[u8]) -> Result<(), CliError> {
    outputs::write(out, bytes)
}

/// Writes a cut through the one writer (`io::cut_writer`: GLB holds it all,
/// mesh formats get the `.points.ply` and `.layerK` files beside them).
pub fn write_cut(
    out: &std::path::Path,
    set: &lodstudio_core::lod::DrawSet,
) -> Result<(), CliError> {
    for (path, bytes) in io::cut_writer::encode(out, set).map_err(CliError::BadInput)? {
        outputs::write(&path, &bytes)?;
    }
    Ok(())
}

pub fn write_mesh(out: &std::path::Path, mesh: &lodstudio_core::TriMesh) -> Result<(), CliError> {
    let bytes = io::encode_mesh(out, mesh).map_err(CliError::BadInput)?;
    outputs::write(out, &bytes)
}
