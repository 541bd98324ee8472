//! The menu bar.

use std::path::PathBuf;

use lodstudio_core::builtins;

use super::StudioApp;

impl StudioApp {
    pub(super) fn menu_bar(&mut self, ui: &mut egui::Ui) {
        egui::MenuBar::new().ui(ui, |ui| {
            ui.menu_button("File", |ui| {
                if ui.button("Open…").clicked() {
                    self.open_dialog(ui.ctx());
                }
                ui.menu_button("Built-in models", |ui| {
                    for (name, description) in builtins::NAMES {
                        if ui.button(*name).on_hover_text(*description).clicked() {
                            self.open(format!("builtin:{name}"));
                        }
                    }
                });
                ui.add_enabled_ui(!self.recent.is_empty(), |ui| {
                    ui.menu_button("Recent files", |ui| {
                        if let Some(path) = self.recent_list(ui) {
                            self.open(path);
                        }
                    });
                });
                ui.separator();
                if ui.button("Quit").clicked() {
                    ui.ctx().send_viewport_cmd(egui::ViewportCommand::Close);
                }
            });
        });
    }

    /// Buttons for the recent files; returns the one clicked.
    pub(super) fn recent_list(&self, ui: &mut egui::Ui) -> Option<PathBuf> {
        let mut clicked = None;
        for path in &self.recent {
            let name = path
                .file_name()
                .map_or_else(|| path.to_string_lossy(), |n| n.to_string_lossy());
            if ui
                .button(name)
                .on_hover_text(path.display().to_string())
                .clicked()
            {
                clicked = Some(path.clone());
            }
        }
        clicked
    }
}
