//! `export`: LOD chains as glTF (MSFT_lod + MSFT_screencoverage).

use std::path::Path;

use super::*;
use lodstudio_core::io::gltf_writer::{PointsAs, write_lod_chain};
use lodstudio_core::lod::chain::lod_screen_coverages;
use lodstudio_core::lod::{DrawSet, Method};
use lodstudio_core::simplify;

/// `--method`: a [`Method`] by its tag.
fn parse_method(tag: &str) -> Result<Method, String> {
    Method::from_tag(tag).ok_or_else(|| format!("expected one of {}", Method::tags()))
}

#[derive(Args, Debug)]
pub struct ExportArgs {
    /// A mesh file, builtin:NAME, a folder (every model file in it) or a glob
    /// pattern such as 'models/*.obj' (one output per model, in the folder -o).
    file: PathBuf,
    /// How the LODs are built: simplify (edge collapse, every LOD from the
    /// original, certified), hybrid (cuts of one MRG: triangles + points with
    /// `_RADIUS`), mergetree (uniform cuts of one merge tree), voxel (pyramid
    /// levels, certified against the input), amg (levels of the vertices as
    /// textured splats; bound: the largest domain plane error).
    #[arg(long, value_parser = parse_method, value_name = "simplify|hybrid|mergetree|voxel|amg")]
    method: Method,
    /// Comma-separated LOD tolerances: "1%" (error relative to the bounding-box
    /// diagonal), "8px" (pixels on a --viewport-height screen when the object
    /// covers --coverage of its height), or a bare number in (0,1] (a triangle
    /// ratio). LODs are written in decreasing quality, whatever the order here.
    #[arg(long, value_name = "LIST", allow_hyphen_values = true)]
    lods: String,
    /// Output .glb, or .gltf (with its buffer in OUT.bin beside it); for a
    /// folder or glob input, the folder that receives one MODEL.glb each.
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
    /// Keep UV/normal seams (textured materials map exactly): vertices are not
    /// welded across attribute seams, and seam and border vertices never move.
    #[arg(long, conflicts_with_all = ["weld_tolerance", "no_weld"])]
    keep_seams: bool,
    /// Hybrid: points per triangle's rendering time (κ).
    #[arg(long, default_value_t = 3.0)]
    kappa: f32,
    /// Hybrid: transition factor τ.
    #[arg(long, default_value_t = 1.0)]
    tau: f32,
    /// Voxel: finest pyramid resolution (voxels along the longest side).
    #[arg(long, default_value_t = 64)]
    resolution: usize,
    /// How hybrid points are written: "points" (a POINTS primitive with the
    /// per-point object-space radius `_RADIUS`, for renderers that splat),
    /// "quads" or "discs" (a small double-sided mesh per point, facing its
    /// normal and covering its disc, for clients that draw POINTS as pixels).
    #[arg(long, value_name = "points|quads|discs", default_value = "points", value_parser = str::parse::<PointsAs>)]
    points_as: PointsAs,
    #[command(flatten)]
    post: PostArgs,
    #[command(flatten)]
    report: ReportArgs,
    #[command(flatten)]
    input: InputArgs,
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

pub fn run(mut args: ExportArgs) -> Result<(), CliError> {
    args.input.no_weld |= args.keep_seams;
    args.lock_borders |= args.keep_seams;
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
    if let Some(files) = batch_inputs(&args.file)? {
        return batch(&args, &items, &files);
    }
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
    let j = export_one(&args, &items, &args.file, &args.output)?;
    if args.report.json {
        println!("{j}");
    } else {
        print_summary(&j);
    }
    Ok(())
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

/// The model files a folder or glob names; `None` for one file or built-in.
fn batch_inputs(file: &Path) -> Result<Option<Vec<PathBuf>>, CliError> {
    let text = file.to_string_lossy();
    let mut files: Vec<PathBuf> = if file.is_dir() {
        let entries = std::fs::read_dir(file)
            .map_err(|e| CliError::BadInput(format!("{}: cannot list: {e}", file.display())))?;
        entries
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.is_file() && io::is_model_path(p))
            .collect()
    } else if !file.exists() && text.contains(['*', '?', '[']) {
        let paths = glob::glob(&text)
            .map_err(|e| CliError::BadInput(format!("{text}: bad pattern: {e}")))?;
        paths
            .filter_map(Result::ok)
            .filter(|p| p.is_file())
            .collect()
    } else {
        return Ok(None);
    };
    if files.is_empty() {
        return Err(CliError::BadInput(format!("{text}: no model files there")));
    }
    files.sort();
    Ok(Some(files))
}

/// One export per model into the folder `-o`, a progress bar on stderr, and a
/// summary; failures are reported and the others still written.
fn batch(
    args: &ExportArgs,
    items: &[(String, LodTolerance)],
    files: &[PathBuf],
) -> Result<(), CliError> {
    let dir = &args.output;
    std::fs::create_dir_all(dir)
        .map_err(|e| CliError::BadInput(format!("{}: cannot create: {e}", dir.display())))?;
    let start = std::time::Instant::now();
    let bar = indicatif::ProgressBar::new(files.len() as u64).with_style(
        indicatif::ProgressStyle::with_template("{bar:30} {pos}/{len} {elapsed} {msg}")
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    let (mut done, mut failed) = (Vec::new(), Vec::new());
    for file in files {
        bar.set_message(
            file.file_name()
                .unwrap_or_default()
                .to_string_lossy()
                .into_owned(),
        );
        let stem = file.file_stem().unwrap_or_default().to_string_lossy();
        let stem = stem.strip_suffix(".ply").unwrap_or(&stem);
        let out = dir.join(format!("{stem}.glb"));
        let result = check_output(&out, args.report.force)
            .and_then(|()| export_one(args, items, file, &out));
        match result {
            Ok(j) => done.push(j),
            Err(e) => failed.push(serde_json::json!({
                "file": file.display().to_string(),
                "error": e.message(),
            })),
        }
        bar.inc(1);
    }
    bar.finish_and_clear();
    let seconds = start.elapsed().as_secs_f64();
    if args.report.json {
        println!(
            "{}",
            serde_json::json!({"models": done, "failed": failed, "seconds": seconds})
        );
    } else {
        for j in &done {
            print_summary(j);
        }
        println!(
            "{} of {} models exported to {} in {seconds:.1} s",
            done.len(),
            files.len(),
            dir.display()
        );
    }
    match failed.first() {
        None => Ok(()),
        Some(first) => Err(CliError::BadInput(format!(
            "{} of {} models failed; first: {}: {}",
            failed.len(),
            files.len(),
            first["file"].as_str().unwrap_or_default(),
            first["error"].as_str().unwrap_or_default()
        ))),
    }
}

/// One LOD: what is drawn and its guaranteed (object-space) error bound.
struct Lod {
    label: String,
    set: DrawSet,
    bound: f32,
}

/// Builds the LODs of `file`, writes them to `output` and returns the JSON
/// report (nothing is printed).
fn export_one(
    args: &ExportArgs,
    items: &[(String, LodTolerance)],
    file: &Path,
    output: &Path,
) -> Result<serde_json::Value, CliError> {
    let loaded = lodstudio_core::open::open(file, &args.input.load_options()?, &Progress::new())?;
    // AMG takes point sets too; every other method needs a triangle mesh.
    let mut point_set = None;
    let (mesh, bounds) = match loaded.model {
        Model::Mesh(m) => {
            let b = m.bounds();
            (m, b)
        }
        Model::Points(p) if args.method == Method::Amg => {
            let b = p.bounds();
            point_set = Some(p);
            (lodstudio_core::TriMesh::default(), b)
        }
        other => {
            return Err(CliError::BadInput(format!(
                "{}: this method needs a triangle mesh, not a {}",
                file.display(),
                other.kind()
            )));
        }
    };
    let start = std::time::Instant::now();
    let diag = bounds.diagonal();
    // The bounding box's circumscribed sphere bounds the object.
    let radius = 0.5 * diag;
    // p pixels at coverage C: e = p · 2r / (H · C).
    let pixels_to_error = |p: f32| p * 2.0 * radius / (args.viewport_height * args.coverage);
    let triangles = mesh.triangles.len();
    let mut lods = match args.method {
        Method::EdgeCollapse => simplify_lods(args, items, &mesh, pixels_to_error)?,
        Method::Amg => {
            let points = match point_set {
                Some(p) => p,
                None => lodstudio_core::amg::point_set(&Model::Mesh(mesh.clone()))
                    .ok_or_else(|| CliError::BadInput("no points to decompose".into()))?,
            };
            let hierarchy = amg_hierarchy(&points)?;
            hierarchy_lods(hierarchy, items, points.positions.len(), pixels_to_error)?
        }
        Method::Hybrid => hierarchy_lods(
            hybrid_hierarchy(args, &mesh)?,
            items,
            triangles,
            pixels_to_error,
        )?,
        Method::MergeTree => {
            let hierarchy = merge_tree_hierarchy(&mesh)?;
            hierarchy_lods(hierarchy, items, triangles, pixels_to_error)?
        }
        Method::Voxel => {
            let hierarchy = voxel_hierarchy(args, &mesh)?;
            hierarchy_lods(hierarchy, items, triangles, pixels_to_error)?
        }
    };
    // Decreasing quality: increasing bound, then decreasing primitive count.
    lods.sort_by(|a, b| {
        a.bound
            .total_cmp(&b.bound)
            .then(b.set.primitive_count().cmp(&a.set.primitive_count()))
    });
    // Tolerances met by the same LOD share it (one node, both labels).
    lods.dedup_by(|later, kept| {
        let same = later.bound == kept.bound && later.set == kept.set;
        if same {
            kept.label = format!("{},{}", kept.label, later.label);
        }
        same
    });
    let bounds: Vec<f32> = lods.iter().map(|l| l.bound).collect();
    let coverages = lod_screen_coverages(&bounds, radius, args.pixels, args.viewport_height);
    let sets: Vec<DrawSet> = lods.iter().map(|l| l.set.clone()).collect();
    let glb = write_lod_chain(&sets, &coverages, args.points_as);
    let bytes = write_gltf(output, glb)?;
    let seconds = start.elapsed().as_secs_f64();
    let per_lod: Vec<serde_json::Value> = lods
        .iter()
        .zip(&coverages)
        .map(|(l, c)| {
            serde_json::json!({
                "tolerance": l.label,
                "triangles": l.set.mesh.triangles.len(),
                "points": l.set.points.len(),
                "splats": l.set.splats.len(),
                "layers": l.set.layers.len(),
                "vertices": l.set.mesh.positions.len(),
                "error_bound": l.bound,
                "error_bound_relative": l.bound / diag,
                "error_bound_kind": l.set.error_bound_kind.name(),
                "screen_coverage": c,
                // Geometric bounds say nothing of textures: how far the UVs moved.
                "uv_error": lodstudio_core::distance::uv_error(&mesh, &l.set.mesh),
            })
        })
        .collect();
    let method = args.method.tag();
    Ok(serde_json::json!({
        "file": file.display().to_string(),
        "method": method,
        "lods": per_lod,
        "bytes": bytes,
        "input_triangles": mesh.triangles.len(),
        "bbox_diagonal": diag,
        "pixels": args.pixels,
        "viewport_height": args.viewport_height,
        "seconds": seconds,
        "output": output.display().to_string(),
    }))
}

/// Edge collapse: every LOD simplified from the original, one thread each.
/// Each equals the prefix of the progressive collapse at its count (the
/// `progressive` tests check it triangle for triangle); fresh runs in
/// parallel are faster than recording the whole sequence with a bound per
/// step (the dragon: 3.5 s a run, 46 s to record; BENCHMARKS.md).
fn simplify_lods(
    args: &ExportArgs,
    items: &[(String, LodTolerance)],
    mesh: &lodstudio_core::TriMesh,
    pixels_to_error: impl Fn(f32) -> f32,
) -> Result<Vec<Lod>, CliError> {
    let targets: Vec<(String, Target)> = items
        .iter()
        .map(|(label, tol)| {
            let target = match *tol {
                LodTolerance::Relative(e) => Target::RelativeError(e),
                LodTolerance::Pixels(p) => Target::Error(pixels_to_error(p)),
                LodTolerance::Ratio(r) => Target::Ratio(r),
            };
            (label.clone(), target)
        })
        .collect();
    let collapse = CollapseOptions {
        lock_borders: args.lock_borders,
        ..Default::default()
    };
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
                    scope.spawn(move || simplify::simplify(mesh, &opts, &Progress::new()))
                })
                .collect();
            handles
                .into_iter()
                .map(|h| h.join().unwrap_or_else(|p| std::panic::resume_unwind(p)))
                .collect()
        });
    targets
        .into_iter()
        .zip(results)
        .map(|((label, _), result)| {
            let r = result.map_err(|e| match e {
                simplify::SimplifyError::BadTarget(m) => {
                    CliError::BadInput(format!("--lods {label}: {m}"))
                }
                simplify::SimplifyError::Cancelled => CliError::Failure(e.to_string()),
            })?;
            Ok(Lod {
                label,
                bound: r.error_bound(),
                set: DrawSet {
                    mesh: r.mesh,
                    ..Default::default()
                },
            })
        })
        .collect()
}

