//! Building the AMG multiscale of a point set on a worker (AMG paper §2) and
//! handing it to the studio as a live cut of domain primitives (§3–4).

use std::time::Instant;

use lodstudio_core::amg::{self, AmgError, AmgHierarchy, AmgOptions};
use lodstudio_core::io::Model;
use lodstudio_core::progress::{Cancelled, Progress};

use super::{Built, Plot, Row};
use crate::settings::BuildParams;
use crate::settings::amg::AmgSettings;

/// Decomposes the points of `model` (a point set, or a mesh's vertices).
///
/// # Errors
/// `Err(Cancelled)` when `progress` was cancelled; `Ok(Err(message))` when
/// the model has no points or the decomposition refuses them.
pub fn run(
    model: &Model,
    settings: AmgSettings,
    progress: &Progress,
) -> Result<Result<Built, String>, Cancelled> {
    let Some(points) = amg::point_set(model) else {
        return Ok(Err(
            "AMG simplification needs points: a point set or a mesh's vertices.".into(),
        ));
    };
    // The level shown first: its primitives are built here, not by the first cut.
    let shown = (!settings.auto_level).then_some(settings.level);
    let settings = settings.build_params();
    let opts = AmgOptions {
        k: settings.k,
        ..AmgOptions::default()
    };
    let start = Instant::now();
    let ms = match amg::decompose(&points, &opts, progress) {
        Ok(ms) => ms,
        Err(AmgError::Cancelled) => return Err(Cancelled),
        Err(AmgError::BadInput(m)) => return Ok(Err(m)),
    };
    let seconds = start.elapsed().as_secs_f32();
    let texel = settings.texel * ms.default_texel();
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
    let mut hierarchy = AmgHierarchy::new(ms, texel);
    hierarchy.build_levels(shown, progress)?;
    hierarchy.set_level(shown);
    Ok(Ok(Built::live(
        Box::new(hierarchy),
        points.bounds(),
        BuildParams::Amg(settings),
        seconds,
        rows,
        vec![plot],
    )))
}
