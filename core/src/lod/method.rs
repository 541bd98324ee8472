//! The five methods, listed once: their names, papers and saved-file tags.
//! The CLI's `--method`, the studio's method list and saved hierarchies all
//! name a method through [`Method`]. Chains have one more kind of row, the
//! octahedral impostor ([`Method::CHAIN`]): one textured card set, no
//! hierarchy to cut.

use serde::{Deserialize, Serialize};

/// An LOD method of lodstudio.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default, Serialize, Deserialize)]
pub enum Method {
    /// Edge collapse with a certified Hausdorff bound (hybrid paper §5.2).
    #[default]
    EdgeCollapse,
    /// Low-pass filtering of a sampled volume and marching cubes (voxel paper §2).
    Voxel,
    /// View-dependent refinement of a merge tree (merge-tree paper).
    MergeTree,
    /// A multi-resolution graph of triangles and points (hybrid paper).
    Hybrid,
    /// Domain primitives of a point set by algebraic multigrid (AMG paper).
    Amg,
    /// Textured cards rendered from an octahedral map of views: a chain's
    /// farthest row, not a hierarchy (`impostor`).
    Impostor,
}

impl Method {
    /// Every method, in the order lists show them.
    pub const ALL: [Method; 5] = [
        Method::EdgeCollapse,
        Method::Hybrid,
        Method::MergeTree,
        Method::Voxel,
        Method::Amg,
    ];

    /// What a chain's rows may be: every method, and the impostor.
    pub const CHAIN: [Method; 6] = [
        Method::EdgeCollapse,
        Method::Hybrid,
        Method::MergeTree,
        Method::Voxel,
        Method::Amg,
        Method::Impostor,
    ];

    /// The name on the command line (`--method`, subcommands) and in saved
    /// hierarchies.
    pub fn tag(self) -> &'static str {
        match self {
            Method::EdgeCollapse => "simplify",
            Method::Voxel => "voxel",
            Method::MergeTree => "mergetree",
            Method::Hybrid => "hybrid",
            Method::Amg => "amg",
            Method::Impostor => "impostor",
        }
    }

    /// The method (or chain row kind) a [`Method::tag`] names.
    pub fn from_tag(tag: &str) -> Option<Method> {
        Method::CHAIN.into_iter().find(|m| m.tag() == tag)
    }

    /// Every tag, for messages: "simplify, hybrid, mergetree, voxel, amg, impostor".
    pub fn tags() -> String {
        Method::CHAIN.map(Method::tag).join(", ")
    }

    /// The name the studio shows.
    pub fn name(self) -> &'static str {
        match self {
            Method::EdgeCollapse => "Edge collapse",
            Method::Voxel => "Voxel (low-pass + marching cubes)",
            Method::MergeTree => "Merge tree (view-dependent)",
            Method::Hybrid => "Hybrid (triangles + points)",
            Method::Amg => "AMG (splats)",
            Method::Impostor => "Octahedral impostor (cards)",
        }
    }

    /// The paper (in `../shared/papers/`) and the section behind it.
    pub fn paper(self) -> &'static str {
        match self {
            Method::EdgeCollapse => "hybrid simplification, §5.2",
            Method::Voxel => "voxel-based object simplification, §2-§5",
            Method::MergeTree => "view-dependent merge trees, §3-§4",
            Method::Hybrid => "hybrid simplification (MRG), §4-§6",
            Method::Amg => "AMG extreme simplification, §2-§4",
            Method::Impostor => "octahedral impostors (Brucks 2018), issue 50",
        }
    }

    /// What it does, in the papers' terms (the studio's hover text).
    pub fn description(self) -> &'static str {
        match self {
            Method::EdgeCollapse => {
                "Collapses edges in order of quadric error and records every step with a \
                 certified bound: a guarantee on the two-sided Hausdorff distance between \
                 the original and the simplified surface (hybrid simplification paper, \
                 §5.2), so the target moves live."
            }
            Method::Voxel => {
                "Samples the solid (or thresholds a volume) into a volume buffer, low-pass \
                 filters it into a density \
                 (Gaussian or hyper-cone) and extracts the iso-density surface by marching \
                 cubes: wider filters remove small features, holes and tunnels, so the genus \
                 falls (voxel-based object simplification paper, §2)."
            }
            Method::Amg => {
                "Decomposes a point set (or a mesh's vertices) into quasi-flat domains \
                 by algebraic multigrid on a stiffness matrix of local finite elements, and \
                 draws each domain as a textured quad whose alpha is its partition-of-unity \
                 weight, so overlapping splats blend seamlessly (AMG extreme \
                 simplification paper)."
            }
            Method::Hybrid => {
                "Simplifies by edge collapse and by replacing triangles with points and \
                 merging points, whichever removes more primitives for its error, into a \
                 multi-resolution graph; every cut of it has a guaranteed error bound, and \
                 the cut follows the camera and the threshold live (hybrid \
                 simplification paper)."
            }
            Method::Impostor => {
                "Renders the model from views² directions on an octahedral map into one \
                 atlas (colour and coverage, normal and depth) and shows the frames facing \
                 the axes as alpha-masked cards: the farthest LOD, one draw call, its \
                 switch distance from its measured silhouette error."
            }
            Method::MergeTree => {
                "Builds a merge tree of vertex merges level by level with their \
                 dependencies, then refines or coarsens it every frame from the previous \
                 frame's vertices so each region's error stays within the threshold in \
                 pixels, coarser on back faces, finer on silhouettes and where the \
                 lighting changes (view-dependent merge trees paper)."
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tags_name_each_method_once() {
        for m in Method::ALL {
            assert_eq!(Method::from_tag(m.tag()), Some(m));
        }
        assert_eq!(Method::from_tag("voxels"), None);
        assert_eq!(
            Method::tags(),
            "simplify, hybrid, mergetree, voxel, amg, impostor"
        );
        assert_eq!(Method::from_tag("impostor"), Some(Method::Impostor));
    }
}