/// A hierarchy built for export, as every other part of lodstudio cuts it.
type Built = Result<Box<dyn lodstudio_core::lod::Hierarchy>, CliError>;

fn cancelled(_: lodstudio_core::progress::Cancelled) -> CliError {
    CliError::Failure("cancelled".into())
}

/// The hybrid MRG of `mesh` with `--kappa` and `--tau`.
fn hybrid_hierarchy(args: &ExportArgs, mesh: &lodstudio_core::TriMesh) -> Built {
    let opts = lodstudio_core::hybrid::HybridOptions {
        kappa: args.kappa,
        tau: args.tau,
        ..Default::default()
    };
    opts.validate().map_err(CliError::BadInput)?;
    let mrg = lodstudio_core::hybrid::build(mesh, &opts, &Progress::new()).map_err(cancelled)?;
    Ok(Box::new(lodstudio_core::hybrid::HybridCut::new(
        std::sync::Arc::new(mrg),
    )))
}

/// The merge tree of `mesh` with the default build options and criteria.
fn merge_tree_hierarchy(mesh: &lodstudio_core::TriMesh) -> Built {
    let tree = lodstudio_core::mergetree::build(mesh, &Default::default(), &Progress::new())
        .map_err(cancelled)?;
    Ok(Box::new(lodstudio_core::mergetree::MergeTreeView::new(
        std::sync::Arc::new(tree),
        Default::default(),
    )))
}

