//! Controls of edge collapse: the target that chooses a prefix of the
//! recorded collapses, and the legality rules, explained in the papers' terms.

use crate::settings::simplify::{
    ERROR_PERCENT_RANGE, EdgeCollapseSettings, GUARD_RANGE, MAX_TRIANGLES, RATIO_RANGE, TargetMode,
};

const TARGET_HINT: &str = "Where to stop collapsing edges. Edges collapse in order of \
    quadric error; each collapse merges an edge's two vertices into one and removes the \
    triangles on that edge. The build records every collapse down to 0.1 % of the \
    triangles, each step with its certified bound, so moving the target needs no rebuild.";

const RATIO_HINT: &str = "Keep this fraction of the input's triangles.";

const TRIANGLES_HINT: &str = "Collapse until at most this many triangles remain (fewer \
    are possible only if no legal collapse is left).";

const ERROR_HINT: &str = "As few triangles as possible while the certified two-sided \
    Hausdorff bound stays within this percentage of the bounding-box diagonal.";

const THRESHOLD_HINT: &str = "Follow the view's error threshold (object space, or pixels \
    at the camera) like every other hierarchy: the coarsest step within it.";

const LOCK_HINT: &str = "Border vertices never move, so open boundaries, seams between \
    parts and non-manifold edges keep their exact shape. Off: they may still only slide \
    along the border, never off it.";

const QUALITY_HINT: &str = "Sliver guard: reject a collapse that creates a triangle of \
    quality q = 4√3·area / (l0² + l1² + l2²) below this (merge-tree paper, eq. 3; q = 1 \
    for an equilateral triangle, 0 for a degenerate one), unless the triangle was already \
    worse. 0 turns the guard off.";

const FOLD_HINT: &str = "Fold guard: reject a collapse that turns any triangle's normal \
    by more than the angle whose cosine this is, so the surface does not fold over \
    itself. 0 rejects only turns beyond 90°; higher is stricter.";

impl EdgeCollapseSettings {
    /// The controls; `input_triangles` (the open mesh's count) turns a ratio
    /// into the count it means. True when any value changed.
    pub fn ui(&mut self, ui: &mut egui::Ui, input_triangles: Option<usize>) -> bool {
        let before = *self;
        ui.label("Target").on_hover_text(TARGET_HINT);
        ui.horizontal(|ui| {
            for (mode, name, hint) in [
                (TargetMode::Ratio, "Ratio", RATIO_HINT),
                (TargetMode::Triangles, "Triangles", TRIANGLES_HINT),
                (TargetMode::Error, "Error", ERROR_HINT),
                (TargetMode::Threshold, "Threshold", THRESHOLD_HINT),
            ] {
                ui.selectable_value(&mut self.mode, mode, name)
                    .on_hover_text(hint);
            }
        });
        match self.mode {
            TargetMode::Ratio => {
                ui.add(
                    egui::Slider::new(&mut self.ratio, RATIO_RANGE)
                        .logarithmic(true)
                        .text("ratio"),
                )
                .on_hover_text(RATIO_HINT);
                if let Some(n) = input_triangles {
                    let kept = (f64::from(self.ratio) * n as f64).round() as usize;
                    ui.weak(format!("≈ {kept} of {n} triangles"));
                }
            }
            TargetMode::Triangles => {
                ui.horizontal(|ui| {
                    ui.add(
                        egui::DragValue::new(&mut self.triangles)
                            .range(1..=MAX_TRIANGLES)
                            .speed(10.0),
                    )
                    .on_hover_text(TRIANGLES_HINT);
                    match input_triangles {
                        Some(n) => ui.weak(format!("of {n} triangles")),
                        None => ui.weak("triangles"),
                    };
                });
            }
            TargetMode::Error => {
                ui.add(
                    egui::Slider::new(&mut self.error_percent, ERROR_PERCENT_RANGE)
                        .logarithmic(true)
                        .suffix(" %")
                        .text("error"),
                )
                .on_hover_text(ERROR_HINT);
                ui.weak("of the bounding-box diagonal");
            }
            TargetMode::Threshold => {
                ui.weak("the error threshold below chooses");
            }
        }
        ui.checkbox(&mut self.lock_borders, "Lock borders")
            .on_hover_text(LOCK_HINT);
        ui.add(egui::Slider::new(&mut self.min_quality, GUARD_RANGE).text("sliver guard"))
            .on_hover_text(QUALITY_HINT);
        ui.add(egui::Slider::new(&mut self.min_normal_cos, GUARD_RANGE).text("fold guard"))
            .on_hover_text(FOLD_HINT);
        let degrees = self.min_normal_cos.clamp(-1.0, 1.0).acos().to_degrees();
        ui.weak(format!("normals may turn up to {degrees:.0}°"));
        *self != before
    }
}
