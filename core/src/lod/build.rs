//! One way to build a hierarchy: [`build`] from typed [`Params`], the call
//! the studio, the CLI, recipes and the tests all make, as named steps
//! (check the parameters, take what the method works on, build it).
//!
//! [`Params`] has one variant per method, each the method's own parameter
//! struct owning its defaults and ranges (`simplify::progressive`,
//! `voxel::params`, `mergetree`, `hybrid::build`, `amg`), so every consumer
//! reads the same default and refuses the same values. A new method is one
//! variant here, one arm in [`build`] and one [`Hierarchy`] impl.
//!
//! This module sits above the methods (they know only the interface in
//! `lod`), which is why it is the one `lod` module that names them.

use std::sync::Arc;

use serde::{Deserialize, Serialize};

use super::{Hierarchy, Method, ParamError};
use crate::amg::{self, AmgError, AmgParams};
use crate::geom::{Model, PointSet, TriMesh, Volume};
use crate::hybrid::{self, HybridCut, HybridOptions};
use crate::implicit::{Implicit, MeshSolid};
use crate::impostor::{ImpostorCards, ImpostorOptions};
use crate::mergetree::{self, MergeTreeOptions, MergeTreeView};
use crate::progress::{Cancelled, Progress};
use crate::simplify::progressive::ProgressiveOptions;
use crate::voxel::{Source, VoxelParams};

/// What a build of one method is made with besides its input; in files,
/// tagged with the method's tag ([`Method::tag`]).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "method", rename_all = "lowercase")]
pub enum Params {
    /// The collapses' legality and the record's floor (the target chooses a
    /// prefix at run time).
    #[serde(rename = "simplify")]
    EdgeCollapse(ProgressiveOptions),
    Voxel(VoxelParams),
    /// The tree's build options (its criteria apply at run time).
    MergeTree(MergeTreeOptions),
    Hybrid(HybridOptions),
    /// The decomposition and the texel (the level is chosen at run time).
    Amg(AmgParams),
    /// The views and the atlas (a chain row, not a hierarchy to cut).
    Impostor(ImpostorOptions),
}

impl Params {
    /// `method` with every parameter at its default.
    pub fn default_for(method: Method) -> Params {
        match method {
            Method::EdgeCollapse => Params::EdgeCollapse(Default::default()),
            Method::Voxel => Params::Voxel(Default::default()),
            Method::MergeTree => Params::MergeTree(Default::default()),
            Method::Hybrid => Params::Hybrid(Default::default()),
            Method::Amg => Params::Amg(Default::default()),
            Method::Impostor => Params::Impostor(Default::default()),
        }
    }

    pub fn method(&self) -> Method {
        match self {
            Params::EdgeCollapse(_) => Method::EdgeCollapse,
            Params::Voxel(_) => Method::Voxel,
            Params::MergeTree(_) => Method::MergeTree,
            Params::Hybrid(_) => Method::Hybrid,
            Params::Amg(_) => Method::Amg,
            Params::Impostor(_) => Method::Impostor,
        }
    }

    /// Bytes of memory a build may reach at its peak for an input that
    /// parses from `parsed_bytes` bytes (what batch runs schedule by): per
    /// parsed byte, from BENCHMARKS.md's dragon figures (peak RSS over the
    /// PLY's bytes: hybrid 2.0 GB, AMG 0.8 GB, edge collapse 0.33 GB, merge
    /// tree 0.24 GB of a 32 MB file), plus a voxel pyramid's few float grids
    /// of resolution³ (sampled, filtered, the coarser levels).
    pub fn peak_bytes(&self, parsed_bytes: u64) -> u64 {
        let (per_byte, grids) = match self {
            Params::Hybrid(_) => (64, 0),
            Params::Amg(_) => (26, 0),
            Params::EdgeCollapse(_) => (11, 0),
            Params::MergeTree(_) => (8, 0),
            Params::Voxel(v) => (8, (v.resolution as u64).pow(3) * 4 * 4),
            // Its BVH and the frames: a few floats per texel of the atlas.
            Params::Impostor(i) => (8, (i.texture as u64).pow(2) * 32),
        };
        parsed_bytes.saturating_mul(per_byte).saturating_add(grids)
    }

