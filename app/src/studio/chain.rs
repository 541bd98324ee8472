//! The LOD chain, the studio's main object: rows from any method built on a
//! worker by the builder `lodstudio export` uses (`recipe::build_chain`, so
//! the studio's chain export is byte for byte the CLI's), a row shown on
//! click, the switch preview (a dolly from near to far drawing the LOD the
//! chain uses there, with the bound in pixels at each switch), and the
//! chain's export and recipe files.

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::mpsc::{Receiver, TryRecvError};

use lodstudio_core::distance::visual::Difference;
use lodstudio_core::io::LoadOptions;
use lodstudio_core::lod::Texture;
use lodstudio_core::progress::Cancelled;
use lodstudio_core::recipe::{Chain, ChainError, Recipe, build_chain};

use super::StudioApp;
use super::loading::{MAX_RECENT, absolute, pick_file};
use crate::export;
use crate::job::{Job, Poll};
use crate::panels::chain::RowFigures;
use crate::render::camera::{coverage_at_distance, distance_at_coverage};
use crate::render::{Camera, Offscreen, Scene, SceneStyle};
use crate::settings::chain::ChainSettings;

/// Seconds the dolly takes from near to far.
const DOLLY_SECONDS: f64 = 6.0;
/// The visual difference's fixed views around the model, and their size.
const DIFFERENCE_VIEWS: usize = 8;
const DIFFERENCE_SIZE: [u32; 2] = [256, 256];

/// One LOD against the original, rendered by the viewport's renderer from
/// the camera and from [`DIFFERENCE_VIEWS`] views around the model.
#[derive(Debug, Clone)]
pub struct LodDifference {
    /// From the viewport's camera.
    pub here: Difference,
    /// The means over the fixed views.
    pub around: Difference,
    /// Where they differ from the viewport's camera (red: only the original
    /// covers, green: only the LOD, else the shading's difference × 4).
    pub image: Texture,
}

/// A chain built for the model on screen, with what the viewport and the
/// table show of it.
pub struct BuiltChain {
    pub chain: Arc<Chain>,
    /// One scene per LOD, made on the worker.
    scenes: Vec<Arc<Scene>>,
    /// Per recipe row: its LOD and its table cells.
    figures: Vec<RowFigures>,
}

impl BuiltChain {
    /// The recipe it was built with.
    pub fn recipe(&self) -> &Recipe {
        &self.chain.recipe
    }

    fn new(chain: Chain) -> BuiltChain {
        let scenes = chain
            .lods
            .iter()
            .map(|l| Arc::new(Scene::from_draw_set(&l.set, &SceneStyle::default())))
            .collect();
        let figures = figures(&chain);
        BuiltChain {
            chain: Arc::new(chain),
            scenes,
            figures,
        }
    }
}

/// The table's cells of every recipe row (rows met by one cut share its LOD).
fn figures(chain: &Chain) -> Vec<RowFigures> {
    let mut out: Vec<Option<RowFigures>> = vec![None; chain.recipe.rows.len()];
    for (k, lod) in chain.lods.iter().enumerate() {
        let c_out = chain.coverages[k];
        let c_in = chain.coverage_in(k);
        let set = &lod.set;
        let cells = [
            set.mesh.triangles.len().to_string(),
            set.points.len().to_string(),
            set.splats.len().to_string(),
            format!(
                "{} ({:.3}%)",
                crate::build::length(lod.bound()),
                100.0 * lod.bound() / chain.diagonal
            ),
            format!("{:.2}", chain.pixels_at(k, c_in)),
            format!("{c_out:.4} · {:.1} r", distance_at_coverage(c_out)),
            format!("{:.2} s", lod.build_seconds),
        ];
        let estimate = set.error_bound_kind == lodstudio_core::lod::BoundKind::Estimate;
        for &r in &lod.rows {
            out[r] = Some(RowFigures {
                lod: k,
                cells: cells.clone(),
                estimate,
            });
        }
    }
    out.into_iter()
        .map(|f| f.expect("every row has its LOD"))
        .collect()
}

/// The switch preview: the camera's distance (in bounding radii) picks the
/// LOD a loader would draw there.
#[derive(Debug, Clone, Copy, Default)]
struct SwitchPreview {
    on: bool,
    /// egui time the dolly started at, while it runs.
    dolly_from: Option<f64>,
}

