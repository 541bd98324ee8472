//! A glTF asset in the studio (issue 49, item 7): the outliner (the node
//! tree by name, each mesh's triangles and instances; a click highlights the
//! node and what hangs under it), the chain panel's rows built for every
//! mesh at once with a per-mesh exclude and the triangles summed per level,
//! and the animation timeline, which poses the shown level on the CPU by
//! the linear blend skinning `export --poses` measures with
//! (`lodstudio_core::scene::drawing`).

use std::sync::Arc;

use glam::Vec3;
use lodstudio_core::TriMesh;
use lodstudio_core::io::LoadOptions;
use lodstudio_core::io::scene::Scene as Asset;
use lodstudio_core::recipe::{ChainError, Recipe};
use lodstudio_core::scene::drawing::Drawing;
use lodstudio_core::scene::{Layout, SceneChains};
use serde_json::Value;

use crate::job::{Job, Poll};
use crate::render::Scene;

/// Colours of the highlighted node's triangles and of the rest.
const HIGHLIGHT: Vec3 = Vec3::new(1.0, 0.55, 0.1);
const DIMMED: Vec3 = Vec3::new(0.55, 0.57, 0.6);

/// What a build hands back: the chains, their drawing, the worker's seconds.
type Built = (SceneChains, Drawing, f64);

/// One row of the outliner: a node at its depth in the scene's tree.
struct OutlineRow {
    node: usize,
    depth: usize,
    label: String,
    /// The scene mesh it draws (its place in `Asset::meshes`).
    mesh: Option<usize>,
    /// One past the last row of its subtree.
    end: usize,
}

/// The asset on screen, its chains and its pose.
pub struct AssetState {
    asset: Arc<Asset>,
    rows: Vec<OutlineRow>,
    /// The row clicked in the outliner.
    pub selected: Option<usize>,
    /// Per scene mesh: left out of the chain (whole at every level).
    pub excluded: Vec<bool>,
    /// The viewport shows the asset (posed, at `level`) instead of the
    /// flattened model.
    pub show: bool,
    pub level: usize,
    pub animation: usize,
    pub playing: bool,
    /// Seconds into the animation.
    pub time: f32,
    drawing: Drawing,
    /// The last build's chains (what Export scene… writes).
    chains: Option<Arc<SceneChains>>,
    /// The build on its worker: the chains, their drawing, and the
    /// worker's own seconds (what the log reports).
    job: Option<Job<Result<Built, ChainError>>>,
    /// Seconds the last build took on its worker.
    pub last_build_seconds: Option<f64>,
    note: Option<String>,
    /// Reused each frame the asset moves.
    colors: Vec<Vec3>,
    /// What the viewport draws; `None` once something changed.
    view: Option<Arc<Scene>>,
}

impl AssetState {
    pub fn new(asset: Asset) -> AssetState {
        let rows = outline(&asset);
        let drawing = Drawing::new(&asset, None);
        AssetState {
            excluded: vec![false; asset.meshes.len()],
            asset: Arc::new(asset),
            rows,
            selected: None,
            show: false,
            level: 0,
            animation: 0,
            playing: false,
            time: 0.0,
            drawing,
            chains: None,
            job: None,
            last_build_seconds: None,
            note: None,
            colors: Vec::new(),
            view: None,
        }
    }

    /// The outliner's labels, top to bottom.
    pub fn outline_labels(&self) -> impl Iterator<Item = &str> {
        self.rows.iter().map(|r| r.label.as_str())
    }

    /// The mesh drawn for the viewport (world space, posed) now.
    pub fn drawn(&mut self) -> &TriMesh {
        let animation = (!self.asset.rig.animations.is_empty()).then_some(self.animation);
        self.drawing
            .draw(&self.asset, self.level, animation, self.time)
            .0
    }

    /// The levels the chains have (1 before a build).
    pub fn levels(&self) -> usize {
        self.drawing.levels()
    }

