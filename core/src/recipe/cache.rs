//! What a chain build made, kept so that the next build of an edited recipe
//! makes only what the edit changed, and a restarted studio none of it.
//!
//! A recipe's rows fall into groups that share one hierarchy
//! ([`super::Row::same_hierarchy`]): one progressive collapse for the
//! edge-collapse rows, one built hierarchy cut once per row for each other
//! method and parameters. A group's LODs are a function of the model, the
//! group's parameters and its rows' tolerances (with the recipe's viewport
//! height and coverage, which turn pixel rows into object-space errors), and
//! of nothing else, so they are kept under that key ([`group_key`]). The
//! built hierarchies are kept as well, in memory only, under their
//! parameters: a tolerance edited on a hierarchy row re-cuts the hierarchy
//! without building it again. An edge-collapse group has no hierarchy to
//! keep (its collapse runs to its rows' targets), so an edited
//! edge-collapse tolerance runs that group's collapse again, and only it.
//!
//! The model is named by the SHA-256 of its content, so a cache never
//! answers for another model, and entries the last build did not use are
//! dropped: the cache holds one chain's work, never a growing history.

use std::io::Write;

use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};

use super::{Recipe, RowTolerance};
use crate::geom::Model;
use crate::io::hierarchy_file::{self, HierarchyFileError};
use crate::lod::{DrawSet, Hierarchy, Params};

/// The method name of a saved chain cache in the saved-hierarchy container.
const SAVED_AS: &str = "chain cache";

/// One group's LODs (one per row, in the group's row order).
#[derive(Debug, Clone, Serialize, Deserialize)]
struct Group {
    key: String,
    sets: Vec<DrawSet>,
    /// What building them took when they were built.
    seconds: f64,
    #[serde(skip)]
    used: bool,
}

/// A built hierarchy and its parameters' key.
struct Kept {
    key: String,
    hierarchy: Box<dyn Hierarchy>,
    used: bool,
}

/// The work of the last chain build on one model (see the module doc).
#[derive(Default, Serialize, Deserialize)]
pub struct ChainCache {
    /// [`fingerprint`] of the model the entries were made on.
    model: String,
    groups: Vec<Group>,
    #[serde(skip)]
    hierarchies: Vec<Kept>,
}

/// A group's LODs found in the cache.
pub(super) struct Hit {
    pub sets: Vec<DrawSet>,
    pub seconds: f64,
}

impl ChainCache {
    /// Starts a build on the model with `fingerprint`: a cache of another
    /// model is emptied.
    pub(super) fn begin(&mut self, fingerprint: &str) {
        if self.model != fingerprint {
            *self = ChainCache {
                model: fingerprint.to_string(),
                ..ChainCache::default()
            };
        }
        self.groups.iter_mut().for_each(|g| g.used = false);
        self.hierarchies.iter_mut().for_each(|h| h.used = false);
    }

    /// The LODs of the group with `key`, when they were built before.
    pub(super) fn group(&mut self, key: &str) -> Option<Hit> {
        let g = self.groups.iter_mut().find(|g| g.key == key)?;
        g.used = true;
        Some(Hit {
            sets: g.sets.clone(),
            seconds: g.seconds,
        })
    }

    /// Keeps a group's LODs under `key`.
    pub(super) fn keep_group(&mut self, key: String, sets: Vec<DrawSet>, seconds: f64) {
        self.groups.retain(|g| g.key != key);
        self.groups.push(Group {
            key,
            sets,
            seconds,
            used: true,
        });
    }

    /// The hierarchy built with the parameters of `key`, taken out (given
    /// back with [`ChainCache::keep_hierarchy`] once cut).
    pub(super) fn take_hierarchy(&mut self, key: &str) -> Option<Box<dyn Hierarchy>> {
        let at = self.hierarchies.iter().position(|h| h.key == key)?;
        Some(self.hierarchies.swap_remove(at).hierarchy)
    }

    pub(super) fn keep_hierarchy(&mut self, key: String, hierarchy: Box<dyn Hierarchy>) {
        self.hierarchies.push(Kept {
            key,
            hierarchy,
            used: true,
        });
    }

    /// Ends a build that finished: what it did not use is dropped.
    pub(super) fn finish(&mut self) {
        self.groups.retain(|g| g.used);
        self.hierarchies.retain(|h| h.used);
    }

    /// Whether the entries were made on the model with `fingerprint`.
    pub fn is_for(&self, fingerprint: &str) -> bool {
        self.model == fingerprint
    }

    /// Groups of LODs kept (for reports and tests).
    pub fn groups(&self) -> usize {
        self.groups.len()
    }

    /// The cache as a file, with the recipe whose build filled it, in the
    /// saved-hierarchy container (versioned, checksummed).
    pub fn to_bytes(&self, recipe: &Recipe) -> Vec<u8> {
        let recipe = serde_json::to_value(recipe).unwrap_or_default();
        hierarchy_file::save(SAVED_AS, &recipe, self)
    }

    /// A cache read back from [`ChainCache::to_bytes`], with its recipe.
    pub fn from_bytes(bytes: &[u8]) -> Result<(Recipe, ChainCache), HierarchyFileError> {
        let (header, cache) = hierarchy_file::load::<ChainCache>(bytes, SAVED_AS)?;
        let recipe =
            serde_json::from_value(header.params).map_err(|e| HierarchyFileError::Corrupt {
                what: "recipe",
                why: e.to_string(),
            })?;
        Ok((recipe, cache))
    }
}

/// The SHA-256 of a model's content (every attribute, bit for bit).
pub fn fingerprint(model: &Model) -> String {
    struct Hashing(Sha256);
    impl Write for Hashing {
        fn write(&mut self, bytes: &[u8]) -> std::io::Result<usize> {
            self.0.update(bytes);
            Ok(bytes.len())
        }
        fn flush(&mut self) -> std::io::Result<()> {
            Ok(())
        }
    }
    let mut h = Hashing(Sha256::new());
    h.0.update(model.kind().as_bytes());
    // Serialising plain data into a hasher cannot fail.
    let written = match model {
        Model::Mesh(m) => bincode::serialize_into(&mut h, m),
        Model::Points(p) => bincode::serialize_into(&mut h, p),
        Model::Volume(v) => bincode::serialize_into(&mut h, v),
    };
    debug_assert!(written.is_ok());
    h.0.finalize().iter().map(|b| format!("{b:02x}")).collect()
}

/// The key of a hierarchy: its parameters.
pub(super) fn hierarchy_key(params: &Params) -> String {
    serde_json::to_string(params).unwrap_or_default()
}

/// The key of a group's LODs: its parameters, its rows' tolerances, and the
/// viewport height and coverage that turn pixel rows into errors.
pub(super) fn group_key(recipe: &Recipe, group: &[usize]) -> String {
    let tolerances: Vec<&RowTolerance> = group.iter().map(|&j| &recipe.rows[j].tolerance).collect();
    let key = (
        recipe.row_params(group[0]),
        tolerances,
        recipe.viewport_height,
        recipe.coverage,
        recipe.rows[group[0]].frees_topology(),
    );
    serde_json::to_string(&key).unwrap_or_default()
}
