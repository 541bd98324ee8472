//! Run-time knobs: what changes a cut without a rebuild, typed. The studio
//! hands every live hierarchy the same [`Knobs`]; each method reads its own,
//! says whether its cut may change, and says which knobs it reads and
//! whether one of them overrides the tolerance ([`Controls`]), so the studio
//! shows only live controls and never a threshold that does nothing.

/// Which view-dependent criteria refine or coarsen beyond the screen-space
/// projection (§3). Each multiplies the pixel threshold of a node.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Criteria {
    /// Visibility culling: nodes wholly back-facing or outside the view
    /// frustum are simplified harder.
    pub backface: bool,
    /// Silhouettes: nodes whose normals straddle the view direction are refined.
    pub silhouette: bool,
    /// Local illumination: nodes across which the diffuse shading of the
    /// view's light changes most are refined.
    pub lighting: bool,
}

impl Default for Criteria {
    fn default() -> Self {
        Self {
            backface: true,
            silhouette: true,
            lighting: true,
        }
    }
}

/// What chooses an edge collapse's prefix instead of the view's tolerance
/// (the studio's ratio and triangle budgets; an error target is the
/// tolerance itself).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum PrefixTarget {
    /// The first prefix with at most this many triangles.
    Triangles(usize),
}

/// Every method's run-time knobs.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Knobs {
    /// Merge tree: the view-dependent criteria (§3).
    pub criteria: Criteria,
    /// Voxel pyramid: a continuous position (§5) instead of the coarsest
    /// level within the tolerance.
    pub pyramid_position: Option<f32>,
    /// AMG: a level instead of the coarsest within the tolerance.
    pub amg_level: Option<usize>,
    /// Edge collapse: a prefix target instead of the tolerance.
    pub collapse: Option<PrefixTarget>,
}

/// One run-time knob (a field of [`Knobs`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Knob {
    /// [`Knobs::criteria`].
    Criteria,
    /// [`Knobs::pyramid_position`].
    PyramidPosition,
    /// [`Knobs::amg_level`].
    AmgLevel,
    /// [`Knobs::collapse`].
    CollapseTarget,
}

/// What chooses a hierarchy's cut at run time, as its last knobs left it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Controls {
    /// The knobs its cuts read.
    pub knobs: &'static [Knob],
    /// The knob that chooses the cut instead of the tolerance, when one does.
    pub overridden_by: Option<Knob>,
    /// Whether it has cuts to choose between at all (a single extracted
    /// level has one: no tolerance or knob changes it).
    pub has_levels: bool,
}

impl Controls {
    /// Whether the tolerance chooses the cut now.
    pub fn follows_tolerance(&self) -> bool {
        self.has_levels && self.overridden_by.is_none()
    }
}
