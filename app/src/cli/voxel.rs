//! `voxel`: low-pass filtered volume buffers and marching cubes (voxel paper).

use super::*;
use lodstudio_core::lod::Input;
use lodstudio_core::voxel::{Filter, VoxelParams};

#[derive(clap::ValueEnum, Debug, Clone, Copy)]
enum FilterArg {
    Gaussian,
    Cone,
}

#[derive(Args, Debug)]
pub struct VoxelArgs {
    /// A mesh (sampled through its generalised winding number), builtin:sphereflake,
    /// builtin:csg-part, or a volume (NRRD, NIfTI, INR, raw).
    file: PathBuf,
    /// Voxels along the longest side of an implicit solid's bounds (volumes keep their grid).
    #[arg(long, default_value_t = VoxelParams::default().resolution)]
    resolution: usize,
    /// Filter support radius R in voxels of that grid.
    #[arg(long, default_value_t = VoxelParams::default().radius)]
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
    /// Multi-layered surfaces (§3): the fewest translucent layers whose
    /// piecewise-constant fit of the density fall-off has a mean density error
    /// at most D (eq. 6); 0.5 gives one layer, 0.03 several.
    #[arg(long, value_name = "D", conflicts_with = "pyramid")]
    layers_error: Option<f32>,
    /// §5: extract at a continuous pyramid position T (0 = finest level, 1 =
    /// the next, 1.5 = halfway between them) from interpolated buffers.
    #[arg(long, value_name = "T", conflicts_with = "pyramid")]
    at: Option<f32>,
    /// Output mesh (.obj, .ply, .glb); with --pyramid, a folder for one .ply per
    /// level; with layers, a .glb holds them all (other formats get one file
    /// per layer, OUT.layerK.EXT beside OUT for K ≥ 1).
    #[arg(short = 'o', long = "output", value_name = "OUT")]
    output: Option<PathBuf>,
    #[command(flatten)]
    post: PostArgs,
    #[command(flatten)]
    save: SaveArgs,
    #[command(flatten)]
    report: ReportArgs,
    #[command(flatten)]
    input: InputArgs,
}

/// What the voxel method samples: a built-in implicit solid, or the model
/// opened (a mesh through its winding number, or a volume on its own grid).
enum VoxelInput {
    Solid(Box<dyn lodstudio_core::implicit::Implicit>),
    Model(Box<Model>),
}

impl VoxelInput {
    fn input(&self) -> Input<'_> {
        match self {
            VoxelInput::Solid(solid) => Input::Solid(solid.as_ref()),
            VoxelInput::Model(model) => model.as_ref().into(),
        }
    }

    /// The input surface levels are certified against, where there is one.
    fn surface(&self) -> Option<&lodstudio_core::TriMesh> {
        match self.input() {
            Input::Mesh(mesh) => Some(mesh),
            Input::Solid(solid) => solid.surface(),
            Input::Points(_) | Input::Volume(_) => None,
        }
    }
}

fn voxel_input(args: &VoxelArgs) -> Result<VoxelInput, CliError> {
    if let Some(solid) = args
        .file
        .to_str()
        .and_then(|s| s.strip_prefix("builtin:"))
        .and_then(builtins::implicit)
    {
        return Ok(VoxelInput::Solid(solid));
    }
    let loaded =
        lodstudio_core::open::open(&args.file, &args.input.load_options()?, &Progress::new())?;
    Ok(VoxelInput::Model(Box::new(loaded.model)))
}

/// The parameters the arguments name (`--at` browses a pyramid).
fn params(args: &VoxelArgs) -> Result<VoxelParams, CliError> {
    let d = VoxelParams::default();
    Ok(VoxelParams {
        resolution: args.resolution,
        radius: args.radius,
        filter: match args.filter {
            FilterArg::Gaussian => Filter::Gaussian,
            FilterArg::Cone => Filter::Cone,
        },
        threshold: args.iso,
        layers_error: args.layers_error.unwrap_or(d.layers_error),
        post: args.post.post()?,
        pyramid: args.pyramid || args.at.is_some(),
        ..d
    })
}

