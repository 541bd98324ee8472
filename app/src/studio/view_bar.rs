//! The bar above the viewport: which version is shown and how it is coloured.

use lodstudio_core::lod::DrawSet;

use super::StudioApp;
use crate::live_cut::set_has_errors;

/// Which version of the model the viewport shows.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum View {
    Original,
    /// The last build's result (the original while there is none).
    Simplified,
    /// The original on the left, the result on the right, through one camera.
    SideBySide,
}

impl View {
    /// Whether the result (the LOD) is on screen.
    pub fn shows_lod(self) -> bool {
        self != View::Original
    }
}

impl StudioApp {
    /// Original / simplified toggle and the heat-map switch above the viewport.
    pub(super) fn view_bar(&mut self, ui: &mut egui::Ui) {
        let has_result = self.has_lod();
        // What the bar colours: the chain LOD shown, else the live cut.
        let shown_set = self.shown_set();
        let has_heat = shown_set.is_some_and(set_has_errors);
        let region = shown_set.and_then(DrawSet::regions);
        let live = shown_set.is_some();
        // Without a result the original is what is shown, whatever was chosen.
        let mut shown = if has_result {
            self.view
        } else {
            View::Original
        };
        let mut heat = self.heat;
        egui::Frame::new()
            .inner_margin(egui::Margin::symmetric(6, 3))
            .show(ui, |ui| {
                ui.horizontal_wrapped(|ui| {
                    ui.add_enabled_ui(has_result, |ui| {
                        ui.selectable_value(&mut shown, View::Original, "Original")
                            .on_hover_text("Show the model as opened.");
                        ui.selectable_value(&mut shown, View::Simplified, "Simplified")
                            .on_hover_text("Show the last build's result, or the chain's row or switch preview.")
                            .on_disabled_hover_text("Build a LOD first.");
                        ui.selectable_value(&mut shown, View::SideBySide, "Side by side")
                            .on_hover_text(
                                "The original on the left, the result on the right, seen through \
                                 one camera: orbiting either turns both.",
                            )
                            .on_disabled_hover_text("Build a LOD first.");
                        ui.separator();
                        ui.add_enabled(
                            shown.shows_lod() && has_heat,
                            egui::Checkbox::new(&mut heat, "Colour by certified bound"),
                        )
                        .on_hover_text(
                            "Colour each simplified triangle (and each point of a hybrid cut) \
                             by its guaranteed error bound, from dark (near 0) to yellow (the \
                             largest).",
                        )
                        .on_disabled_hover_text(
                            "Only edge collapse, hybrid and merge-tree cuts carry a bound per \
                             primitive.",
                        );
                    });
                    ui.separator();
                    ui.add_enabled(
                        live,
                        egui::Checkbox::new(&mut self.by_type, "Colour by type"),
                    )
                    .on_hover_text("Triangles orange, points blue; splats keep their textures.")
                    .on_disabled_hover_text("Build a hierarchy first.");
                    ui.add_enabled(
                        region.is_some(),
                        egui::Checkbox::new(
                            &mut self.regions,
                            format!("Colour by {}", region.unwrap_or("region")),
                        ),
                    )
                    .on_hover_text(
                        "Merge tree: each triangle by the highest tree level among its display \
                         vertices (dark: original, yellow: the coarsest). AMG: each domain \
                         primitive in a hue of its own. Voxel: each translucent layer in a hue \
                         of its own.",
                    )
                    .on_disabled_hover_text(
                        "Merge-tree cuts, AMG splats and layered voxel cuts have regions.",
                    );
                    ui.add_enabled(
                        live,
                        egui::Checkbox::new(&mut self.outlines, "Splat outlines"),
                    )
                    .on_hover_text("Outline every domain primitive (AMG paper, Fig. 12).")
                    .on_disabled_hover_text("Build a hierarchy first.");
                    ui.checkbox(&mut self.wireframe, "Wireframe")
                        .on_hover_text("Draw every triangle edge over the surface.");
                    ui.separator();
                    ui.checkbox(&mut self.viewport.camera.fly, "Fly")
                        .on_hover_text(
                            "Walk through the scene: W/S forward and back, A/D sideways, Q/E down \
                         and up (Shift: faster); drag to look around.",
                        );
                });
            });
        if has_result {
            self.view = shown;
            self.heat = heat;
        }
    }
}