/// The chain panel's state.
#[derive(Default)]
pub(super) struct ChainView {
    pub(super) settings: ChainSettings,
    job: Option<Job<Result<BuiltChain, String>>>,
    built: Option<BuiltChain>,
    /// The recipe row whose LOD is shown.
    selected: Option<usize>,
    preview: SwitchPreview,
    picker: Option<Receiver<Option<PathBuf>>>,
    pub(super) recent_recipes: Vec<PathBuf>,
    /// Why the last chain build failed.
    note: Option<String>,
    /// The visual difference of every LOD, measuring or measured.
    measuring: Option<Job<Result<Vec<LodDifference>, String>>>,
    differences: Option<Vec<LodDifference>>,
    /// The shown LOD's difference image, uploaded once.
    difference_image: Option<(usize, egui::TextureHandle)>,
}

impl StudioApp {
    /// The chain's rows and settings (what Save recipe… writes).
    pub fn chain_settings(&self) -> &ChainSettings {
        &self.chain.settings
    }

    /// Replaces the chain's recipe (as opening a recipe does).
    pub fn set_chain_recipe(&mut self, recipe: Recipe) {
        self.chain.settings.recipe = recipe;
        self.chain.selected = None;
    }

    /// Builds the chain on the model on screen, replacing any chain build.
    pub fn build_chain(&mut self, ctx: &egui::Context) {
        self.chain.note = None;
        // A measurement of the chain being replaced would land on the new one.
        self.chain.measuring = None;
        let Some(current) = &self.current else {
            self.chain.note = Some("Open a model first".into());
            return;
        };
        let recipe = self.chain.settings.recipe.clone();
        let loaded = Arc::clone(&current.loaded);
        let path = current.path.clone();
        let work = move |progress: &lodstudio_core::Progress| {
            // The model as `lodstudio export` loads it for this recipe.
            let reloaded;
            let model = if recipe.weld() == LoadOptions::default().repair.weld {
                &loaded.model
            } else {
                let mut options = LoadOptions::default();
                options.repair.weld = recipe.weld();
                match lodstudio_core::open::open(&path, &options, progress) {
                    Ok(l) => {
                        reloaded = l;
                        &reloaded.model
                    }
                    Err(e) => return Ok(Err(e.to_string())),
                }
            };
            match build_chain(model, &recipe, progress) {
                Ok(chain) => Ok(Ok(BuiltChain::new(chain))),
                Err(ChainError::Cancelled) => Err(Cancelled),
                Err(ChainError::BadInput(m)) => Ok(Err(m)),
            }
        };
        match Job::spawn("chain", "Chain".into(), ctx, work) {
            Ok(job) => self.chain.job = Some(job),
            Err(e) => self.error(format!("cannot start the chain build: {e}")),
        }
    }

    pub fn is_building_chain(&self) -> bool {
        self.chain.job.is_some()
    }

    /// The last chain built for the model on screen.
    pub fn built_chain(&self) -> Option<&BuiltChain> {
        self.chain.built.as_ref()
    }

    /// Renders every LOD of the built chain and the original off-screen,
    /// from the viewport's camera and from 8 views around, on a worker.
    pub fn measure_difference(&mut self, ctx: &egui::Context) {
        let (Some(rs), Some(built), Some(current)) =
            (&self.render_state, &self.chain.built, &self.current)
        else {
            self.error("Visual difference: build the chain (with a GPU renderer) first".into());
            return;
        };
        let mut offscreen = Offscreen::new(rs);
        let original = Arc::clone(&current.scene);
        let lods = built.scenes.clone();
        let mut cameras = vec![self.viewport.camera];
        cameras.extend(Camera::views_around(
            original.sphere(),
            DIFFERENCE_VIEWS,
            1.0,
        ));
        let work = move |progress: &lodstudio_core::Progress| {
            progress.stage("visual difference");
            let mut out = Vec::with_capacity(lods.len());
            for (k, lod) in lods.iter().enumerate() {
                progress.check()?;
                progress.set_fraction(k as f32 / lods.len() as f32);
                let views = match offscreen.compare(&original, lod, &cameras, DIFFERENCE_SIZE) {
                    Ok(v) => v,
                    Err(e) => return Ok(Err(e)),
                };
                let around = &views[1..];
                let mean = |f: fn(&Difference) -> f64| {
                    around.iter().map(|v| f(&v.difference)).sum::<f64>() / around.len() as f64
                };
                out.push(LodDifference {
                    here: views[0].difference,
                    around: Difference {
                        silhouette: mean(|d| d.silhouette),
                        psnr: mean(|d| d.psnr),
                    },
                    image: views[0].image.clone(),
                });
            }
            Ok(Ok(out))
        };
        match Job::spawn("difference", "Visual difference".into(), ctx, work) {
            Ok(job) => self.chain.measuring = Some(job),
            Err(e) => self.error(format!("cannot start the visual difference: {e}")),
        }
    }

