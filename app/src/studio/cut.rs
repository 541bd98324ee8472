//! The live cut on screen: re-selecting it for the camera and the knobs,
//! choosing the scene the view shows, side by side, and picking.

use std::sync::Arc;

use lodstudio_core::lod::{DrawSet, Picked};

use super::{Current, StudioApp, View};
use crate::build;
use crate::live_cut::CutStyle;
use crate::render::Scene;

impl StudioApp {
    /// Re-selects a live cut for the camera and the threshold (only when the
    /// hierarchy says they change it).
    pub(super) fn update_cut(&mut self) {
        let style = self.cut_style();
        if let Some(live) = self.result.as_mut().map(|b| &mut b.live) {
            live.set_style(style);
            let mut view = self.viewport.core_view();
            let input_triangles = self
                .current
                .as_ref()
                .and_then(Current::mesh)
                .map_or(0, |m| m.triangles.len());
            let mt = &self.methods.merge_tree;
            if let Some(light) = mt.light() {
                view.light_dir = light;
            }
            live.set_knobs(&self.methods.knobs(input_triangles));
            live.update(&view, self.methods.threshold.tolerance());
        }
    }

    /// How the view bar asks a LOD to be drawn (the live cut or a chain LOD).
    fn cut_style(&self) -> CutStyle {
        let lod = self.view.shows_lod();
        CutStyle {
            heat: self.heat && lod,
            by_type: self.by_type && lod,
            regions: self.regions && lod,
            outlines: self.outlines,
            wireframe: self.wireframe,
        }
    }

    /// The primitives the viewport draws as the LOD: a chain row's or the
    /// switch preview's when one is shown, else the live cut's.
    pub(super) fn shown_set(&self) -> Option<&DrawSet> {
        let chain = self.chain.shown_set(self.viewport.camera.distance);
        chain
            .filter(|_| self.view.shows_lod())
            .or_else(|| self.result.as_ref().map(|b| b.live.draw_set()))
    }

    /// Shows the scene the view toggles ask for (uploads only on a change).
    pub(super) fn sync_view(&mut self) {
        if self.sync_tileset() {
            return;
        }
        if let Some(preview) = &self.preview {
            // Watching the build: its intermediate state.
            self.viewport.swap_scene(preview);
            return;
        }
        // A glTF asset as its nodes place it, when asked for.
        if let Some(asset) = self.asset.as_mut().filter(|a| a.show) {
            let scene = asset.view_scene();
            self.viewport.swap_scene(&scene);
            return;
        }
        // A chain row or the switch preview, when one is asked for.
        if self.view.shows_lod()
            && let Some(scene) = self
                .chain
                .scene(self.viewport.camera.distance, self.cut_style())
        {
            self.viewport.swap_scene(&scene);
            return;
        }
        let scene = match (&self.result, self.view) {
            (Some(built), View::Simplified | View::SideBySide) => Arc::clone(built.live.scene()),
            _ => match self.original_scene() {
                Some(scene) => scene,
                None => return,
            },
        };
        self.viewport.swap_scene(&scene);
    }

    /// The model as opened, with its wireframe when that is on (made once).
    fn original_scene(&mut self) -> Option<Arc<Scene>> {
        let current = self.current.as_mut()?;
        if !self.wireframe || current.mesh().is_none() {
            return Some(Arc::clone(&current.scene));
        }
        if current.wire_scene.is_none()
            && let Some(mesh) = current.mesh()
        {
            current.wire_scene = Some(Arc::new(Scene::clone(&current.scene).with_wireframe(mesh)));
        }
        current.wire_scene.clone()
    }

    /// Shows a new result, side by side with the original if that is the view.
    pub(super) fn show_result(&mut self) {
        if self.view == View::Original {
            self.view = View::Simplified;
        }
    }

    /// Compares the original (left) with the result (right, the main viewport:
    /// cuts are taken and picked there) through one camera.
    pub(super) fn show_side_by_side(&mut self, ui: &mut egui::Ui) {
        let Some(original) = self.original_scene() else {
            return;
        };
        self.compare.swap_scene(&original);
        self.compare.follow(&self.viewport);
        let full = ui.available_rect_before_wrap();
        let (left, right) = full.split_left_right_at_fraction(0.5);
        let gap = egui::vec2(1.0, 0.0);
        ui.scope_builder(egui::UiBuilder::new().max_rect(left.shrink2(gap)), |ui| {
            self.compare.show(ui);
        });
        if !self.compare.same_camera(&self.viewport) {
            self.viewport.follow(&self.compare);
        }
        ui.scope_builder(egui::UiBuilder::new().max_rect(right.shrink2(gap)), |ui| {
            self.viewport.show(ui);
        });
    }

    /// Inspects what a click in the viewport hit on the live cut.
    pub(super) fn pick(&mut self) {
        let Some((origin, dir)) = self.viewport.take_click() else {
            return;
        };
        let Some(set) = self.shown_set() else {
            return;
        };
        let diagonal = self
            .current
            .as_ref()
            .map_or(1.0, |c| c.scene.bounds().diagonal())
            .max(f32::MIN_POSITIVE);
        let bound = |e: f32| format!("bound {} ({:.3} %)", build::length(e), 100.0 * e / diagonal);
        // Merge-tree triangles also tell their tree level.
        let level = |t: usize| {
            set.triangle_levels
                .get(t)
                .map_or(String::new(), |l| format!(", level {l}"))
        };
        self.picked = Some(match set.pick(origin, dir) {
            None => "nothing under the pointer".to_string(),
            Some((_, Picked::Triangle { index, error })) => match error {
                Some(e) => format!("triangle {index}, {}{}", bound(e), level(index)),
                None => format!("triangle {index}{}", level(index)),
            },
            Some((
                _,
                Picked::Point {
                    index,
                    radius,
                    error,
                },
            )) => {
                format!(
                    "point {index}, radius {}, {}",
                    build::length(radius),
                    bound(error)
                )
            }
            Some((_, Picked::Splat { index, domain })) => format!("splat {index}, domain {domain}"),
            Some((_, Picked::Layer { layer, isodensity })) => {
                format!("voxel layer {layer}, isodensity {isodensity:.3}")
            }
        });
    }
}
