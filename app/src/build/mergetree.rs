//! What the inspector shows of a merge tree (merge-tree paper §4): its
//! levels, merges and dependencies.

use lodstudio_core::mergetree::MergeTreeView;

use super::{Inspection, Plot, Row, build_time};

/// The tree's depth, merges and dependencies, and its vertices per level.
pub fn inspect(view: &MergeTreeView, seconds: f32) -> Inspection {
    let tree = view.tree();
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
        build_time(
            seconds,
            "Time to build the tree, its ranges and dependencies.",
        ),
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
    Inspection {
        rows,
        plots: vec![plot],
        voxel: None,
    }
}
