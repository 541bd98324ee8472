//! 3D Tiles in the studio: the viewer's maximum screen-space error, the
//! colouring, the tile budget and the build button (left panel), and the
//! open tileset's levels, cut and per-tile certified bounds (inspector).

use crate::build::{bound_text, length};
use crate::heatmap;
use crate::settings::tiles::{SSE_RANGE, TilesSettings};
use crate::tileset_view::TilesetView;

/// The tileset controls; `can_build` when a triangle mesh is on screen.
/// True when "Build tileset…" was clicked.
pub fn tiles_ui(ui: &mut egui::Ui, s: &mut TilesSettings, can_build: bool) -> bool {
    ui.add(
        egui::Slider::new(&mut s.max_sse_px, SSE_RANGE)
            .logarithmic(true)
            .suffix(" px")
            .text("max screen-space error"),
    )
    .on_hover_text(
        "A tile is replaced by its children while its certified error covers more pixels than this from the camera (CesiumJS's maximumScreenSpaceError; 16 px by default).",
    );
    ui.checkbox(&mut s.by_level, "Colour by level")
        .on_hover_text(
            "Each drawn tile in its level's colour (root to leaves), or in its materials.",
        );
    let range = lodstudio_core::tiles::TILE_TRIANGLES;
    ui.add(
        egui::Slider::new(&mut s.tile_triangles, range)
            .logarithmic(true)
            .text("triangles per leaf"),
    )
    .on_hover_text("A tileset built here splits the model into leaves of at most this many original triangles (lodstudio tiles --tile-triangles).");
    ui.add_enabled(can_build, egui::Button::new("Build tileset…"))
        .on_hover_text(
            "Builds a tileset of the model on screen into a folder you choose, then opens it.",
        )
        .on_disabled_hover_text("Open a triangle mesh first.")
        .clicked()
}

/// The open tileset: its tree, the cut drawn now and each drawn tile's
/// level, triangles, certified error and screen-space error.
pub fn tileset_inspector_ui(ui: &mut egui::Ui, view: &TilesetView, max_sse_px: f32) {
    let set = &view.set;
    let drawn = view.drawn();
    let triangles: usize = drawn.iter().map(|d| view.triangles(d.tile)).sum();
    let worst = drawn.iter().map(|d| d.sse_px).fold(0.0, f32::max);
    let name = view.path.parent().and_then(|p| p.file_name());
    ui.label(egui::RichText::new("Tileset").strong())
        .on_hover_text(view.path.display().to_string());
    egui::Grid::new("tileset grid")
        .num_columns(2)
        .striped(true)
        .show(ui, |ui| {
            let rows = [
                (
                    "folder",
                    name.map_or(String::new(), |n| n.to_string_lossy().into()),
                ),
                ("tiles", set.tiles.len().to_string()),
                ("levels", set.levels().to_string()),
                ("root error", bound_text(set.tiles[0].error, view.diagonal)),
                ("drawn tiles", drawn.len().to_string()),
                ("drawn triangles", triangles.to_string()),
                (
                    "largest SSE drawn",
                    format!("{worst:.2} px (max {max_sse_px:.2})"),
                ),
            ];
            for (label, value) in rows {
                ui.label(label);
                ui.label(value);
                ui.end_row();
            }
        });
    ui.horizontal_wrapped(|ui| {
        ui.label("levels:");
        let top = set.levels().saturating_sub(1).max(1) as f32;
        for level in 0..set.levels() {
            let size = egui::vec2(12.0, 12.0);
            let (swatch, _) = ui.allocate_exact_size(size, egui::Sense::hover());
            let colour = heatmap::color32(level as f32 / top);
            ui.painter().rect_filled(swatch, 2.0, colour);
            ui.label(level.to_string());
        }
    });
    ui.separator();
    ui.label("Drawn tiles").on_hover_text(
        "geometricError is lodstudio's certified two-sided Hausdorff bound of the tile against the original triangles below it; SSE is that bound in pixels from the camera.",
    );
    egui::ScrollArea::vertical()
        .id_salt("drawn tiles")
        .max_height(260.0)
        .show(ui, |ui| {
            egui::Grid::new("drawn tiles grid")
                .num_columns(5)
                .striped(true)
                .show(ui, |ui| {
                    for head in ["tile", "level", "triangles", "certified error", "SSE"] {
                        ui.strong(head);
                    }
                    ui.end_row();
                    for d in drawn {
                        let t = &set.tiles[d.tile];
                        ui.label(d.tile.to_string());
                        ui.label(t.depth.to_string());
                        ui.label(view.triangles(d.tile).to_string());
                        ui.label(length(t.error));
                        ui.label(format!("{:.2} px", d.sse_px));
                        ui.end_row();
                    }
                });
        });
}
