//! Rows that do not earn their place in a chain (issue 50, item 6): a row
//! whose LOD is the cut of the row before it, an LOD no loader ever shows
//! (it hands over where it takes over, `lod::chain::never_shown`), and an
//! LOD that costs more to draw than the finer one before it (the hybrid's
//! points drawn as discs: 8 triangles each). `lodstudio export --json` and
//! the studio's chain table flag them; Auto chain leaves them out
//! ([`Chain::pruned`]).

use serde::Serialize;

use super::{Chain, ChainCache, ChainError, Recipe, build_chain_cached};
use crate::geom::Model;
use crate::lod::DrawSet;
use crate::lod::chain::never_shown;
use crate::progress::Progress;

/// Builds `recipe` (as [`build_chain_cached`]) and, while the chain flags
/// a row, the recipe without the flagged rows ([`Chain::pruned`]): what
/// Auto chain keeps. Each round drops a row, so it ends.
pub fn build_unflagged(
    model: &Model,
    recipe: &Recipe,
    progress: &Progress,
    cache: &mut ChainCache,
) -> Result<Chain, ChainError> {
    let mut chain = build_chain_cached(model, recipe, progress, cache)?;
    loop {
        let pruned = chain.pruned();
        if pruned.rows.len() == chain.recipe.rows.len() {
            return Ok(chain);
        }
        chain = build_chain_cached(model, &pruned, progress, cache)?;
    }
}

/// Why an LOD (or some of its rows) is flagged.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
#[serde(tag = "flag", rename_all = "snake_case")]
pub enum Flag {
    /// These recipe rows (labels) gave the very cut of the LOD's first row.
    Duplicate { rows: Vec<String>, of: String },
    /// The LOD hands over where it takes over: no viewer ever draws it.
    NeverShown,
    /// The LOD draws more primitives than the finer LOD before it.
    Costlier { drawn: usize, finer_drawn: usize },
}

impl Flag {
    /// The word the studio's table shows.
    pub fn name(&self) -> &'static str {
        match self {
            Flag::Duplicate { .. } => "same LOD",
            Flag::NeverShown => "never shown",
            Flag::Costlier { .. } => "costlier",
        }
    }

    /// The sentence the JSON (`why`) and the studio's hover give.
    pub fn why(&self) -> String {
        match self {
            Flag::Duplicate { rows, of } => format!(
                "{} gave the same LOD as {of}: the row adds nothing; remove it or ask for \
                 another tolerance (a budget past what the method reaches says why in unmet)",
                rows.join(", ")
            ),
            Flag::NeverShown => "never shown: the next LOD's bound is no larger, so it hands over \
                 where it takes over (or its bound spans the whole object)"
                .to_string(),
            Flag::Costlier { drawn, finer_drawn } => format!(
                "costs more to draw than the finer LOD before it: {drawn} primitives against \
                 {finer_drawn} (points as the recipe writes them)"
            ),
        }
    }

    /// The flag as the JSON reports write it: its fields and `why`.
    pub fn json(&self) -> serde_json::Value {
        let mut j = serde_json::json!(self);
        j["why"] = self.why().into();
        j
    }
}

/// What a client draws of `set`: triangles, each point as
/// `points_as` writes it, each splat a quad, each layer's triangles.
fn drawn_primitives(set: &DrawSet, points_as: crate::io::gltf_writer::PointsAs) -> usize {
    set.mesh.triangles.len()
        + set.points.len() * points_as.primitives_per_point()
        + 2 * set.splats.len()
        + set
            .layers
            .iter()
            .map(|l| l.mesh.triangles.len())
            .sum::<usize>()
}

impl Chain {
    /// What a client draws of LOD `k` (points as the recipe writes them).
    pub fn drawn(&self, k: usize) -> usize {
        drawn_primitives(&self.lods[k].set, self.recipe.points_as)
    }

