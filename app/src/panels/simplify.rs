//! Controls of edge collapse: the legality rules of its build, and the
//! budgets (a ratio, a triangle count) that choose a prefix of the recorded
//! collapses as units of the cut section's threshold, explained in the
//! papers' terms.

use crate::settings::simplify::{
    ATTRIBUTE_WEIGHT_RANGE, EdgeCollapseSettings, GUARD_RANGE, MAX_TRIANGLES, RATIO_RANGE,
    TargetMode, TopologyMode, UV_TOLERANCE_RANGE,
};

pub const TARGET_HINT: &str = "Where to stop collapsing edges. Edges collapse in order of \
    quadric error; each collapse merges an edge's two vertices into one and removes the \
    triangles on that edge. The build records every collapse down to 0.1 % of the \
    triangles, each step with its certified bound, so moving the target needs no rebuild.";

pub const RATIO_HINT: &str = "Keep this fraction of the input's triangles.";

pub const TRIANGLES_HINT: &str = "Collapse until at most this many triangles remain (fewer \
    are possible only if no legal collapse is left).";

const LOCK_HINT: &str = "Border vertices never move, so open boundaries, seams between \
    parts and non-manifold edges keep their exact shape. Off: they may still only slide \
    along the border, never off it.";

const TOPOLOGY_HINT: &str = "Where pieces or handles stop the collapse short of the floor, \
    the build may prune small pieces and contract pairs of vertices across gaps and holes \
    (Garland and Heckbert's virtual edges), so pieces merge and holes close. That step is \
    certified against the input, and the collapse goes on from it; cuts before the step \
    are the plain collapse's.";

const QUALITY_HINT: &str = "Sliver guard: reject a collapse that creates a triangle of \
    quality q = 4√3·area / (l0² + l1² + l2²) below this (merge-tree paper, eq. 3; q = 1 \
    for an equilateral triangle, 0 for a degenerate one), unless the triangle was already \
    worse. 0 turns the guard off.";

const FOLD_HINT: &str = "Fold guard: reject a collapse that turns any triangle's normal \
    by more than the angle whose cosine this is, so the surface does not fold over \
    itself. 0 rejects only turns beyond 90°; higher is stricter.";

const WEIGHTS_HINT: &str = "Appearance in the collapse order: what a collapse loses of the \
    normals, texture coordinates and colours at the vertex it removes, as a length (a \
    normal turned by Δn over the distance the vertex moves, a texel shown that far away), \
    times this weight, added to its geometric cost (Hoppe 1999). The certified bound stays \
    geometric; 0 leaves an attribute out.";

const UV_TOLERANCE_HINT: &str = "Seam crossing: a vertex on a UV seam may leave its seam \
    (or two seams may meet) when no texture coordinate the collapse moves lands more than \
    this many texels from where its chart shows it (texture deviation, Cohen et al. 1998). \
    Textured props then go below their seam floor. 0 keeps every seam.";

impl EdgeCollapseSettings {
    /// The build's controls; true when any value changed.
    pub fn ui(&mut self, ui: &mut egui::Ui) -> bool {
        let before = *self;
        ui.checkbox(&mut self.lock_borders, "Lock borders")
            .on_hover_text(LOCK_HINT);
        let mut free = self.topology == TopologyMode::Free;
        if ui
            .checkbox(&mut free, "Prune, merge pieces, close holes")
            .on_hover_text(TOPOLOGY_HINT)
            .changed()
        {
            self.topology = match free {
                true => TopologyMode::Free,
                false => TopologyMode::Keep,
            };
        }
        ui.add(egui::Slider::new(&mut self.min_quality, GUARD_RANGE).text("sliver guard"))
            .on_hover_text(QUALITY_HINT);
        ui.add(egui::Slider::new(&mut self.min_normal_cos, GUARD_RANGE).text("fold guard"))
            .on_hover_text(FOLD_HINT);
        ui.add(
            egui::Slider::new(&mut self.uv_tolerance, UV_TOLERANCE_RANGE)
                .logarithmic(true)
                .text("UV tolerance (texels)"),
        )
        .on_hover_text(UV_TOLERANCE_HINT);
        ui.collapsing("Appearance weights", |ui| {
            let w = &mut self.attribute_weights;
            for (value, name) in [
                (&mut w.normal, "normal"),
                (&mut w.uv, "UV"),
                (&mut w.color, "colour"),
            ] {
                ui.add(
                    egui::Slider::new(value, ATTRIBUTE_WEIGHT_RANGE)
                        .logarithmic(true)
                        .text(name),
                )
                .on_hover_text(WEIGHTS_HINT);
            }
        });
        let degrees = self.min_normal_cos.clamp(-1.0, 1.0).acos().to_degrees();
        ui.weak(format!("normals may turn up to {degrees:.0}°"));
        *self != before
    }

    /// The budget the cut section shows in `mode`'s unit (ratio or
    /// triangles; `input_triangles` turns a ratio into the count it means).
    pub fn budget_ui(&mut self, ui: &mut egui::Ui, input_triangles: Option<usize>) {
        match self.mode {
            TargetMode::Ratio => {
                let name = ui.label("ratio");
                ui.add(egui::Slider::new(&mut self.ratio, RATIO_RANGE).logarithmic(true))
                    .labelled_by(name.id)
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
            TargetMode::Threshold => {}
        }
    }
}
