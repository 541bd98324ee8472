//! A recipe applied to a model: the LOD chain every consumer writes (the
//! studio's chain panel, `lodstudio export`, batch runs). Rows that build the
//! same hierarchy share it: edge-collapse rows are one progressive collapse
//! (`simplify::simplify_chain`), the other methods' rows cuts of one
//! hierarchy chosen in object space (`lod::chain`), so every viewer gets the
//! same chain. LODs are ordered by certified bound and switch where the next
//! one's bound projects to the recipe's pixel tolerance.

use std::time::Instant;

use super::cache::{self, ChainCache, Hit};
use super::{Recipe, RowTolerance};
use crate::geom::{Model, TriMesh};
use crate::io::gltf_writer::write_lod_chain;
use crate::lod::chain::{ChainItem, choose, lod_screen_coverages};
use crate::lod::{self, BuildError, DrawSet, Hierarchy, Method, Params, Unmet};
use crate::progress::{Cancelled, Progress};
use crate::simplify::{self, CollapseOptions, SimplifyError, Target};
use crate::view::View;

/// One LOD of a built chain.
#[derive(Debug, Clone)]
pub struct ChainLod {
    /// The recipe rows this LOD answers (rows met by the same cut share it).
    pub rows: Vec<usize>,
    /// Their labels as `--lods` writes them ("simplify:0.5%").
    pub labels: Vec<String>,
    pub method: Method,
    pub set: DrawSet,
    /// Seconds spent on the hierarchy behind it (shared by its rows).
    pub build_seconds: f64,
    /// Taken from a [`ChainCache`]: this build made nothing for it.
    pub reused: bool,
    /// Its own texture, baked (`bake`), when its row asked for one.
    pub baked: Option<crate::bake::BakeReport>,
}

impl ChainLod {
    /// The LOD's error bound in object space (certified, or AMG's estimate).
    pub fn bound(&self) -> f32 {
        self.set.error_bound
    }
}

/// A built LOD chain: its LODs by increasing bound, with their switch
/// coverages (`MSFT_screencoverage`).
#[derive(Debug, Clone)]
pub struct Chain {
    pub lods: Vec<ChainLod>,
    pub coverages: Vec<f32>,
    /// Bounding-box diagonal of the input (what relative bounds refer to).
    pub diagonal: f32,
    pub recipe: Recipe,
}

/// Why a chain could not be built.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ChainError {
    /// The recipe does not fit the model (a row no cut meets, a mesh method on
    /// a point set): names the row.
    #[error("{0}")]
    BadInput(String),
    /// One row does not fit the model (`rest` follows `rows[row]` in the
    /// message: ".tolerance: …", ": …", " (source) …").
    #[error("rows[{row}]{rest}")]
    Row { row: usize, rest: String },
    #[error("cancelled")]
    Cancelled,
}

impl From<Cancelled> for ChainError {
    fn from(_: Cancelled) -> Self {
        ChainError::Cancelled
    }
}

impl Chain {
    /// The chain as one GLB (MSFT_lod + MSFT_screencoverage), the one writer
    /// the studio's export and `lodstudio export` share.
    pub fn glb(&self) -> Vec<u8> {
        let sets: Vec<DrawSet> = self.lods.iter().map(|l| l.set.clone()).collect();
        let glb = write_lod_chain(&sets, &self.coverages, self.recipe.points_as);
        self.recipe.compress.apply(glb)
    }

    /// The bounding sphere's radius the coverages assume.
    pub fn radius(&self) -> f32 {
        0.5 * self.diagonal
    }

    /// The LOD a loader shows at screen coverage `c` (the object's projected
    /// height over the viewport's): the first (finest) whose threshold `c`
    /// reaches, or `None` below the last threshold (the object is left out).
    pub fn lod_at_coverage(&self, c: f32) -> Option<usize> {
        self.coverages.iter().position(|&t| c >= t)
    }

    /// The coverage at which LOD `k` takes over from the finer one (where
    /// LOD k−1 switches out; LOD0: the object filling the viewport).
    pub fn coverage_in(&self, k: usize) -> f32 {
        match k {
            0 => 1.0,
            _ => self.coverages[k - 1],
        }
    }

    /// The pixels LOD `i`'s bound covers at coverage `c` on the recipe's
    /// viewport: `e·H·c / (2r)` (`lod::chain`).
    pub fn pixels_at(&self, i: usize, c: f32) -> f32 {
        self.lods[i].bound() * self.recipe.viewport_height * c
            / self.diagonal.max(f32::MIN_POSITIVE)
    }
}

