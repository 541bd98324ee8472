//! Batch export at scale (DESIGN.md, "The LOD chain and recipes"): many
//! models, one recipe, on one machine or split over a cluster by an index
//! (Kubernetes Indexed Jobs, CI matrices, Slurm arrays) with no scheduler of
//! ours. Every part is deterministic, so any thread or shard count writes the
//! same bytes.
//!
//! - `manifest`: the inputs (a manifest file, a folder or a glob), each with
//!   its per-asset recipe overrides, confined to the asset root;
//! - `shard`: which shard runs an input (balanced by size, largest first)
//!   and the shard index from the environment;
//! - `cache`: outputs keyed by the content of the inputs, the recipe and the
//!   tool, kept in the output folder, with the temporaries of killed runs
//!   removed by the next (never a live run's);
//! - `schedule`: the models of one machine on workers within a memory budget
//!   (a gzip input counted at its inflated size).

pub mod cache;
pub mod manifest;
pub mod schedule;
pub mod shard;

pub use cache::{Cache, Lookup, Record};
pub use manifest::{Entry, read_manifest};
pub use schedule::{estimate_peak, parsed_size, run_within_budget};
pub use shard::{Shard, assign};
