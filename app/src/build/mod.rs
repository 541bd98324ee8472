//! One LOD build of the open model on a worker thread: the hierarchy from
//! `lod::build` (the one build path the CLI, recipes and tests take too),
//! and what the inspector shows of it. One module per method says what
//! that is: its rows and plots, read from the method's own structure.

pub mod amg;
pub mod hybrid;
pub mod mergetree;
mod reopen;
pub mod simplify;
pub mod voxel;

pub use reopen::{Reopened, reopen};

use std::sync::Arc;
use std::time::Instant;

use lodstudio_core::TriMesh;
use lodstudio_core::implicit::Implicit;
use lodstudio_core::io::Loaded;
use lodstudio_core::lod::{self, BuildError, Hierarchy, Input, Knobs, Params};
use lodstudio_core::progress::Progress;
use lodstudio_core::view::{Tolerance, View};
use lodstudio_core::voxel::VoxelLevel;

use crate::live_cut::LiveCut;
use crate::settings::Method;

/// One inspector row, with what it means when hovered.
pub struct Row {
    pub label: &'static str,
    pub value: String,
    pub hint: &'static str,
}

/// A curve or bar series for the inspector's plots.
pub struct Plot {
    pub title: &'static str,
    pub x_label: &'static str,
    pub y_label: &'static str,
    pub log_y: bool,
    /// Named series of (x, y) points.
    pub series: Vec<(String, Vec<[f64; 2]>)>,
}

/// What the inspector shows of a build besides its cut.
#[derive(Default)]
pub struct Inspection {
    pub rows: Vec<Row>,
    pub plots: Vec<Plot>,
    /// A voxel build's level (the surface nearest the 0.5 density) and its
    /// topology; the finest level of a pyramid.
    pub voxel: Option<Box<VoxelLevel>>,
}

/// A finished build: always a hierarchy, cut live for the camera and the
/// threshold, so picking, cutting, heat colouring and export take one path.
pub struct Built {
    /// The hierarchy and its current cut.
    pub live: LiveCut,
    /// The parameters it was built with.
    pub params: Params,
    /// Time of `lod::build` (without preparing the view).
    pub seconds: f32,
    pub rows: Vec<Row>,
    pub plots: Vec<Plot>,
    /// A voxel build's level and its topology (see [`Inspection::voxel`]).
    pub voxel: Option<Box<VoxelLevel>>,
}

/// What a studio build works on: the model on screen and, for a built-in
/// implicit, its exact solid (voxel builds sample it, not its tessellation).
#[derive(Clone)]
pub struct Source {
    pub loaded: Arc<Loaded>,
    pub solid: Option<Arc<dyn Implicit>>,
}

impl Source {
    /// What `method` takes of it.
    pub fn input(&self, method: Method) -> Input<'_> {
        match (method, &self.solid) {
            (Method::Voxel, Some(solid)) => Input::Solid(solid.as_ref()),
            _ => (&self.loaded.model).into(),
        }
    }
}

/// Whether `method` can build `source`, or why not (for the user).
///
/// # Errors
/// `BuildError::BadInput` naming what the model is instead.
pub fn check(method: Method, source: &Source) -> Result<(), BuildError> {
    lod::accepts(method, source.input(method))
}

