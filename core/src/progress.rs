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
    /// The part of a larger job running now ([`Progress::part`]).
    part: Mutex<Option<Part>>,
    /// Two fills the bar reported since it last restarted, and when: the
    /// rate between the older and now gives [`Progress::time_left`].
    bar_window: Mutex<Option<Window>>,
    fraction: AtomicU32,
    cancel: AtomicBool,
    watched: AtomicBool,
    /// The latest intermediate state and when it was published.
    preview: Mutex<(Option<DrawSet>, Option<Instant>)>,
}

/// A named share `[lo, hi]` of the bar.
#[derive(Debug, Clone)]
struct Part {
    name: String,
    lo: f32,
    hi: f32,
}

/// Fills of the bar and when they were reported: the older one is at most
/// [`WINDOW`] × 2 old, so the rate follows a stage that slows down (later
/// collapses cost more to bound than early ones).
#[derive(Debug, Clone, Copy)]
struct Window {
    older: (Instant, f32),
    newer: (Instant, f32),
}

const WINDOW: Duration = Duration::from_secs(5);

/// The shortest time between two published intermediate states.
const PREVIEW_INTERVAL: Duration = Duration::from_millis(250);

impl Progress {
    pub fn new() -> Self {
        Self::default()
    }

    /// Starts a named stage and resets the fraction to 0: the bar restarts,
    /// unless the stage belongs to a part, whose share of the bar it fills.
    pub fn stage(&self, name: &str) {
        if let Ok(mut s) = self.stage.lock() {
            s.clear();
            s.push_str(name);
        }
        self.set_fraction(0.0);
        if self.part.lock().is_ok_and(|p| p.is_none()) {
            self.restart_bar();
        }
    }

    /// Starts part `name` of a larger job (a chain's row), filling the
    /// share `lo..=hi` of the bar: its stages are named after it and move
    /// the bar within that share, so the bar never restarts while the job
    /// runs (a part from 0 starts it).
    pub fn part(&self, name: &str, lo: f32, hi: f32) {
        if let Ok(mut p) = self.part.lock() {
            *p = Some(Part {
                name: name.to_string(),
                lo,
                hi: hi.max(lo),
            });
        }
        if lo <= 0.0 {
            self.restart_bar();
        }
        self.stage("");
    }

    fn restart_bar(&self) {
        if let Ok(mut w) = self.bar_window.lock() {
            *w = None;
        }
    }

    pub fn set_fraction(&self, f: f32) {
        let f = if f.is_finite() {
            f.clamp(0.0, 1.0)
        } else {
            0.0
        };
        self.fraction.store(f.to_bits(), Ordering::Relaxed);
        if let Ok(mut w) = self.bar_window.lock() {
            let now = (Instant::now(), self.fraction());
            match &mut *w {
                None => {
                    *w = Some(Window {
                        older: now,
                        newer: now,
                    })
                }
                Some(w) if w.newer.0.elapsed() >= WINDOW => {
                    w.older = w.newer;
                    w.newer = now;
                }
                Some(_) => {}
            }
        }
    }

    /// How full the bar is: the stage's fraction, within its part's share.
    pub fn fraction(&self) -> f32 {
        let f = f32::from_bits(self.fraction.load(Ordering::Relaxed));
        match self.part.lock().ok().and_then(|p| p.clone()) {
            Some(Part { lo, hi, .. }) => lo + f * (hi - lo),
            None => f,
        }
    }

    /// Whether the bar stands for the whole job (its parts), not only the
    /// stage running now.
    pub fn has_parts(&self) -> bool {
        self.part.lock().is_ok_and(|p| p.is_some())
    }

    /// The time left until the bar is full, at the rate it filled over the
    /// last 5–10 s (a stage may start half full, with work done ahead by
    /// another thread, and slow down as it goes); `None` until a second and
    /// 2 % of the bar have passed (too early to tell).
    pub fn time_left(&self) -> Option<Duration> {
        let (t0, f0) = (*self.bar_window.lock().ok()?)?.older;
        let (elapsed, f) = (t0.elapsed(), self.fraction());
        (f - f0 >= 0.02 && elapsed >= Duration::from_secs(1))
            .then(|| elapsed.mul_f32((1.0 - f) / (f - f0)))
    }

    /// The stage's name, after its part's where it has one ("row 2 of
    /// 4: hybrid · sampling").
    pub fn stage_name(&self) -> String {
        let stage = self.stage.lock().map(|s| s.clone()).unwrap_or_default();
        match self.part.lock().ok().and_then(|p| p.clone()) {
            Some(part) if stage.is_empty() => part.name,
            Some(part) => format!("{} · {stage}", part.name),
            None => stage,
        }
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

#[cfg(test)]
mod tests {
    use super::*;

    /// A job's parts fill their shares of the bar, whatever their stages do,
    /// and name them; a bar too young tells no time.
    #[test]
    fn parts_fill_their_share_and_name_their_stages() {
        let p = Progress::new();
        p.stage("load");
        p.set_fraction(0.5);
        assert_eq!((p.fraction(), p.stage_name().as_str()), (0.5, "load"));
        assert!(!p.has_parts());
        p.part("row 1 of 4: hybrid", 0.0, 0.5);
        assert!(p.has_parts());
        p.stage("sampling");
        p.set_fraction(0.5);
        assert_eq!(p.fraction(), 0.25);
        assert_eq!(p.stage_name(), "row 1 of 4: hybrid · sampling");
        p.stage("merging");
        assert_eq!(
            p.fraction(),
            0.0,
            "a part's stage starts at its share's start"
        );
        p.set_fraction(1.0);
        p.part("row 3 of 4: amg", 0.5, 1.0);
        assert_eq!(p.fraction(), 0.5);
        assert_eq!(p.stage_name(), "row 3 of 4: amg");
        assert_eq!(p.time_left(), None, "too early to tell");
    }

    /// A stage that starts half full and fills a quarter in a second has
    /// about a second left (not the third of a second its start suggests).
    #[test]
    fn the_time_left_follows_the_rate_the_bar_filled() {
        let p = Progress::new();
        p.stage("work");
        p.set_fraction(0.5);
        std::thread::sleep(Duration::from_millis(1050));
        assert_eq!(p.time_left(), None, "no progress yet");
        p.set_fraction(0.75);
        let left = p.time_left().expect("an estimate").as_secs_f32();
        assert!((1.0..3.0).contains(&left), "{left} s");
        p.stage("next");
        assert_eq!(p.time_left(), None, "a new stage: too early");
    }
}
