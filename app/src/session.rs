//! The studio's session autosave: the model on screen, recent files, method
//! settings and thresholds, written every couple of seconds while they change
//! so a crash or a kill loses at most that much tuning, and reopened on the
//! next start.
//!
//! The file is written atomically on a worker thread (never on the frame
//! path): a kill in the middle of a write leaves the previous session whole.

use std::path::{Path, PathBuf};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use serde::{Deserialize, Serialize};

use crate::settings::MethodSettings;
use crate::settings::chain::ChainSettings;
use crate::settings::tiles::TilesSettings;

/// At most this much tuning is lost when the studio dies.
pub const INTERVAL: Duration = Duration::from_secs(2);
/// Folder of the session file; without it, eframe's storage folder for the app.
pub const STATE_DIR_ENV: &str = "LODSTUDIO_STATE_DIR";
const FILE_NAME: &str = "session.json";

/// What a restarted studio reopens.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct Session {
    /// The model on screen: a file or `builtin:NAME`.
    pub model: Option<PathBuf>,
    /// Recently opened files, newest first.
    pub recent: Vec<PathBuf>,
    pub methods: MethodSettings,
    /// The LOD chain on the chain panel (saved or not).
    pub chain: ChainSettings,
    /// Recently opened or saved recipes, newest first.
    pub recent_recipes: Vec<PathBuf>,
    /// The voxel threshold and the volume it was chosen for: it is in that
    /// volume's value units, so it only applies when the same volume reopens.
    #[serde(deserialize_with = "threshold_of")]
    pub volume_threshold: Option<(PathBuf, f32)>,
    /// The tileset view's screen-space error and the studio's tile budget.
    pub tiles: TilesSettings,
}

/// A threshold beyond f32 reads as infinite (then dropped by
/// [`Session::from_json`]) instead of failing the whole session: serde_json
/// parses f32 fields exactly and refuses what overflows them.
fn threshold_of<'de, D: serde::Deserializer<'de>>(
    d: D,
) -> Result<Option<(PathBuf, f32)>, D::Error> {
    let wide: Option<(PathBuf, f64)> = serde::Deserialize::deserialize(d)?;
    Ok(wide.map(|(path, t)| (path, t as f32)))
}

impl Session {
    /// A session read back; damaged or out-of-range values never reach a build.
    pub fn from_json(json: &str) -> Option<Session> {
        let mut session: Session = serde_json::from_str(json).ok()?;
        session.methods = session.methods.sanitized();
        session.chain = session.chain.sanitized();
        session.tiles = session.tiles.sanitized();
        session.volume_threshold = session.volume_threshold.filter(|(_, t)| t.is_finite());
        Some(session)
    }
}

/// Writes the session when it changed, at most once per interval.
pub struct Autosave {
    /// `None`: autosave is off (tests, or no storage folder on this system).
    file: Option<PathBuf>,
    interval: Duration,
    /// When the session was last compared with the file.
    checked: Option<Instant>,
    /// The JSON last handed to the writer: an unchanged session is not rewritten.
    written: String,
    writer: Option<JoinHandle<std::io::Result<()>>>,
}

impl Autosave {
    /// Autosave into `dir` (created when first written).
    pub fn in_dir(dir: impl AsRef<Path>) -> Self {
        let mut autosave = Self::off();
        autosave.file = Some(dir.as_ref().join(FILE_NAME));
        autosave
    }

    /// The folder named by [`STATE_DIR_ENV`], else eframe's storage folder.
    pub fn from_env() -> Self {
        match std::env::var_os(STATE_DIR_ENV)
            .map(PathBuf::from)
            .or_else(|| eframe::storage_dir("lodstudio"))
        {
            Some(dir) => Self::in_dir(dir),
            None => Self::off(),
        }
    }

    pub fn off() -> Self {
        Autosave {
            file: None,
            interval: INTERVAL,
            checked: None,
            written: String::new(),
            writer: None,
        }
    }

    /// Checks at most this often (tests shorten it).
    pub fn with_interval(mut self, interval: Duration) -> Self {
        self.interval = interval;
        self
    }

    pub fn file(&self) -> Option<&Path> {
        self.file.as_deref()
    }

    /// The saved session: `Ok(None)` when there is none, `Err` when the file is
    /// unreadable or damaged (the studio then starts afresh and says so).
    pub fn load(&self) -> Result<Option<Session>, SessionError> {
        let Some(file) = &self.file else {
            return Ok(None);
        };
        let json = match std::fs::read_to_string(file) {
            Ok(json) => json,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
            Err(e) => {
                return Err(SessionError::Read {
                    file: file.clone(),
                    reason: e.to_string(),
                });
            }
        };
        Session::from_json(&json)
            .map(Some)
            .ok_or_else(|| SessionError::Damaged { file: file.clone() })
    }

