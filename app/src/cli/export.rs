//! `export`: LOD chains as glTF (MSFT_lod + MSFT_screencoverage), from
//! `--method`/`--lods` or a recipe (`--recipe`), for one model or a batch
//! (`batch.rs`).

use std::path::Path;

use super::*;
use lodstudio_core::io::gltf_writer::PointsAs;
use lodstudio_core::lod::Method;
use lodstudio_core::recipe::{Chain, ChainError, Flag, Recipe, build_chain, parse_lods};
use lodstudio_core::simplify::collapse::AttributeWeights;

mod batch;
mod scene;

/// `--method`: a [`Method`] by its tag.
fn parse_method(tag: &str) -> Result<Method, String> {
    Method::from_tag(tag).ok_or_else(|| format!("expected one of {}", Method::tags()))
}

#[derive(Args, Debug)]
pub struct ExportArgs {
    /// A mesh file, builtin:NAME, a folder (every model file in it) or a glob
    /// pattern such as 'models/*.obj' (one output per model, in the folder -o).
    #[arg(required_unless_present = "manifest", conflicts_with = "manifest")]
    file: Option<PathBuf>,
    /// A manifest: one model a line, optionally with `recipe=R.json` or
    /// `lods=LIST` overrides after it (README, "Batch").
    #[arg(long, value_name = "M.txt")]
    manifest: Option<PathBuf>,
    /// A recipe (the studio's Save recipe…, or --save-recipe) to replay: the
    /// rows, their methods and parameters, the switch tolerance.
    #[arg(long, value_name = "R.json", conflicts_with_all = [
        "method", "lods", "pixels", "viewport_height", "coverage", "lock_borders", "keep_seams",
        "uv_tolerance", "attribute_weights", "topology", "bake", "no_bake", "texture_size", "kappa", "tau", "resolution", "points_as", "no_simplify", "post_error", "post_triangles",
        "weld_tolerance", "no_weld",
    ])]
    recipe: Option<PathBuf>,
    /// Write the recipe of this run (replay it with --recipe).
    #[arg(long, value_name = "R.json")]
    save_recipe: Option<PathBuf>,
    /// How the LODs of bare --lods items are built: simplify (edge collapse,
    /// certified), hybrid (cuts of one MRG: triangles + points with
    /// `_RADIUS`), mergetree (uniform cuts of one merge tree), voxel (pyramid
    /// levels, certified against the input), amg (levels of the vertices as
    /// textured splats; bound: the largest domain plane error).
    #[arg(long, value_parser = parse_method, value_name = "simplify|hybrid|mergetree|voxel|amg")]
    method: Option<Method>,
    /// Comma-separated LOD tolerances: "1%" (error relative to the bounding-box
    /// diagonal), "8px" (pixels on a --viewport-height screen when the object
    /// covers --coverage of its height), or a bare number in (0,1] (a triangle
    /// ratio); each may name its method ("simplify:0.5%,amg:15%"). LODs are
    /// written in decreasing quality, whatever the order here.
    #[arg(
        long,
        value_name = "LIST",
        allow_hyphen_values = true,
        required_unless_present = "recipe"
    )]
    lods: Option<String>,
    /// Output .glb, or .gltf (with its buffer in OUT.bin beside it); for a
    /// folder, glob or manifest, the folder that receives one MODEL.glb each.
    #[arg(short = 'o', long = "output", value_name = "OUT.glb")]
    output: PathBuf,
    /// How a glTF scene's chains are laid out: msft_lod (MSFT_lod on each
    /// node, Babylon.js), nodes (children NAME_LOD0…NAME_LODn, which Unity,
    /// Unreal and Godot importers read as LOD groups) or files (OUT.glb,
    /// OUT_LOD1.glb…, each the whole scene at one level) [default: the
    /// recipe's, else msft_lod].
    #[arg(long, value_name = "msft_lod|nodes|files", value_parser = str::parse::<lodstudio_core::scene::Layout>)]
    layout: Option<lodstudio_core::scene::Layout>,
    /// How the GLBs store their buffers: none, or meshopt
    /// (EXT_meshopt_compression: meshoptimizer's codecs, lossless for
    /// positions and every bound; normals 8-bit octahedral) [default: the
    /// recipe's, else none].
    #[arg(long, value_name = "none|meshopt", value_parser = str::parse::<lodstudio_core::io::meshopt_compression::Compression>)]
    compress: Option<lodstudio_core::io::meshopt_compression::Compression>,
    /// Skinned glTF meshes: poses sampled evenly in time from each
    /// animation, at which the skinned LOD is measured against the
    /// skinned original (JSON lods[].pose_error).
    #[arg(long, value_name = "N", default_value_t = 8, value_parser = clap::value_parser!(u64).range(0..=256))]
    poses: u64,
    /// Pixel tolerance for the MSFT_screencoverage thresholds: a LOD is shown
    /// only where its error bound projects to at most this many pixels.
    #[arg(long, value_name = "P", default_value_t = Recipe::new(Vec::new()).pixels)]
    pixels: f32,
    /// Viewport height in pixels, for the thresholds and for "px" tolerances.
    #[arg(long, value_name = "H", default_value_t = Recipe::new(Vec::new()).viewport_height)]
    viewport_height: f32,
    /// Screen coverage (object height / viewport height) at which "px" tolerances
    /// are converted to object space: e = px · diagonal / (H · coverage).
    #[arg(long, value_name = "C", default_value_t = Recipe::new(Vec::new()).coverage)]
    coverage: f32,
    /// Border, seam and non-manifold vertices never move.
    #[arg(long)]
    lock_borders: bool,
    /// Keep UV/normal seams (textured materials map exactly): vertices are not
    /// welded across attribute seams, and seam and border vertices never move.
    #[arg(long, conflicts_with_all = ["weld_tolerance", "no_weld"])]
    keep_seams: bool,
    /// Edge collapse rows: texels a seam crossing may move a texture
    /// coordinate off its UV seam (default 1; 0 keeps every seam).
    #[arg(long, value_name = "TEXELS")]
    uv_tolerance: Option<f32>,
    /// Edge collapse rows: appearance in the collapse order, normal=W,uv=W,color=W
    /// (as simplify's).
    #[arg(long, value_name = "WEIGHTS", value_parser = AttributeWeights::parse)]
    attribute_weights: Option<AttributeWeights>,
    /// Edge collapse rows: keep (the default) or free, which may prune
    /// components where that is certified (as simplify's --topology).
    #[arg(long, value_name = "keep|free")]
    topology: Option<lodstudio_core::simplify::prune::TopologyMode>,
    #[command(flatten)]
    bake: BakeArgs,
    /// Hybrid: points per triangle's rendering time (κ).
    #[arg(long)]
    kappa: Option<f32>,
    /// Hybrid: transition factor τ.
    #[arg(long)]
    tau: Option<f32>,
    /// Voxel: finest pyramid resolution (voxels along the longest side) [default: 64].
    #[arg(long)]
    resolution: Option<usize>,
    /// How hybrid points are written: "points" (a POINTS primitive with the
    /// per-point object-space radius `_RADIUS`, for renderers that splat),
    /// "quads" or "discs" (a small double-sided mesh per point, facing its
    /// normal and covering its disc, for clients that draw POINTS as pixels).
    #[arg(long, value_name = "points|quads|discs", default_value = "points", value_parser = str::parse::<PointsAs>)]
    points_as: PointsAs,
    #[command(flatten)]
    post: PostArgs,
    #[command(flatten)]
    shards: batch::BatchArgs,
    #[command(flatten)]
    report: ReportArgs,
    #[command(flatten)]
    input: InputArgs,
}

