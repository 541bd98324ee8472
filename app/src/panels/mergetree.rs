//! Parameters of view-dependent simplification with merge trees (merge-tree
//! paper) and their controls: how the tree is built (§4, §6) and which
//! criteria refine or coarsen it while the camera moves (§3, §5).

use std::ops::RangeInclusive;

use lodstudio_core::mergetree::{Criteria, MergeTreeOptions};
use lodstudio_core::simplify::CollapseOptions;
use serde::{Deserialize, Serialize};

const MIN_VERTICES_RANGE: RangeInclusive<usize> = 4..=100_000;
const QUALITY_RANGE: RangeInclusive<f32> = 0.0..=0.5;

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

/// Everything the merge tree needs besides the mesh.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct MergeTreeSettings {
    pub min_vertices: usize,
    pub min_quality: f32,
    pub backface: bool,
    pub silhouette: bool,
    pub lighting: bool,
    /// The light comes from the eye (else from azimuth/elevation).
    pub light_from_eye: bool,
    /// Degrees.
    pub light_azimuth: f32,
    pub light_elevation: f32,
}

impl Default for MergeTreeSettings {
    fn default() -> Self {
        let o = MergeTreeOptions::default();
        let c = Criteria::default();
        MergeTreeSettings {
            min_vertices: o.min_vertices,
            min_quality: o.collapse.min_quality,
            backface: c.backface,
            silhouette: c.silhouette,
            lighting: c.lighting,
            light_from_eye: true,
            light_azimuth: 45.0,
            light_elevation: 45.0,
        }
    }
}

impl MergeTreeSettings {
    pub fn sanitized(self) -> Self {
        let d = Self::default();
        let q = if self.min_quality.is_nan() {
            d.min_quality
        } else {
            self.min_quality
        };
        let angle = |a: f32, lim: f32, f: f32| if a.is_finite() { a.clamp(-lim, lim) } else { f };
        MergeTreeSettings {
            min_vertices: self
                .min_vertices
                .clamp(*MIN_VERTICES_RANGE.start(), *MIN_VERTICES_RANGE.end()),
            min_quality: q.clamp(*QUALITY_RANGE.start(), *QUALITY_RANGE.end()),
            light_azimuth: angle(self.light_azimuth, 180.0, d.light_azimuth),
            light_elevation: angle(self.light_elevation, 90.0, d.light_elevation),
            ..self
        }
    }

    /// What the tree's build depends on (the criteria apply at run time).
    pub fn options(&self) -> MergeTreeOptions {
        MergeTreeOptions {
            min_vertices: self.min_vertices,
            collapse: CollapseOptions {
                min_quality: self.min_quality,
                ..MergeTreeOptions::default().collapse
            },
        }
    }

    pub fn criteria(&self) -> Criteria {
        Criteria {
            backface: self.backface,
            silhouette: self.silhouette,
            lighting: self.lighting,
        }
    }

    /// Direction towards the light, or `None` when it follows the eye.
    pub fn light(&self) -> Option<glam::Vec3> {
        if self.light_from_eye {
            return None;
        }
        let (a, e) = (
            self.light_azimuth.to_radians(),
            self.light_elevation.to_radians(),
        );
        Some(glam::Vec3::new(
            e.cos() * a.sin(),
            e.sin(),
            e.cos() * a.cos(),
        ))
    }

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
                egui::Slider::new(&mut self.light_azimuth, -180.0..=180.0)
                    .suffix("°")
                    .text("light azimuth"),
            )
            .on_hover_text(LIGHT_HINT);
            ui.add(
                egui::Slider::new(&mut self.light_elevation, -90.0..=90.0)
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
