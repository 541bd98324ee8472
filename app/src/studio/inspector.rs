//! The right panel: the model's summary, the build's rows and plots, and the
//! live cut's counts, bound, timings and picked primitive.

use super::{StudioApp, chain};
use crate::{build, heatmap};

impl StudioApp {
    pub(super) fn inspector(&self, ui: &mut egui::Ui) {
        ui.heading("Inspector");
        if let Some(view) = &self.tileset {
            crate::panels::tiles::tileset_inspector_ui(ui, view, self.tiles.max_sse_px);
            return;
        }
        let Some(current) = &self.current else {
            ui.label("No model loaded");
            return;
        };
        egui::ScrollArea::vertical().show(ui, |ui| {
            egui::Grid::new("inspector grid")
                .num_columns(2)
                .striped(true)
                .show(ui, |ui| {
                    for (label, value) in &current.rows {
                        ui.label(label);
                        ui.label(value);
                        ui.end_row();
                    }
                });
            if let Some(built) = &self.result {
                ui.separator();
                ui.label(egui::RichText::new(built.method().name()).strong());
                egui::Grid::new("build grid")
                    .num_columns(2)
                    .striped(true)
                    .show(ui, |ui| {
                        for row in &built.rows {
                            ui.label(row.label).on_hover_text(row.hint);
                            ui.label(&row.value);
                            ui.end_row();
                        }
                    });
                for plot in &built.plots {
                    ui.separator();
                    ui.label(plot.title);
                    let mut chart = egui_plot::Plot::new(plot.title)
                        .height(140.0)
                        .x_axis_label(plot.x_label)
                        .y_axis_label(if plot.log_y {
                            format!("log10 {}", plot.y_label)
                        } else {
                            plot.y_label.to_string()
                        })
                        .allow_scroll(false)
                        .legend(egui_plot::Legend::default());
                    chart = chart.allow_drag(false);
                    chart.show(ui, |p| {
                        for (name, points) in &plot.series {
                            let pts: Vec<[f64; 2]> = points
                                .iter()
                                .map(|&[x, y]| [x, if plot.log_y { y.max(1e-12).log10() } else { y }])
                                .collect();
                            p.line(egui_plot::Line::new(name.as_str(), egui_plot::PlotPoints::from(pts)));
                        }
                    });
                }
                let live = &built.live;
                ui.separator();
                ui.label(egui::RichText::new("Cut").strong());
                let distance = self.viewport.camera.distance;
                if self.view.shows_lod() && self.chain.shown_lod(distance).is_some() {
                    ui.weak("The viewport shows a chain LOD: see the LOD chain below.");
                    chain::ui::inspector_ui(&self.chain, ui, distance);
                    return;
                }
                let st = live.stats;
                let pixels = self.viewport.core_view().pixels(
                    st.error_bound,
                    self.viewport.camera.target,
                    0.0,
                );
                // A view-dependent cut keeps each primitive within the
                // threshold at its own depth, not its coarsest one at the target.
                let projected = match st.screen_pixels {
                    Some(px) => ("largest on screen", px, "The largest bound of a primitive in view and facing the camera, projected at its own depth: what the pixel threshold limits. Far, hidden and off-screen parts may be coarser."),
                    None => ("bound at target", pixels, "The cut's bound projected at the camera's target distance."),
                };
                egui::Grid::new("cut grid").num_columns(2).striped(true).show(ui, |ui| {
                    let diagonal = current.scene.bounds().diagonal().max(f32::MIN_POSITIVE);
                    for (label, value, hint) in [
                        ("cut triangles", st.triangles.to_string(), "Triangles on the current cut."),
                        ("cut points", st.points.to_string(), "Point primitives (discs) on the current cut."),
                        ("cut splats", st.splats.to_string(), "Textured domain primitives on the current cut."),
                        ("layer triangles", st.layer_triangles.to_string(), "Triangles of the translucent voxel layers."),
                        ("cut bound", build::bound_text(st.error_bound, diagonal), "The cut's object-space error bound (max over its elements); unbounded where there is no input surface to certify against (an implicit solid, a volume)."),
                        ("bound is", st.error_bound_kind.name().to_string(), "Certified: no point of the cut or of the original lies farther than the bound from the other (a dense measurement never exceeds it). Estimate: a measure of the method's own (AMG: the largest distance of a domain's points to its splat's plane), not a bound on the distance to the original."),
                        (projected.0, format!("{:.2} px", projected.1), projected.2),
                        ("cut time", format!("{:.2} ms", st.cut_ms), "Time of the last re-selection of the cut and its scene."),
                        ("frame time", self.frame_summary(), "Median time between frames of the studio over the last second, and the median CPU time of a frame (layout, cut, tessellation and submitting the draw)."),
                        ("picked", self.picked.clone().unwrap_or_else(|| "click the model".into()), "What the last click in the viewport hit on the cut: its type, index and error bound (or domain, layer)."),
                    ] {
                        ui.label(label).on_hover_text(hint);
                        ui.label(value);
                        ui.end_row();
                    }
                });
                if live.has_errors() && self.heat && self.view.shows_lod() {
                    ui.add_space(4.0);
                    ui.label("error bound per primitive");
                    heatmap::legend(ui, &build::length(live.stats.error_bound));
                }
            }
            chain::ui::inspector_ui(&self.chain, ui, self.viewport.camera.distance);
        });
    }
}
