//! The one LOD interface every method, the studio, the exporter and the
//! tests share (DESIGN.md): given a view and a tolerance, which primitives
//! to draw.
//!
//! - `budget`: a triangle budget met or explained ([`Unmet`]);
//! - `hierarchy`: the [`Hierarchy`] trait every method's built structure
//!   implements, and cutting any of them to a triangle count;
//! - `draw_set`: what a cut draws ([`DrawSet`]: triangles, points, splats,
//!   layers, with their bounds);
//! - `pick`: the studio's click to inspect, on any cut;
//! - `method`: the five methods, listed once ([`Method`]);
//! - `chain`: which cut each LOD of a chain is, and where it takes over;
//! - `knobs`: what changes a cut at run time ([`Knobs`]), typed;
//! - `params`: why a build's parameters are refused ([`ParamError`]);
//! - `build`: building any method's hierarchy from typed [`Params`], the one
//!   build path (above the methods, which know only the modules before it).

mod budget;
pub mod build;
pub mod chain;
mod draw_set;
mod hierarchy;
mod knobs;
mod method;
mod params;
mod pick;

pub use budget::{Blocker, Unmet};
pub use build::{BuildError, Input, Params, accepts, build, input_primitives};
pub use draw_set::{BoundKind, CutPoint, DrawSet, Layer, Splat, Texture};
pub use hierarchy::{Hierarchy, select_triangles};
pub use knobs::{Controls, Criteria, Knob, Knobs, PrefixTarget};
pub use method::Method;
pub use params::{ParamError, in_range};
pub use pick::Picked;