    pub fn is_measuring_difference(&self) -> bool {
        self.chain.measuring.is_some()
    }

    /// The last visual difference of the built chain's LODs.
    pub fn chain_differences(&self) -> Option<&[LodDifference]> {
        self.chain.differences.as_deref()
    }

    /// Turns the switch preview on at `distance` bounding radii from the
    /// target (off with `None`).
    pub fn set_switch_distance(&mut self, distance: Option<f32>) {
        self.preview_on(distance.is_some());
        self.chain.preview.dolly_from = None;
        if let (Some(d), Some(r)) = (distance, self.chain_radius()) {
            self.viewport.camera.distance = d * r;
        }
    }

    /// The LOD the switch preview draws, and its name ("LOD1 simplify:2%");
    /// `None` without a preview.
    pub fn switch_lod(&self) -> Option<(usize, String)> {
        let built = self
            .chain
            .built
            .as_ref()
            .filter(|_| self.chain.preview.on)?;
        let r = self.chain_radius()?;
        let c = coverage_at_distance(self.viewport.camera.distance / r);
        let chain = &built.chain;
        let k = chain.lod_at_coverage(c).unwrap_or(chain.lods.len() - 1);
        Some((k, format!("LOD{k} {}", chain.lods[k].labels.join(","))))
    }

    /// Writes the built chain to `path` (GLB, or glTF + bin) on a worker.
    pub fn export_chain_to(&mut self, path: impl Into<PathBuf>, ctx: &egui::Context) {
        let path = path.into();
        if let Some(chain) = self.current_chain() {
            self.spawn_save(ctx, move || export::write_chain(&chain.glb(), &path));
        }
    }

    /// Writes the chain's recipe to `path` on a worker.
    pub fn save_recipe_to(&mut self, path: impl Into<PathBuf>, ctx: &egui::Context) {
        let path = path.into();
        self.remember_recipe(&path);
        let bytes = self.chain.settings.recipe.to_json();
        self.spawn_save(ctx, move || export::write_bytes(&bytes, &path));
    }

    /// Reads a recipe into the chain panel; a bad one is reported (naming
    /// the row and the field) and the rows stay as they were.
    pub fn open_recipe(&mut self, path: &Path) {
        let read = Recipe::read(path);
        match read {
            Ok(recipe) => {
                self.info(format!("Opened the recipe {}", path.display()));
                self.set_chain_recipe(recipe);
                self.remember_recipe(path);
            }
            Err(e) => self.load_failed(format!("Recipe not opened: {e}")),
        }
    }

    fn remember_recipe(&mut self, path: &Path) {
        let path = absolute(path);
        let recent = &mut self.chain.recent_recipes;
        recent.retain(|p| p != &path);
        recent.insert(0, path);
        recent.truncate(MAX_RECENT);
    }

    /// The built chain, when it was built with the rows as they are.
    fn current_chain(&mut self) -> Option<Arc<Chain>> {
        match &self.chain.built {
            Some(b) if b.recipe() == &self.chain.settings.recipe => Some(Arc::clone(&b.chain)),
            _ => {
                self.error("Build the chain first (its rows changed since the last build)".into());
                None
            }
        }
    }

    fn chain_radius(&self) -> Option<f32> {
        self.chain
            .built
            .as_ref()
            .map(|b| b.chain.radius().max(f32::MIN_POSITIVE))
    }

    /// A new model: its chain is still to be built.
    pub(super) fn forget_chain(&mut self) {
        self.chain.job = None;
        self.chain.built = None;
        self.chain.measuring = None;
        self.chain.differences = None;
        self.chain.difference_image = None;
        self.chain.selected = None;
        self.chain.preview = SwitchPreview::default();
    }