    /// Every value inside its range, or the first one that is not, by name.
    pub fn validate(&self) -> Result<(), ParamError> {
        match self {
            Params::EdgeCollapse(p) => p.validate(),
            Params::Voxel(p) => p.validate(),
            Params::MergeTree(p) => p.validate(),
            Params::Hybrid(p) => p.validate(),
            Params::Amg(p) => p.validate(),
            Params::Impostor(p) => p.validate(),
        }
    }
}

/// What a build works on: an opened model's mesh, points or volume, or an
/// implicit solid (the built-ins' exact inside, which voxel builds sample
/// instead of their tessellation).
#[derive(Clone, Copy)]
pub enum Input<'a> {
    Mesh(&'a TriMesh),
    Points(&'a PointSet),
    Volume(&'a Volume),
    Solid(&'a dyn Implicit),
}

impl<'a> From<&'a Model> for Input<'a> {
    fn from(model: &'a Model) -> Self {
        match model {
            Model::Mesh(m) => Input::Mesh(m),
            Model::Points(p) => Input::Points(p),
            Model::Volume(v) => Input::Volume(v),
        }
    }
}

impl<'a> From<&'a TriMesh> for Input<'a> {
    fn from(mesh: &'a TriMesh) -> Self {
        Input::Mesh(mesh)
    }
}

/// Why a build did not give a hierarchy.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum BuildError {
    /// A parameter out of its range.
    #[error(transparent)]
    Param(#[from] ParamError),
    /// The input does not suit the method (points for a mesh method, an
    /// empty mesh, too few points), in words for the user.
    #[error("{0}")]
    BadInput(String),
    #[error("cancelled")]
    Cancelled,
}

impl From<Cancelled> for BuildError {
    fn from(_: Cancelled) -> Self {
        BuildError::Cancelled
    }
}

/// Builds the hierarchy `params` asks of `input`.
pub fn build<'a>(
    params: &Params,
    input: impl Into<Input<'a>>,
    progress: &Progress,
) -> Result<Box<dyn Hierarchy>, BuildError> {
    params.validate()?;
    let input = input.into();
    let method = params.method();
    accepts(method, input)?;
    let refused = || refusal(method, input);
    Ok(match params {
        Params::EdgeCollapse(p) => {
            Box::new(p.build(mesh_of(input).ok_or_else(refused)?, progress)?)
        }
        Params::Hybrid(p) => {
            let mrg = hybrid::build(mesh_of(input).ok_or_else(refused)?, p, progress)?;
            Box::new(HybridCut::new(Arc::new(mrg)))
        }
        Params::Impostor(p) => Box::new(ImpostorCards::build(
            mesh_of(input).ok_or_else(refused)?,
            p,
            progress,
        )?),
        Params::MergeTree(p) => {
            let tree = mergetree::build(mesh_of(input).ok_or_else(refused)?, p, progress)?;
            Box::new(MergeTreeView::new(Arc::new(tree), Default::default()))
        }
        Params::Voxel(p) => match input {
            Input::Solid(solid) => p.build(Source::Solid(solid), progress)?,
            Input::Volume(volume) => {
                let (lo, hi) = volume.value_range();
                let threshold = p.threshold.unwrap_or(0.5 * (lo + hi));
                p.build(Source::Volume(volume, threshold), progress)?
            }
            Input::Mesh(mesh) => p.build(Source::Solid(&MeshSolid::new(mesh)), progress)?,
            Input::Points(_) => return Err(refused()),
        },
        Params::Amg(p) => {
            let owned;
            let points = match input {
                Input::Points(points) => points,
                Input::Mesh(mesh) => {
                    owned = amg::mesh_points(mesh);
                    &owned
                }
                Input::Volume(_) | Input::Solid(_) => return Err(refused()),
            };
            Box::new(p.build(points, progress).map_err(|e| match e {
                AmgError::BadInput(m) => BuildError::BadInput(m),
                AmgError::Cancelled => BuildError::Cancelled,
            })?)
        }
    })
}

