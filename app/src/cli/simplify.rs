//! `simplify`: edge collapse with a certified two-sided Hausdorff bound.

use super::*;
use lodstudio_core::simplify;
use lodstudio_core::simplify::collapse::AttributeWeights;
use lodstudio_core::simplify::prune::TopologyMode;

#[derive(Args, Debug)]
#[command(group(clap::ArgGroup::new("target").required(true).args(["triangles", "ratio", "error"])))]
pub struct SimplifyArgs {
    /// A mesh file, or builtin:NAME.
    file: PathBuf,
    /// Output mesh (.obj, .ply or .glb).
    #[arg(short = 'o', long = "output", value_name = "OUT")]
    output: PathBuf,
    /// Keep at most N triangles (N >= 1).
    #[arg(long, value_name = "N")]
    triangles: Option<usize>,
    /// Keep at most this fraction of the triangles, in (0, 1].
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
    #[arg(long, value_name = "Q", default_value_t = CollapseOptions::default().min_quality)]
    min_quality: f32,
    /// Seam crossing: texels a collapse may move a texture coordinate off
    /// its UV seam (texture deviation); 0 keeps every seam.
    #[arg(long, value_name = "TEXELS", default_value_t = CollapseOptions::default().uv_tolerance)]
    uv_tolerance: f32,
    /// Appearance in the collapse order, as weights of lengths:
    /// normal=W,uv=W,color=W (any subset, the rest 0; default all 0: the
    /// order is geometric). The certified bound stays geometric.
    #[arg(long, value_name = "WEIGHTS", value_parser = AttributeWeights::parse)]
    attribute_weights: Option<AttributeWeights>,
    /// keep: every component and handle stays (the default). free: components
    /// whose removal costs at most the error (half of it for --error) are
    /// pruned where that lowers the certified bound, and pairs closer than a
    /// cell contracted across gaps and holes where the collapse stops short
    /// (`topology` in the JSON: components and genus before and after, what
    /// pruning and contraction took).
    #[arg(long, value_name = "keep|free", default_value = "keep")]
    topology: TopologyMode,
    #[command(flatten)]
    bake: BakeArgs,
    #[command(flatten)]
    report: ReportArgs,
    /// Also save the progressive collapse, from the input down to this run's
    /// result, each prefix with its certified bound (cut it with `cut`).
    #[command(flatten)]
    save: SaveArgs,
    #[command(flatten)]
    input: InputArgs,
}