/// Builds the chain `recipe` asks of `model`.
pub fn build_chain(
    model: &Model,
    recipe: &Recipe,
    progress: &Progress,
) -> Result<Chain, ChainError> {
    build(model, recipe, progress, None)
}

/// [`build_chain`], taking from `cache` what an earlier build on the same
/// model made and leaving there what this one makes (`recipe::cache`): the
/// same chain, bit for bit, without building its unchanged groups again.
pub fn build_chain_cached(
    model: &Model,
    recipe: &Recipe,
    progress: &Progress,
    cache: &mut ChainCache,
) -> Result<Chain, ChainError> {
    progress.stage("fingerprint");
    cache.begin(&cache::fingerprint(model));
    let chain = build(model, recipe, progress, Some(&mut *cache))?;
    cache.finish();
    Ok(chain)
}

fn build(
    model: &Model,
    recipe: &Recipe,
    progress: &Progress,
    mut cache: Option<&mut ChainCache>,
) -> Result<Chain, ChainError> {
    recipe
        .check()
        .map_err(|e| ChainError::BadInput(e.to_string()))?;
    let (mesh, points) = match model {
        Model::Mesh(m) => (Some(m), None),
        Model::Points(p) => (None, Some(p)),
        Model::Volume(_) => {
            return Err(ChainError::BadInput(
                "an LOD chain needs a triangle mesh or a point set, not a volume".into(),
            ));
        }
    };
    let diagonal = match (mesh, points) {
        (Some(m), _) => m.bounds().diagonal(),
        (_, Some(p)) => p.bounds().diagonal(),
        _ => unreachable!("a mesh or points"),
    };
    if !(diagonal.is_finite() && diagonal > 0.0) {
        return Err(ChainError::BadInput(
            "the model is empty or has no extent: no LOD to build".into(),
        ));
    }
    // p pixels at coverage C: e = p · 2r / (H · C), r = diagonal / 2.
    let pixels_to_error = |p: f32| p * diagonal / (recipe.viewport_height * recipe.coverage);
    let mut lods: Vec<ChainLod> = Vec::new();
    // Groups of rows that share one hierarchy, in recipe order.
    let mut done = vec![false; recipe.rows.len()];
    for first in 0..recipe.rows.len() {
        if done[first] {
            continue;
        }
        let row = &recipe.rows[first];
        if row.tolerance == RowTolerance::Source {
            done[first] = true;
            lods.push(source_lod(recipe, first, mesh)?);
            continue;
        }
        let group: Vec<usize> = (first..recipe.rows.len())
            .filter(|&j| {
                !done[j]
                    && recipe.rows[j].tolerance != RowTolerance::Source
                    && recipe.rows[j].same_hierarchy(row)
            })
            .collect();
        for &j in &group {
            done[j] = true;
        }
        let (n, done_rows) = (recipe.rows.len(), done.iter().filter(|&&d| d).count());
        progress.part(
            &format!("row {} of {n}: {}", first + 1, row.method.name()),
            (done_rows - group.len()) as f32 / n as f32,
            done_rows as f32 / n as f32,
        );
        let build = |recipe: &Recipe, group: &[usize], cache: Option<&mut ChainCache>| {
            cached_group(recipe, group, model, mesh, cache, progress, pixels_to_error)
        };
        let (
            Hit {
                sets,
                seconds: build_seconds,
            },
            reused,
        ) = build(recipe, &group, cache.as_deref_mut())?;
        // Watchers see each group's coarsest LOD once it is made.
        if progress.wants_preview()
            && let Some(last) = sets.last()
        {
            progress.publish(last.clone());
        }
        for (j, mut set) in group.into_iter().zip(sets) {
            // A row that asks for its own texture gets it baked from the
            // model; a textured model's row that says neither is baked where
            // its seams keep it short of its budget or where baked it
            // measures closer to the model (`bake::choice`), unless the
            // recipe keeps every seam.
            let size = recipe.rows[j].texture;
            let row_error = |e: String| ChainError::Row {
                row: j,
                rest: format!(": baking: {e}"),
            };
            let baked = match mesh {
                Some(original) if recipe.rows[j].bakes() && !set.mesh.triangles.is_empty() => {
                    progress.stage("baking");
                    let size = size.unwrap_or_else(|| {
                        crate::bake::default_size(original, set.mesh.triangles.len())
                    });
                    let b = crate::bake::bake(original, &set.mesh, size).map_err(row_error)?;
                    set.mesh = b.mesh;
                    Some(b.report)
                }
                Some(original) if recipe.rows[j].bake.is_none() && !recipe.keep_seams => {
                    // A textured model's row may bake: the stage says so
                    // (it builds a second candidate and bakes it).
                    if crate::bake::choice::textured(original) {
                        progress.stage("measuring whether to bake");
                    }
                    let mut baking = recipe.clone();
                    baking.rows[j].bake = Some(true);
                    let free = || build(&baking, &[j], cache.as_deref_mut());
                    fn first((hit, _): &(Hit, bool)) -> &TriMesh {
                        &hit.sets[0].mesh
                    }
                    let unmet = set.unmet.clone();
                    match crate::bake::bake_unasked(
                        original,
                        &set.mesh,
                        crate::bake::Asked {
                            unmet: unmet.as_ref(),
                            count: matches!(recipe.rows[j].tolerance, RowTolerance::Ratio(_))
                                && recipe.rows[j].method == Method::EdgeCollapse,
                            size,
                        },
                        free,
                        first,
                        row_error,
                    )? {
                        Some(((hit, _), b)) => {
                            set = hit.sets.into_iter().next().expect("one set per row");
                            set.mesh = b.mesh;
                            Some(b.report)
                        }
                        None => None,
                    }
                }
                _ => None,
            };
            lods.push(ChainLod {
                rows: vec![j],
                labels: vec![recipe.rows[j].label()],
                method: recipe.rows[j].method,
                set,
                build_seconds,
                reused,
                baked,
            });
        }
    }
    // Decreasing quality: increasing bound, then decreasing primitive count,
    // then recipe order (so equal rows sort the same on every run).
    lods.sort_by(|a, b| {
        a.bound()
            .total_cmp(&b.bound())
            .then(b.set.primitive_count().cmp(&a.set.primitive_count()))
            .then(a.rows[0].cmp(&b.rows[0]))
    });
    // Rows met by the same cut share it (one node, both labels), even when
    // they asked for different budgets below it (the first one's is kept).
    lods.dedup_by(|later, kept| {
        let (a, b) = (later.set.unmet.take(), kept.set.unmet.take());
        let reached = |u: &Option<lod::Unmet>| u.as_ref().map(|u| (u.reached, u.blockers.clone()));
        let same =
            later.method == kept.method && later.set == kept.set && reached(&a) == reached(&b);
        (later.set.unmet, kept.set.unmet) = (a, b);
        if same {
            kept.rows.append(&mut later.rows);
            kept.labels.append(&mut later.labels);
        }
        same
    });
    let bounds: Vec<f32> = lods.iter().map(ChainLod::bound).collect();
    let coverages = lod_screen_coverages(
        &bounds,
        0.5 * diagonal,
        recipe.pixels,
        recipe.viewport_height,
    );
    Ok(Chain {
        lods,
        coverages,
        diagonal,
        recipe: recipe.clone(),
    })
}

