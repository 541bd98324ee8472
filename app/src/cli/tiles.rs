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
    /// Memory the build may use, e.g. 1G: a PLY input larger than it is
    /// streamed and partitioned out of core; the tileset's bytes are the
    /// same either way [default: a quarter of the machine's memory].
    #[arg(long, value_name = "SIZE", value_parser = io::limits::parse_size)]
    memory: Option<u64>,
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
    let memory = args
        .memory
        .unwrap_or_else(|| io::limits::machine_total() / 4);
    let mut counts = tiles::Counts::default();
    let mut streamed = false;
    let leaves = |p: &tiles::Plan| p.children.iter().filter(|k| k.is_empty()).count();
    if planned.is_none() && Store::foreign_tiles(&args.output) && !args.report.force {
        return Err(CliError::BadInput(format!(
            "{}: holds files lodstudio did not make (use --force to replace them)",
            args.output.join("tiles").display()
        )));
    }
    // The run lock is held shared while tiles are made (see `store`).
    let (store, _run_lock, plan) = match planned {
        Some(_) => {
            let store = open_store(&args.output)?;
            let lock = store
                .run_lock(false)
                .map_err(|e| store_error(&args.output, e))?;
            // Read again under the lock: another input may have replaced it.
            let Some(plan) = store.plan().filter(|p| p.key == key) else {
                return Err(CliError::BadInput(format!(
                    "{}: another input's tiles replaced these while this run waited",
                    args.output.display()
                )));
            };
            counts.reused += leaves(&plan);
            (store, lock, plan)
        }
        None => {
            let out_of_core = out_of_core(&args, memory)?;
            // In memory, the input is read (and refused) before anything is written.
            let mesh = match out_of_core {
                true => None,
                false => Some(load_mesh(&args.file, &args.input)?),
            };
            if mesh.as_ref().is_some_and(|m| m.triangles.is_empty()) {
                return Err(CliError::BadInput(format!(
                    "{}: no triangles to tile",
                    args.file.display()
                )));
            }
            let made_here = !args.output.exists();
            let store = open_store(&args.output)?;
            let planning = store
                .planning_lock()
                .map_err(|e| store_error(&args.output, e))?;
            let plan = match store.plan() {
                Some(p) if p.key == key => {
                    counts.reused += leaves(&p);
                    let run = store
                        .run_lock(false)
                        .map_err(|e| store_error(&args.output, e))?;
                    (p, run)
                }
                Some(_) if !args.report.force => {
                    return Err(CliError::BadInput(format!(
                        "{}: holds the tiles of another input or budget (use --force to replace them)",
                        args.output.display()
                    )));
                }
                _ => {
                    // Waits for the shards of a plan being replaced.
                    let run = store
                        .run_lock(true)
                        .map_err(|e| store_error(&args.output, e))?;
                    let plan = match &mesh {
                        Some(mesh) => {
                            tiles::plan(&store, mesh, args.tile_triangles, &key, &progress)
                                .map_err(|e| tiles_error(&args.output, e))
                        }
                        None => {
                            streamed = true;
                            plan_streamed(&args, &store, &key, memory, &progress)
                        }
                    };
                    let plan = plan.inspect_err(|_| {
                        // A refused input leaves nothing behind.
                        if made_here {
                            let _ = std::fs::remove_dir_all(&args.output);
                        }
                    })?;
                    counts.built += leaves(&plan);
                    run.lock_shared()
                        .map_err(|e| store_error(&args.output, e))?;
                    (plan, run)
                }
            };
            drop(planning);
            let (plan, run) = plan;
            (store, run, plan)
        }
    };
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
            "memory_limit_bytes": memory,
            "out_of_core": streamed,
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

/// Bytes a mesh file of `bytes` takes to tile in memory: its bytes, the
/// mesh, its repair and its partition (twelve dragons, a 199 MB binary
/// PLY: 1.28 GB), four times that for gzip.
fn in_memory_bytes(file: &std::path::Path) -> u64 {
    let bytes = std::fs::metadata(file).map_or(0, |m| m.len());
    let gz = std::fs::File::open(file)
        .and_then(|mut f| {
            let mut magic = [0u8; 2];
            std::io::Read::read_exact(&mut f, &mut magic).map(|_| magic == [0x1f, 0x8b])
        })
        .unwrap_or(false);
    bytes.saturating_mul(if gz { 28 } else { 7 })
}

/// Whether the input is streamed out of core: a PLY that would not fit
/// `memory` in memory. Another format over it is refused when the memory
/// was asked for, and said otherwise.
fn out_of_core(args: &TilesArgs, memory: u64) -> Result<bool, CliError> {
    let need = in_memory_bytes(&args.file);
    if need <= memory {
        return Ok(false);
    }
    let ply = io::extension(&args.file) == "ply"
        || args
            .file
            .to_string_lossy()
            .to_ascii_lowercase()
            .ends_with(".ply.gz");
    let shown = args.file.display();
    let gib = |b: u64| b as f64 / (1u64 << 30) as f64;
    match (ply, args.memory) {
        (true, _) => Ok(true),
        (false, Some(_)) => Err(CliError::BadInput(format!(
            "{shown}: tiling it in memory takes about {:.1} GiB, over --memory {:.1} GiB; out of core reads PLY (binary or ascii, gzip too)",
            gib(need),
            gib(memory)
        ))),
        (false, None) => {
            eprintln!(
                "lodstudio: {shown}: tiling it in memory takes about {:.1} GiB, over a quarter of this machine; out of core reads PLY",
                gib(need)
            );
            Ok(false)
        }
    }
}

/// Plans the tileset of a PLY streamed out of core, its cells split on disk
/// while over a quarter of `memory`.
fn plan_streamed(
    args: &TilesArgs,
    store: &Store,
    key: &str,
    memory: u64,
    progress: &Progress,
) -> Result<tiles::Plan, CliError> {
    let dir = args.output.as_path();
    let spill = store.spill_dir().map_err(|e| store_error(dir, e))?;
    let weld = args.input.load_options()?.repair.weld;
    outputs::input(&args.file)?;
    let streamed =
        tiles::stream::stream_ply(&args.file, &spill, weld, progress).map_err(|e| match e {
            tiles::stream::StreamError::Input(m) => CliError::BadInput(m),
            tiles::stream::StreamError::Io(e) => outputs::io_error(&args.file, "read", &e),
        })?;
    let cells = tiles::partition::Spill {
        dir: Some(spill),
        in_memory: (memory / 4 / tiles::partition::REC_BYTES as u64) as usize,
    };
    tiles::plan_streamed(store, streamed, args.tile_triangles, key, &cells, progress)
        .map_err(|e| tiles_error(dir, e))
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
