//! The bottom panel (progress rows with cancel, the log), the load-error
//! window and the drop hint.

use super::StudioApp;

/// Older log lines are dropped beyond this many.
const MAX_LOG: usize = 500;

pub(super) struct LogLine {
    pub(super) text: String,
    pub(super) error: bool,
}

impl StudioApp {
    pub(super) fn info(&mut self, text: String) {
        self.push_log(text, false);
    }

    pub(super) fn error(&mut self, text: String) {
        self.push_log(text, true);
    }

    pub(super) fn load_failed(&mut self, text: String) {
        self.error(text.clone());
        self.error = Some(text);
    }

    fn push_log(&mut self, text: String, error: bool) {
        // Measured sessions (scripts/studio-session.sh) read the log too.
        if self.frame_stats.reporting() {
            eprintln!("log {text}");
        }
        if self.log.len() >= MAX_LOG {
            self.log.drain(..MAX_LOG / 10);
        }
        self.log.push(LogLine { text, error });
    }

    pub(super) fn status_panel(&mut self, ui: &mut egui::Ui) {
        if self.job.as_ref().is_some_and(|l| l.job.progress_row(ui)) {
            self.cancel_load();
        }
        if self.build.as_ref().is_some_and(|b| b.progress_row(ui)) {
            self.cancel_build();
        }
        if self
            .tileset_job
            .as_ref()
            .is_some_and(|j| j.progress_row(ui))
        {
            // Dropping the job cancels it.
            self.tileset_job = None;
            self.info("Stopped the tileset".into());
        }
        if self.build.is_some() {
            // The UI keeps its frame rate while the worker builds: show it.
            ui.weak(format!("frame {}", self.frame_summary()))
                .on_hover_text("Time between frames, and the CPU time of the last frame.");
        }
        let row_height = ui.text_style_height(&egui::TextStyle::Body);
        let error_color = ui.visuals().error_fg_color;
        egui::ScrollArea::vertical()
            .auto_shrink([false, false])
            .stick_to_bottom(true)
            .show_rows(ui, row_height, self.log.len(), |ui, rows| {
                for line in &self.log[rows] {
                    if line.error {
                        ui.colored_label(error_color, &line.text);
                    } else {
                        ui.label(&line.text);
                    }
                }
            });
    }

    /// "16.7 ms (CPU 3.2 ms)": the median frame interval over the last second
    /// and, under eframe, the median CPU time (the last frame's until a second
    /// has passed).
    pub(super) fn frame_summary(&self) -> String {
        let stats = &self.frame_stats;
        let (interval, cpu) = if stats.median_ms > 0.0 {
            (stats.median_ms, stats.median_cpu_ms)
        } else {
            (self.frame_ms, self.cpu_ms)
        };
        match cpu {
            Some(cpu) => format!("{interval:.1} ms (CPU {cpu:.1} ms)"),
            None => format!("{interval:.1} ms"),
        }
    }

    /// A dismissable window with the last load error.
    pub(super) fn error_window(&mut self, ctx: &egui::Context) {
        let Some(message) = &self.error else {
            return;
        };
        let mut dismissed = false;
        egui::Window::new("Could not open model")
            .collapsible(false)
            .resizable(false)
            .anchor(egui::Align2::CENTER_CENTER, [0.0, 0.0])
            .show(ctx, |ui| {
                ui.colored_label(ui.visuals().error_fg_color, message);
                ui.label("The previous model is still open.");
                dismissed = ui.button("OK").clicked();
            });
        if dismissed {
            self.error = None;
        }
    }
}

/// Tells the user a file dragged over the window will open when dropped.
pub(super) fn drop_hint(ctx: &egui::Context) {
    if ctx.input(|i| i.raw.hovered_files.is_empty()) {
        return;
    }
    let painter = ctx.layer_painter(egui::LayerId::new(
        egui::Order::Foreground,
        egui::Id::unique("drop hint"),
    ));
    let rect = ctx.content_rect();
    painter.rect_filled(rect, 0.0, egui::Color32::from_black_alpha(160));
    painter.text(
        rect.center(),
        egui::Align2::CENTER_CENTER,
        "Drop to open",
        egui::FontId::proportional(28.0),
        egui::Color32::WHITE,
    );
}
