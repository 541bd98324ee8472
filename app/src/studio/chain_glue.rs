//! The studio's side of the LOD chain (the component in `chain/`): the calls
//! scripted sessions and tests make, the per-frame poll, the chain panel, and
//! what the chain asks of the studio (a build of the model on screen, a
//! measurement with the viewport's renderer, a save, a log line).

use std::path::{Path, PathBuf};
use std::sync::Arc;

use lodstudio_core::recipe::Recipe;

use super::StudioApp;
use super::chain::{self, BuiltChain, ChainEvent, ChainRequest, LodDifference, Source, Target};
use crate::settings::chain::ChainSettings;

impl StudioApp {
    /// The chain's rows and settings (what Save recipe… writes).
    pub fn chain_settings(&self) -> &ChainSettings {
        &self.chain.settings
    }

    /// Replaces the chain's recipe (as opening a recipe does).
    pub fn set_chain_recipe(&mut self, recipe: Recipe) {
        self.chain.set_recipe(recipe);
    }

    /// Builds the chain on the model on screen, replacing any chain build.
    pub fn build_chain(&mut self, ctx: &egui::Context) {
        if let Some(event) = self.chain.start_build(self.chain_source(), ctx) {
            self.report_chain(event);
        }
    }

    /// Replaces the rows by the Auto chain rule's and builds them on the
    /// model on screen, leaving out the rows the chain flags.
    pub fn auto_chain(&mut self, ctx: &egui::Context) {
        if let Some(event) = self.chain.start_auto(self.chain_source(), ctx) {
            self.report_chain(event);
        }
    }

    /// Reopens the chain the last session built on the model on screen with
    /// the rows on the panel, when its work was kept.
    pub(super) fn reopen_chain(&mut self, ctx: &egui::Context) {
        if let Some(source) = self.chain_source()
            && let Some(event) = self.chain.reopen(source, ctx)
        {
            self.report_chain(event);
        }
    }

    fn chain_source(&self) -> Option<Source> {
        self.current.as_ref().map(|c| Source {
            loaded: Arc::clone(&c.loaded),
            path: c.path.clone(),
        })
    }

    pub fn is_building_chain(&self) -> bool {
        self.chain.is_building()
    }

    /// The last chain built for the model on screen.
    pub fn built_chain(&self) -> Option<&BuiltChain> {
        self.chain.built()
    }

    /// Renders every LOD of the built chain and the original off-screen,
    /// from the viewport's camera and from 8 views around, on a worker.
    pub fn measure_difference(&mut self, ctx: &egui::Context) {
        let original = self.current.as_ref().map(|c| &c.scene);
        let camera = self.viewport.camera;
        if let Some(event) =
            self.chain
                .start_measuring(ctx, self.render_state.as_ref(), original, camera)
        {
            self.report_chain(event);
        }
    }

    pub fn is_measuring_difference(&self) -> bool {
        self.chain.is_measuring()
    }

    /// The last visual difference of the built chain's LODs.
    pub fn chain_differences(&self) -> Option<&[LodDifference]> {
        self.chain.differences()
    }

    /// Turns the switch preview on at `distance` bounding radii from the
    /// target (off with `None`).
    pub fn set_switch_distance(&mut self, distance: Option<f32>) {
        self.chain
            .set_switch_distance(distance, &mut self.viewport.camera, &mut self.view);
    }

    /// The LOD the switch preview draws, and its name ("LOD1 simplify:2%");
    /// `None` without a preview.
    pub fn switch_lod(&self) -> Option<(usize, String)> {
        self.chain.switch_lod(self.viewport.camera.distance)
    }

    /// Writes the built chain to `path` (GLB, or glTF + bin) on a worker.
    pub fn export_chain_to(&mut self, path: impl Into<PathBuf>, ctx: &egui::Context) {
        let request = self.chain.export(Target::File(path.into())).into();
        self.run_chain_request(request, ctx);
    }

    /// Writes the chain's recipe to `path` on a worker.
    pub fn save_recipe_to(&mut self, path: impl Into<PathBuf>, ctx: &egui::Context) {
        let save = self.chain.save_recipe(Target::File(path.into()));
        self.spawn_save(ctx, save);
    }

    /// Reads a recipe into the chain panel; a bad one is reported (naming
    /// the row and the field) and the rows stay as they were.
    pub fn open_recipe(&mut self, path: &Path) {
        let event = self.chain.open_recipe(path);
        self.report_chain(event);
    }

    /// What the chain's workers and dialog finished, and the dolly's step.
    pub(super) fn poll_chain(&mut self, ctx: &egui::Context) {
        for event in self.chain.poll() {
            self.report_chain(event);
        }
        let now = ctx.input(|i| i.time);
        if self.chain.step_dolly(now, &mut self.viewport.camera) {
            ctx.request_repaint();
        }
    }

    pub(super) fn chain_panel(&mut self, ui: &mut egui::Ui) {
        let context = chain::ui::PanelContext {
            camera: &mut self.viewport.camera,
            view: &mut self.view,
            model_name: self.current.as_ref().map(|c| c.name.as_str()),
            can_render: self.render_state.is_some(),
            saving: self.export.is_some(),
        };
        let requests = chain::ui::panel_ui(&mut self.chain, ui, context);
        for request in requests {
            self.run_chain_request(request, ui.ctx());
        }
    }

    fn run_chain_request(&mut self, request: ChainRequest, ctx: &egui::Context) {
        match request {
            ChainRequest::Build => self.build_chain(ctx),
            ChainRequest::Auto => self.auto_chain(ctx),
            ChainRequest::MeasureDifference => self.measure_difference(ctx),
            ChainRequest::Save(save) => self.spawn_save(ctx, save),
            ChainRequest::Report(event) => self.report_chain(event),
        }
    }

    fn report_chain(&mut self, event: ChainEvent) {
        let text = event.to_string();
        match event {
            // Like a model that did not open: in the error window too.
            ChainEvent::RecipeNotOpened(_) => self.load_failed(text),
            event if event.is_error() => self.error(text),
            _ => self.info(text),
        }
    }
}
