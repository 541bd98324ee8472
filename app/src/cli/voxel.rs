//! `voxel`: low-pass filtered volume buffers and marching cubes (voxel paper).

use super::*;

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

/// What the voxel method samples: an implicit solid or a scalar volume.
enum VoxelInput {
    Solid(Box<dyn lodstudio_core::implicit::Implicit>),
    Volume(lodstudio_core::Volume, f32),
    /// A mesh, inside where its generalised winding number is ≥ ½.
    Mesh(lodstudio_core::TriMesh),
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
        Model::Mesh(m) if !m.triangles.is_empty() => Ok(VoxelInput::Mesh(m)),
        other => Err(CliError::BadInput(format!(
            "{}: the voxel method samples solids (meshes, implicit built-ins, volumes), not {} input",
            args.file.display(),
            other.kind()
        ))),
    }
}

pub fn run(args: VoxelArgs) -> Result<(), CliError> {
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
    // What is sampled: a solid (built-in, or a mesh through its winding number)
    // or a volume on its own grid.
    let mesh_solid;
    let sampled: Result<&dyn lodstudio_core::implicit::Implicit, (&lodstudio_core::Volume, f32)> =
        match &input {
            VoxelInput::Solid(solid) => Ok(solid.as_ref()),
            VoxelInput::Mesh(m) => {
                mesh_solid = lodstudio_core::implicit::MeshSolid::new(m);
                Ok(&mesh_solid)
            }
            VoxelInput::Volume(v, iso) => Err((v, *iso)),
        };
    let run = |resolution: usize, radius: f32| match sampled {
        Ok(solid) => {
            voxel::simplify_implicit(solid, resolution, radius, filter, DENSITY_ISO, &progress)
        }
        Err((v, iso)) => voxel::simplify_volume(v, iso, radius, filter, &progress),
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