/// Whether `method` works on `input` (the studio asks before a build, to
/// say why not under its Build button), or why not.
pub fn accepts(method: Method, input: Input<'_>) -> Result<(), BuildError> {
    let ok = match (method, input) {
        (Method::Amg, Input::Points(_) | Input::Mesh(_)) => true,
        (Method::Amg, Input::Volume(_) | Input::Solid(_)) => false,
        (Method::Voxel, Input::Solid(_) | Input::Volume(_)) => true,
        (Method::Voxel, Input::Mesh(mesh)) => !mesh.triangles.is_empty(),
        (Method::Voxel, Input::Points(_)) => false,
        (Method::EdgeCollapse | Method::Hybrid | Method::MergeTree | Method::Impostor, _) => {
            mesh_of(input).is_some()
        }
    };
    if ok {
        Ok(())
    } else {
        Err(refusal(method, input))
    }
}

/// What `method`'s budgets count of `input` (a recipe's ratio rows):
/// triangles, AMG's points.
pub fn input_primitives(method: Method, input: Input<'_>) -> usize {
    match (method, input) {
        (Method::Amg, Input::Points(points)) => points.positions.len(),
        (Method::Amg, Input::Mesh(mesh)) => mesh.positions.len(),
        _ => mesh_of(input).map_or(0, |m| m.triangles.len()),
    }
}

/// The triangle mesh a mesh method works on, if the input has one.
fn mesh_of(input: Input<'_>) -> Option<&TriMesh> {
    let mesh = match input {
        Input::Mesh(mesh) => Some(mesh),
        Input::Solid(solid) => solid.surface(),
        Input::Points(_) | Input::Volume(_) => None,
    };
    mesh.filter(|m| !m.triangles.is_empty())
}

