//! `tiles`: an OGC 3D Tiles 1.1 tileset of a mesh, a hierarchical LOD whose
//! every `geometricError` is a certified bound (`lodstudio_core::tiles`).

use std::time::Instant;

use super::*;
use crate::cli::shard::{ShardArgs, tool_id};
use lodstudio_core::batch::cache;
use lodstudio_core::tiles::{self, Made, Store, TilesError};

#[derive(Args, Debug)]
pub struct TilesArgs {
    /// A mesh file, or builtin:NAME.
    file: PathBuf,
    /// The tileset's folder: `tileset.json` and `tiles/N.glb` are written in it.
    #[arg(short = 'o', long = "output", value_name = "DIR")]
    output: PathBuf,
    /// Most triangles of a leaf tile (the original triangles of its cell).
    #[arg(long, value_name = "N", default_value_t = tiles::DEFAULT_TILE_TRIANGLES)]
    tile_triangles: usize,
    /// Tiles of a level made at once [default: every core].
    #[arg(long, value_name = "T")]
    threads: Option<usize>,
    /// Make only the tiles at this depth (0: the root) whose children are
    /// made, e.g. one Kubernetes Indexed Job per level from the deepest;
    /// `tileset.json` is written with level 0 [default: every level, each
    /// waiting for the last tile of the one below].
    #[arg(long, value_name = "L")]
    level: Option<usize>,
    #[command(flatten)]
    shard: ShardArgs,
    #[command(flatten)]
    report: ReportArgs,
    #[command(flatten)]
    input: InputArgs,
}

pub fn run(args: TilesArgs) -> Result<(), CliError> {
    if !tiles::TILE_TRIANGLES.contains(&args.tile_triangles) {
        return Err(CliError::BadInput(format!(
            "--tile-triangles must be in {}..={}, got {}",
            tiles::TILE_TRIANGLES.start(),
            tiles::TILE_TRIANGLES.end(),
            args.tile_triangles
        )));
    }
    let threads = args
        .threads
        .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
    if threads == 0 {
        return Err(CliError::BadInput("--threads must be at least 1".into()));
    }
    let shard = args.shard.shard()?;
    if args.output.exists() && !args.output.is_dir() {
        return Err(CliError::BadInput(format!(
            "{}: not a folder (the tileset is a folder)",
            args.output.display()
        )));
    }
    // The tiles of a level on `threads` workers, each collapse's own
    // parallel parts on rayon's pool of as many (first use: nothing has
    // started it yet).
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build_global()
        .map_err(|e| CliError::Failure(format!("cannot start {threads} threads: {e}")))?;
    let start = Instant::now();
    let key = input_key(&args)?;
    // A work folder of this key is this very tileset: its run goes on.
    let planned = Store::plan_in(&args.output).filter(|p| p.key == key);
    let tileset = args.output.join("tileset.json");
    check_output(&tileset, args.report.force || planned.is_some())?;
    let progress = Progress::new();
    let mut counts = tiles::Counts::default();
    let leaves = |p: &tiles::Plan| p.children.iter().filter(|k| k.is_empty()).count();
    let plan = match planned {
        Some(plan) => {
            counts.reused += leaves(&plan);
            plan
        }
        None => {
            // Read (and refused) before anything is written.
            let mesh = load_mesh(&args.file, &args.input)?;
            if mesh.triangles.is_empty() {
                return Err(CliError::BadInput(format!(
                    "{}: no triangles to tile",
                    args.file.display()
                )));
            }
            let store = open_store(&args.output)?;
            let _planning = store
                .lock("plan", true)
                .map_err(|e| store_error(&args.output, e))?;
            match store.plan() {
                Some(p) if p.key == key => {
                    counts.reused += leaves(&p);
                    p
                }
                Some(_) if !args.report.force => {
                    return Err(CliError::BadInput(format!(
                        "{}: holds the tiles of another input or budget (use --force to replace them)",
                        args.output.display()
                    )));
                }
                _ => {
                    let plan = tiles::plan(&store, &mesh, args.tile_triangles, &key, &progress)
                        .map_err(|e| tiles_error(&args.output, e))?;
                    counts.built += leaves(&plan);
                    plan
                }
            }
        }
    };
    let store = open_store(&args.output)?;
    let deepest = plan.levels() - 1;
    let levels: Vec<usize> = match args.level {
        Some(l) if l > deepest => {
            return Err(CliError::BadInput(format!(
                "--level {l}: the tree's levels are 0..={deepest}"
            )));
        }
        Some(l) => vec![l],
        None => (0..=deepest).rev().collect(),
    };
    for level in levels {
        progress.stage(&format!("tiles: level {level} of {deepest}"));
        counts += tiles::make_level(&store, &plan, level, shard, threads, &progress)
            .map_err(|e| tiles_error(&args.output, e))?;
    }
    // Every tile made (the last level, or the root by another shard):
    // the tileset, the same bytes whichever process writes it.
    let made: Option<Vec<Made>> = (0..plan.children.len()).map(|i| store.made(i)).collect();
    if let Some(made) = &made {
        write_output(&tileset, &tiles::tileset::encode(&plan, made))?;
    }
    let seconds = start.elapsed().as_secs_f64();
    let root = made.as_ref().map(|m| m[0]);
    if args.report.json {
        let json = serde_json::json!({
            "tiles": plan.children.len(),
            "levels": plan.levels(),
            "root_geometric_error": root.map(|r| r.error),
            "root_triangles": root.map(|r| r.triangles),
            "input_triangles": plan.input_triangles,
            "bbox_diagonal": plan.bbox_diagonal,
            "output": made.is_some().then(|| tileset.display().to_string()),
            "built": counts.built,
            "reused": counts.reused,
            "shard": format!("{}/{}", shard.index, shard.count),
            "level": args.level,
            "seconds": seconds,
            "peak_memory_bytes": peak_memory_bytes(),
        });
        println!("{json}");
    } else {
        match root {
            Some(root) => println!(
                "{} tiles in {} levels ({} made here, {} found made): root {} triangles within {} of the original; {} ({seconds:.2} s)",
                plan.children.len(),
                plan.levels(),
                counts.built,
                counts.reused,
                root.triangles,
                root.error,
                tileset.display()
            ),
            None => println!(
                "level {} made ({} tiles made here, {} found made); the root is not made yet ({seconds:.2} s)",
                args.level.unwrap_or(0),
                counts.built,
                counts.reused
            ),
        }
    }
    Ok(())
}