/// A source row's LOD: the mesh as loaded, its bound 0 (nothing simplified).
fn source_lod(recipe: &Recipe, j: usize, mesh: Option<&TriMesh>) -> Result<ChainLod, ChainError> {
    let mesh = mesh.ok_or_else(|| ChainError::Row {
        row: j,
        rest: " (source) needs a triangle mesh, not a point set".into(),
    })?;
    Ok(ChainLod {
        rows: vec![j],
        labels: vec![recipe.rows[j].label()],
        method: recipe.rows[j].method,
        set: DrawSet {
            mesh: mesh.clone(),
            error_bound: 0.0,
            ..Default::default()
        },
        build_seconds: 0.0,
        reused: false,
        baked: None,
    })
}

/// Builds one group's LODs (one per row): its collapse, or its hierarchy
/// (taken from `cache` when built there before) cut once per row.
/// The LODs of a group of rows, from `cache` where it holds them (and
/// whether it did), else built and kept there.
fn cached_group(
    recipe: &Recipe,
    group: &[usize],
    model: &Model,
    mesh: Option<&TriMesh>,
    mut cache: Option<&mut ChainCache>,
    progress: &Progress,
    pixels_to_error: impl Fn(f32) -> f32,
) -> Result<(Hit, bool), ChainError> {
    let key = cache::group_key(recipe, group);
    if let Some(hit) = cache.as_deref_mut().and_then(|c| c.group(&key)) {
        return Ok((hit, true));
    }
    let hit = build_group(
        recipe,
        group,
        model,
        mesh,
        cache.as_deref_mut(),
        progress,
        pixels_to_error,
    )?;
    if let Some(c) = cache {
        c.keep_group(key, hit.sets.clone(), hit.seconds);
    }
    Ok((hit, false))
}