    /// Time left before the next check, zero when one is due; `None` when off.
    pub fn wait(&self) -> Option<Duration> {
        self.file.as_ref()?;
        Some(self.checked.map_or(Duration::ZERO, |at| {
            self.interval.saturating_sub(at.elapsed())
        }))
    }

    /// Hands `session` to a writer thread when it differs from the last one
    /// written (and the previous write is done), and restarts the interval.
    /// Returns the error of a previous write, if it failed.
    pub fn offer(&mut self, session: &Session) -> Result<(), SessionError> {
        let Some(file) = self.file.clone() else {
            return Ok(());
        };
        self.checked = Some(Instant::now());
        if self.writer.as_ref().is_some_and(|w| !w.is_finished()) {
            return Ok(()); // a slow disk: the next check writes the newest state
        }
        let done = self.finish();
        let json = serde_json::to_string_pretty(session)
            .map_err(|e| SessionError::Encode(e.to_string()))?;
        if json != self.written {
            self.written = json.clone();
            self.writer = Some(std::thread::spawn(move || {
                if let Some(dir) = file.parent() {
                    std::fs::create_dir_all(dir)?;
                }
                lodstudio_core::io::write_atomic(&file, json.as_bytes())
            }));
        }
        done
    }

    /// Writes `session` now and waits for it (on exit).
    pub fn save_now(&mut self, session: &Session) -> Result<(), SessionError> {
        self.finish()?;
        self.offer(session)?;
        self.finish()
    }

    /// Waits for the write under way; its error, if it failed.
    pub fn finish(&mut self) -> Result<(), SessionError> {
        let Some(writer) = self.writer.take() else {
            return Ok(());
        };
        let file = self.file.as_deref().unwrap_or(Path::new(FILE_NAME));
        match writer.join() {
            Ok(Ok(())) => Ok(()),
            Ok(Err(e)) => {
                self.written.clear(); // try again at the next check
                Err(SessionError::Write {
                    file: file.to_path_buf(),
                    reason: e.to_string(),
                })
            }
            Err(_) => Err(SessionError::WriterStopped),
        }
    }
}

/// Why the last session was not read or the current one not saved.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SessionError {
    #[error("cannot read the last session {}: {reason}", file.display())]
    Read { file: PathBuf, reason: String },
    #[error("the last session {} is damaged; starting afresh", file.display())]
    Damaged { file: PathBuf },
    #[error("cannot encode the session: {0}")]
    Encode(String),
    #[error("cannot autosave the session to {}: {reason}", file.display())]
    Write { file: PathBuf, reason: String },
    #[error("the autosave writer stopped")]
    WriterStopped,
}

impl Drop for Autosave {
    fn drop(&mut self) {
        let _ = self.finish();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn session_round_trips_and_unchanged_sessions_are_not_rewritten() {
        let tmp = tempfile::tempdir().unwrap();
        let dir = tmp.path().join("session");
        let mut autosave = Autosave::in_dir(&dir);
        assert_eq!(autosave.load(), Ok(None));
        assert_eq!(
            autosave.wait(),
            Some(Duration::ZERO),
            "the first check is due at once"
        );
        let mut session = Session {
            model: Some("builtin:sphere".into()),
            recent: vec!["/models/a.obj".into()],
            volume_threshold: Some(("/models/ct.nrrd".into(), 812.5)),
            ..Default::default()
        };
        session.methods.auto_rebuild = false;
        autosave.offer(&session).unwrap();
        autosave.finish().unwrap();
        assert!(autosave.wait().unwrap() > Duration::ZERO);
        assert_eq!(autosave.load(), Ok(Some(session.clone())));

        // Unchanged: the file is left alone (its removal stays unnoticed).
        let file = autosave.file().unwrap().to_path_buf();
        std::fs::remove_file(&file).unwrap();
        autosave.offer(&session).unwrap();
        autosave.finish().unwrap();
        assert!(!file.exists());
        session.recent.clear();
        autosave.save_now(&session).unwrap();
        assert_eq!(autosave.load(), Ok(Some(session)));

        std::fs::write(&file, "{ damaged").unwrap();
        assert!(matches!(
            autosave.load(),
            Err(SessionError::Damaged { file }) if Some(file.as_path()) == autosave.file()
        ));
        let odd = r#"{"methods": {"edge_collapse": {"ratio": 7.0}}, "volume_threshold": ["/v.nrrd", 1e40]}"#;
        let restored = Session::from_json(odd).expect("partial sessions parse");
        assert_eq!(
            restored.methods.edge_collapse.ratio, 1.0,
            "out of range → clamped"
        );
        assert_eq!(restored.volume_threshold, None);
    }
}
