//! Building a merge tree on a worker (merge-tree paper §4) and handing it to
//! the studio as a live cut that refines while the camera moves (§5).

use std::sync::Arc;
use std::time::Instant;

use lodstudio_core::io::Model;
use lodstudio_core::mergetree::{self, MergeTreeView};
use lodstudio_core::progress::{Cancelled, Progress};

use super::{Built, Plot, Row, mesh_of};
use crate::settings::BuildParams;
use crate::settings::mergetree::MergeTreeSettings;

/// Builds the merge tree of `model`'s mesh.
///
/// # Errors
/// `Err(Cancelled)` when `progress` was cancelled; `Ok(Err(message))` when the
/// model is no triangle mesh.
pub fn run(
    model: &Model,
    settings: MergeTreeSettings,
    progress: &Progress,
) -> Result<Result<Built, String>, Cancelled> {
    let mesh = match mesh_of(model) {
        Ok(mesh) => mesh,
        Err(message) => return Ok(Err(message.replace("Edge collapse", "The merge tree"))),
    };
    let settings = settings.sanitized();
    let start = Instant::now();
    let tree = Arc::new(mergetree::build(mesh, &settings.options(), progress)?);
    let seconds = start.elapsed().as_secs_f32();
    progress.stage("first cut");
    let levels = tree.levels().to_vec();
    let dependencies = tree.dependency_count();
    let merges = tree.merges().len();
    let rows = vec![
        Row {
            label: "tree levels",
            value: levels.len().to_string(),
            hint: "Depth of the merge tree (§4.1): each level collapses as many \
                   independent edges as it can.",
        },
        Row {
            label: "merges",
            value: merges.to_string(),
            hint: "Nodes of the tree: vertex pairs merged, each with its up- and \
                   down-switch distances (§5.1).",
        },
        Row {
            label: "dependencies",
            value: dependencies.to_string(),
            hint: "Vertices that must be present before a merge or split (§4.3).",
        },
        Row {
            label: "build time",
            value: format!("{seconds:.2} s"),
            hint: "Time to build the tree, its ranges and dependencies.",
        },
    ];
    let plot = Plot {
        title: "vertices per tree level",
        x_label: "level",
        y_label: "vertices",
        log_y: true,
        series: vec![(
            "merge tree".to_string(),
            levels
                .iter()
                .enumerate()
                .map(|(i, &n)| [i as f64, n as f64])
                .collect(),
        )],
    };
    Ok(Ok(Built::live(
        Box::new(MergeTreeView::new(tree, settings.criteria())),
        mesh.bounds(),
        BuildParams::MergeTree(settings.options()),
        seconds,
        rows,
        vec![plot],
    )))
}