    /// Each LOD's flags, in chain order.
    pub fn flags(&self) -> Vec<Vec<Flag>> {
        let all: Vec<usize> = (0..self.lods.len()).collect();
        let (never, costlier) = self.unseen_or_costlier(&all);
        self.lods
            .iter()
            .enumerate()
            .map(|(k, lod)| {
                let mut flags = Vec::new();
                if lod.labels.len() > 1 {
                    flags.push(Flag::Duplicate {
                        rows: lod.labels[1..].to_vec(),
                        of: lod.labels[0].clone(),
                    });
                }
                if never[k] {
                    flags.push(Flag::NeverShown);
                }
                if costlier[k] {
                    flags.push(Flag::Costlier {
                        drawn: self.drawn(k),
                        finer_drawn: self.drawn(k - 1),
                    });
                }
                flags
            })
            .collect()
    }

    /// The recipe without the rows the chain flags: one row per LOD, and
    /// no LOD never shown or costlier than the one before. LODs costlier
    /// than the one before go first (it is both finer and cheaper, whatever
    /// stands beside them), then those never shown (of LODs with one bound,
    /// the last and cheapest stays), until none is left (leaving an LOD out
    /// moves its neighbours' switches). LOD0 always stays. A row's LOD may
    /// depend on the rows beside it (error rows continue one collapse from
    /// each other), so [`build_unflagged`] builds the pruned recipe again.
    pub fn pruned(&self) -> Recipe {
        let mut kept: Vec<usize> = (0..self.lods.len()).collect();
        loop {
            let (never, costlier) = self.unseen_or_costlier(&kept);
            let out = match costlier.contains(&true) {
                true => costlier,
                false => never,
            };
            if !out.contains(&true) {
                break;
            }
            kept = kept
                .iter()
                .zip(out)
                .filter(|(_, o)| !o)
                .map(|(k, _)| *k)
                .collect();
        }
        let mut rows: Vec<usize> = kept.iter().map(|&k| self.lods[k].rows[0]).collect();
        rows.sort_unstable();
        Recipe {
            rows: rows
                .into_iter()
                .map(|r| self.recipe.rows[r].clone())
                .collect(),
            ..self.recipe.clone()
        }
    }

