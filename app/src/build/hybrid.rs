//! What the inspector shows of a hybrid build (hybrid paper §5): the
//! multi-resolution graph's nodes, and its primitives against error beside
//! its triangle-only twin's.

use lodstudio_core::hybrid::{self, HybridCut, HybridOptions, NodeKind};
use lodstudio_core::lod::{self, BuildError, Input, Params};
use lodstudio_core::progress::Progress;

use super::{Inspection, Plot, Row, build_time};

/// Points of the curves kept for the plot.
const CURVE_STEPS: usize = 120;

/// The MRG's node counts, and its primitives-versus-error curve beside the
/// triangle-only twin's (built here, on the worker, through `lod::build`).
///
/// # Errors
/// `BuildError::Cancelled` when `progress` was cancelled.
pub fn inspect(
    cut: &HybridCut,
    opts: &HybridOptions,
    input: Input<'_>,
    seconds: f32,
    progress: &Progress,
) -> Result<Inspection, BuildError> {
    let mrg = cut.mrg();
    progress.stage("triangle-only curve");
    let twin = lod::build(&Params::Hybrid(opts.triangles_only()), input, progress)?;
    let triangles_only = twin
        .downcast_ref::<HybridCut>()
        .map(|t| hybrid::curve::curve(t.mrg()))
        .unwrap_or_default();
    let input = mrg.input_triangles as f64;
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
                thin(hybrid::curve::curve(mrg)),
            ),
            ("triangles only".to_string(), thin(triangles_only)),
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
        build_time(
            seconds,
            "Time to build the graph (without the triangle-only curve).",
        ),
    ];
    Ok(Inspection {
        rows,
        plots: vec![plot],
        voxel: None,
    })
}