pub(super) fn parse_error_target(e: &str) -> Result<Target, CliError> {
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

pub fn run(args: SimplifyArgs) -> Result<(), CliError> {
    check_output(&args.output, args.report.force)?;
    let target = match (args.triangles, args.ratio, &args.error) {
        // "At most 0" cannot be honoured (a mesh keeps a triangle): refused,
        // not answered with what the collapse could reach.
        (Some(0), _, _) => {
            return Err(CliError::BadInput(
                "--triangles must be at least 1, got 0".into(),
            ));
        }
        (Some(n), _, _) => Target::Triangles(n),
        (_, Some(r), _) if !(r > 0.0 && r <= 1.0) => {
            return Err(CliError::BadInput(format!(
                "--ratio must be in (0, 1], got {r}"
            )));
        }
        (_, Some(r), _) => Target::Ratio(r),
        (_, _, Some(e)) => parse_error_target(e)?,
        _ => unreachable!("clap requires one target"),
    };
    let collapse = CollapseOptions {
        lock_borders: args.lock_borders || args.keep_seams,
        min_quality: args.min_quality,
        uv_tolerance: args.uv_tolerance,
        // A baked result wears a new atlas: the old one's seams stop nothing.
        free_seams: args.bake.bake,
        attribute_weights: args.attribute_weights.unwrap_or_default(),
        ..Default::default()
    };
    collapse.validate()?;
    let glb = args
        .output
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("glb"));
    if args.bake.bake && !glb {
        return Err(CliError::BadInput(
            "--bake writes a texture: give a .glb output".into(),
        ));
    }
    if let Some(size) = args.bake.texture_size
        && !lodstudio_core::bake::TEXTURE_SIZE_RANGE.contains(&size)
    {
        return Err(CliError::BadInput(format!(
            "--texture-size must be in {}..={}, got {size}",
            lodstudio_core::bake::TEXTURE_SIZE_RANGE.start(),
            lodstudio_core::bake::TEXTURE_SIZE_RANGE.end(),
        )));
    }
    args.save.check(args.report.force)?;
    let mut input = args.input;
    input.no_weld |= args.keep_seams;
    let mesh = load_mesh(&args.file, &input)?;
    let start = std::time::Instant::now();
    let opts = SimplifyOptions {
        per_triangle_bounds: false,
        target,
        collapse,
    };
    let run = |opts: &SimplifyOptions| {
        let progress = Progress::new();
        match args.topology {
            TopologyMode::Keep => simplify::simplify(&mesh, opts, &progress).map(|r| (r, None)),
            TopologyMode::Free => simplify::prune::simplify_free(&mesh, opts, &progress)
                .map(|f| (f.result, Some(f.report))),
        }
        .map_err(|e| match e {
            simplify::SimplifyError::BadTarget(m) => CliError::BadInput(m),
            simplify::SimplifyError::Cancelled => CliError::Failure(e.to_string()),
        })
    };
    let (mut result, mut topology) = run(&opts)?;
    // Neither --bake nor --no-bake: a textured model's LOD bakes where its
    // seams keep it short of its count or where baked it measures closer
    // to the original (`bake::choice`).
    let mut automatic = false;
    let mut baked = None;
    if args.bake.bake {
        baked = Some(
            lodstudio_core::bake::bake(
                &mesh,
                &result.mesh,
                args.bake.texture_size(&mesh, result.mesh.triangles.len()),
            )
            .map_err(CliError::Failure)?,
        );
    } else if args.bake.choice().is_none() && !args.keep_seams && glb {
        let mut free = opts;
        free.collapse.free_seams = true;
        if let Some((free, b)) = lodstudio_core::bake::bake_unasked(
            &mesh,
            &result.mesh,
            lodstudio_core::bake::Asked {
                unmet: result.unmet.as_ref(),
                count: args.error.is_none(),
                size: args.bake.texture_size,
            },
            || run(&free),
            |r| &r.0.mesh,
            CliError::Failure,
        )? {
            ((result, topology), baked, automatic) = (free, Some(b), true);
        }
    }
    let seconds = start.elapsed().as_secs_f64();
    write_mesh(
        &args.output,
        baked.as_ref().map_or(&result.mesh, |b| &b.mesh),
    )?;
    if args.save.save.is_some() {
        // The record down to this run's result, built as every
        // edge-collapse hierarchy is.
        let floor = result.mesh.triangles.len();
        let params = Params::EdgeCollapse(simplify::progressive::ProgressiveOptions {
            collapse: CollapseOptions {
                free_seams: collapse.free_seams || automatic,
                ..collapse
            },
            floor: Some(floor),
            topology: args.topology,
        });
        let progressive: Box<simplify::progressive::ProgressiveCut> =
            super::build(&params, &mesh, &args.file)?;
        args.save.write(
            progressive.as_ref(),
            serde_json::json!({
                "file": args.file.display().to_string(),
                "floor": floor,
                "lock_borders": opts.collapse.lock_borders,
                "min_quality": opts.collapse.min_quality,
                "topology": args.topology,
            }),
        )?;
    }
    let diag = mesh.bounds().diagonal();
    let bound = result.error_bound();
    if args.report.json {
        let mut report = serde_json::json!({
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
        });
        // A count the collapse could not reach, and why.
        if let Some(unmet) = &result.unmet {
            report["unmet"] = serde_json::json!(unmet);
        }
        if let Some(b) = &baked {
            report["baked"] = serde_json::json!(b.report);
        }
        if let Some(t) = &topology {
            report["topology"] = serde_json::json!(t);
        }
        println!("{report}");
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
        if let Some(u) = &result.unmet {
            eprintln!(
                "note: asked for {} triangles, reached {}: {}",
                u.asked, u.reached, u.why
            );
        }
    }
    Ok(())
}