    /// Triangles at `level`: each mesh once, and once per instance.
    pub fn triangles(&self, level: usize) -> (usize, usize) {
        self.drawing.triangles(&self.asset, level)
    }

    pub fn is_building(&self) -> bool {
        self.job.is_some()
    }

    /// How long the running build has run (the studio polls long builds
    /// less often).
    pub fn building_for(&self) -> Option<std::time::Duration> {
        self.job.as_ref().map(Job::elapsed)
    }

    /// Whether it changes by itself (playing), so frames keep coming.
    pub fn is_moving(&self) -> bool {
        self.show && self.playing && !self.asset.rig.animations.is_empty()
    }

    /// Builds `recipe`'s chain for every mesh not excluded, on a worker.
    pub fn start_build(&mut self, recipe: &Recipe, ctx: &egui::Context) {
        let (asset, excluded) = (Arc::clone(&self.asset), self.excluded.clone());
        let mut repair = LoadOptions::default().repair;
        repair.weld = recipe.weld();
        let recipe = recipe.clone();
        let spawned = Job::spawn("asset chains", "every mesh".into(), ctx, move |progress| {
            let start = std::time::Instant::now();
            progress.stage("building each mesh's chain");
            let built = lodstudio_core::scene::build(&asset, &recipe, &excluded, &repair, progress);
            progress.check()?;
            progress.stage("carrying skins to the LODs");
            Ok(built.map(|chains| {
                let drawing = Drawing::new(&asset, Some(&chains));
                (chains, drawing, start.elapsed().as_secs_f64())
            }))
        });
        match spawned {
            Ok(job) => {
                self.job = Some(job);
                self.note = None;
            }
            Err(e) => self.note = Some(format!("cannot start the build: {e}")),
        }
    }

    /// Takes a finished build; what to log.
    pub fn poll(&mut self) -> Option<String> {
        let outcome = match self.job.as_ref()?.poll() {
            Poll::Running => return None,
            Poll::Done(outcome) => outcome,
            Poll::Lost => Err(ChainError::BadInput(
                "the build stopped (internal error)".into(),
            )),
        };
        self.job = None;
        match outcome {
            Ok((chains, drawing, seconds)) => {
                self.last_build_seconds = Some(seconds);
                let skipped: usize = chains.skipped.iter().map(Vec::len).sum();
                self.note = (skipped > 0).then(|| {
                    let first = (self.asset.meshes.iter().zip(&chains.skipped))
                        .find_map(|(m, s)| Some((m, s.first()?)));
                    match first {
                        Some((m, s)) => format!(
                            "{skipped} row(s) left out where a mesh does not fit them, e.g. {} on \"{}\": {}",
                            s.label, m.name, s.why
                        ),
                        None => String::new(),
                    }
                });
                self.chains = Some(Arc::new(chains));
                self.drawing = drawing;
                self.level = self.level.min(self.drawing.levels() - 1);
                self.view = None;
                let (once, drawn) = self.triangles(self.levels() - 1);
                Some(format!(
                    "Built {} levels for {} meshes in {seconds:.2} s (coarsest: {once} triangles, {drawn} drawn)",
                    self.levels(),
                    self.asset.meshes.len()
                ))
            }
            Err(e) => {
                self.note = Some(e.to_string());
                Some(format!("Building the asset's chains failed: {e}"))
            }
        }
    }