pub fn run(args: ExportArgs) -> Result<(), CliError> {
    let mut recipe = match &args.recipe {
        Some(path) => read_recipe(path)?,
        None => recipe_of(&args)?,
    };
    if let Some(layout) = args.layout {
        recipe.layout = layout;
    }
    if let Some(compress) = args.compress {
        recipe.compress = compress;
    }
    if let Some(path) = &args.save_recipe {
        check_output(path, args.report.force)?;
    }
    // The recipe is saved once the run has happened (a batch whose models
    // partly failed ran it too); a refused run leaves no file behind.
    let save = || -> Result<(), CliError> {
        match &args.save_recipe {
            Some(path) => write_output(path, &recipe.to_json()),
            None => Ok(()),
        }
    };
    let entries = match (&args.manifest, &args.file) {
        (Some(m), _) => Some(lodstudio_core::batch::read_manifest(m)?),
        (None, Some(file)) => lodstudio_core::batch::manifest::folder_or_glob(file)
            .map_err(CliError::BadInput)?
            .map(|files| {
                files
                    .into_iter()
                    .map(lodstudio_core::batch::Entry::new)
                    .collect()
            }),
        (None, None) => None,
    };
    if let Some(entries) = entries {
        let ran = batch::run(&args, &recipe, entries)?;
        // The batch ran (whatever became of its models): its recipe is kept.
        save()?;
        super::outputs::commit()?;
        return ran.into_result();
    }
    let file = args.file.as_deref().expect("a file when no manifest");
    let format = output_format(&args.output).ok_or_else(|| {
        CliError::BadInput(format!(
            "{}: export writes glTF: name the output .glb or .gltf",
            args.output.display()
        ))
    })?;
    check_output(&args.output, args.report.force)?;
    if format == Format::Gltf {
        check_output(&args.output.with_extension("bin"), args.report.force)?;
    }
    let scene_input = io::scene::is_scene(file);
    // One mesh has no scene to lay out: its chain is MSFT_lod nodes.
    if !scene_input && recipe.layout != lodstudio_core::scene::Layout::MsftLod {
        return Err(CliError::BadInput(format!(
            "{}: --layout {} lays out a glTF scene's nodes; this input is one mesh, written as an MSFT_lod chain (leave --layout out)",
            file.display(),
            recipe.layout.name()
        )));
    }
    let j = match scene_input {
        true => scene::export_scene(
            &args.input,
            &recipe,
            file,
            &args.output,
            args.report.force,
            args.poses as usize,
        )?,
        false => export_one(&args.input, &recipe, file, &args.output)?,
    };
    save()?;
    if args.report.json {
        println!("{j}");
    } else if j.get("meshes").is_some() {
        scene::print_summary(&j);
    } else {
        print_summary(&j);
    }
    Ok(())
}