/// The pyramid of the mesh's solid, each level certified against the input.
fn voxel_hierarchy(args: &ExportArgs, mesh: &lodstudio_core::TriMesh) -> Built {
    use lodstudio_core::voxel::{Filter, Pyramid, Source, pyramid::PyramidCut};
    let resolutions = lodstudio_core::voxel::RESOLUTION_RANGE;
    if !resolutions.contains(&args.resolution) {
        return Err(CliError::BadInput(format!(
            "--resolution must be in {resolutions:?}, got {}",
            args.resolution
        )));
    }
    let progress = Progress::new();
    let solid = lodstudio_core::implicit::MeshSolid::new(mesh);
    let source = Source::Solid(&solid);
    let mut pyramid = Pyramid::build(source, args.resolution, 1.0, Filter::Gaussian, &progress)
        .map_err(cancelled)?;
    pyramid.post = args.post.post()?;
    pyramid
        .certify(source.surface(), &progress)
        .map_err(cancelled)?;
    Ok(Box::new(PyramidCut::new(pyramid, None)))
}

/// The multiscale of the points (a mesh's vertices), splats at the median radius.
fn amg_hierarchy(points: &lodstudio_core::PointSet) -> Built {
    use lodstudio_core::amg::{self, AmgError, AmgOptions};
    let ms =
        amg::decompose(points, &AmgOptions::default(), &Progress::new()).map_err(|e| match e {
            AmgError::BadInput(m) => CliError::BadInput(m),
            AmgError::Cancelled => CliError::Failure("cancelled".into()),
        })?;
    let texel = ms.default_texel();
    Ok(Box::new(amg::AmgHierarchy::new(ms, texel)))
}