    /// The scene with its built LODs, as `lodstudio export` writes it (in
    /// the layout and compression of the recipe built with), and the
    /// layout; `None` before a build.
    pub fn export(&self) -> Option<impl FnOnce() -> (Vec<Vec<u8>>, Layout) + Send + 'static> {
        let (asset, chains) = (Arc::clone(&self.asset), Arc::clone(self.chains.as_ref()?));
        Some(move || {
            let recipe = &chains.chains[0].recipe;
            let layout = recipe.layout;
            (chains.write(&asset, layout, recipe.points_as), layout)
        })
    }

    /// Draws it again at the next frame (after a change made from outside
    /// the section, as scripted sessions and the bench make).
    pub fn redraw(&mut self) {
        self.view = None;
    }

    /// Advances a playing animation by `dt` seconds (looping).
    pub fn tick(&mut self, dt: f32) {
        if !self.is_moving() {
            return;
        }
        let (start, end) = self.asset.rig.animations[self.animation].span();
        let length = (end - start).max(1e-3);
        self.time = start + (self.time - start + dt).rem_euclid(length);
        self.view = None;
    }

    /// What the viewport draws: the asset at its level and pose, the
    /// selected node's triangles highlighted (else in their materials).
    /// Drawn again only after a change, posing the positions in place.
    pub fn view_scene(&mut self) -> Arc<Scene> {
        if let Some(view) = &self.view {
            return Arc::clone(view);
        }
        let animation = (!self.asset.rig.animations.is_empty()).then_some(self.animation);
        let (mesh, drawn) = self
            .drawing
            .draw(&self.asset, self.level, animation, self.time);
        self.colors.clear();
        if let Some(r) = self.selected.filter(|&r| r < self.rows.len()) {
            let under = &self.rows[r..self.rows[r].end];
            self.colors.resize(mesh.triangles.len(), DIMMED);
            for d in drawn {
                if under.iter().any(|r| r.node == d.node) {
                    self.colors[d.triangles.clone()].fill(HIGHLIGHT);
                }
            }
        }
        let view = Arc::new(Scene::from_mesh_with_triangle_colors(mesh, &self.colors));
        self.view = Some(Arc::clone(&view));
        view
    }
}

/// The scene's node tree, depth first (the reader refused cycles and nodes
/// under several parents).
fn outline(asset: &Asset) -> Vec<OutlineRow> {
    let doc = &asset.doc;
    let nodes = doc["nodes"].as_array().map_or(&[][..], |n| n);
    let indices = |v: &Value| -> Vec<usize> {
        v.as_array()
            .into_iter()
            .flatten()
            .filter_map(|i| i.as_u64().map(|i| i as usize))
            .filter(|&i| i < nodes.len())
            .collect()
    };
    let roots = match asset.scene {
        Some(s) => indices(&doc["scenes"][s]["nodes"]),
        None => (0..nodes.len()).collect(),
    };
    let mut rows: Vec<OutlineRow> = Vec::new();
    let mut stack: Vec<(usize, usize)> = roots.into_iter().rev().map(|n| (n, 0)).collect();
    let mut open: Vec<usize> = Vec::new();
    while let Some((node, depth)) = stack.pop() {
        if rows.len() > 100_000 {
            break;
        }
        // Rows deeper than this one have ended.
        while open.last().is_some_and(|&r| rows[r].depth >= depth) {
            let r = open.pop().unwrap_or_default();
            rows[r].end = rows.len();
        }
        let n = &nodes[node];
        let mesh = n["mesh"]
            .as_u64()
            .and_then(|m| asset.meshes.iter().position(|s| s.index == m as usize));
        let mut label = match n["name"].as_str() {
            Some(name) => name.to_string(),
            None => format!("node {node}"),
        };
        if let Some(m) = mesh.map(|m| &asset.meshes[m]) {
            label.push_str(&format!(
                "  [{}: {} triangles, {} instance{}]",
                m.name,
                m.mesh.triangles.len(),
                m.instances.len(),
                if m.instances.len() == 1 { "" } else { "s" }
            ));
        }
        open.push(rows.len());
        rows.push(OutlineRow {
            node,
            depth,
            label,
            mesh,
            end: 0,
        });
        for child in indices(&n["children"]).into_iter().rev() {
            stack.push((child, depth + 1));
        }
    }
    for r in open {
        rows[r].end = rows.len();
    }
    rows
}

/// What the asset section asks of the studio.
#[derive(Default)]
pub struct AssetResponse {
    /// What the viewport shows changed.
    pub changed: bool,
    /// Export scene… was clicked.
    pub export: bool,
}