/// Builds `params` on `source` and prepares what the studio shows of it: the
/// inspector's rows and plots, and the first cut with `knobs` (the levels
/// it will be cut at are made here, on the worker, not by the first frames).
///
/// # Errors
/// A parameter out of range, an input the method does not take, or a
/// cancellation.
pub fn run(
    params: &Params,
    source: &Source,
    knobs: &Knobs,
    progress: &Progress,
) -> Result<Built, BuildError> {
    let input = source.input(params.method());
    let start = Instant::now();
    let mut hierarchy = lod::build(params, input, progress)?;
    let seconds = start.elapsed().as_secs_f32();
    progress.check()?;
    hierarchy.set_knobs(knobs);
    let inspection = match params {
        Params::EdgeCollapse(_) => simplify::inspect(concrete(hierarchy.as_ref())?, seconds),
        Params::Hybrid(options) => hybrid::inspect(
            concrete(hierarchy.as_ref())?,
            options,
            input,
            seconds,
            progress,
        )?,
        Params::MergeTree(_) => mergetree::inspect(concrete(hierarchy.as_ref())?, seconds),
        Params::Voxel(p) => voxel::inspect(hierarchy.as_mut(), p, seconds, progress)?,
        // A chain row only (the studio's method list leaves it out): its
        // cards are all there is to inspect.
        Params::Impostor(_) => Inspection {
            rows: vec![build_time(
                seconds,
                "Time to render the frames and measure the silhouette.",
            )],
            plots: Vec::new(),
            voxel: None,
        },
        Params::Amg(_) => {
            let shown = knobs.amg_level;
            amg::inspect(concrete_mut(hierarchy.as_mut())?, shown, seconds, progress)?
        }
    };
    progress.stage("first cut");
    let bounds = source.loaded.model.bounds();
    let view = View::orbit(bounds.center(), bounds.diagonal(), 0.6, 0.4);
    Ok(Built {
        live: LiveCut::new(hierarchy, &view, Tolerance::Pixels(1.0)),
        params: *params,
        seconds,
        rows: inspection.rows,
        plots: inspection.plots,
        voxel: inspection.voxel,
    })
}

/// The method's own structure behind `hierarchy`.
fn concrete<T: Hierarchy>(hierarchy: &dyn Hierarchy) -> Result<&T, BuildError> {
    let method = hierarchy.method();
    hierarchy.downcast_ref().ok_or_else(|| internal(method))
}

fn concrete_mut<T: Hierarchy>(hierarchy: &mut dyn Hierarchy) -> Result<&mut T, BuildError> {
    let method = hierarchy.method();
    hierarchy.downcast_mut().ok_or_else(|| internal(method))
}

fn internal(method: Method) -> BuildError {
    BuildError::BadInput(format!(
        "internal error: {} built an unexpected hierarchy",
        method.name()
    ))
}

impl Built {
    pub fn method(&self) -> Method {
        self.params.method()
    }

    /// The triangles of the current cut.
    pub fn mesh(&self) -> &TriMesh {
        &self.live.draw_set().mesh
    }

    /// One line for the log, after the job's label.
    pub fn report(&self) -> String {
        match &self.voxel {
            Some(level) => format!(
                "{} triangles, {} components, genus {} (resolution {}, filter radius {:.1} voxels), {:.2} s",
                level.mesh.triangles.len(),
                level.components,
                level.genus,
                level.resolution,
                level.radius,
                self.seconds
            ),
            None => {
                let rows: Vec<String> = self
                    .rows
                    .iter()
                    .map(|r| format!("{} {}", r.label, r.value))
                    .collect();
                rows.join(", ")
            }
        }
    }
}

/// The inspector's build-time row.
pub fn build_time(seconds: f32, hint: &'static str) -> Row {
    Row {
        label: "build time",
        value: format!("{seconds:.2} s"),
        hint,
    }
}

/// A distance with four significant digits (model units vary wildly).
pub fn length(x: f32) -> String {
    if !x.is_finite() {
        return "unbounded".to_string();
    }
    if x == 0.0 {
        return "0".to_string();
    }
    let decimals = (3 - x.abs().log10().floor() as i32).clamp(0, 9) as usize;
    format!("{x:.decimals$}")
}

/// A bound and its share of the diagonal ("unbounded" alone when infinite).
pub fn bound_text(bound: f32, diagonal: f32) -> String {
    match bound.is_finite() {
        true => format!("{} ({:.3} %)", length(bound), 100.0 * bound / diagonal),
        false => length(bound),
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use lodstudio_core::io::{Format, Model};

    /// A model as the studio holds it once opened.
    pub fn source(model: Model) -> Source {
        Source {
            loaded: Arc::new(Loaded {
                model,
                format: Format::Builtin,
                repairs: Default::default(),
                asset: lodstudio_core::io::AssetReport::single(),
            }),
            solid: None,
        }
    }

    #[test]
    fn lengths_keep_four_significant_digits() {
        assert_eq!(length(0.012_345_6), "0.01235");
        assert_eq!(length(12.345_67), "12.35");
        assert_eq!(length(12_345.6), "12346");
        assert_eq!(length(0.0), "0");
        assert_eq!(length(f32::INFINITY), "unbounded");
    }
}
