//! Exporting what is on screen and saving the built hierarchy, on workers.

use std::path::PathBuf;

use super::StudioApp;
use crate::export::{self, Saved};
use crate::job::{Job, Poll};

/// Why Save hierarchy has nothing to write.
const NOTHING_TO_SAVE: &str = "Nothing to save: build a hierarchy first (a single voxel \
    level is no hierarchy; build the whole pyramid to save one)";

impl StudioApp {
    /// Runs `write` (which may show a dialog) on the last result, on a worker.
    pub(super) fn start_export(
        &mut self,
        ctx: &egui::Context,
        write: impl FnOnce(&lodstudio_core::lod::DrawSet) -> Saved + Send + 'static,
    ) {
        if self.export.is_some() {
            return;
        }
        let Some(built) = &self.result else {
            self.error("Nothing to export yet: build a LOD first".into());
            return;
        };
        // What is on screen: the live cut, every primitive of it.
        let set = built.live.draw_set().clone();
        match Job::spawn("export", "Exporting".into(), ctx, move |_| Ok(write(&set))) {
            Ok(job) => self.export = Some(job),
            Err(e) => self.error(format!("cannot start the export: {e}")),
        }
    }

    pub(super) fn export_dialog(&mut self, ctx: &egui::Context) {
        let (Some(current), Some(built)) = (&self.current, &self.result) else {
            return;
        };
        let name = export::suggested_name(&current.path, built.mesh().triangles.len());
        self.start_export(ctx, move |set| export::choose_and_write(set, &name));
    }

    /// Asks where to write the asset's scene with its LODs, then writes it.
    pub(super) fn export_asset_dialog(&mut self, ctx: &egui::Context) {
        let (Some(current), Some(write)) =
            (&self.current, self.asset.as_ref().and_then(|a| a.export()))
        else {
            return;
        };
        let name = format!(
            "{}-lods.glb",
            current.name.split('.').next().unwrap_or("scene")
        );
        self.spawn_save(ctx, move || {
            let (glbs, layout) = write();
            export::choose_and_write_scene(&glbs, layout, &name)
        });
    }

    /// Writes the asset's scene with its LODs to `path` on a worker (no
    /// dialog), as `lodstudio export` would.
    pub fn export_asset_to(&mut self, path: impl Into<PathBuf>, ctx: &egui::Context) {
        let path = path.into();
        match self.asset.as_ref().and_then(|a| a.export()) {
            Some(write) => self.spawn_save(ctx, move || {
                let (glbs, layout) = write();
                export::write_scene(&glbs, layout, &path)
            }),
            None => self.error("Nothing to export: build for every mesh first".into()),
        }
    }

    /// The running result's hierarchy as saved-hierarchy bytes, with the
    /// parameters it was built with.
    fn hierarchy_bytes(&self) -> Option<Vec<u8>> {
        let built = self.result.as_ref()?;
        let params = serde_json::to_value(built.params).ok()?;
        built.live.save(&params)
    }

    /// Saves the built hierarchy to `path` on a worker (no dialog).
    pub fn save_hierarchy_to(&mut self, path: impl Into<PathBuf>, ctx: &egui::Context) {
        let path = path.into();
        match self.hierarchy_bytes() {
            Some(bytes) => self.spawn_save(ctx, move || export::write_bytes(&bytes, &path)),
            None => self.error(NOTHING_TO_SAVE.into()),
        }
    }

    pub(super) fn save_hierarchy_dialog(&mut self, ctx: &egui::Context) {
        let (Some(current), Some(bytes)) = (&self.current, self.hierarchy_bytes()) else {
            self.error(NOTHING_TO_SAVE.into());
            return;
        };
        let name = format!(
            "{}.lodh",
            current
                .name
                .trim_start_matches("builtin:")
                .split('.')
                .next()
                .unwrap_or("model")
        );
        self.spawn_save(ctx, move || {
            export::choose_and_write_hierarchy(&bytes, &name)
        });
    }

    /// Runs a save (dialog and writing) on a worker, reported like exports.
    pub(super) fn spawn_save(
        &mut self,
        ctx: &egui::Context,
        save: impl FnOnce() -> Saved + Send + 'static,
    ) {
        if self.export.is_some() {
            return;
        }
        match Job::spawn("export", "Saving".into(), ctx, move |_| Ok(save())) {
            Ok(job) => self.export = Some(job),
            Err(e) => self.error(format!("cannot start saving: {e}")),
        }
    }

    pub(super) fn poll_export(&mut self) {
        let Some(job) = &self.export else {
            return;
        };
        let saved = match job.poll() {
            Poll::Running => return,
            Poll::Done(saved) => saved,
            Poll::Lost => Saved::Failed("the export stopped unexpectedly (internal error)".into()),
        };
        self.export = None;
        match saved {
            Saved::Written {
                path,
                bytes,
                beside,
            } => {
                let beside: Vec<String> = beside.iter().map(|p| p.display().to_string()).collect();
                let also = if beside.is_empty() {
                    String::new()
                } else {
                    format!(", with {}", beside.join(", "))
                };
                self.info(format!("Exported {}{also} ({bytes} bytes)", path.display()));
            }
            Saved::NoFile => self.info(
                "Nothing exported: no file chosen (the dialog needs xdg-desktop-portal)".into(),
            ),
            Saved::Failed(message) => self.error(format!("Export failed: {message}")),
        }
    }
}