/// The asset section: outliner, chain for every mesh, level and timeline.
pub fn asset_ui(ui: &mut egui::Ui, state: &mut AssetState, recipe: &Recipe) -> AssetResponse {
    let mut changed = false;
    let mut export = false;
    changed |= ui
        .checkbox(&mut state.show, "Show the asset")
        .on_hover_text("Draw the scene as its nodes place it: the shown level, posed by the animation, the selected node highlighted.")
        .changed();
    ui.label(format!(
        "{} nodes, {} meshes, {} instances",
        state.rows.len(),
        state.asset.meshes.len(),
        state
            .asset
            .meshes
            .iter()
            .map(|m| m.instances.len())
            .sum::<usize>()
    ));
    egui::ScrollArea::vertical()
        .id_salt("outliner")
        .max_height(220.0)
        .show(ui, |ui| {
            for (i, row) in state.rows.iter().enumerate() {
                ui.horizontal(|ui| {
                    ui.add_space(12.0 * row.depth as f32);
                    if let Some(m) = row.mesh {
                        let mut keep = !state.excluded[m];
                        if ui
                            .checkbox(&mut keep, "")
                            .on_hover_text("Build LODs of this mesh (off: it stays whole at every level, on every node that draws it).")
                            .changed()
                        {
                            state.excluded[m] = !keep;
                        }
                    }
                    let selected = state.selected == Some(i);
                    if ui.selectable_label(selected, &row.label).clicked() {
                        state.selected = (!selected).then_some(i);
                        state.show = true;
                        changed = true;
                    }
                });
            }
        });
    ui.horizontal(|ui| {
        let build = ui
            .add_enabled(state.job.is_none(), egui::Button::new("Build for every mesh"))
            .on_hover_text("Build the chain panel's rows for each mesh once, in its own space (as `export` does).");
        if build.clicked() {
            state.start_build(recipe, ui.ctx());
        }
        export = ui
            .add_enabled(state.chains.is_some(), egui::Button::new("Export scene…"))
            .on_hover_text("Write the scene with every mesh's LODs, as `lodstudio export` does (the recipe's layout and compression).")
            .on_disabled_hover_text("Build for every mesh first.")
            .clicked();
    });
    if let Some(job) = &state.job
        && job.progress_row(ui)
    {
        state.job = None;
    }
    if let Some(note) = &state.note {
        ui.colored_label(ui.visuals().error_fg_color, note);
    }
    let levels = state.levels();
    if levels > 1 {
        egui::Grid::new("asset levels")
            .striped(true)
            .show(ui, |ui| {
                ui.strong("level");
                ui.strong("triangles");
                ui.strong("drawn");
                ui.end_row();
                for k in 0..levels {
                    let (once, drawn) = state.triangles(k);
                    if ui
                        .selectable_label(state.level == k, format!("LOD{k}"))
                        .clicked()
                    {
                        state.level = k;
                        state.show = true;
                        changed = true;
                    }
                    ui.label(once.to_string());
                    ui.label(drawn.to_string());
                    ui.end_row();
                }
            });
    }
    let animations = &state.asset.rig.animations;
    if !animations.is_empty() {
        ui.horizontal(|ui| {
            let name = |a: usize| {
                animations[a]
                    .name
                    .clone()
                    .unwrap_or_else(|| format!("animation {a}"))
            };
            egui::ComboBox::from_label("Animation")
                .selected_text(name(state.animation))
                .show_ui(ui, |ui| {
                    for a in 0..animations.len() {
                        changed |= ui
                            .selectable_value(&mut state.animation, a, name(a))
                            .changed();
                    }
                });
            let play = if state.playing { "Pause" } else { "Play" };
            if ui.button(play).clicked() {
                state.playing = !state.playing;
                state.show = true;
                changed = true;
            }
        });
        let (start, end) = animations[state.animation].span();
        changed |= ui
            .add(egui::Slider::new(&mut state.time, start..=end.max(start)).text("s"))
            .changed();
    }
    if changed {
        state.view = None;
    }
    AssetResponse { changed, export }
}
