//! Building the hybrid multi-resolution graph on a worker (hybrid paper §5),
//! with its triangle-only twin for the primitives-versus-error plot, and
//! handing it to the studio as a live cut (§6).

use std::sync::Arc;
use std::time::Instant;

use lodstudio_core::hybrid::{self, HybridCut, NodeKind};
use lodstudio_core::io::Model;
use lodstudio_core::progress::{Cancelled, Progress};

use super::{Built, Plot, Row, mesh_of};
use crate::settings::BuildParams;
use crate::settings::hybrid::HybridSettings;

/// Points of the curves kept for the plot.
const CURVE_STEPS: usize = 120;

/// Builds the MRG of `model`'s mesh and the triangle-only curve beside it.
///
/// # Errors
/// `Err(Cancelled)` when `progress` was cancelled; `Ok(Err(message))` when the
/// model is no triangle mesh.
pub fn run(
    model: &Model,
    settings: HybridSettings,
    progress: &Progress,
) -> Result<Result<Built, String>, Cancelled> {
    let mesh = match mesh_of(model) {
        Ok(mesh) => mesh,
        Err(message) => {
            return Ok(Err(
                message.replace("Edge collapse", "Hybrid simplification")
            ));
        }
    };
    let opts = settings.options();
    let start = Instant::now();
    let mrg = Arc::new(hybrid::build(mesh, &opts, progress)?);
    let seconds = start.elapsed().as_secs_f32();
    progress.stage("triangle-only curve");
    let triangles_only = hybrid::build(mesh, &opts.triangles_only(), progress)?;
    let input = mesh.triangles.len() as f64;
    let thin = |c: Vec<(f32, f64)>| {
        let mut points = hybrid::curve::thin(&c, CURVE_STEPS);
        points.retain(|p| p[0] > 0.0);
        points.insert(0, [0.0, input]);
        points
    };
    let plot = Plot {
        title: "primitives vs error",
        x_label: "error bound (object space)",
        y_label: "primitives",
        log_y: true,
        series: vec![
            (
                format!("hybrid κ={} τ={}", opts.kappa, opts.tau),
                thin(hybrid::curve::curve(&mrg)),
            ),
            (
                "triangles only".to_string(),
                thin(hybrid::curve::curve(&triangles_only)),
            ),
        ],
    };
    let rows = vec![
        Row {
            label: "MRG nodes",
            value: mrg.nodes.len().to_string(),
            hint: "Nodes of the multi-resolution graph: triangle simplifications (edge \
                   collapses), point replacements and point simplifications (§4).",
        },
        Row {
            label: "edge collapses",
            value: mrg.count(NodeKind::TriangleSimplification).to_string(),
            hint: "TS nodes: each replaces the triangles around an edge (§5.2).",
        },
        Row {
            label: "point replacements",
            value: mrg.count(NodeKind::PointReplacement).to_string(),
            hint: "PR nodes: each replaces one triangle by at most ⌊κ⌋ points (§5.3).",
        },
        Row {
            label: "point merges",
            value: mrg.count(NodeKind::PointSimplification).to_string(),
            hint: "PS nodes: each merges up to 8 points into one sphere (§5.4).",
        },
        Row {
            label: "build time",
            value: format!("{seconds:.2} s"),
            hint: "Time to build the graph (without the triangle-only curve).",
        },
    ];
    progress.stage("first cut");
    Ok(Ok(Built::live(
        Box::new(HybridCut::new(mrg)),
        mesh.bounds(),
        BuildParams::Hybrid(settings.sanitized()),
        seconds,
        rows,
        vec![plot],
    )))
}
