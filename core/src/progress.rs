//! Shared progress / cancel handle for long work (loading, building hierarchies).
//!
//! Workers publish a stage name and a fraction; the GUI polls them every frame and
//! may raise the cancel flag, which workers check between chunks of work. When
//! someone watches ([`Progress::watch`]), workers also publish what they have
//! built so far (a [`DrawSet`]) a few times a second, so the studio can show the
//! hierarchy as it grows; nobody watching costs one atomic load.

use std::sync::Mutex;
use std::sync::atomic::{AtomicBool, AtomicU32, Ordering};
use std::time::{Duration, Instant};

use crate::lod::DrawSet;

/// Returned by work that stopped because [`Progress::cancel`] was called.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[error("cancelled")]
pub struct Cancelled;

/// Stage name, fraction done (0..=1) and a cancel flag, shared between threads.
#[derive(Debug, Default)]
pub struct Progress {
    stage: Mutex<String>,
    fraction: AtomicU32,
    cancel: AtomicBool,
    watched: AtomicBool,
    /// The latest intermediate state and when it was published.
    preview: Mutex<(Option<DrawSet>, Option<Instant>)>,
}

/// The shortest time between two published intermediate states.
const PREVIEW_INTERVAL: Duration = Duration::from_millis(250);

impl Progress {
    pub fn new() -> Self {
        Self::default()
    }

    /// Starts a named stage and resets the fraction to 0.
    pub fn stage(&self, name: &str) {
        if let Ok(mut s) = self.stage.lock() {
            s.clear();
            s.push_str(name);
        }
        self.set_fraction(0.0);
    }

    pub fn set_fraction(&self, f: f32) {
        let f = if f.is_finite() {
            f.clamp(0.0, 1.0)
        } else {
            0.0
        };
        self.fraction.store(f.to_bits(), Ordering::Relaxed);
    }

    pub fn fraction(&self) -> f32 {
        f32::from_bits(self.fraction.load(Ordering::Relaxed))
    }

    pub fn stage_name(&self) -> String {
        self.stage.lock().map(|s| s.clone()).unwrap_or_default()
    }

    pub fn cancel(&self) {
        self.cancel.store(true, Ordering::Relaxed);
    }

    pub fn is_cancelled(&self) -> bool {
        self.cancel.load(Ordering::Relaxed)
    }

    /// Asks workers to publish intermediate states.
    pub fn watch(&self) {
        self.watched.store(true, Ordering::Relaxed);
    }

    /// Whether a worker should publish now: someone watches and the last state
    /// is older than a quarter second.
    pub fn wants_preview(&self) -> bool {
        self.watched.load(Ordering::Relaxed)
            && self
                .preview
                .lock()
                .is_ok_and(|p| p.1.is_none_or(|t| t.elapsed() >= PREVIEW_INTERVAL))
    }

    /// Publishes what is built so far (replacing any state not yet taken).
    pub fn publish(&self, state: DrawSet) {
        if let Ok(mut p) = self.preview.lock() {
            *p = (Some(state), Some(Instant::now()));
        }
    }

    /// The latest state published since the last call.
    pub fn take_preview(&self) -> Option<DrawSet> {
        self.preview.lock().ok().and_then(|mut p| p.0.take())
    }

    /// `Err(Cancelled)` once cancel was requested; call between chunks of work.
    pub fn check(&self) -> Result<(), Cancelled> {
        if self.is_cancelled() {
            Err(Cancelled)
        } else {
            Ok(())
        }
    }
}