fn build_group(
    recipe: &Recipe,
    group: &[usize],
    model: &Model,
    mesh: Option<&TriMesh>,
    cache: Option<&mut ChainCache>,
    progress: &Progress,
    pixels_to_error: impl Fn(f32) -> f32,
) -> Result<Hit, ChainError> {
    let first = group[0];
    let start = Instant::now();
    let sets = match (recipe.row_params(first), mesh) {
        (Params::EdgeCollapse(p), Some(mesh)) => {
            simplify_rows(recipe, group, mesh, p.collapse, pixels_to_error, progress)?
        }
        (params @ Params::Amg(_), _) | (params, Some(_)) => {
            let input = lod::input_primitives(params.method(), model.into());
            let key = cache::hierarchy_key(&params);
            let kept = match cache {
                Some(c) => (c.take_hierarchy(&key), Some(c)),
                None => (None, None),
            };
            let (mut h, cache) = match kept {
                (Some(h), cache) => (h, cache),
                (None, cache) => (
                    lod::build(&params, model, progress).map_err(|e| match e {
                        BuildError::Cancelled => ChainError::Cancelled,
                        e => ChainError::Row {
                            row: first,
                            rest: format!(": {e}"),
                        },
                    })?,
                    cache,
                ),
            };
            let sets = hierarchy_rows(recipe, group, h.as_mut(), input, pixels_to_error);
            if let Some(c) = cache {
                c.keep_hierarchy(key, h);
            }
            sets?
        }
        (params, None) => {
            return Err(ChainError::Row {
                row: first,
                rest: format!(
                    " ({}) needs a triangle mesh, not a point set (only amg rows take points)",
                    params.method().tag()
                ),
            });
        }
    };
    Ok(Hit {
        sets,
        seconds: start.elapsed().as_secs_f64(),
    })
}

/// Edge-collapse rows: one progressive collapse to all their targets.
fn simplify_rows(
    recipe: &Recipe,
    group: &[usize],
    mesh: &TriMesh,
    collapse: CollapseOptions,
    pixels_to_error: impl Fn(f32) -> f32,
    progress: &Progress,
) -> Result<Vec<DrawSet>, ChainError> {
    let targets = row_targets(recipe, group, pixels_to_error)?;
    // Rows free to prune components (`"topology": "free"`) are each their
    // own `simplify::prune::simplify_free`, not one shared collapse: each
    // prunes what its own budget affords.
    if recipe.rows[group[0]].frees_topology() {
        return targets
            .into_iter()
            .zip(group)
            .map(|(target, &j)| {
                let opts = simplify::SimplifyOptions {
                    target,
                    collapse,
                    per_triangle_bounds: false,
                };
                simplify::prune::simplify_free(mesh, &opts, progress)
                    .map(|free| simplified_set(free.result))
                    .map_err(|e| simplify_error(e, j))
            })
            .collect();
    }
    let results = simplify::simplify_chain(mesh, &targets, collapse, false, progress)
        .map_err(|e| simplify_error(e, group[0]))?;
    Ok(results.into_iter().map(simplified_set).collect())
}

/// Each row's simplification target.
fn row_targets(
    recipe: &Recipe,
    group: &[usize],
    pixels_to_error: impl Fn(f32) -> f32,
) -> Result<Vec<Target>, ChainError> {
    group
        .iter()
        .map(|&j| {
            let target = match recipe.rows[j].tolerance {
                RowTolerance::Percent(p) => Target::RelativeError(p / 100.0),
                RowTolerance::Pixels(p) => Target::Error(pixels_to_error(p)),
                RowTolerance::Ratio(r) => Target::Ratio(r),
                RowTolerance::Source => Target::Ratio(1.0),
            };
            match target {
                // A finite tolerance can still overflow in object space.
                Target::Error(e) | Target::RelativeError(e) if !e.is_finite() => {
                    Err(ChainError::Row {
                        row: j,
                        rest: format!(
                            ".tolerance: {} is no finite error on this model",
                            recipe.rows[j].label()
                        ),
                    })
                }
                t => Ok(t),
            }
        })
        .collect()
}