/// Why `method` does not work on `input`, in words for the user.
fn refusal(method: Method, input: Input<'_>) -> BuildError {
    let needs = match method {
        Method::Voxel => "samples solids (meshes, implicit built-ins, volumes)",
        Method::Amg => "needs points (a point set or a mesh's vertices)",
        Method::EdgeCollapse | Method::Hybrid | Method::MergeTree | Method::Impostor => {
            "needs a triangle mesh"
        }
    };
    let what = match input {
        Input::Mesh(mesh) if mesh.triangles.is_empty() => "a mesh without triangles".into(),
        Input::Mesh(mesh) => format!("a mesh ({} triangles)", mesh.triangles.len()),
        Input::Points(points) => format!("a point set ({} points)", points.positions.len()),
        Input::Volume(_) => "a volume".into(),
        Input::Solid(_) => "an implicit solid".into(),
    };
    BuildError::BadInput(format!(
        "{} {needs}, and this model is {what}.",
        method.name()
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lod::{Knob, Knobs, PrefixTarget};

    fn torus() -> Model {
        Model::Mesh(crate::builtins::torus(1.0, 0.35, 24, 12))
    }

    #[test]
    fn defaults_are_valid_and_round_trip_and_bad_values_name_their_field() {
        for method in Method::ALL {
            let params = Params::default_for(method);
            assert_eq!(params.method(), method);
            params.validate().expect("defaults are in range");
            let json = serde_json::to_string(&params).expect("serialises");
            assert!(
                json.contains(&format!("\"method\":\"{}\"", method.tag())),
                "{json}"
            );
            let back: Params = serde_json::from_str(&json).expect("parses");
            assert_eq!(back, params);
        }
        // A missing field takes its default; one out of range is named.
        let sparse: Params = serde_json::from_str(r#"{"method":"hybrid","kappa":5}"#).unwrap();
        assert_eq!(
            sparse,
            Params::Hybrid(HybridOptions {
                kappa: 5.0,
                ..Default::default()
            })
        );
        let bad = Params::Hybrid(HybridOptions {
            tau: f32::NAN,
            ..Default::default()
        });
        assert_eq!(bad.validate().unwrap_err().field, "tau");
        let model = torus();
        let e = build(&bad, &model, &Progress::new())
            .err()
            .expect("refused");
        assert!(
            matches!(e, BuildError::Param(ref p) if p.field == "tau"),
            "{e}"
        );
        let voxel = Params::Voxel(VoxelParams {
            resolution: 4,
            ..Default::default()
        });
        assert_eq!(voxel.validate().unwrap_err().field, "resolution");
    }

    #[test]
    fn each_method_takes_what_it_works_on_and_says_why_not() {
        let mesh = torus();
        let points = Model::Points(crate::amg::point_set(&mesh).unwrap());
        for method in Method::ALL {
            assert!(
                accepts(method, (&mesh).into()).is_ok(),
                "{method:?} on a mesh"
            );
            let on_points = accepts(method, (&points).into());
            assert_eq!(
                on_points.is_ok(),
                method == Method::Amg,
                "{method:?} on points: {on_points:?}"
            );
            if let Err(e) = on_points {
                assert!(e.to_string().contains("a point set ("), "{e}");
            }
        }
        let empty = Model::Mesh(TriMesh::default());
        let e = build(
            &Params::default_for(Method::Hybrid),
            &empty,
            &Progress::new(),
        )
        .err()
        .expect("an empty mesh is refused");
        assert_eq!(
            e.to_string(),
            "Hybrid (triangles + points) needs a triangle mesh, and this model is a mesh without triangles."
        );
        let cancelled = Progress::new();
        cancelled.cancel();
        let e = build(&Params::default_for(Method::MergeTree), &mesh, &cancelled).err();
        assert_eq!(e, Some(BuildError::Cancelled));
    }

    /// Every built hierarchy says which knobs it reads, and a knob that
    /// chooses its cut is reported as overriding the tolerance until cleared.
    #[test]
    fn hierarchies_say_which_knob_overrides_the_tolerance() {
        let mesh = torus();
        let overriding = Knobs {
            collapse: Some(PrefixTarget::Triangles(100)),
            pyramid_position: Some(1.0),
            amg_level: Some(1),
            ..Default::default()
        };
        for method in Method::ALL {
            let params = match Params::default_for(method) {
                Params::Voxel(v) => Params::Voxel(VoxelParams {
                    pyramid: true,
                    resolution: 24,
                    ..v
                }),
                Params::Amg(a) => Params::Amg(AmgParams { k: 12, ..a }),
                p => p,
            };
            let mut h = build(&params, &mesh, &Progress::new()).unwrap();
            let free = h.controls();
            assert!(free.follows_tolerance(), "{method:?}: {free:?}");
            h.set_knobs(&overriding);
            let set = h.controls();
            let expected = match method {
                Method::EdgeCollapse => Some(Knob::CollapseTarget),
                Method::Voxel => Some(Knob::PyramidPosition),
                Method::Amg => Some(Knob::AmgLevel),
                Method::MergeTree | Method::Hybrid | Method::Impostor => None,
            };
            assert_eq!(set.overridden_by, expected, "{method:?}");
            assert!(
                expected.is_none_or(|k| set.knobs.contains(&k)),
                "{method:?}"
            );
            h.set_knobs(&Knobs::default());
            assert!(h.controls().follows_tolerance(), "{method:?} cleared");
        }
        // One extracted level has no cut to choose.
        let level = build(
            &Params::Voxel(VoxelParams {
                resolution: 24,
                ..Default::default()
            }),
            &mesh,
            &Progress::new(),
        )
        .unwrap();
        assert!(!level.controls().follows_tolerance());
    }
}
