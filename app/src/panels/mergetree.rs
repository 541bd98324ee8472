//! Controls of the merge tree: its build options and the run-time criteria.

use crate::settings::mergetree::{
    AZIMUTH_RANGE, ELEVATION_RANGE, MIN_VERTICES_RANGE, MergeTreeSettings, QUALITY_RANGE,
};

const MIN_VERTICES_HINT: &str = "§4.1: the tree is built level by level, collapsing as \
    many edges per level as possible whose regions of influence share no triangle; it stops \
    once this few vertices remain.";

const QUALITY_HINT: &str = "§6 sliver guard: a collapse may not make a triangle of \
    quality 4√3·area / (l0² + l1² + l2²) below this (eq. 3). 0 turns it off (scanned meshes \
    full of slivers stall with it on).";

const BACKFACE_HINT: &str = "Regions whose normal cone faces wholly away from the eye (or \
    lie outside the view) are simplified harder (§3, visibility).";

const SILHOUETTE_HINT: &str = "Regions whose normal cone straddles the view direction (the \
    silhouette) are refined (§3).";

const LIGHTING_HINT: &str = "Regions across which the diffuse shading of the light changes \
    fastest are refined (§3, local illumination).";

const LIGHT_HINT: &str = "Direction of the light for the illumination criterion: from the \
    eye, or fixed by azimuth and elevation.";

impl MergeTreeSettings {
    /// The controls; `(rebuild, recut)`: whether the tree must be rebuilt, and
    /// whether only the run-time criteria changed.
    pub fn ui(&mut self, ui: &mut egui::Ui) -> (bool, bool) {
        let before = *self;
        ui.add(
            egui::Slider::new(&mut self.min_vertices, MIN_VERTICES_RANGE)
                .logarithmic(true)
                .text("min vertices"),
        )
        .on_hover_text(MIN_VERTICES_HINT);
        ui.add(egui::Slider::new(&mut self.min_quality, QUALITY_RANGE).text("sliver guard"))
            .on_hover_text(QUALITY_HINT);
        ui.label("Criteria");
        ui.checkbox(&mut self.backface, "back faces coarser")
            .on_hover_text(BACKFACE_HINT);
        ui.checkbox(&mut self.silhouette, "silhouettes finer")
            .on_hover_text(SILHOUETTE_HINT);
        ui.checkbox(&mut self.lighting, "lighting")
            .on_hover_text(LIGHTING_HINT);
        ui.checkbox(&mut self.light_from_eye, "light from the eye")
            .on_hover_text(LIGHT_HINT);
        if !self.light_from_eye {
            ui.add(
                egui::Slider::new(&mut self.light_azimuth, AZIMUTH_RANGE)
                    .suffix("°")
                    .text("light azimuth"),
            )
            .on_hover_text(LIGHT_HINT);
            ui.add(
                egui::Slider::new(&mut self.light_elevation, ELEVATION_RANGE)
                    .suffix("°")
                    .text("light elevation"),
            )
            .on_hover_text(LIGHT_HINT);
        }
        let rebuild = self.options() != before.options();
        let recut = !rebuild && *self != before;
        (rebuild, recut)
    }
}