/// Hybrid, merge tree, voxel pyramid, AMG: one hierarchy built once, and an
/// LOD per item chosen from it (`lod::chain`) in object space
/// (view-independent, so every viewer gets the same chain): the coarsest cut
/// within an error, the finest within a share of the `input` primitives
/// (triangles; AMG: points). An error no cut meets is refused.
fn hierarchy_lods(
    mut hierarchy: Box<dyn lodstudio_core::lod::Hierarchy>,
    items: &[(String, LodTolerance)],
    input: usize,
    pixels_to_error: impl Fn(f32) -> f32,
) -> Result<Vec<Lod>, CliError> {
    use lodstudio_core::lod::chain::{ChainItem, choose};
    let diag = hierarchy.diagonal().max(f32::MIN_POSITIVE);
    let view = lodstudio_core::view::View::orbit(glam::Vec3::ZERO, diag, 0.0, 0.0);
    items
        .iter()
        .map(|(label, item)| {
            let wanted = match *item {
                LodTolerance::Relative(f) => ChainItem::Error(f),
                LodTolerance::Pixels(p) => ChainItem::Error(pixels_to_error(p) / diag),
                LodTolerance::Ratio(r) => {
                    ChainItem::Primitives((r as f64 * input as f64).ceil() as usize)
                }
            };
            let set = choose(hierarchy.as_mut(), &view, wanted);
            if let ChainItem::Error(f) = wanted
                && set.error_bound > f * diag * (1.0 + 1e-6)
            {
                return Err(CliError::BadInput(format!(
                    "--lods {label}: no {} cut is that fine (the finest bound is {:.3}% of the diagonal{})",
                    hierarchy.method().tag(),
                    100.0 * set.error_bound / diag,
                    if hierarchy.method() == Method::Voxel { "; raise --resolution" } else { "" },
                )));
            }
            Ok(Lod {
                label: label.clone(),
                bound: set.error_bound,
                set,
            })
        })
        .collect()
}