    /// Per LOD of the sub-chain `lods` (chain indices, in order): never
    /// shown, and drawing more than the one before it.
    fn unseen_or_costlier(&self, lods: &[usize]) -> (Vec<bool>, Vec<bool>) {
        let bounds: Vec<f32> = lods.iter().map(|&k| self.lods[k].bound()).collect();
        let never = never_shown(
            &bounds,
            self.radius(),
            self.recipe.pixels,
            self.recipe.viewport_height,
        );
        let drawn: Vec<usize> = lods.iter().map(|&k| self.drawn(k)).collect();
        let costlier = (0..lods.len())
            .map(|i| i > 0 && drawn[i] > drawn[i - 1])
            .collect();
        (never, costlier)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::{Model, TriMesh};
    use crate::io::gltf_writer::PointsAs;
    use crate::lod::{CutPoint, Method};
    use crate::progress::Progress;
    use crate::recipe::{ChainLod, build_chain, parse_lods};

    /// An LOD of `triangles` triangles and `points` points, bound `bound`.
    fn lod(row: usize, triangles: usize, points: usize, bound: f32) -> ChainLod {
        let mesh = TriMesh {
            positions: vec![glam::Vec3::ZERO; 3],
            triangles: vec![[0, 1, 2]; triangles],
            ..Default::default()
        };
        let point = CutPoint {
            center: glam::Vec3::ZERO,
            radius: 0.1,
            color: glam::Vec3::ONE,
            normal: glam::Vec3::Z,
            error: bound,
        };
        ChainLod {
            rows: vec![row],
            labels: vec![format!("row{row}")],
            method: Method::EdgeCollapse,
            set: DrawSet {
                mesh,
                points: vec![point; points],
                error_bound: bound,
                ..Default::default()
            },
            build_seconds: 0.0,
            reused: false,
            baked: None,
        }
    }

    /// LOD1 shares LOD2's bound (never shown), LOD3's 20 discs draw 160
    /// triangles more than LOD2's 40 (costlier); as points it is not.
    #[test]
    fn flags_name_unseen_and_costlier_lods_and_pruning_keeps_the_cheaper() {
        let rows = parse_lods("source,0.5,0.4,0.1,0.05", Some(Method::EdgeCollapse)).unwrap();
        let mut recipe = Recipe::new(rows);
        recipe.points_as = PointsAs::Discs;
        let mut first = lod(0, 100, 0, 0.0);
        first.rows.push(5);
        first.labels.push("row5".into());
        let lods = vec![
            first,
            lod(1, 50, 0, 0.01),
            lod(2, 40, 0, 0.01),
            lod(3, 10, 20, 0.05),
            lod(4, 5, 0, 0.1),
        ];
        let mut chain = Chain {
            coverages: vec![1.0; lods.len()],
            lods,
            diagonal: 1.0,
            recipe,
        };
        let flags = chain.flags();
        assert_eq!(
            flags[0],
            [Flag::Duplicate {
                rows: vec!["row5".into()],
                of: "row0".into()
            }]
        );
        assert_eq!(flags[1], [Flag::NeverShown]);
        assert!(flags[2].is_empty() && flags[4].is_empty(), "{flags:?}");
        assert_eq!(
            flags[3],
            [Flag::Costlier {
                drawn: 170,
                finer_drawn: 40
            }]
        );
        let why = flags[3][0].json();
        assert_eq!(
            (&why["flag"], &why["drawn"]),
            (&"costlier".into(), &170.into())
        );
        assert!(
            why["why"]
                .as_str()
                .unwrap()
                .contains("170 primitives against 40")
        );
        // LOD3 goes first; then LOD1 (LOD2, as fine, draws less) and row 5.
        let kept: Vec<String> = chain.pruned().rows.iter().map(|r| r.label()).collect();
        assert_eq!(kept, ["source", "simplify:0.4", "simplify:0.05"]);
        // Drawn as points, the 20 points cost 20: nothing is costlier.
        chain.recipe.points_as = PointsAs::Points;
        assert!(chain.flags()[3].is_empty());
    }

    /// On a real build: two rows within a pixel where the object fills the
    /// viewport (the first never shown, or one cut with the second), and two
    /// budgets below the torus' topology floor (one LOD). Built without the
    /// flagged rows, nothing is flagged and the budget rows keep their counts.
    #[test]
    fn a_chain_built_unflagged_keeps_one_row_per_lod_it_shows() {
        let model = Model::Mesh(crate::builtins::torus(1.0, 0.3, 48, 24));
        let rows = parse_lods(
            "source,simplify:0.05%,simplify:0.08%,simplify:0.25,simplify:0.002,simplify:0.001",
            None,
        )
        .unwrap();
        let chain = build_chain(&model, &Recipe::new(rows), &Progress::new()).unwrap();
        let flags = chain.flags();
        let last = flags.last().unwrap();
        assert!(
            matches!(&last[..], [Flag::Duplicate { rows, of }] if rows == &["simplify:0.001"] && of == "simplify:0.002"),
            "{flags:?}"
        );
        // Row 1 (0.05%) is either never shown or the very cut of row 2.
        let one = chain.lods.iter().position(|l| l.rows.contains(&1)).unwrap();
        assert!(chain.lods[one].rows.len() > 1 || flags[one] == [Flag::NeverShown]);

        let mut cache = ChainCache::default();
        let kept = build_unflagged(&model, &chain.recipe, &Progress::new(), &mut cache).unwrap();
        assert!(kept.flags().iter().all(Vec::is_empty), "{:?}", kept.flags());
        let labels: Vec<String> = kept.recipe.rows.iter().map(|r| r.label()).collect();
        assert_eq!(
            labels,
            [
                "source",
                "simplify:0.08%",
                "simplify:0.25",
                "simplify:0.002"
            ]
        );
        // The met budget keeps its count (the collapse beside other rows may
        // take other edges to get there); the unmet one still says so.
        let lod = |c: &Chain, label: &str| {
            let l = c.lods.iter().find(|l| l.labels.iter().any(|x| x == label));
            l.unwrap().set.clone()
        };
        let count = |c: &Chain| lod(c, "simplify:0.25").mesh.triangles.len();
        assert_eq!(count(&kept), count(&chain));
        assert!(lod(&kept, "simplify:0.002").unmet.is_some());
    }
}
