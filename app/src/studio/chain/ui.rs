//! The chain's panel, its visual difference window and its inspector rows,
//! drawn from a [`ChainState`]; what they ask of the studio comes back as
//! [`ChainRequest`]s.

use std::sync::Arc;

use super::{ChainEvent, ChainRequest, ChainState, Target};
use crate::render::Camera;
use crate::render::camera::{coverage_at_distance, distance_at_coverage};
use crate::studio::View;

/// What the chain panel reads from the studio, and what its switch preview
/// and rows move there.
pub struct PanelContext<'a> {
    /// The viewport's camera (the switch preview moves it).
    pub camera: &'a mut Camera,
    pub view: &'a mut View,
    /// The model on screen, by name; none: nothing to build.
    pub model_name: Option<&'a str>,
    /// Whether off-screen renders can run (the visual difference).
    pub can_render: bool,
    /// Whether a save is running (the studio runs one at a time).
    pub saving: bool,
}

/// The chain panel: the rows with what they built, Auto chain, Build,
/// Export, recipes, and the switch preview.
pub fn panel_ui(
    state: &mut ChainState,
    ui: &mut egui::Ui,
    studio: PanelContext<'_>,
) -> Vec<ChainRequest> {
    let PanelContext {
        camera,
        view,
        model_name,
        can_render,
        saving,
    } = studio;
    let mut requests = Vec::new();
    ui.horizontal_wrapped(|ui| {
        ui.strong("LOD chain").on_hover_text(
            "Rows LOD0…LODn from any method; each LOD switches where the next one's \
             certified bound projects to the recipe's pixel tolerance.",
        );
        let can_build = model_name.is_some() && !state.is_building();
        if ui
            .add_enabled(can_build, egui::Button::new("Build chain"))
            .on_hover_text("Build every row on a worker (rows of one method and parameters share one hierarchy).")
            .clicked()
        {
            requests.push(ChainRequest::Build);
        }
        let fresh = state.fresh().is_some();
        if ui
            .add_enabled(fresh && !saving, egui::Button::new("Export chain…"))
            .on_hover_text("One GLB: MSFT_lod + MSFT_screencoverage, written by the code `lodstudio export` runs.")
            .on_disabled_hover_text("Build the chain first.")
            .clicked()
        {
            let name = format!("{}-chain.glb", stem(model_name));
            requests.push(state.export(Target::Dialog(name)).into());
        }
        if ui
            .add_enabled(!saving, egui::Button::new("Save recipe…"))
            .on_hover_text("The rows as a recipe file `lodstudio export --recipe` replays.")
            .clicked()
        {
            let name = format!("{}-recipe.json", stem(model_name));
            requests.push(ChainRequest::Save(state.save_recipe(Target::Dialog(name))));
        }
        let can_measure = fresh && can_render && !state.is_measuring();
        if ui
            .add_enabled(can_measure, egui::Button::new("Visual difference"))
            .on_hover_text("Render the original and every LOD off-screen (the viewport's renderer) from this camera and 8 views around: silhouette difference (% of pixels covered by one only) and PSNR.")
            .on_disabled_hover_text("Build the chain first (needs the GPU renderer).")
            .clicked()
        {
            requests.push(ChainRequest::MeasureDifference);
        }
        if ui.button("Open recipe…").clicked()
            && let Err(e) = state.open_dialog(ui.ctx())
        {
            requests.push(ChainRequest::Report(ChainEvent::Failed(e)));
        }
        let mut reopen = None;
        ui.menu_button("Recent recipes", |ui| {
            if state.recent_recipes.is_empty() {
                ui.weak("none yet");
            }
            for path in &state.recent_recipes {
                let name = path.file_name().unwrap_or_default().to_string_lossy();
                if ui.button(name).on_hover_text(path.display().to_string()).clicked() {
                    reopen = Some(path.clone());
                }
            }
        });
        if let Some(path) = reopen {
            requests.push(ChainRequest::Report(state.open_recipe(&path)));
        }
        match (&state.note, &state.built) {
            (Some(note), _) => {
                ui.colored_label(ui.visuals().error_fg_color, note);
            }
            (None, Some(_)) if !fresh => {
                ui.weak("Rows changed since the last build.");
            }
            _ => {}
        }
    });
    if state.job.as_ref().is_some_and(|job| job.progress_row(ui)) {
        requests.push(ChainRequest::Report(state.cancel_build()));
    }
    if state
        .measuring
        .as_ref()
        .is_some_and(|job| job.progress_row(ui))
    {
        state.cancel_measuring();
    }
    // The toolbar above stays in view; the rows scroll under it.
    egui::ScrollArea::vertical()
        .id_salt("chain rows")
        .show(ui, |ui| {
            ui.horizontal(|ui| {
                if state.settings.auto_ui(ui) {
                    requests.push(ChainRequest::Auto);
                }
            });
            switch_preview_ui(state, ui, camera, view);
            // Solid scroll bars: floating ones would lie over the last row.
            ui.style_mut().spacing.scroll = egui::style::ScrollStyle::solid();
            egui::ScrollArea::horizontal().show(ui, |ui| {
                let figures = state
                    .built
                    .as_ref()
                    .filter(|b| b.recipe() == &state.settings.recipe)
                    .map(|b| b.figures.as_slice());
                let response = state.settings.rows_ui(ui, figures, state.selected);
                if let Some(row) = response.clicked {
                    state.select_row(row, view);
                }
                if response.changed {
                    state.selected = None;
                }
            });
            if state.settings.add_row_ui(ui) {
                state.selected = None;
            }
        });
    requests
}

