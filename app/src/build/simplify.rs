//! What the inspector shows of an edge-collapse build (hybrid paper §5.2):
//! the recorded collapses down to the floor and the certified bound of
//! every step.

use lodstudio_core::simplify::progressive::{Progressive, ProgressiveCut};

use super::{Inspection, Plot, Row, build_time, length};

pub fn inspect(cut: &ProgressiveCut, seconds: f32) -> Inspection {
    let recorded = cut.progressive();
    Inspection {
        rows: rows(recorded, seconds),
        plots: vec![bound_curve(recorded)],
        voxel: None,
    }
}

fn rows(p: &Progressive, seconds: f32) -> Vec<Row> {
    let floor = p.collapses();
    let bound = p.bound_at(floor);
    vec![
        Row {
            label: "original triangles",
            value: p.triangles_at(0).to_string(),
            hint: "Triangles of the model as opened (after repair).",
        },
        Row {
            label: "recorded collapses",
            value: floor.to_string(),
            hint: "Edge collapses recorded, each with the certified bound of the triangles \
                   it made; the target and the threshold choose how many are shown.",
        },
        Row {
            label: "floor triangles",
            value: p.triangles_at(floor).to_string(),
            hint: "Triangles after every recorded collapse: the coarsest step.",
        },
        Row {
            label: "bound at the floor",
            value: format!(
                "{} ({:.3} %)",
                length(bound),
                100.0 * bound / p.diagonal().max(f32::MIN_POSITIVE)
            ),
            hint: "Guaranteed upper bound on the two-sided Hausdorff distance between the \
                   original and the coarsest step: no point of either lies farther than \
                   this from the other (hybrid paper §5.2).",
        },
        build_time(
            seconds,
            "Time to collapse and bound every step, without preparing the view.",
        ),
    ]
}

/// The certified bound of each step against its triangle count.
fn bound_curve(p: &Progressive) -> Plot {
    let n = p.collapses();
    let stride = (n / 256).max(1);
    let diagonal = p.diagonal().max(f32::MIN_POSITIVE);
    let points = (0..=n)
        .step_by(stride)
        .chain(std::iter::once(n))
        .map(|k| {
            let bound = 100.0 * p.bound_at(k) / diagonal;
            [p.triangles_at(k) as f64, f64::from(bound)]
        })
        .collect();
    Plot {
        title: "certified bound per step",
        x_label: "triangles",
        y_label: "bound (% of the diagonal)",
        log_y: true,
        series: vec![("bound".to_string(), points)],
    }
}

#[cfg(test)]
mod tests {
    use lodstudio_core::builtins::torus;
    use lodstudio_core::geom::PointSet;
    use lodstudio_core::io::Model;
    use lodstudio_core::lod::{BuildError, Knobs, Params, PrefixTarget};
    use lodstudio_core::progress::Progress;
    use lodstudio_core::view::{Tolerance, View};

    use crate::build::{run, tests::source};
    use crate::settings::Method;

    #[test]
    fn builds_a_torus_and_explains_points() {
        let params = Params::default_for(Method::EdgeCollapse);
        let model = source(Model::Mesh(torus(1.0, 0.35, 32, 16)));
        let mut built =
            run(&params, &model, &Knobs::default(), &Progress::new()).expect("a mesh builds");
        assert_eq!(built.method(), Method::EdgeCollapse);
        // The target moves the cut without a rebuild: a quarter of the triangles.
        let live = &mut built.live;
        let knobs = |n| Knobs {
            collapse: Some(PrefixTarget::Triangles(n)),
            ..Default::default()
        };
        live.set_knobs(&knobs(256));
        let view = View::orbit(glam::Vec3::ZERO, 3.0, 0.2, 0.3);
        assert!(live.update(&view, Tolerance::Pixels(1.0)));
        let (n, bound) = (live.stats.triangles, live.stats.error_bound);
        assert!((250..=256).contains(&n), "{n}");
        assert!(bound > 0.0 && bound.is_finite());
        live.set_knobs(&knobs(900));
        live.update(&view, Tolerance::Pixels(1.0));
        assert!(live.stats.triangles > n && live.stats.error_bound <= bound);
        assert!(live.has_errors(), "per-triangle bounds for the heat map");
        // Down to the floor, or as far as the torus's topology lets it go.
        assert!(built.rows.iter().any(
            |r| r.label == "floor triangles" && r.value.parse::<usize>().is_ok_and(|f| f < 64)
        ));

        let points = source(Model::Points(PointSet::default()));
        let Err(BuildError::BadInput(message)) =
            run(&params, &points, &Knobs::default(), &Progress::new())
        else {
            panic!("points do not build");
        };
        assert!(message.contains("needs a triangle mesh"), "{message}");

        let cancelled = Progress::new();
        cancelled.cancel();
        assert!(matches!(
            run(&params, &model, &Knobs::default(), &cancelled),
            Err(BuildError::Cancelled)
        ));
    }
}
