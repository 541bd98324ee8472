//! lodstudio: the eframe/wgpu studio for level-of-detail hierarchies.

pub mod build;
pub mod export;
pub mod file_dialog;
pub mod frame_stats;
pub mod heatmap;
pub mod job;
pub mod live_cut;
pub mod panels;
pub mod render;
pub mod session;
pub mod settings;
pub mod studio;
pub mod tileset_view;

use std::path::PathBuf;

/// Opens the studio window on `initial` (or the bundled default model) and
/// runs until it is closed.
///
/// # Errors
/// A one-line message (never a panic) when there is no display or no usable
/// graphics adapter.
pub fn run_studio(initial: Option<PathBuf>) -> Result<(), eframe::Error> {
    let options = eframe::NativeOptions {
        renderer: eframe::Renderer::Wgpu,
        viewport: egui::ViewportBuilder::default()
            .with_title("lodstudio")
            .with_app_id("lodstudio")
            .with_inner_size([1280.0, 800.0])
            .with_min_inner_size([640.0, 400.0])
            .with_drag_and_drop(true),
        // The viewport's blit pipeline is built for egui's pass as configured
        // here: one sample, no depth buffer (the 3D view has its own).
        multisampling: 0,
        depth_buffer: 0,
        persist_window: true,
        ..Default::default()
    };
    eframe::run_native(
        "lodstudio",
        options,
        Box::new(|cc| Ok(Box::new(studio::StudioApp::new(cc, initial)))),
    )
}
