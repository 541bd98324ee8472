//! The one LOD interface every method, the studio, the exporter and the
//! tests share (DESIGN.md): given a view and a tolerance, which primitives
//! to draw.
//!
//! - `hierarchy`: the [`Hierarchy`] trait every method's built structure
//!   implements, and cutting any of them to a triangle count;
//! - `draw_set`: what a cut draws ([`DrawSet`]: triangles, points, splats,
//!   layers, with their bounds);
//! - `pick`: the studio's click to inspect, on any cut.

mod draw_set;
mod hierarchy;
mod pick;

pub use draw_set::{CutPoint, DrawSet, Layer, Splat, Texture};
pub use hierarchy::{Hierarchy, select_triangles};
pub use pick::Picked;