pub fn run(args: VoxelArgs) -> Result<(), CliError> {
    use lodstudio_core::voxel::{self, layers::Layered, pyramid::PyramidCut};
    let voxel_params = params(&args)?;
    let params = Params::Voxel(voxel_params);
    params.validate()?;
    if let Some(t) = args.at
        && !(t.is_finite() && t >= 0.0)
    {
        return Err(CliError::BadInput(format!(
            "--at must be a pyramid position >= 0, got {t}"
        )));
    }
    let input = voxel_input(&args)?;
    if let Some(out) = &args.output {
        check_output(out, args.report.force || (args.pyramid && out.is_dir()))?;
    }
    let progress = Progress::new();
    let level_json = |l: &voxel::VoxelLevel| {
        serde_json::json!({
            "resolution": l.resolution,
            "radius": l.radius,
            "triangles": l.mesh.triangles.len(),
            "components": l.components,
            "genus": l.genus,
        })
    };
    let start = std::time::Instant::now();
    let failed = |_| CliError::Failure("cancelled".into());
    if voxel_params.pyramid {
        args.save.check(args.report.force)?;
        let cut: Box<PyramidCut> = super::build(&params, input.input(), &args.file)?;
        let against = if cut.pyramid.against_input {
            "input surface"
        } else {
            "finest level"
        };
        let diagonal = cut.pyramid.diagonal;
        let with_bound = |mut j: serde_json::Value, bound: f32| {
            if bound.is_finite() {
                j["error_bound"] = bound.into();
                j["error_bound_relative"] = (bound / diagonal.max(f32::MIN_POSITIVE)).into();
            }
            j["empty"] = bound.is_infinite().into();
            j
        };
        args.save.write(
            cut.as_ref(),
            serde_json::json!({"resolution": args.resolution, "radius": args.radius, "file": args.file.display().to_string()}),
        )?;
        let pyramid = cut.pyramid;
        if let Some(t) = args.at {
            let l = pyramid.in_between(t, &progress).map_err(failed)?;
            if let Some(out) = &args.output {
                write_mesh(out, &l.mesh)?;
            }
            let finest = pyramid.level(0, &progress).map_err(failed)?.mesh;
            let reference = input.surface().unwrap_or(&finest);
            let original = lodstudio_core::simplify::Original::new(reference);
            let opts = lodstudio_core::simplify::BoundOptions::for_diagonal(pyramid.diagonal);
            let bound = voxel::pyramid::level_bound(&original, &l.mesh, &opts, &progress)
                .map_err(failed)?;
            let mut j = with_bound(level_json(&l), bound);
            j["error_bound_against"] = against.into();
            j["at"] = t.into();
            j["layers"] = 1.into();
            j["seconds"] = start.elapsed().as_secs_f64().into();
            return report_level(&args, &l, j);
        }
        if let Some(dir) = &args.output {
            std::fs::create_dir_all(dir).map_err(|e| {
                CliError::BadInput(format!("{}: cannot create: {e}", dir.display()))
            })?;
        }
        let mut levels = Vec::new();
        for i in 0..pyramid.levels.len() {
            let l = pyramid.level(i, &progress).map_err(failed)?;
            if let Some(dir) = &args.output {
                let path = dir.join(format!("level{i}_{}.ply", l.resolution));
                check_output(&path, args.report.force)?;
                write_mesh(&path, &l.mesh)?;
            }
            let j = with_bound(level_json(&l), pyramid.error_bounds[i]);
            if !args.report.json {
                println!(
                    "resolution {:>5}  radius {:>7.2}  triangles {:>8}  components {:>4}  genus {:>4}  bound {}",
                    j["resolution"],
                    j["radius"].as_f64().unwrap_or(0.0),
                    j["triangles"],
                    j["components"],
                    j["genus"],
                    j.get("error_bound")
                        .map_or("— (empty)".into(), |b| b.to_string()),
                );
            }
            levels.push(j);
        }
        if args.report.json {
            println!(
                "{}",
                serde_json::json!({
                    "levels": levels,
                    "error_bound_against": against,
                    "vanishes_at": pyramid.vanishes_at(),
                    "bbox_diagonal": pyramid.diagonal,
                    "seconds": start.elapsed().as_secs_f64(),
                })
            );
        }
        return Ok(());
    }
    // One level: its layers (one surface unless δ asks for more), certified
    // against a mesh's surface.
    let built: Box<Layered> = super::build(&params, input.input(), &args.file)?;
    let (Some(l), Some(plan)) = (built.level.as_deref(), built.plan.as_ref()) else {
        return Err(CliError::Failure(
            "internal error: a voxel level without its extraction".into(),
        ));
    };
    if let Some(out) = &args.output {
        write_cut(
            out,
            &lodstudio_core::lod::DrawSet {
                layers: built.layers.clone(),
                ..Default::default()
            },
        )?;
    }
    let mut j = level_json(l);
    j["layers"] = built.layers.len().into();
    j["isodensities"] = serde_json::json!(plan.isodensities);
    j["opacities"] = serde_json::json!(plan.opacities);
    j["layer_triangles"] = serde_json::json!(
        built
            .layers
            .iter()
            .map(|l| l.mesh.triangles.len())
            .collect::<Vec<_>>()
    );
    j["layers_error"] = plan.error.into();
    if let Some(surface) = input.surface() {
        let diagonal = surface.bounds().diagonal().max(f32::MIN_POSITIVE);
        j["error_bound"] = built.error_bound.into();
        j["error_bound_relative"] = (built.error_bound / diagonal).into();
    }
    j["seconds"] = start.elapsed().as_secs_f64().into();
    report_level(&args, l, j)
}

/// Prints one level's JSON, or its summary line.
fn report_level(
    args: &VoxelArgs,
    l: &lodstudio_core::voxel::VoxelLevel,
    j: serde_json::Value,
) -> Result<(), CliError> {
    if args.report.json {
        println!("{j}");
    } else {
        println!(
            "{}: resolution {}, radius {} voxels -> {} triangles, {} components, genus {}, {} layer(s)",
            args.file.display(),
            l.resolution,
            l.radius,
            l.mesh.triangles.len(),
            l.components,
            l.genus,
            j["layers"]
        );
    }
    Ok(())
}