    pub(super) fn poll_chain(&mut self, ctx: &egui::Context) {
        self.poll_recipe_picker();
        if let Some(job) = &self.chain.job {
            let outcome = match job.poll() {
                Poll::Running => None,
                Poll::Done(r) => Some(r),
                Poll::Lost => Some(Err(
                    "the chain build stopped unexpectedly (internal error)".into()
                )),
            };
            if let Some(outcome) = outcome {
                let seconds = job.elapsed().as_secs_f64();
                self.chain.job = None;
                match outcome {
                    Ok(built) => {
                        self.chain.measuring = None;
                        self.chain.differences = None;
                        self.chain.difference_image = None;
                        self.info(format!(
                            "Built a chain of {} LODs in {seconds:.2} s",
                            built.chain.lods.len()
                        ));
                        self.chain.built = Some(built);
                    }
                    Err(m) => {
                        self.error(format!("Chain not built: {m}"));
                        self.chain.note = Some(m);
                    }
                }
            }
        }
        self.poll_difference();
        self.run_dolly(ctx);
    }

    fn poll_difference(&mut self) {
        let Some(job) = &self.chain.measuring else {
            return;
        };
        let outcome = match job.poll() {
            Poll::Running => return,
            Poll::Done(r) => r,
            Poll::Lost => Err("the visual difference stopped unexpectedly (internal error)".into()),
        };
        self.chain.measuring = None;
        match outcome {
            Ok(d) => {
                self.chain.differences = Some(d);
                self.chain.difference_image = None;
            }
            Err(e) => self.error(format!("Visual difference failed: {e}")),
        }
    }

    /// Moves the camera along the dolly, near to far, while it runs.
    fn run_dolly(&mut self, ctx: &egui::Context) {
        let (Some(from), Some(r), Some(built)) = (
            self.chain.preview.dolly_from,
            self.chain_radius(),
            self.chain.built.as_ref(),
        ) else {
            return;
        };
        let (near, far) = dolly_range(&built.chain);
        let t = ((ctx.input(|i| i.time) - from) / DOLLY_SECONDS).clamp(0.0, 1.0) as f32;
        self.viewport.camera.distance = r * near * (far / near).powf(t);
        if t >= 1.0 {
            self.chain.preview.dolly_from = None;
        } else {
            ctx.request_repaint();
        }
    }

    /// The scene a chain row or the switch preview shows, if any.
    pub(super) fn chain_scene(&self) -> Option<Arc<Scene>> {
        let built = self.chain.built.as_ref()?;
        let k = match (self.switch_lod(), self.chain.selected) {
            (Some((k, _)), _) => k,
            (None, Some(row)) => built.figures.get(row)?.lod,
            (None, None) => return None,
        };
        built.scenes.get(k).cloned()
    }

