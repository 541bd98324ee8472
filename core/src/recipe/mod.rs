//! Recipes: the settings of an LOD chain, saved by the studio and replayed
//! by `lodstudio export --recipe` (DESIGN.md, "The LOD chain and recipes").
//!
//! - `file`: the versioned recipe ([`Recipe`]): rows LOD0…LODn, each a
//!   method, its parameters and a tolerance; read with errors that name the
//!   row and the field;
//! - `build`: a recipe applied to a model ([`build_chain`]): one hierarchy
//!   per method and parameters, an LOD per row, its switch coverage from the
//!   certified bound, and the GLB every consumer writes ([`Chain::glb`]);
//! - `flags`: rows that do not earn their place (the same LOD as the row
//!   before, never shown, costlier to draw than the finer LOD), and the
//!   recipe without them ([`Chain::pruned`], what Auto chain keeps);
//! - `cache`: what a chain build made, by the model's content hash and each
//!   group's settings ([`ChainCache`]), so an edited recipe rebuilds only
//!   what the edit changed.

mod build;
mod cache;
mod file;
mod flags;

pub use build::{Chain, ChainError, ChainLod, build_chain, build_chain_cached};
pub use cache::{ChainCache, fingerprint};
pub use file::{
    FORMAT, PostSpec, Recipe, RecipeError, Row, RowTolerance, VERSION, WeldSpec, parse_lods,
};
pub use flags::{Flag, build_unflagged};
