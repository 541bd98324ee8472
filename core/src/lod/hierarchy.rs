//! What every hierarchy answers: given a view and a tolerance, which
//! primitives to draw (DESIGN.md).

use std::any::Any;

use super::DrawSet;
use crate::view::{Tolerance, View};

/// A built LOD hierarchy. `Any`, so a caller that built one through
/// `lod::build` can read its method's own structure (the inspector, the
/// CLI's reports) with [`downcast_ref`](dyn Hierarchy::downcast_ref).
pub trait Hierarchy: Any + Send + Sync {
    /// The method that built it.
    fn method(&self) -> super::Method;
    /// Bounding-box diagonal of the model it was built from (what relative
    /// tolerances and bounds refer to).
    fn diagonal(&self) -> f32;
    /// The primitives to draw for `view` within `tolerance`. Hierarchies that
    /// adapt incrementally keep the previous cut and start from it.
    fn select(&mut self, view: &View, tolerance: Tolerance) -> DrawSet;
    /// Equal keys for two views promise equal cuts at `tolerance`, so a caller
    /// re-selecting every frame can skip the work; `None` (the default) when
    /// any change of the view may change the cut.
    fn view_key(&self, _view: &View, _tolerance: Tolerance) -> Option<u64> {
        None
    }
    /// The finest cut with at most `n` triangles, for methods whose cuts
    /// form one sequence (edge collapse); `None` for the others.
    fn select_triangles(&mut self, _n: usize) -> Option<DrawSet> {
        None
    }
    /// Takes the run-time knobs it reads (the merge tree's criteria, say);
    /// true when its cut may change with them.
    fn set_knobs(&mut self, _knobs: &super::Knobs) -> bool {
        false
    }
    /// Whether it has levels to choose between; a single extracted level is
    /// a hierarchy of one (the tolerance changes nothing, nothing to save).
    fn has_levels(&self) -> bool {
        true
    }
    /// The knobs its cuts read, and the one that overrides the tolerance
    /// now (as the last [`set_knobs`](Hierarchy::set_knobs) left it); the
    /// default reads none and follows the tolerance.
    fn controls(&self) -> super::Controls {
        super::Controls {
            knobs: &[],
            overridden_by: None,
            has_levels: self.has_levels(),
        }
    }
    /// The built hierarchy in a saved-hierarchy file with `params` (see
    /// `io::hierarchy_file`); `None` for hierarchies that do not save.
    fn save(&self, _params: &serde_json::Value) -> Option<Vec<u8>> {
        None
    }
}

impl dyn Hierarchy {
    /// The built structure as its own type, when it is a `T`.
    pub fn downcast_ref<T: Hierarchy>(&self) -> Option<&T> {
        (self as &dyn Any).downcast_ref()
    }

    pub fn downcast_mut<T: Hierarchy>(&mut self) -> Option<&mut T> {
        (self as &mut dyn Any).downcast_mut()
    }
}

/// The finest cut of `hierarchy` with at most `n` triangles: its own where
/// its cuts form one sequence, else the cut at the least relative tolerance
/// that keeps to `n` (the coarsest cut if none does).
pub fn select_triangles(hierarchy: &mut dyn Hierarchy, view: &View, n: usize) -> DrawSet {
    match hierarchy.select_triangles(n) {
        Some(set) => set,
        None => super::chain::finest_within(hierarchy, view, |s| s.mesh.triangles.len() <= n),
    }
}