/// Reads a recipe file; a bad value's error names the file, row and field.
pub fn read_recipe(path: &Path) -> Result<Recipe, CliError> {
    Recipe::read(path).map_err(CliError::BadInput)
}

/// The recipe the options describe.
fn recipe_of(args: &ExportArgs) -> Result<Recipe, CliError> {
    let lods = args.lods.as_deref().expect("--lods without --recipe");
    let mut rows = parse_lods(lods, args.method).map_err(CliError::BadInput)?;
    let post = args.post.post()?;
    let explicit_post = args.post.no_simplify
        || args.post.post_error.is_some()
        || args.post.post_triangles.is_some();
    for row in &mut rows {
        if row.tolerance != lodstudio_core::recipe::RowTolerance::Source {
            row.bake = args.bake.choice();
            row.texture = args.bake.texture_size;
        }
        match row.method {
            Method::EdgeCollapse => {
                row.uv_tolerance = args.uv_tolerance;
                row.attribute_weights = args.attribute_weights;
                if row.tolerance != lodstudio_core::recipe::RowTolerance::Source {
                    row.topology = args.topology;
                }
            }
            Method::Hybrid => {
                row.kappa = args.kappa.or(row.kappa);
                row.tau = args.tau.or(row.tau);
            }
            Method::Voxel => {
                row.resolution = args.resolution.or(row.resolution);
                if explicit_post {
                    row.post = Some(post.into());
                }
            }
            _ => {}
        }
    }
    let mut recipe = Recipe::new(rows);
    recipe.pixels = args.pixels;
    recipe.viewport_height = args.viewport_height;
    recipe.coverage = args.coverage;
    recipe.points_as = args.points_as;
    recipe.keep_seams = args.keep_seams;
    recipe.lock_borders = args.lock_borders;
    recipe.weld = match (args.input.no_weld, args.input.weld_tolerance) {
        (true, _) => lodstudio_core::recipe::WeldSpec::Off,
        (_, Some(t)) => lodstudio_core::recipe::WeldSpec::Tolerance(t),
        _ => lodstudio_core::recipe::WeldSpec::Exact,
    };
    // Options are named as the CLI names them, not as the recipe's fields.
    recipe.check().map_err(|e| {
        let field = e.field.rsplit('.').next().unwrap_or(&e.field);
        let option = match field {
            "tolerance" if e.field.starts_with("weld") => "--weld-tolerance",
            "tolerance" => "--lods",
            "post" => "--post-error / --post-triangles",
            "kappa" => "--kappa",
            "tau" => "--tau",
            "resolution" => "--resolution",
            "pixels" => "--pixels",
            "viewport_height" => "--viewport-height",
            "coverage" => "--coverage",
            "uv_tolerance" => "--uv-tolerance",
            "texture" => "--texture-size",
            "attribute_weights" => "--attribute-weights",
            "topology" => "--topology",
            _ => "--lods",
        };
        CliError::BadInput(format!("{option}: {}", e.message))
    })?;
    Ok(recipe)
}

