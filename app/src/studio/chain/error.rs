//! Why a chain action failed, in the words the studio shows.

use lodstudio_core::io::LoadError;
use lodstudio_core::progress::Cancelled;

/// Why the chain was not built, measured, exported or read; the message is
/// what the log and the chain panel show.
#[derive(Debug, thiserror::Error)]
pub enum ChainError {
    #[error("Open a model first")]
    NoModel,
    /// The visual difference needs a built chain and the GPU renderer.
    #[error("Visual difference: build the chain (with a GPU renderer) first")]
    NothingToMeasure,
    /// The rows changed since the chain was built: it is not theirs to export.
    #[error("Build the chain first (its rows changed since the last build)")]
    Stale,
    /// The OS refused a worker thread for `task`.
    #[error("cannot start {task}: {source}")]
    Spawn {
        task: &'static str,
        source: std::io::Error,
    },
    #[error("cannot open the file dialog: {0}")]
    Dialog(std::io::Error),
    /// The model, reopened with the recipe's welding, did not load.
    #[error(transparent)]
    Reload(#[from] LoadError),
    /// The recipe does not fit the model (the message names the row).
    #[error("{0}")]
    BadInput(String),
    /// A recipe file unreadable or failing its checks (the message names
    /// the row and the field).
    #[error("{0}")]
    Recipe(String),
    /// The off-screen renderer failed.
    #[error(transparent)]
    Render(#[from] crate::render::offscreen::RenderError),
    /// The worker of the named task ended without an answer (it panicked).
    #[error("the {0} stopped unexpectedly (internal error)")]
    Lost(&'static str),
    /// Stopped by the user: never shown, a cancelled job sends nothing.
    #[error("cancelled")]
    Cancelled,
}

impl From<Cancelled> for ChainError {
    fn from(_: Cancelled) -> Self {
        ChainError::Cancelled
    }
}

impl From<lodstudio_core::recipe::ChainError> for ChainError {
    fn from(e: lodstudio_core::recipe::ChainError) -> Self {
        match e {
            lodstudio_core::recipe::ChainError::Cancelled => ChainError::Cancelled,
            e => ChainError::BadInput(e.to_string()),
        }
    }
}
