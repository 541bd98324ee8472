//! The chain's kept work (`recipe::cache`): one cache shared by the chain's
//! builds, so an edited row rebuilds only its own group, and its file beside
//! the session, so a restarted (or crashed) studio reopens the last chain
//! without building it, and builds an edited one from what it already had.

use std::path::PathBuf;
use std::sync::{Arc, Mutex, MutexGuard};

use lodstudio_core::recipe::{ChainCache, Recipe};

/// The file of the kept work, in the session's folder.
pub const FILE_NAME: &str = "chain.lodc";

/// The cache the chain's builds share, and where it is saved.
#[derive(Clone, Default)]
pub struct Kept {
    cache: Arc<Mutex<ChainCache>>,
    /// `None`: nothing is saved (no session folder, as in tests).
    file: Option<PathBuf>,
}

impl Kept {
    /// Kept work saved into `file`.
    pub fn in_file(file: Option<PathBuf>) -> Kept {
        Kept {
            file,
            ..Kept::default()
        }
    }

    /// An empty cache saved to the same file (another model: what was kept
    /// for the last one is of no use, and a build still holding it keeps
    /// its own).
    pub fn emptied(&self) -> Kept {
        Kept::in_file(self.file.clone())
    }

    /// The cache, for one build at a time. A build that panicked leaves
    /// entries that are each whole (they are keyed by what made them).
    pub fn lock(&self) -> MutexGuard<'_, ChainCache> {
        self.cache.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Whether work was saved (by this session or an earlier one).
    pub fn has_saved(&self) -> bool {
        self.file.as_ref().is_some_and(|f| f.is_file())
    }

    /// The saved cache and its recipe, when one was saved for the model
    /// with `fingerprint` (a damaged or foreign file is no cache).
    pub fn saved(&self, fingerprint: &str) -> Option<(Recipe, ChainCache)> {
        let bytes = std::fs::read(self.file.as_ref()?).ok()?;
        ChainCache::from_bytes(&bytes)
            .ok()
            .filter(|(_, cache)| cache.is_for(fingerprint))
    }

    /// Saves `cache`, filled by a build of `recipe`, atomically.
    pub fn save(&self, cache: &ChainCache, recipe: &Recipe) -> Result<(), String> {
        let Some(file) = &self.file else {
            return Ok(());
        };
        if let Some(dir) = file.parent() {
            std::fs::create_dir_all(dir).map_err(|e| e.to_string())?;
        }
        lodstudio_core::io::write_atomic(file, &cache.to_bytes(recipe))
            .map_err(|e| format!("{}: {e}", file.display()))
    }
}
