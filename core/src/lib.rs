//! lodstudio-core: geometry, model I/O, distance measurement and the
//! level-of-detail methods of lodstudio. No GUI crates live here.
//!
//! Every long operation takes a [`progress::Progress`] handle so a caller (the
//! studio's worker threads, the CLI) can show the stage, the fraction done and
//! cancel at once.

// A library answers bad input with an error, never a panic: no unwrap
// outside tests (clippy.toml allows them in tests).
#![warn(clippy::unwrap_used)]

pub mod amg;
pub mod bake;
pub mod batch;
pub mod builtins;
pub mod distance;
pub mod geom;
pub mod hybrid;
mod id_set;
pub mod implicit;
pub mod impostor;
pub mod io;
pub mod lod;
pub mod mergetree;
pub mod open;
pub mod progress;
pub mod recipe;
pub mod rng;
pub mod scene;
mod simd;
pub mod simplify;
pub mod stats;
pub mod tiles;
pub mod view;
pub mod voxel;

pub use geom::Model;
pub use geom::{Aabb, PointSet, TriMesh, Volume};
pub use io::{LoadError, Loaded};
pub use progress::Progress;