/// What the tiles are built from: the input's bytes (a built-in's name),
/// the options that shape the mesh and the budget, and the tool.
fn input_key(args: &TilesArgs) -> Result<String, CliError> {
    let recipe = format!(
        "tiles --tile-triangles {} {:?}",
        args.tile_triangles, args.input
    );
    if !args.file.exists() {
        // A built-in (anything else fails to load, with its own message).
        return Ok(cache::sha256_hex(
            format!("{recipe} {} {}", args.file.display(), tool_id()).as_bytes(),
        ));
    }
    cache::streamed_key(&args.file, recipe.as_bytes(), tool_id())
        .map_err(|e| outputs::io_error(&args.file, "read", &e))
}

fn open_store(dir: &std::path::Path) -> Result<Store, CliError> {
    Store::open(dir).map_err(|e| outputs::write_error(dir, &e))
}

fn store_error(dir: &std::path::Path, e: std::io::Error) -> CliError {
    CliError::Failure(format!(
        "{}: {e}",
        dir.join(tiles::store::DIR_NAME).display()
    ))
}

fn tiles_error(dir: &std::path::Path, e: TilesError) -> CliError {
    match e {
        TilesError::NotReady { .. } => CliError::BadInput(e.to_string()),
        TilesError::Io(e) => store_error(dir, e),
        TilesError::Cancelled(_) => CliError::Failure(e.to_string()),
    }
}

/// This process's peak resident memory so far.
fn peak_memory_bytes() -> u64 {
    // SAFETY: getrusage fills the struct it is given.
    let mut usage: libc::rusage = unsafe { std::mem::zeroed() };
    if unsafe { libc::getrusage(libc::RUSAGE_SELF, &mut usage) } != 0 {
        return 0;
    }
    // ru_maxrss is in kilobytes on Linux.
    usage.ru_maxrss.max(0) as u64 * 1024
}