fn simplify_error(e: SimplifyError, row: usize) -> ChainError {
    match e {
        SimplifyError::BadTarget(m) => ChainError::Row {
            row,
            rest: format!(": {m}"),
        },
        SimplifyError::Cancelled => ChainError::Cancelled,
    }
}

fn simplified_set(r: simplify::Simplified) -> DrawSet {
    DrawSet {
        error_bound: r.error_bound(),
        mesh: r.mesh,
        unmet: r.unmet,
        ..Default::default()
    }
}

/// Rows of one hierarchy: an LOD per row chosen from it in object space
/// (view-independent): the coarsest cut within an error, the finest within a
/// share of the `input` primitives (triangles; AMG: points). An error no cut
/// meets is refused, naming the row.
fn hierarchy_rows(
    recipe: &Recipe,
    group: &[usize],
    hierarchy: &mut dyn Hierarchy,
    input: usize,
    pixels_to_error: impl Fn(f32) -> f32,
) -> Result<Vec<DrawSet>, ChainError> {
    let diag = hierarchy.diagonal().max(f32::MIN_POSITIVE);
    let view = View::orbit(glam::Vec3::ZERO, diag, 0.0, 0.0);
    group
        .iter()
        .map(|&j| {
            let row = &recipe.rows[j];
            let wanted = match row.tolerance {
                RowTolerance::Percent(p) => ChainItem::Error(p / 100.0),
                RowTolerance::Pixels(p) => ChainItem::Error(pixels_to_error(p) / diag),
                RowTolerance::Ratio(r) => {
                    ChainItem::Primitives((r as f64 * input as f64).ceil() as usize)
                }
                // Never grouped (`source_lod`); as a budget, the whole input.
                RowTolerance::Source => ChainItem::Primitives(input),
            };
            let mut set = choose(hierarchy, &view, wanted);
            // A budget below the coarsest cut is said, not met silently.
            if let ChainItem::Primitives(n) = wanted
                && set.primitive_count() > n
                && set.unmet.is_none()
            {
                set.unmet = Some(Unmet::past_coarsest(row.method, n, set.primitive_count()));
            }
            // An impostor has one cut: its row's tolerance chooses nothing,
            // its measured silhouette error places its switch.
            if let ChainItem::Error(f) = wanted
                && set.error_bound > f * diag * (1.0 + 1e-6)
                && row.method != Method::Impostor
            {
                return Err(ChainError::Row {
                    row: j,
                    rest: format!(
                    ".tolerance: {}: no {} cut is that fine (the finest bound is {:.3}% of the diagonal{})",
                    row.label(),
                    row.method.tag(),
                    100.0 * set.error_bound / diag,
                    if row.method == Method::Voxel {
                        "; raise the resolution"
                    } else {
                        ""
                    },
                    ),
                });
            }
            Ok(set)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::recipe::{Row, parse_lods};

    fn torus() -> Model {
        Model::Mesh(crate::builtins::torus(1.0, 0.3, 48, 24))
    }

    /// A chain's edge-collapse rows equal fresh runs to the same counts, its
    /// LODs come by increasing bound with decreasing coverages, and an AMG
    /// impostor row joins them.
    #[test]
    fn mixed_chains_order_their_lods_and_share_one_collapse() {
        let rows = parse_lods("simplify:0.25,simplify:0.5,amg:20%", None).unwrap();
        let recipe = Recipe::new(rows);
        let chain = build_chain(&torus(), &recipe, &Progress::new()).unwrap();
        assert_eq!(chain.lods.len(), 3);
        let methods: Vec<Method> = chain.lods.iter().map(|l| l.method).collect();
        assert_eq!(
            methods,
            [Method::EdgeCollapse, Method::EdgeCollapse, Method::Amg]
        );
        assert!(chain.lods.windows(2).all(|w| w[0].bound() <= w[1].bound()));
        assert!(chain.coverages.windows(2).all(|w| w[1] < w[0]));
        let Model::Mesh(mesh) = torus() else {
            unreachable!()
        };
        for (lod, ratio) in chain.lods[..2].iter().zip([0.5f32, 0.25]) {
            let fresh = simplify::simplify(
                &mesh,
                &simplify::SimplifyOptions {
                    target: Target::Ratio(ratio),
                    collapse: Default::default(),
                    per_triangle_bounds: false,
                },
                &Progress::new(),
            )
            .unwrap();
            assert_eq!(lod.set.mesh, fresh.mesh, "ratio {ratio}");
            assert_eq!(lod.bound(), fresh.error_bound());
        }
        assert!(!chain.lods[2].set.splats.is_empty());
        // Coverage c shows the LOD whose threshold it reaches.
        assert_eq!(chain.lod_at_coverage(1.0), Some(0));
        assert_eq!(chain.lod_at_coverage(chain.coverages[1]), Some(1));
        assert_eq!(chain.lod_at_coverage(0.5 * chain.coverages[2]), None);
    }

    /// Error rows continue from each other and still meet their errors; the
    /// same recipe gives the same bytes twice.
    #[test]
    fn error_rows_meet_their_errors_and_builds_repeat_bytewise() {
        let recipe = Recipe::new(parse_lods("2%,0.5%,1%", Some(Method::EdgeCollapse)).unwrap());
        let a = build_chain(&torus(), &recipe, &Progress::new()).unwrap();
        let wanted = [0.005, 0.01, 0.02];
        for (lod, w) in a.lods.iter().zip(wanted) {
            assert!(lod.bound() <= w * a.diagonal, "{} > {w}", lod.bound());
        }
        assert!(
            a.lods
                .windows(2)
                .all(|w| w[0].set.mesh.triangles.len() > w[1].set.mesh.triangles.len())
        );
        let b = build_chain(&torus(), &recipe, &Progress::new()).unwrap();
        assert_eq!(a.glb(), b.glb());
    }

    /// A source row is LOD0: the mesh as loaded, bound 0, whatever the
    /// other rows; on a point set it is refused by row.
    #[test]
    fn a_source_row_is_the_input_itself() {
        let rows = parse_lods("simplify:0.5,source,hybrid:1%", None).unwrap();
        assert_eq!(rows[1].tolerance, RowTolerance::Source);
        assert_eq!(rows[1].label(), "source");
        let recipe = Recipe::new(rows);
        let model = torus();
        let chain = build_chain(&model, &recipe, &Progress::new()).unwrap();
        let Model::Mesh(mesh) = &model else {
            unreachable!()
        };
        assert_eq!(chain.lods.len(), 3);
        assert_eq!(chain.lods[0].rows, [1], "the source is LOD0");
        assert_eq!(chain.lods[0].set.mesh, *mesh);
        assert_eq!(chain.lods[0].bound(), 0.0);
        assert!(chain.lods[1].bound() > 0.0);
        // The recipe file round-trips it.
        let back = Recipe::from_json(&recipe.to_json()).unwrap();
        assert_eq!(back.rows[1].tolerance, RowTolerance::Source);
        let points = Model::Points(crate::amg::point_set(&model).unwrap());
        let only = Recipe::new(parse_lods("source,amg:20%", None).unwrap());
        let e = build_chain(&points, &only, &Progress::new()).unwrap_err();
        assert!(e.to_string().starts_with("rows[0] (source)"), "{e}");
    }

    /// Rows a model cannot answer are refused by row: a mesh method on points,
    /// an error finer than a voxel pyramid goes.
    #[test]
    fn rows_the_model_cannot_answer_are_named() {
        let points = Model::Points(crate::amg::point_set(&torus()).unwrap());
        let recipe = Recipe::new(parse_lods("amg:20%,simplify:1%", None).unwrap());
        let e = build_chain(&points, &recipe, &Progress::new()).unwrap_err();
        assert!(e.to_string().contains("rows[1]"), "{e}");
        let mut row = Row::new(Method::Voxel, RowTolerance::Percent(0.001));
        row.resolution = Some(16);
        let e = build_chain(&torus(), &Recipe::new(vec![row]), &Progress::new()).unwrap_err();
        assert!(e.to_string().starts_with("rows[0].tolerance"), "{e}");
        let empty = Model::Mesh(TriMesh::default());
        assert!(
            build_chain(
                &empty,
                &Recipe::new(vec![Row::new(
                    Method::EdgeCollapse,
                    RowTolerance::Ratio(0.5)
                )]),
                &Progress::new()
            )
            .is_err()
        );
    }

    /// A budget below a hierarchy's coarsest cut is reported with what
    /// reaches further; one its cuts meet says nothing.
    #[test]
    fn a_budget_past_the_coarsest_cut_is_unmet_with_why() {
        let mut rows = parse_lods("voxel:0.5,voxel:0.0001", None).unwrap();
        for row in &mut rows {
            row.resolution = Some(16);
        }
        let chain = build_chain(&torus(), &Recipe::new(rows), &Progress::new()).unwrap();
        let input = 48 * 24 * 2;
        let [met, far] = &chain.lods[..] else {
            panic!("two LODs: {:?}", chain.lods.len())
        };
        assert!(met.set.primitive_count() <= input / 2 && met.set.unmet.is_none());
        let unmet = far
            .set
            .unmet
            .as_ref()
            .expect("0.0001 of the torus is no voxel cut");
        assert_eq!(unmet.asked, 1);
        assert_eq!(unmet.reached, far.set.primitive_count());
        assert!(unmet.reached > 1);
        assert!(
            unmet.why.starts_with("the coarsest voxel cut"),
            "{}",
            unmet.why
        );
    }

    /// A cached rebuild is the fresh chain bit for bit; an edited row
    /// rebuilds its own group alone (a re-cut where its hierarchy is kept);
    /// a cache written and read back serves the whole chain; another model
    /// is never answered from it.
    #[test]
    fn cached_builds_rebuild_only_what_an_edit_changes() {
        let model = torus();
        let mut recipe =
            Recipe::new(parse_lods("simplify:0.5,hybrid:1%,hybrid:4%,amg:20%", None).unwrap());
        let mut cache = ChainCache::default();
        let p = Progress::new();
        let first = build_chain_cached(&model, &recipe, &p, &mut cache).unwrap();
        assert!(first.lods.iter().all(|l| !l.reused));
        assert_eq!(first.glb(), build_chain(&model, &recipe, &p).unwrap().glb());
        assert_eq!(cache.groups(), 3);
        let again = build_chain_cached(&model, &recipe, &p, &mut cache).unwrap();
        assert!(again.lods.iter().all(|l| l.reused));
        assert_eq!(again.glb(), first.glb());
        // One hybrid row edited: its group is cut again from the kept
        // hierarchy, the others come from the cache.
        recipe.rows[2] = parse_lods("hybrid:2%", None).unwrap().remove(0);
        let edited = build_chain_cached(&model, &recipe, &p, &mut cache).unwrap();
        assert_eq!(
            edited.glb(),
            build_chain(&model, &recipe, &p).unwrap().glb()
        );
        for lod in &edited.lods {
            let hybrid = lod.method == Method::Hybrid;
            assert_eq!(lod.reused, !hybrid, "{:?}", lod.labels);
        }
        assert_eq!(cache.groups(), 3, "the old hybrid group is dropped");
        // Saved and read back: the whole chain without a build.
        let (saved_recipe, mut reread) = ChainCache::from_bytes(&cache.to_bytes(&recipe)).unwrap();
        assert_eq!(saved_recipe, recipe);
        let reopened = build_chain_cached(&model, &recipe, &p, &mut reread).unwrap();
        assert!(reopened.lods.iter().all(|l| l.reused));
        assert_eq!(reopened.glb(), edited.glb());
        // Another model empties it.
        let other = Model::Mesh(crate::builtins::torus(1.0, 0.25, 48, 24));
        let fresh = build_chain_cached(&other, &recipe, &p, &mut reread).unwrap();
        assert!(fresh.lods.iter().all(|l| !l.reused));
    }

    /// A watched chain build shows what it has made (its rows' LODs as
    /// they are built), and its bar ends full, never restarting per stage.
    #[test]
    fn a_watched_chain_build_publishes_what_it_made() {
        let recipe = Recipe::new(parse_lods("simplify:0.5,hybrid:2%", None).unwrap());
        let p = Progress::new();
        p.watch();
        let chain = build_chain(&torus(), &recipe, &p).unwrap();
        let shown = p.take_preview().expect("a state shown while building");
        assert!(shown.primitive_count() > 0);
        assert!(shown.primitive_count() <= 2 * chain.lods[0].set.primitive_count());
        assert!(
            p.stage_name().starts_with("row 2 of 2: "),
            "{}",
            p.stage_name()
        );
        assert!(p.fraction() >= 0.5);
    }
}
