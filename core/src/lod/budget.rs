//! A budget met or explained (issue 48, item 5): a count the collapse could
//! not reach is reported with the rule that kept the edges left and what
//! would reach further, never written silently; so is a budget below a
//! hierarchy's coarsest cut, with what would reach it.

use super::Method;

/// The rule that keeps an edge from collapsing: what would have to give for
/// a budget the collapse cannot reach.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, serde::Serialize, serde::Deserialize,
)]
#[serde(rename_all = "snake_case")]
pub enum Blocker {
    /// Borders and part, UV or colour seams keep their place (every border
    /// with `lock_borders`).
    Seams,
    /// The link condition: the collapse would pinch the surface, close a
    /// handle or make a piece vanish.
    Topology,
    /// No joint moves both ends (a skin's bone boundary).
    Bones,
    /// Every placement folds a triangle past the fold guard or makes a
    /// sliver below the sliver guard.
    Guards,
}

impl Blocker {
    /// What keeps the edges, and what would reach further.
    pub fn why(self) -> &'static str {
        match self {
            Blocker::Seams => {
                "borders and seams stay: the edges left lie on a border or a part, UV or colour \
                 seam (all borders with --lock-borders); a larger --uv-tolerance lets UV seams \
                 be crossed, --bake (a texture of its own) frees every seam, and voxel or amg, \
                 which make a new surface, reach any count"
            }
            Blocker::Topology => {
                "topology kept: every edge left would pinch the surface, close a handle or make \
                 a piece vanish; --topology free prunes pieces, merges them and closes holes \
                 and handles at a certified cost, and voxel, which changes the topology, \
                 reaches fewer"
            }
            Blocker::Bones => "bone boundaries kept: the vertices left share no joint",
            Blocker::Guards => {
                "fold and sliver guards: every placement left turns a triangle past \
                 min_normal_cos or makes a sliver below min_quality"
            }
        }
    }
}

/// A triangle budget not met: asked, reached, and the rules that kept the
/// edges left (issue 48, item 5), most common first.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Unmet {
    pub asked: usize,
    pub reached: usize,
    /// The most common rule's explanation.
    pub why: String,
    /// Edges left per rule.
    pub blockers: Vec<(Blocker, usize)>,
}

impl Unmet {
    /// A budget of `asked` primitives below the coarsest cut of `method`'s
    /// hierarchy (`reached` primitives): no cut of it reaches fewer.
    pub fn past_coarsest(method: Method, asked: usize, reached: usize) -> Unmet {
        let further = match method {
            Method::Voxel => "a lower resolution (or the next pyramid level) reaches fewer",
            _ => "simplify (edge collapse) or voxel at a low resolution reaches fewer",
        };
        Unmet {
            asked,
            reached,
            why: format!(
                "the coarsest {} cut has {reached} primitives: {further}",
                method.tag()
            ),
            blockers: Vec::new(),
        }
    }
}