    /// The chain panel: the rows with what they built, Auto chain, Build,
    /// Export, recipes, and the switch preview.
    pub(super) fn chain_panel(&mut self, ui: &mut egui::Ui) {
        let ctx = ui.ctx().clone();
        ui.horizontal_wrapped(|ui| {
            ui.strong("LOD chain").on_hover_text(
                "Rows LOD0…LODn from any method; each LOD switches where the next one's \
                 certified bound projects to the recipe's pixel tolerance.",
            );
            let can_build = self.current.is_some() && self.chain.job.is_none();
            if ui
                .add_enabled(can_build, egui::Button::new("Build chain"))
                .on_hover_text("Build every row on a worker (rows of one method and parameters share one hierarchy).")
                .clicked()
            {
                self.build_chain(&ctx);
            }
            let fresh = self
                .chain
                .built
                .as_ref()
                .is_some_and(|b| b.recipe() == &self.chain.settings.recipe);
            if ui
                .add_enabled(fresh && self.export.is_none(), egui::Button::new("Export chain…"))
                .on_hover_text("One GLB: MSFT_lod + MSFT_screencoverage, written by the code `lodstudio export` runs.")
                .on_disabled_hover_text("Build the chain first.")
                .clicked()
                && let Some(chain) = self.current_chain()
            {
                let name = format!("{}-chain.glb", self.model_stem());
                self.spawn_save(&ctx, move || export::choose_and_write_chain(&chain.glb(), &name));
            }
            if ui
                .add_enabled(self.export.is_none(), egui::Button::new("Save recipe…"))
                .on_hover_text("The rows as a recipe file `lodstudio export --recipe` replays.")
                .clicked()
            {
                let bytes = self.chain.settings.recipe.to_json();
                let name = format!("{}-recipe.json", self.model_stem());
                self.spawn_save(&ctx, move || export::choose_and_write_recipe(&bytes, &name));
            }
            let can_measure = fresh && self.render_state.is_some() && self.chain.measuring.is_none();
            if ui
                .add_enabled(can_measure, egui::Button::new("Visual difference"))
                .on_hover_text("Render the original and every LOD off-screen (the viewport's renderer) from this camera and 8 views around: silhouette difference (% of pixels covered by one only) and PSNR.")
                .on_disabled_hover_text("Build the chain first (needs the GPU renderer).")
                .clicked()
            {
                self.measure_difference(&ctx);
            }
            if ui.button("Open recipe…").clicked() {
                self.recipe_dialog(&ctx);
            }
            let mut reopen = None;
            ui.menu_button("Recent recipes", |ui| {
                if self.chain.recent_recipes.is_empty() {
                    ui.weak("none yet");
                }
                for path in &self.chain.recent_recipes {
                    let name = path.file_name().unwrap_or_default().to_string_lossy();
                    if ui.button(name).on_hover_text(path.display().to_string()).clicked() {
                        reopen = Some(path.clone());
                    }
                }
            });
            if let Some(path) = reopen {
                self.open_recipe(&path);
            }
            match (&self.chain.note, &self.chain.built) {
                (Some(note), _) => {
                    ui.colored_label(ui.visuals().error_fg_color, note);
                }
                (None, Some(_)) if !fresh => {
                    ui.weak("Rows changed since the last build.");
                }
                _ => {}
            }
        });
        if let Some(job) = &self.chain.job
            && job.progress_row(ui)
        {
            self.chain.job = None;
            self.info("Stopped building the chain".into());
        }
        if let Some(job) = &self.chain.measuring
            && job.progress_row(ui)
        {
            self.chain.measuring = None;
        }
        ui.horizontal(|ui| {
            if self.chain.settings.auto_ui(ui) {
                self.chain.selected = None;
            }
        });
        self.switch_preview_ui(ui);
        let figures = self
            .chain
            .built
            .as_ref()
            .filter(|b| b.recipe() == &self.chain.settings.recipe)
            .map(|b| b.figures.as_slice());
        // Solid scroll bars: floating ones would lie over the last row.
        ui.style_mut().spacing.scroll = egui::style::ScrollStyle::solid();
        egui::ScrollArea::horizontal().show(ui, |ui| {
            let response = self
                .chain
                .settings
                .rows_ui(ui, figures, self.chain.selected);
            if let Some(row) = response.clicked {
                self.chain.selected = Some(row);
                self.chain.preview.on = false;
                if self.view == super::View::Original {
                    self.view = super::View::Simplified;
                }
            }
            if response.changed {
                self.chain.selected = None;
            }
        });
        if self.chain.settings.add_row_ui(ui) {
            self.chain.selected = None;
        }
    }

    /// The visual difference's window (open once measured, until closed).
    pub(super) fn difference_window(&mut self, ctx: &egui::Context) {
        if self.chain.differences.is_none() {
            return;
        }
        let mut open = true;
        egui::Window::new("Visual difference")
            .open(&mut open)
            .default_pos(egui::pos2(300.0, 100.0))
            .show(ctx, |ui| self.difference_ui(ui));
        if !open {
            self.chain.differences = None;
            self.chain.difference_image = None;
        }
    }

