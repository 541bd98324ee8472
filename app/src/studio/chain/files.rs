//! The chain's files: its export, and its recipe saved, opened (from a
//! dialog or the recent list) and remembered.

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::mpsc::TryRecvError;

use lodstudio_core::recipe::Recipe;

use super::{ChainError, ChainEvent, ChainState, SaveWork};
use crate::export;
use crate::studio::loading::{MAX_RECENT, absolute, pick_file};

/// Where a save goes.
pub enum Target {
    File(PathBuf),
    /// A file the user picks in a dialog, which suggests this name.
    Dialog(String),
}

impl ChainState {
    /// The built chain's GLB (MSFT_lod + MSFT_screencoverage) written to
    /// `target`, when it was built with the rows as they are.
    pub fn export(&self, target: Target) -> Result<SaveWork, ChainError> {
        let chain = Arc::clone(&self.fresh().ok_or(ChainError::Stale)?.chain);
        Ok(match target {
            Target::File(path) => Box::new(move || export::write_chain(&chain.glb(), &path)),
            Target::Dialog(name) => {
                Box::new(move || export::choose_and_write_chain(&chain.glb(), &name))
            }
        })
    }

    /// The rows as a recipe file written to `target`; a named file joins the
    /// recent recipes.
    pub fn save_recipe(&mut self, target: Target) -> SaveWork {
        let bytes = self.settings.recipe.to_json();
        match target {
            Target::File(path) => {
                self.remember_recipe(&path);
                Box::new(move || export::write_bytes(&bytes, &path))
            }
            Target::Dialog(name) => {
                Box::new(move || export::choose_and_write_recipe(&bytes, &name))
            }
        }
    }

    /// Reads a recipe into the rows; a bad one leaves them as they were and
    /// the event names the row and the field.
    pub fn open_recipe(&mut self, path: &Path) -> ChainEvent {
        match Recipe::read(path) {
            Ok(recipe) => {
                self.set_recipe(recipe);
                self.remember_recipe(path);
                ChainEvent::RecipeOpened(path.to_path_buf())
            }
            Err(m) => ChainEvent::RecipeNotOpened(ChainError::Recipe(m)),
        }
    }

    fn remember_recipe(&mut self, path: &Path) {
        let path = absolute(path);
        let recent = &mut self.recent_recipes;
        recent.retain(|p| p != &path);
        recent.insert(0, path);
        recent.truncate(MAX_RECENT);
    }

    /// Asks for a recipe file in a dialog on a worker (one at a time); the
    /// answer arrives at [`ChainState::poll`].
    pub(super) fn open_dialog(&mut self, ctx: &egui::Context) -> Result<(), ChainError> {
        if self.picker.is_none() {
            const FILTERS: &[(&str, &[&str])] = &[("Recipes (json)", &["json"])];
            self.picker =
                Some(pick_file("Open a recipe", FILTERS, ctx).map_err(ChainError::Dialog)?);
        }
        Ok(())
    }

    pub(super) fn poll_picker(&mut self) -> Option<ChainEvent> {
        let chosen = match self.picker.as_ref()?.try_recv() {
            Err(TryRecvError::Empty) => return None,
            Ok(chosen) => chosen,
            Err(TryRecvError::Disconnected) => None,
        };
        self.picker = None;
        Some(match chosen {
            Some(path) => self.open_recipe(&path),
            None => ChainEvent::NoRecipeChosen,
        })
    }
}
