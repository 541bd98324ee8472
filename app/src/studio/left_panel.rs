//! The left panel: the model (open, built-in, recent) and the method with
//! its parameters, the cut threshold and Build / Export / Save.

use lodstudio_core::builtins;

use lodstudio_core::lod::{Controls, Knob};

use super::loading::display_name;
use super::{Current, StudioApp};
use crate::settings::Method;

impl StudioApp {
    /// The model section, then the method section, scrolling together
    /// above Build / Export / Save, which stay in view however long the
    /// parameters grow.
    pub(super) fn left_panel(&mut self, ui: &mut egui::Ui) {
        egui::Panel::bottom("build bar")
            .show_separator_line(true)
            .show(ui, |ui| self.build_bar(ui));
        egui::ScrollArea::vertical().show(ui, |ui| {
            self.model_section(ui);
            if let Some(asset) = &mut self.asset {
                ui.separator();
                let response = egui::CollapsingHeader::new("Asset")
                    .default_open(true)
                    .show(ui, |ui| {
                        super::asset::asset_ui(ui, asset, &self.chain.settings.recipe)
                    })
                    .body_returned;
                if response.is_some_and(|r| r.export) {
                    self.export_asset_dialog(ui.ctx());
                }
            }
            ui.separator();
            let can_build = self.current.as_ref().and_then(Current::mesh).is_some();
            let tiles = egui::CollapsingHeader::new("3D Tiles")
                .default_open(self.tileset.is_some())
                .show(ui, |ui| {
                    crate::panels::tiles::tiles_ui(ui, &mut self.tiles, can_build)
                })
                .body_returned;
            if tiles == Some(true) {
                self.build_tileset(None, ui.ctx());
            }
            ui.separator();
            self.method_section(ui);
        });
    }

    fn model_section(&mut self, ui: &mut egui::Ui) {
        ui.heading("Model");
        match &self.current {
            Some(c) => {
                ui.label(egui::RichText::new(&c.name).strong())
                    .on_hover_text(c.path.display().to_string());
            }
            None => match &self.tileset {
                Some(t) => {
                    ui.label(egui::RichText::new(display_name(&t.path)).strong())
                        .on_hover_text(t.path.display().to_string());
                }
                None => {
                    ui.label("No model loaded");
                }
            },
        }
        if ui.button("Open…").clicked() {
            self.open_dialog(ui.ctx());
        }
        egui::CollapsingHeader::new("Built-in models")
            .default_open(true)
            .show(ui, |ui| {
                for (name, description) in builtins::NAMES {
                    if ui.button(*name).on_hover_text(*description).clicked() {
                        self.open(format!("builtin:{name}"));
                    }
                }
            });
        egui::CollapsingHeader::new("Recent files")
            .default_open(true)
            .show(ui, |ui| {
                if self.recent.is_empty() {
                    ui.weak("none yet");
                } else if let Some(path) = self.recent_list(ui) {
                    self.open(path);
                }
            });
    }

    /// The method list, its parameters and the cut.
    fn method_section(&mut self, ui: &mut egui::Ui) {
        ui.heading("Method");
        let mut changed = self.methods.method_list(ui);
        ui.add_space(4.0);
        let input_triangles = self
            .current
            .as_ref()
            .and_then(Current::mesh)
            .map(|m| m.triangles.len());
        match self.methods.method {
            Method::EdgeCollapse => {
                changed |= self.methods.edge_collapse.ui(ui);
            }
            Method::Voxel => {
                let volume = self.current.as_ref().and_then(|c| c.volume);
                changed |= self.methods.voxel.ui(ui, volume.as_ref());
            }
            Method::Hybrid => {
                changed |= self.methods.hybrid.ui(ui);
            }
            Method::Amg => {
                let levels = self
                    .result
                    .as_ref()
                    .filter(|b| b.method() == Method::Amg)
                    .and_then(|b| b.plots.first())
                    .and_then(|p| p.series.first())
                    .map(|s| s.1.len());
                changed |= self.methods.amg.ui(ui, levels);
            }
            Method::MergeTree => {
                // Criteria changes re-cut the live tree; only build options rebuild.
                changed |= self.methods.merge_tree.ui(ui).0;
            }
            // A chain row's kind, not in the method list.
            Method::Impostor => {}
        }
        // The cut: its threshold (or, for edge collapse, a budget as the
        // threshold's unit), disabled saying why where it chooses nothing;
        // before a build, what the chosen method's cut will read.
        let controls = match &self.result {
            Some(built) => built.live.controls(),
            None => Controls {
                knobs: match self.methods.method {
                    Method::EdgeCollapse => &[Knob::CollapseTarget],
                    _ => &[],
                },
                overridden_by: None,
                has_levels: true,
            },
        };
        ui.add_space(4.0);
        ui.label("Cut")
            .on_hover_text("The built hierarchy is cut live for the camera: no rebuild needed.");
        let collapse = controls
            .knobs
            .contains(&Knob::CollapseTarget)
            .then_some((&mut self.methods.edge_collapse, input_triangles));
        // Run-time settings re-cut a result; before the first build they
        // start it (with auto rebuild).
        let cut_changed =
            crate::panels::threshold::cut_ui(ui, &mut self.methods.threshold, collapse, &controls);
        changed |= cut_changed && self.result.is_none();
        ui.add_space(4.0);
        let auto = ui
            .checkbox(&mut self.methods.auto_rebuild, "Auto rebuild")
            .on_hover_text("Rebuild by itself 0.4 s after the last parameter change.");
        if changed || (auto.changed() && self.methods.auto_rebuild && self.result_is_stale()) {
            self.parameters_changed();
        }
    }

    /// Build, Export and Save hierarchy, and why a build cannot start or
    /// is out of date.
    fn build_bar(&mut self, ui: &mut egui::Ui) {
        let input = self.input_check();
        let can_build = matches!(input, Some(Ok(())));
        ui.horizontal(|ui| {
            let build = ui
                .add_enabled(can_build, egui::Button::new("Build"))
                .on_hover_text("Build the LOD now with these parameters.");
            if build.clicked() {
                self.build();
            }
            let can_export = self.result.is_some() && self.export.is_none();
            let export = ui
                .add_enabled(can_export, egui::Button::new("Export…"))
                .on_hover_text("Save what is on screen: glb holds triangles, points, splats and layers; obj and ply get the points in a .points.ply beside them.")
                .on_disabled_hover_text("Build a LOD first.");
            if export.clicked() {
                self.export_dialog(ui.ctx());
            }
            let can_save = self.export.is_none()
                && self.result.as_ref().is_some_and(|b| b.live.has_levels());
            let save = ui
                .add_enabled(can_save, egui::Button::new("Save hierarchy…"))
                .on_hover_text("Save the built hierarchy (versioned, checksummed .lodh) to reopen it later without rebuilding.")
                .on_disabled_hover_text("Build a hierarchy first (a single voxel level is none: build the whole pyramid).");
            if save.clicked() {
                self.save_hierarchy_dialog(ui.ctx());
            }
        });
        let error_color = ui.visuals().error_fg_color;
        if let Some(Err(why)) = &input {
            ui.colored_label(error_color, why.to_string());
        } else if let Some(note) = &self.build_note {
            ui.colored_label(error_color, note);
        } else if self.result.is_some() && !self.is_building() && self.result_is_stale() {
            ui.weak("Parameters changed since the last build.");
        }
    }
}