    /// The visual difference per LOD, and the shown LOD's difference image.
    fn difference_ui(&mut self, ui: &mut egui::Ui) {
        let Some(differences) = &self.chain.differences else {
            return;
        };
        let shown = self
            .switch_lod()
            .map(|(k, _)| k)
            .or_else(|| {
                let built = self.chain.built.as_ref()?;
                Some(built.figures.get(self.chain.selected?)?.lod)
            })
            .unwrap_or(0);
        ui.label("Visual difference against the original (silhouette: pixels covered by one only)");
        egui::Grid::new("chain differences")
            .striped(true)
            .show(ui, |ui| {
                for head in [
                    "LOD",
                    "silhouette here",
                    "PSNR here",
                    "silhouette, 8 views",
                    "PSNR, 8 views",
                ] {
                    ui.strong(head);
                }
                ui.end_row();
                for (k, d) in differences.iter().enumerate() {
                    ui.label(format!("LOD{k}"));
                    ui.label(format!("{:.3}%", 100.0 * d.here.silhouette));
                    ui.label(format!("{:.1} dB", d.here.psnr));
                    ui.label(format!("{:.3}%", 100.0 * d.around.silhouette));
                    ui.label(format!("{:.1} dB", d.around.psnr));
                    ui.end_row();
                }
            });
        let Some(d) = differences.get(shown) else {
            return;
        };
        let texture = match &self.chain.difference_image {
            Some((k, t)) if *k == shown => t.clone(),
            _ => {
                let image = egui::ColorImage::from_rgba_unmultiplied(
                    [d.image.width as usize, d.image.height as usize],
                    bytemuck::cast_slice(&d.image.rgba),
                );
                let t = ui
                    .ctx()
                    .load_texture("chain difference", image, Default::default());
                self.chain.difference_image = Some((shown, t.clone()));
                t
            }
        };
        ui.label(format!(
            "LOD{shown} from the camera (red: original only, green: LOD only)"
        ));
        ui.add(egui::Image::new(&texture).max_size(egui::vec2(192.0, 192.0)));
    }

    /// The switch preview's toggle, distance slider, dolly and strip.
    fn switch_preview_ui(&mut self, ui: &mut egui::Ui) {
        let chain = self.chain.built.as_ref().map(|b| Arc::clone(&b.chain));
        let (Some(chain), Some(r)) = (chain, self.chain_radius()) else {
            return;
        };
        let (near, far) = dolly_range(&chain);
        let switches: Vec<f32> = chain.coverages[..chain.coverages.len() - 1]
            .iter()
            .map(|&c| distance_at_coverage(c))
            .collect();
        let mut on = self.chain.preview.on;
        let mut distance = (self.viewport.camera.distance / r).clamp(near, far);
        let mut dolly = false;
        ui.horizontal(|ui| {
            ui.checkbox(&mut on, "Switch preview").on_hover_text(
                "Draw the LOD the chain uses at the camera's distance (in bounding radii), as a \
                 loader honouring MSFT_screencoverage would.",
            );
            let slider = ui.add_enabled(
                on,
                egui::Slider::new(&mut distance, near..=far)
                    .logarithmic(true)
                    .suffix(" r")
                    .text("distance"),
            );
            if on {
                switch_marks(ui, slider.rect, near, far, &switches);
            }
            dolly = ui
                .button("Dolly")
                .on_hover_text("Move the camera from near to far in 6 s.")
                .clicked();
        });
        if dolly {
            on = true;
            self.chain.preview.dolly_from = Some(ui.ctx().input(|i| i.time));
            distance = near;
        }
        if on != self.chain.preview.on {
            self.preview_on(on);
        }
        if on {
            self.viewport.camera.distance = distance * r;
        }
        if let Some((k, name)) = self.switch_lod() {
            let c = coverage_at_distance(distance);
            let here = chain.pixels_at(k, c);
            let c_in = chain.coverage_in(k);
            let beyond = chain.lod_at_coverage(c).is_none();
            ui.label(format!(
                "{name}: bound {here:.2} px here, {:.2} px at its switch in (tolerance {} px){}",
                chain.pixels_at(k, c_in),
                chain.recipe.pixels,
                if beyond {
                    "; beyond the last switch a loader leaves the model out"
                } else {
                    ""
                }
            ));
        }
    }