/// The model's file stem, for suggested file names.
fn stem(model_name: Option<&str>) -> &str {
    model_name
        .map(|name| name.trim_start_matches("builtin:"))
        .and_then(|name| name.split('.').next())
        .unwrap_or("model")
}

/// The visual difference's window (open once measured, until closed).
pub fn difference_window(state: &mut ChainState, ctx: &egui::Context, camera_distance: f32) {
    if state.differences.is_none() {
        return;
    }
    let mut open = true;
    egui::Window::new("Visual difference")
        .open(&mut open)
        .default_pos(egui::pos2(300.0, 100.0))
        .show(ctx, |ui| difference_ui(state, ui, camera_distance));
    if !open {
        state.close_differences();
    }
}

/// The visual difference per LOD, and the shown LOD's difference image.
fn difference_ui(state: &mut ChainState, ui: &mut egui::Ui, camera_distance: f32) {
    let shown = state.shown_lod(camera_distance).unwrap_or(0);
    let Some(differences) = &state.differences else {
        return;
    };
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
    let texture = match &state.difference_image {
        Some((k, t)) if *k == shown => t.clone(),
        _ => {
            let image = egui::ColorImage::from_rgba_unmultiplied(
                [d.image.width as usize, d.image.height as usize],
                bytemuck::cast_slice(&d.image.rgba),
            );
            let t = ui
                .ctx()
                .load_texture("chain difference", image, Default::default());
            state.difference_image = Some((shown, t.clone()));
            t
        }
    };
    ui.label(format!(
        "LOD{shown} from the camera (red: original only, green: LOD only)"
    ));
    ui.add(egui::Image::new(&texture).max_size(egui::vec2(192.0, 192.0)));
}

/// The switch preview's toggle, distance slider, dolly and strip.
fn switch_preview_ui(
    state: &mut ChainState,
    ui: &mut egui::Ui,
    camera: &mut Camera,
    view: &mut View,
) {
    let chain = state.built.as_ref().map(|b| Arc::clone(&b.chain));
    let (Some(chain), Some(r)) = (chain, state.radius()) else {
        return;
    };
    let (near, far) = super::dolly::range(&chain.coverages);
    let switches: Vec<f32> = chain.coverages[..chain.coverages.len() - 1]
        .iter()
        .map(|&c| distance_at_coverage(c))
        .collect();
    let mut on = state.preview.on;
    let mut distance = (camera.distance / r).clamp(near, far);
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
        state.start_dolly(ui.ctx().input(|i| i.time));
        distance = near;
    }
    if on != state.preview.on {
        state.set_preview(on, view);
    }
    if on {
        camera.distance = distance * r;
    }
    if let Some((k, name)) = state.switch_lod(camera.distance) {
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

/// The inspector's chain rows: the switch tolerance, and with the preview
/// the LOD drawn and its bound in pixels here and at its switch.
pub fn inspector_ui(state: &ChainState, ui: &mut egui::Ui, camera_distance: f32) {
    let (Some(built), Some(r)) = (&state.built, state.radius()) else {
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
            // What the viewport draws when it draws a chain LOD: the inspector
            // describes exactly that, not the method's live cut.
            if let Some(k) = state.shown_lod(camera_distance) {
                let set = &chain.lods[k].set;
                row("shown", format!("LOD{k} {}", chain.lods[k].labels.join(",")), "The chain LOD the viewport draws (a clicked row, or the switch preview).");
                row("LOD triangles", set.mesh.triangles.len().to_string(), "Triangles of the LOD shown.");
                row("LOD points", set.points.len().to_string(), "Point primitives of the LOD shown.");
                row("LOD splats", set.splats.len().to_string(), "Textured domain primitives of the LOD shown.");
                row(
                    "LOD bound",
                    format!(
                        "{} ({:.3} %, {})",
                        crate::build::length(set.error_bound),
                        100.0 * set.error_bound / chain.diagonal.max(f32::MIN_POSITIVE),
                        set.error_bound_kind.name()
                    ),
                    "The LOD's error bound in object space (certified, or AMG's estimate).",
                );
            }
            row(
                "switch tolerance",
                format!("{} px on {} px", chain.recipe.pixels, chain.recipe.viewport_height),
                "Each LOD is shown until the next one's bound projects to this many pixels.",
            );
            if let Some((k, name)) = state.switch_lod(camera_distance) {
                let c = coverage_at_distance(camera_distance / r);
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