/// Writes a GLB as is, or as .gltf + .bin by its extension (atomically);
/// returns the bytes written.
fn write_gltf(output: &Path, glb: Vec<u8>) -> Result<usize, CliError> {
    let fail = |p: &Path, e: std::io::Error| {
        CliError::BadInput(format!("{}: cannot write: {e}", p.display()))
    };
    if output_format(output) == Some(Format::Gltf) {
        let bin_path = output.with_extension("bin");
        let bin_name = bin_path
            .file_name()
            .unwrap_or_default()
            .to_string_lossy()
            .into_owned();
        let (json, bin) = io::gltf::split_glb(&glb, &bin_name).ok_or_else(|| {
            CliError::Failure("internal: the GLB writer made no container".into())
        })?;
        io::write_atomic(&bin_path, &bin).map_err(|e| fail(&bin_path, e))?;
        io::write_atomic(output, &json).map_err(|e| fail(output, e))?;
        return Ok(json.len() + bin.len());
    }
    io::write_atomic(output, &glb).map_err(|e| fail(output, e))?;
    Ok(glb.len())
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
            "  lod{i} {:>8}: {:>8} triangles, {:>7} points, {:>5} splats, bound {:.6} ({:.4}% of the diagonal), shown from coverage {:.4}",
            l["tolerance"].as_str().unwrap_or_default(),
            l["triangles"],
            l["points"],
            l["splats"],
            l["error_bound"].as_f64().unwrap_or_default(),
            100.0 * l["error_bound_relative"].as_f64().unwrap_or_default(),
            l["screen_coverage"].as_f64().unwrap_or_default(),
        );
    }
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
