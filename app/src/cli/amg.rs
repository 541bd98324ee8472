//! `amg`: extreme point-set simplification by algebraic multigrid (AMG paper):
//! decomposition into quasi-flat domains, then textured domain primitives.

use lodstudio_core::amg::{self, AmgParams, Texel};

use super::*;

#[derive(Args, Debug)]
pub struct AmgArgs {
    /// A point set (PLY with or without colours and normals), a mesh (its vertices), or builtin:NAME.
    file: PathBuf,
    /// Neighbours k_min per point for the classifier (§2.1; the paper uses 50–100).
    #[arg(long, default_value_t = AmgParams::default().k)]
    k: usize,
    /// Minimal feature size ε: neighbourhoods grow to the whole ball B_ε (§2.1); 0 = k nearest only.
    #[arg(long, default_value_t = AmgParams::default().epsilon)]
    epsilon: f32,
    /// AMG level to build primitives for, 0 = the points; default L−5 with L the coarsest (§2.3).
    #[arg(long)]
    level: Option<usize>,
    /// Texel size in model units (§3.2); default: the median point radius.
    #[arg(long)]
    texel: Option<f32>,
    /// Output GLB of textured, alpha-blended quads.
    #[arg(short = 'o', long = "output", value_name = "OUT")]
    output: Option<PathBuf>,
    /// Also write the stiffness matrix A (eq. 5–7) as MatrixMarket, e.g. for PyAMG.
    #[arg(long, value_name = "A.mtx")]
    matrix_out: Option<PathBuf>,
    #[command(flatten)]
    save: SaveArgs,
    #[command(flatten)]
    report: ReportArgs,
    #[command(flatten)]
    input: InputArgs,
}

pub fn run(args: AmgArgs) -> Result<(), CliError> {
    let mut amg_params = AmgParams {
        k: args.k,
        epsilon: args.epsilon,
        ..Default::default()
    };
    if let Some(t) = args.texel {
        amg_params.texel = Texel::Length(t);
    }
    let params = Params::Amg(amg_params);
    params.validate()?;
    args.save.check(args.report.force)?;
    for out in [&args.output, &args.matrix_out].into_iter().flatten() {
        check_output(out, args.report.force)?;
    }
    let loaded = open_input(&args.file, &args.input.load_options()?)?;
    let progress = Progress::new();
    let start = std::time::Instant::now();
    let hierarchy: Box<amg::AmgHierarchy> = super::build(&params, &loaded.model, &args.file)?;
    let ms = hierarchy.multiscale();
    let points = &ms.points;
    let seconds_decomposition = start.elapsed().as_secs_f64();
    let coarsest = ms.levels() - 1;
    let level = args.level.unwrap_or(ms.default_level());
    if level > coarsest {
        return Err(CliError::BadInput(format!(
            "--level {level}: the coarsest level is {coarsest}"
        )));
    }
    // The default texel follows the points; one the user names is checked
    // (its domains are found once more for that, not on the default path).
    let texel = hierarchy.texel();
    if args.texel.is_some() {
        amg::primitive::check_texel(ms, level, texel)
            .map_err(|e| CliError::BadInput(format!("--texel: {e}")))?;
    }
    let start = std::time::Instant::now();
    let prims = amg::primitives(ms, level, texel, &progress)
        .map_err(|_| CliError::Failure("cancelled".into()))?;
    let seconds_primitives = start.elapsed().as_secs_f64();
    if args.save.save.is_some() {
        args.save.write(
            hierarchy.as_ref(),
            serde_json::json!({"k": args.k, "texel": texel, "file": args.file.display().to_string()}),
        )?;
    }
    if let Some(out) = &args.matrix_out {
        let mut bytes = Vec::new();
        amg::write_matrix_market(ms, &mut bytes)
            .map_err(|e| CliError::Failure(format!("{}: cannot write: {e}", out.display())))?;
        write_output(out, &bytes)?;
    }
    if let Some(out) = &args.output {
        write_cut(out, &prims.draw_set(None))?;
    }
    let levels: Vec<usize> = (0..ms.levels()).map(|l| ms.domains(l).len()).collect();
    let j = serde_json::json!({
        "points": points.positions.len(),
        "levels": levels,
        "level_sizes": ms.level_sizes(),
        "level": level,
        "coarsest_level": coarsest,
        "primitives": prims.splats.len(),
        "texels": prims.texels(),
        "texel": texel,
        "max_plane_error": prims.errors.iter().copied().fold(0.0, f32::max),
        "error_bound_kind": lodstudio_core::lod::BoundKind::Estimate.name(),
        "seconds_decomposition": seconds_decomposition,
        "seconds_primitives": seconds_primitives,
    });
    if args.report.json {
        println!("{j}");
    } else {
        println!(
            "{}: {} points, domains per level {:?}; level {level} (L-{}): {} primitives, {} texels; decomposition {:.2} s, primitives {:.2} s",
            args.file.display(),
            points.positions.len(),
            levels,
            coarsest - level,
            prims.splats.len(),
            prims.texels(),
            seconds_decomposition,
            seconds_primitives
        );
    }
    Ok(())
}
