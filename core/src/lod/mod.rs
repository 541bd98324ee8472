//! The one LOD interface every method, the studio, the exporter and the
//! tests share (DESIGN.md): given a view and a tolerance, which primitives
//! to draw.
//!
//! - `hierarchy`: the [`Hierarchy`] trait every method's built structure
//!   implements, and cutting any of them to a triangle count;
//! - `draw_set`: what a cut draws ([`DrawSet`]: triangles, points, splats,
//!   layers, with their bounds);
//! - `pick`: the studio's click to inspect, on any cut;
//! - `method`: the five methods, listed once ([`Method`]);
//! - `chain`: which cut each LOD of a chain is, and where it takes over;
//! - `knobs`: what changes a cut at run time ([`Knobs`]), typed.

pub mod chain;
mod draw_set;
mod hierarchy;
mod knobs;
mod method;
mod pick;

pub use draw_set::{BoundKind, CutPoint, DrawSet, Layer, Splat, Texture};
pub use hierarchy::{Hierarchy, select_triangles};
pub use knobs::{Criteria, Knobs, PrefixTarget};
pub use method::Method;
pub use pick::Picked;
