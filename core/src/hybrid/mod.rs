//! Hybrid simplification: triangles and points in one multi-resolution graph
//! (hybrid paper, Cohen, Aliaga & Zhang).
//!
//! Paper: J. D. Cohen, D. G. Aliaga, W. Zhang, "Hybrid Simplification:
//! Combining Multi-resolution Polygon and Point Rendering", Proc. IEEE
//! Visualization 2001 (the "hybrid paper" in this tree's docs).
//!
//! - `mrg`: the graph (§4): nodes, arcs, primitives, invariants.
//! - `build`: the queue of edge collapses and point replacements (§5.1–5.2), τ, κ.
//! - `point_replacement`: §5.3 sampling and the optimal sampling distance.
//! - `point_simplification`: §5.4 octree merging with tight enclosing spheres.
//! - `cut`: view-dependent cuts, fresh and incremental (§4, §6).
//! - `curve`: primitives versus error (Fig. 7–9).
//! - `flythrough`: the fly-through of Fig. 10–11.

pub mod build;
pub mod curve;
pub mod cut;
pub mod flythrough;
pub mod mrg;
pub mod point_replacement;
pub mod point_simplification;

pub use build::{HybridOptions, KAPPA_RANGE, Snapshot, TAU_RANGE, build, build_observed};
pub use cut::HybridCut;
pub use mrg::{Mrg, NodeKind};
