//! What the chain hands the studio: lines for its log, and what its panel
//! asks the studio to do (the chain has no access to the studio itself).

use std::fmt;
use std::path::PathBuf;

use super::ChainError;
use crate::export::Saved;

/// What the chain tells the user through the studio's log.
#[derive(Debug)]
pub enum ChainEvent {
    Built {
        lods: usize,
        /// LODs taken from the kept work (nothing built for them).
        kept: usize,
        /// LODs short of their triangle budget (the table says why).
        short: usize,
        /// Rows flagged: the same LOD as a row before, never shown, or
        /// costlier than the finer LOD (the table says why).
        flagged: usize,
        /// Rows Auto chain left out for one of those reasons.
        left_out: usize,
        seconds: f64,
        /// The last session's chain, reopened without a build.
        reopened: bool,
        /// Why the work could not be saved for the next session.
        not_saved: Option<String>,
    },
    /// The user cancelled the build.
    BuildStopped,
    RecipeOpened(PathBuf),
    NoRecipeChosen,
    /// The build failed (its reason is also noted on the panel).
    NotBuilt(ChainError),
    DifferenceFailed(ChainError),
    /// The rows stay as they were; the studio also shows it in its error
    /// window, as it does a model that did not open.
    RecipeNotOpened(ChainError),
    /// A worker or dialog that did not start, an export of a stale chain.
    Failed(ChainError),
}

impl ChainEvent {
    /// Whether the log shows it as an error.
    pub fn is_error(&self) -> bool {
        !matches!(
            self,
            ChainEvent::Built {
                not_saved: None,
                ..
            } | ChainEvent::BuildStopped
                | ChainEvent::RecipeOpened(_)
                | ChainEvent::NoRecipeChosen
        )
    }
}

impl fmt::Display for ChainEvent {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ChainEvent::Built {
                lods,
                kept,
                seconds,
                reopened,
                not_saved,
                short,
                flagged,
                left_out,
            } => {
                match (reopened, kept) {
                    (true, _) => write!(f, "Reopened the last session's chain of {lods} LODs")?,
                    (false, 0) => write!(f, "Built a chain of {lods} LODs in {seconds:.2} s")?,
                    (false, k) => write!(
                        f,
                        "Built a chain of {lods} LODs in {seconds:.2} s ({k} kept from the last build)"
                    )?,
                }
                if *short > 0 {
                    write!(
                        f,
                        "; {short} short of the triangle budget (the table marks them with !, its hover says why)"
                    )?;
                }
                if *flagged > 0 {
                    write!(
                        f,
                        "; {flagged} rows flagged: the same LOD as a row before, never shown or \
                         costlier to draw (the table's flags column says which and why)"
                    )?;
                }
                if *left_out > 0 {
                    write!(
                        f,
                        "; Auto chain left out {left_out} rows: the same LOD as a row before, \
                         never shown or costlier to draw"
                    )?;
                }
                match not_saved {
                    Some(why) => write!(f, "; not kept for the next session: {why}"),
                    None => Ok(()),
                }
            }
            ChainEvent::BuildStopped => f.write_str("Stopped building the chain"),
            ChainEvent::RecipeOpened(path) => write!(f, "Opened the recipe {}", path.display()),
            ChainEvent::NoRecipeChosen => f.write_str("No recipe chosen"),
            ChainEvent::NotBuilt(e) => write!(f, "Chain not built: {e}"),
            ChainEvent::DifferenceFailed(e) => write!(f, "Visual difference failed: {e}"),
            ChainEvent::RecipeNotOpened(e) => write!(f, "Recipe not opened: {e}"),
            ChainEvent::Failed(e) => write!(f, "{e}"),
        }
    }
}

/// A file write the studio runs on its save worker (one save at a time,
/// with its other exports).
pub type SaveWork = Box<dyn FnOnce() -> Saved + Send>;

/// What the chain panel asks of the studio.
pub enum ChainRequest {
    /// Build the chain of the model on screen.
    Build,
    /// Replace the rows by Auto chain's and build them, less flagged rows.
    Auto,
    /// Measure the visual difference with the viewport's renderer.
    MeasureDifference,
    Save(SaveWork),
    Report(ChainEvent),
}

impl From<Result<SaveWork, ChainError>> for ChainRequest {
    fn from(save: Result<SaveWork, ChainError>) -> Self {
        match save {
            Ok(work) => ChainRequest::Save(work),
            Err(e) => ChainRequest::Report(ChainEvent::Failed(e)),
        }
    }
}
