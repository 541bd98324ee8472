//! OGC 3D Tiles 1.1 as a hierarchical LOD with certified geometric errors
//! (issue 47, item 1).
//!
//! The mesh is split into cells of at most `tile_triangles` triangles
//! ([`partition`]); leaves hold the original triangles, and each parent is
//! its children's union simplified to half its triangles with every border
//! locked ([`hlod`]). A cell's border is where the surface goes on into
//! another cell, so it stays the original polyline in every tile until an
//! ancestor holds both sides: any cut of the tree is watertight where the
//! input was (the locked group borders of Nanite and meshoptimizer's
//! clusterlod, on a k-d tree).
//!
//! A tile's `geometricError` is a certified two-sided Hausdorff bound of its
//! content against the original triangles it stands for, composed by the
//! triangle inequality: `H(P, O_P) ≤ H(P, U) + max_i H(C_i, O_i)`, where
//! `U = ∪ C_i` is the children's union the collapse certified `P` against
//! (`simplify::bound`), `O_P = ∪ O_i`, and the union of pairs within `e_i`
//! of each other is within `max e_i` (every point of `C_i` is within `e_i`
//! of `O_i ⊂ O_P`, and the reverse). Leaves are the original: 0. So errors
//! never decrease upwards, as the 3D Tiles specification asks of them.
//! [`store`] keeps each made tile (its GLB, its mesh, its record) in the
//! tileset's folder, so builds resume and shards share the work (issue 47,
//! item 3); [`tileset`] writes `tileset.json` and reads one back, and
//! [`cut`] selects the tiles a viewer draws (item 4).

pub mod cut;
pub mod hlod;
pub mod partition;
pub mod store;
pub mod stream;
pub mod tileset;

pub use hlod::{Counts, TilesError, build, make_level, plan, plan_streamed};
pub use store::{Made, Plan, Store};

/// Tile budgets (most original triangles of a leaf) a tileset is built
/// with: below 64 triangles a tile costs more in its file than in its
/// triangles; above 2²⁴ a leaf is a whole scan.
pub const TILE_TRIANGLES: std::ops::RangeInclusive<usize> = 64..=1 << 24;

/// The default tile budget: 64k triangles, as 3D Tiles viewers stream well.
pub const DEFAULT_TILE_TRIANGLES: usize = 65_536;