/// Builds `recipe`'s chain of `file`, writes it to `output` and returns the
/// JSON report (nothing is printed).
fn export_one(
    input: &InputArgs,
    recipe: &Recipe,
    file: &Path,
    output: &Path,
) -> Result<serde_json::Value, CliError> {
    let mut options = input.load_options()?;
    options.repair.weld = recipe.weld();
    let loaded = open_input(file, &options)?;
    let start = std::time::Instant::now();
    let chain = build_chain(&loaded.model, recipe, &Progress::new()).map_err(|e| match e {
        ChainError::Cancelled => CliError::Failure("cancelled".into()),
        e => CliError::BadInput(format!("{}: {e}", file.display())),
    })?;
    let mut bytes = 0;
    for (path, data) in
        io::gltf_writer::encode_file(output, &chain.glb()).map_err(CliError::BadInput)?
    {
        bytes += data.len();
        write_output(&path, &data)?;
    }
    let seconds = start.elapsed().as_secs_f64();
    let mesh = match &loaded.model {
        Model::Mesh(m) => Some(m),
        _ => None,
    };
    let mut report = report(&chain, file, output, bytes, seconds, mesh);
    // What the input held that the chain does not carry (issue 49).
    report["dropped"] = serde_json::json!(loaded.asset.dropped);
    Ok(report)
}

