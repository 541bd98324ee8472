//! What the inspector shows of an AMG build (AMG paper §2): the levels of
//! the multiscale and their sizes.

use lodstudio_core::amg::AmgHierarchy;
use lodstudio_core::lod::BuildError;
use lodstudio_core::progress::Progress;

use super::{Inspection, Plot, Row};

/// The AMG levels and their sizes; builds the primitives of every level the
/// threshold can choose and of the `shown` one, so the first cuts do not.
///
/// # Errors
/// `BuildError::Cancelled` when `progress` was cancelled.
pub fn inspect(
    hierarchy: &mut AmgHierarchy,
    shown: Option<usize>,
    seconds: f32,
    progress: &Progress,
) -> Result<Inspection, BuildError> {
    let ms = hierarchy.multiscale();
    let points = &ms.points;
    let sizes = ms.level_sizes();
    let plot = Plot {
        title: "unknowns per AMG level",
        x_label: "level",
        y_label: "unknowns",
        log_y: true,
        series: vec![(
            "Ruge–Stüben".to_string(),
            sizes
                .iter()
                .enumerate()
                .map(|(i, &n)| [i as f64, n as f64])
                .collect(),
        )],
    };
    let rows = vec![
        Row {
            label: "points",
            value: points.positions.len().to_string(),
            hint: "Points decomposed (a mesh contributes its vertices).",
        },
        Row {
            label: "AMG levels",
            value: sizes.len().to_string(),
            hint: "Levels of the Ruge–Stüben hierarchy (§2.3), finest first.",
        },
        Row {
            label: "level sizes",
            value: sizes
                .iter()
                .map(|n| n.to_string())
                .collect::<Vec<_>>()
                .join(" "),
            hint: "Unknowns (domains) per level: each level keeps 2–3× fewer.",
        },
        Row {
            label: "decomposition",
            value: format!("{seconds:.2} s"),
            hint: "Neighbourhoods, classifier, stiffness matrix and coarsening.",
        },
    ];
    progress.stage("domain primitives");
    hierarchy.build_levels(shown, progress)?;
    Ok(Inspection {
        rows,
        plots: vec![plot],
        voxel: None,
    })
}