    /// The inspector's chain rows: the switch tolerance, and with the
    /// preview the LOD drawn and its bound in pixels here and at its switch.
    pub(super) fn chain_inspector(&self, ui: &mut egui::Ui) {
        let (Some(built), Some(r)) = (&self.chain.built, self.chain_radius()) else {
            return;
        };
        let chain = &built.chain;
        ui.separator();
        ui.label(egui::RichText::new("LOD chain").strong());
        egui::Grid::new("chain grid")
            .num_columns(2)
            .striped(true)
            .show(ui, |ui| {
                let mut row = |label: &str, value: String, hint: &str| {
                    ui.label(label).on_hover_text(hint);
                    ui.label(value);
                    ui.end_row();
                };
                row("LODs", chain.lods.len().to_string(), "LODs of the last chain built (rows met by one cut share it).");
                row(
                    "switch tolerance",
                    format!("{} px on {} px", chain.recipe.pixels, chain.recipe.viewport_height),
                    "Each LOD is shown until the next one's bound projects to this many pixels.",
                );
                if let Some((k, name)) = self.switch_lod() {
                    let c = coverage_at_distance(self.viewport.camera.distance / r);
                    let c_in = chain.coverage_in(k);
                    row("preview LOD", name, "The LOD the chain uses at the camera's distance.");
                    row("coverage", format!("{c:.4}"), "The bounding sphere's height over the viewport's at this distance.");
                    row("bound here", format!("{:.2} px", chain.pixels_at(k, c)), "The LOD's bound projected at this distance.");
                    row(
                        "bound at switch",
                        format!("{:.2} px", chain.pixels_at(k, c_in)),
                        "The LOD's bound where it takes over from the finer one: the popping a viewer may see.",
                    );
                }
            });
    }

    /// Turns the switch preview on or off; on, it shows LODs (not the original).
    fn preview_on(&mut self, on: bool) {
        self.chain.preview.on = on;
        self.chain.selected = None;
        if on && self.view == super::View::Original {
            self.view = super::View::Simplified;
        }
    }

    /// Asks for a recipe file on a worker thread.
    fn recipe_dialog(&mut self, ctx: &egui::Context) {
        if self.chain.picker.is_some() {
            return;
        }
        const FILTERS: &[(&str, &[&str])] = &[("Recipes (json)", &["json"])];
        let spawned = pick_file("Open a recipe", FILTERS, ctx);
        match spawned {
            Ok(rx) => self.chain.picker = Some(rx),
            Err(e) => self.error(format!("cannot open the file dialog: {e}")),
        }
    }

    fn poll_recipe_picker(&mut self) {
        let Some(rx) = &self.chain.picker else {
            return;
        };
        match rx.try_recv() {
            Err(TryRecvError::Empty) => {}
            Ok(Some(path)) => {
                self.chain.picker = None;
                self.open_recipe(&path);
            }
            Ok(None) | Err(TryRecvError::Disconnected) => {
                self.chain.picker = None;
                self.info("No recipe chosen".into());
            }
        }
    }

    /// The model's file stem, for suggested file names.
    fn model_stem(&self) -> String {
        self.current
            .as_ref()
            .map(|c| {
                let name = c.name.trim_start_matches("builtin:");
                name.split('.').next().unwrap_or("model").to_string()
            })
            .unwrap_or_else(|| "model".into())
    }
}

/// The preview's distances (bounding radii): from filling the screen to
/// twice as far as the last switch.
fn dolly_range(chain: &Chain) -> (f32, f32) {
    let near = distance_at_coverage(1.0);
    let last = chain.coverages.last().copied().unwrap_or(1.0);
    (near, distance_at_coverage(0.5 * last).max(2.0 * near))
}

/// Ticks under the distance slider at each switch (LOD k -> k+1).
fn switch_marks(ui: &egui::Ui, rect: egui::Rect, near: f32, far: f32, switches: &[f32]) {
    let painter = ui.painter();
    let color = ui.visuals().warn_fg_color;
    // The slider's rail spans its rect minus the handle's radius and the text.
    let rail = egui::Rect::from_min_max(
        rect.min + egui::vec2(rect.height() * 0.5, 0.0),
        egui::pos2(rect.max.x - rect.height() * 0.5, rect.max.y),
    );
    let width = ui.spacing().slider_width;
    for (k, &d) in switches.iter().enumerate() {
        let t = (d / near).ln() / (far / near).ln();
        if !(0.0..=1.0).contains(&t) {
            continue;
        }
        let x = rail.min.x + t * width.min(rail.width());
        painter.line_segment(
            [
                egui::pos2(x, rail.max.y - 4.0),
                egui::pos2(x, rail.max.y + 2.0),
            ],
            egui::Stroke::new(2.0, color),
        );
        painter.text(
            egui::pos2(x, rail.max.y + 2.0),
            egui::Align2::CENTER_TOP,
            format!("{}", k + 1),
            egui::FontId::proportional(9.0),
            color,
        );
    }
}
