//! `tiles`: an OGC 3D Tiles 1.1 tileset of a mesh, a hierarchical LOD whose
//! every `geometricError` is a certified bound (`lodstudio_core::tiles`).

use std::time::Instant;

use super::*;
use lodstudio_core::tiles;

/// Tile budgets the command accepts: below 64 triangles a tile costs more
/// in its file than in its triangles; above 2²⁴ a leaf is a whole scan.
const TILE_TRIANGLES: std::ops::RangeInclusive<usize> = 64..=1 << 24;

#[derive(Args, Debug)]
pub struct TilesArgs {
    /// A mesh file, or builtin:NAME.
    file: PathBuf,
    /// The tileset's folder: `tileset.json` and `tiles/N.glb` are written in it.
    #[arg(short = 'o', long = "output", value_name = "DIR")]
    output: PathBuf,
    /// Most triangles of a leaf tile (the original triangles of its cell).
    #[arg(long, value_name = "N", default_value_t = 65_536)]
    tile_triangles: usize,
    /// Tiles of a level made at once [default: every core].
    #[arg(long, value_name = "T")]
    threads: Option<usize>,
    #[command(flatten)]
    report: ReportArgs,
    #[command(flatten)]
    input: InputArgs,
}

pub fn run(args: TilesArgs) -> Result<(), CliError> {
    if !TILE_TRIANGLES.contains(&args.tile_triangles) {
        return Err(CliError::BadInput(format!(
            "--tile-triangles must be in {}..={}, got {}",
            TILE_TRIANGLES.start(),
            TILE_TRIANGLES.end(),
            args.tile_triangles
        )));
    }
    let threads = args
        .threads
        .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
    if threads == 0 {
        return Err(CliError::BadInput("--threads must be at least 1".into()));
    }
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
    let tileset = args.output.join("tileset.json");
    check_output(&tileset, args.report.force)?;
    let mesh = load_mesh(&args.file, &args.input)?;
    if mesh.triangles.is_empty() {
        return Err(CliError::BadInput(format!(
            "{}: no triangles to tile",
            args.file.display()
        )));
    }
    let start = Instant::now();
    let tree = tiles::build(&mesh, args.tile_triangles, threads, &Progress::new())
        .map_err(|e| CliError::Failure(e.to_string()))?;
    let files = tiles::tileset::encode(&tree);
    // tileset.json was claimed above; each tile is claimed before any is written.
    for (path, _) in &files[1..] {
        check_output(&args.output.join(path), args.report.force)?;
    }
    std::fs::create_dir_all(args.output.join("tiles"))
        .map_err(|e| outputs::write_error(&args.output, &e))?;
    for (path, bytes) in &files {
        write_output(&args.output.join(path), bytes)?;
    }
    let seconds = start.elapsed().as_secs_f64();
    let root = &tree.tiles[0];
    if args.report.json {
        let json = serde_json::json!({
            "tiles": tree.tiles.len(),
            "levels": tree.levels(),
            "root_geometric_error": root.error,
            "root_triangles": root.mesh.triangles.len(),
            "input_triangles": mesh.triangles.len(),
            "bbox_diagonal": mesh.bounds().diagonal(),
            "output": tileset.display().to_string(),
            "seconds": seconds,
            "peak_memory_bytes": peak_memory_bytes(),
        });
        println!("{json}");
    } else {
        println!(
            "{} tiles in {} levels: root {} triangles within {} of the original; {} ({seconds:.2} s)",
            tree.tiles.len(),
            tree.levels(),
            root.mesh.triangles.len(),
            root.error,
            tileset.display()
        );
    }
    Ok(())
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
