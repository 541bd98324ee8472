//! Background jobs (loading a model, building a LOD) with a shared
//! progress/cancel handle, and the one progress row the status panel shows for
//! any of them.
//!
//! The UI polls a job each frame instead of waiting on it, so it never blocks.
//! Dropping a job cancels it: whoever replaces or abandons a job stops its
//! worker without extra bookkeeping, and a cancelled worker's answer is never
//! read.

use std::sync::mpsc::{self, Receiver, TryRecvError};
use std::sync::{Arc, OnceLock};
use std::time::{Duration, Instant};

use lodstudio_core::Progress;
use lodstudio_core::progress::Cancelled;

/// Work running on its own thread.
pub struct Job<T> {
    /// What the progress row names (a model, a method).
    label: String,
    progress: Arc<Progress>,
    started: Instant,
    result: Receiver<T>,
}

/// A job's state at one poll.
pub enum Poll<T> {
    Running,
    Done(T),
    /// The worker ended without an answer (it panicked).
    Lost,
}

impl<T: Send + 'static> Job<T> {
    /// Runs `work` on a thread named `thread`; the UI is woken when it ends.
    /// Work that returns `Err(Cancelled)` sends nothing (nobody waits for it).
    ///
    /// # Errors
    /// The OS refused to start a thread.
    pub fn spawn(
        thread: &str,
        label: String,
        ctx: &egui::Context,
        work: impl FnOnce(&Progress) -> Result<T, Cancelled> + Send + 'static,
    ) -> std::io::Result<Job<T>> {
        let progress = Arc::new(Progress::new());
        let worker_progress = Arc::clone(&progress);
        let (tx, rx) = mpsc::channel();
        let ctx = ctx.clone();
        std::thread::Builder::new()
            .name(thread.into())
            .spawn(move || {
                let answer = match background_pool() {
                    Some(pool) => pool.install(|| work(&worker_progress)),
                    None => work(&worker_progress),
                };
                if let Ok(answer) = answer
                    && !worker_progress.is_cancelled()
                {
                    // The receiver is gone if the job was dropped meanwhile.
                    let _ = tx.send(answer);
                    ctx.request_repaint();
                }
            })?;
        Ok(Job {
            label,
            progress,
            started: Instant::now(),
            result: rx,
        })
    }
}

/// The rayon pool jobs run their parallel work on, apart from the UI's.
/// Its threads run at normal priority: what keeps the UI responsive is that
/// it draws only on input or at the studio's poll interval, not that builds
/// starve (under SCHED_IDLE a build stalled while a software renderer drew:
/// benchmarks/studio.md, "Builds against the CLI"). `None` if it could not
/// start (jobs then use the global pool).
fn background_pool() -> Option<&'static rayon::ThreadPool> {
    static POOL: OnceLock<Option<rayon::ThreadPool>> = OnceLock::new();
    POOL.get_or_init(|| {
        rayon::ThreadPoolBuilder::new()
            .thread_name(|i| format!("build {i}"))
            .build()
            .ok()
    })
    .as_ref()
}

impl<T> Job<T> {
    pub fn poll(&self) -> Poll<T> {
        match self.result.try_recv() {
            Ok(answer) => Poll::Done(answer),
            Err(TryRecvError::Empty) => Poll::Running,
            // Cancelled workers send nothing, but a cancelled job is never polled.
            Err(TryRecvError::Disconnected) => Poll::Lost,
        }
    }

    /// The shared progress handle (stage, fraction, intermediate states).
    pub fn progress(&self) -> &Progress {
        &self.progress
    }

    pub fn label(&self) -> &str {
        &self.label
    }

    pub fn elapsed(&self) -> Duration {
        self.started.elapsed()
    }

    /// A progress bar with the stage name, the time left once it can be
    /// told, and a Cancel button; true when Cancel
    /// was clicked (the caller drops the job, which stops it).
    pub fn progress_row(&self, ui: &mut egui::Ui) -> bool {
        ui.horizontal(|ui| {
            let mut text = format!("{}: {}", self.label, self.progress.stage_name());
            if let Some(left) = self.progress.time_left() {
                // A bar of one stage tells that stage's time only.
                let scope = if self.progress.has_parts() {
                    ""
                } else {
                    " in this stage"
                };
                text.push_str(&format!(" · about {} left{scope}", duration_text(left)));
            }
            ui.add(
                egui::ProgressBar::new(self.progress.fraction())
                    .desired_width((ui.available_width() - 80.0).max(40.0))
                    .text(text),
            );
            ui.button("Cancel").clicked()
        })
        .inner
    }
}

/// "45 s", "3 min 20 s": whole seconds, an estimate needs no more.
fn duration_text(d: Duration) -> String {
    match d.as_secs() {
        s if s < 60 => format!("{s} s"),
        s => format!("{} min {} s", s / 60, s % 60),
    }
}

impl<T> Drop for Job<T> {
    fn drop(&mut self) {
        self.progress.cancel();
    }
}