/// The JSON report of a written chain.
fn report(
    chain: &Chain,
    file: &Path,
    output: &Path,
    bytes: usize,
    seconds: f64,
    input: Option<&lodstudio_core::TriMesh>,
) -> serde_json::Value {
    let diag = chain.diagonal;
    let flags = chain.flags();
    let per_lod: Vec<serde_json::Value> = chain
        .lods
        .iter()
        .zip(&chain.coverages)
        .zip(&flags)
        .enumerate()
        .map(|(k, ((l, c), flags))| {
            let tolerances: Vec<String> = l
                .rows
                .iter()
                .map(|&r| chain.recipe.rows[r].tolerance.to_string())
                .collect();
            let mut j = serde_json::json!({
                "tolerance": tolerances.join(","),
                "rows": l.labels,
                "method": l.method.tag(),
                "triangles": l.set.mesh.triangles.len(),
                "points": l.set.points.len(),
                "splats": l.set.splats.len(),
                "layers": l.set.layers.len(),
                // What a client draws (points as --points-as writes them).
                "drawn_primitives": chain.drawn(k),
                "vertices": l.set.mesh.positions.len(),
                "error_bound": l.bound(),
                "error_bound_relative": l.bound() / diag,
                "error_bound_kind": l.set.error_bound_kind.name(),
                "screen_coverage": c,
                "build_seconds": l.build_seconds,
                // Geometric bounds say nothing of textures: how far the UVs
                // moved beyond what the bound carries them (baked LODs and
                // impostors wear atlases of their own).
                "uv_error": input
                    .filter(|_| l.baked.is_none() && l.method != Method::Impostor)
                    .and_then(|m| lodstudio_core::distance::uv_error(m, &l.set.mesh, l.bound())),
            });
            // Its own texture, when it was baked.
            if let Some(baked) = &l.baked {
                j["baked"] = serde_json::json!(baked);
            }
            // A budget the row could not reach, and why.
            if let Some(unmet) = &l.set.unmet {
                j["unmet"] = serde_json::json!(unmet);
            }
            // Rows that do not earn their place, and why.
            if !flags.is_empty() {
                j["flags"] = flags.iter().map(Flag::json).collect();
            }
            j
        })
        .collect();
    let first = chain.recipe.rows[0].method;
    let method = if chain.recipe.rows.iter().all(|r| r.method == first) {
        first.tag()
    } else {
        "mixed"
    };
    serde_json::json!({
        "file": file.display().to_string(),
        "method": method,
        "lods": per_lod,
        "bytes": bytes,
        "input_triangles": input.map_or(0, |m| m.triangles.len()),
        "bbox_diagonal": diag,
        "pixels": chain.recipe.pixels,
        "viewport_height": chain.recipe.viewport_height,
        "seconds": seconds,
        "output": output.display().to_string(),
    })
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum Format {
    Glb,
    Gltf,
}

fn output_format(path: &Path) -> Option<Format> {
    match path.extension()?.to_str()?.to_ascii_lowercase().as_str() {
        "glb" => Some(Format::Glb),
        "gltf" => Some(Format::Gltf),
        _ => None,
    }
}

/// The human summary of one export report.
fn print_summary(j: &serde_json::Value) {
    let lods = j["lods"].as_array().map_or(&[][..], |l| &l[..]);
    println!(
        "{} -> {}: {} LODs, {} bytes, {:.2} s (MSFT_lod; thresholds for {} px on {} px)",
        j["file"].as_str().unwrap_or_default(),
        j["output"].as_str().unwrap_or_default(),
        lods.len(),
        j["bytes"],
        j["seconds"].as_f64().unwrap_or_default(),
        j["pixels"],
        j["viewport_height"]
    );
    for (i, l) in lods.iter().enumerate() {
        println!(
            "  lod{i} {:>14}: {:>8} triangles, {:>7} points, {:>5} splats ({} drawn), bound {:.6} ({:.4}% of the diagonal), shown from coverage {:.4}",
            l["rows"].as_array().map_or(String::new(), |r| {
                r.iter()
                    .filter_map(|v| v.as_str())
                    .collect::<Vec<_>>()
                    .join(",")
            }),
            l["triangles"],
            l["points"],
            l["splats"],
            l["drawn_primitives"],
            l["error_bound"].as_f64().unwrap_or_default(),
            100.0 * l["error_bound_relative"].as_f64().unwrap_or_default(),
            l["screen_coverage"].as_f64().unwrap_or_default(),
        );
        let notes = [&l["unmet"]]
            .into_iter()
            .chain(l["flags"].as_array().into_iter().flatten());
        for why in notes.filter_map(|n| n["why"].as_str()) {
            println!("        ! {why}");
        }
    }
}
