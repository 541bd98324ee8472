//! One edge-collapse build of the open model, done on a worker thread: the
//! simplified mesh with its certificate, the scenes the viewport shows for it,
//! and the inspector rows that report it.

use std::sync::Arc;
use std::time::Instant;

use lodstudio_core::TriMesh;
use lodstudio_core::io::Model;
use lodstudio_core::progress::{Cancelled, Progress};
use lodstudio_core::simplify::{Simplified, SimplifyError, SimplifyOptions, simplify};

use crate::heatmap;
use crate::viewport::Scene;

/// One inspector row, with what it means when hovered.
pub struct Row {
    pub label: &'static str,
    pub value: String,
    pub hint: &'static str,
}

/// A finished build.
pub struct Built {
    pub simplified: Simplified,
    pub options: SimplifyOptions,
    pub input_triangles: usize,
    /// Bounding-box diagonal of the input (what relative errors refer to).
    pub diagonal: f32,
    /// Time for collapsing and certifying.
    pub seconds: f32,
    /// The simplified mesh as the viewport draws it...
    pub scene: Arc<Scene>,
    /// ...and coloured by each triangle's certified bound.
    pub heat_scene: Arc<Scene>,
    /// The value the heat map's brightest colour stands for.
    pub heat_max: f32,
    pub rows: Vec<Row>,
}

/// The triangle mesh edge collapse works on, or why there is none.
///
/// # Errors
/// A message for the user naming what the model is instead.
pub fn mesh_of(model: &Model) -> Result<&TriMesh, String> {
    let what = match model {
        Model::Mesh(mesh) if !mesh.triangles.is_empty() => return Ok(mesh),
        Model::Mesh(_) => "a mesh without triangles".to_string(),
        Model::Points(points) => format!("a point set ({} points)", points.positions.len()),
        Model::Volume(_) => "a volume".to_string(),
    };
    Err(format!(
        "Edge collapse needs a triangle mesh, and this model is {what}."
    ))
}

/// Simplifies `model` and prepares everything the studio shows of the result.
///
/// # Errors
/// `Err(Cancelled)` when `progress` was cancelled; `Ok(Err(message))` when the
/// model or the options do not allow a build.
pub fn run(
    model: &Model,
    options: SimplifyOptions,
    progress: &Progress,
) -> Result<Result<Built, String>, Cancelled> {
    let mesh = match mesh_of(model) {
        Ok(mesh) => mesh,
        Err(message) => return Ok(Err(message)),
    };
    let start = Instant::now();
    let simplified = match simplify(mesh, &options, progress) {
        Ok(s) => s,
        Err(SimplifyError::Cancelled) => return Err(Cancelled),
        Err(e @ SimplifyError::BadTarget(_)) => return Ok(Err(e.to_string())),
    };
    let seconds = start.elapsed().as_secs_f32();
    progress.check()?;
    progress.stage("preparing the view");
    let scene = Arc::new(Scene::from_mesh(&simplified.mesh));
    let bounds = &simplified.certificate.triangle_bounds;
    let heat_max = bounds
        .iter()
        .copied()
        .filter(|b| b.is_finite())
        .fold(0.0, f32::max);
    let colors: Vec<_> = bounds
        .iter()
        .map(|&b| heatmap::linear(if heat_max > 0.0 { b / heat_max } else { 0.0 }))
        .collect();
    let heat_scene = Arc::new(Scene::from_mesh_with_triangle_colors(
        &simplified.mesh,
        &colors,
    ));
    let diagonal = mesh.bounds().diagonal();
    let input_triangles = mesh.triangles.len();
    let rows = rows(&simplified, input_triangles, diagonal, seconds);
    Ok(Ok(Built {
        simplified,
        options,
        input_triangles,
        diagonal,
        seconds,
        scene,
        heat_scene,
        heat_max,
        rows,
    }))
}

fn rows(simplified: &Simplified, input: usize, diagonal: f32, seconds: f32) -> Vec<Row> {
    let certificate = &simplified.certificate;
    let bound = simplified.error_bound();
    let relative = if bound.is_finite() && diagonal > 0.0 {
        format!("{:.3} %", 100.0 * bound / diagonal)
    } else {
        "—".to_string()
    };
    vec![
        Row {
            label: "original triangles",
            value: input.to_string(),
            hint: "Triangles of the model as opened (after repair).",
        },
        Row {
            label: "simplified triangles",
            value: simplified.mesh.triangles.len().to_string(),
            hint: "Triangles left after the edge collapses.",
        },
        Row {
            label: "certified bound",
            value: length(bound),
            hint: "Guaranteed upper bound on the two-sided Hausdorff distance between the \
                   original and the simplified surface: no point of either lies farther \
                   than this from the other (hybrid paper §5.2).",
        },
        Row {
            label: "bound / diagonal",
            value: relative,
            hint: "The certified bound as a percentage of the bounding-box diagonal.",
        },
        Row {
            label: "forward (O to S)",
            value: length(certificate.forward),
            hint: "Bound on the distance from any point of the original O to the \
                   simplified surface S.",
        },
        Row {
            label: "reverse (S to O)",
            value: length(certificate.reverse),
            hint: "Bound on the distance from any point of the simplified surface S to \
                   the original O.",
        },
        Row {
            label: "collapses",
            value: simplified.collapses.to_string(),
            hint: "Edge collapses performed (for an error target: in the final run).",
        },
        Row {
            label: "build time",
            value: format!("{seconds:.2} s"),
            hint: "Time to collapse and certify, without preparing the view.",
        },
    ]
}

/// A distance with four significant digits (model units vary wildly).
pub fn length(x: f32) -> String {
    if !x.is_finite() {
        return "unbounded".to_string();
    }
    if x == 0.0 {
        return "0".to_string();
    }
    let decimals = (3 - x.abs().log10().floor() as i32).clamp(0, 9) as usize;
    format!("{x:.decimals$}")
}

#[cfg(test)]
mod tests {
    use super::*;
    use lodstudio_core::builtins::torus;
    use lodstudio_core::geom::PointSet;
    use lodstudio_core::simplify::{CollapseOptions, Target};

    #[test]
    fn lengths_keep_four_significant_digits() {
        assert_eq!(length(0.012_345_6), "0.01235");
        assert_eq!(length(12.345_67), "12.35");
        assert_eq!(length(12_345.6), "12346");
        assert_eq!(length(0.0), "0");
        assert_eq!(length(f32::INFINITY), "unbounded");
    }

    #[test]
    fn builds_a_torus_and_explains_points() {
        let options = SimplifyOptions {
            per_triangle_bounds: false,
            target: Target::Ratio(0.25),
            collapse: CollapseOptions::default(),
        };
        let model = Model::Mesh(torus(1.0, 0.35, 32, 16));
        let built = run(&model, options, &Progress::new())
            .expect("not cancelled")
            .expect("a mesh builds");
        assert!(built.simplified.mesh.triangles.len() <= 256);
        assert_eq!(
            built.scene.triangle_count(),
            built.simplified.mesh.triangles.len()
        );
        assert!(built.heat_max > 0.0 && built.heat_max <= built.simplified.error_bound());

        let points = Model::Points(PointSet::default());
        let message = run(&points, options, &Progress::new())
            .expect("not cancelled")
            .err()
            .expect("points do not build");
        assert!(message.contains("needs a triangle mesh"), "{message}");

        let cancelled = Progress::new();
        cancelled.cancel();
        assert!(run(&model, options, &cancelled).is_err());
    }
}
