//! One LOD build of the open model, done on a worker thread: the simplified
//! mesh (with its certificate or topology), the scenes the viewport shows for
//! it, and the inspector rows that report it. One module per hierarchy method.

pub mod amg;
pub mod hybrid;
pub mod mergetree;
mod reopen;

pub use reopen::{Reopened, reopen};

use std::path::Path;
use std::sync::Arc;
use std::time::Instant;

use lodstudio_core::TriMesh;
use lodstudio_core::builtins;
use lodstudio_core::geom::Volume;
use lodstudio_core::implicit::Implicit;
use lodstudio_core::io::Model;
use lodstudio_core::progress::{Cancelled, Progress};
use lodstudio_core::simplify::CollapseOptions;
use lodstudio_core::simplify::progressive::{self, Progressive, ProgressiveCut};
use lodstudio_core::view::{Tolerance, View};
use lodstudio_core::voxel::layers::{self, Layered};
use lodstudio_core::voxel::pyramid::{Pyramid, PyramidCut};
use lodstudio_core::voxel::{DENSITY_ISO, Source, VoxelLevel, density};

use crate::live_cut::LiveCut;
use crate::settings::simplify::EdgeCollapseSettings;
use crate::settings::voxel::{VolumeGrid, VoxelSettings};
use crate::settings::{BuildParams, Method};

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

/// A finished build: always a hierarchy, cut live for the camera and the
/// threshold, so picking, cutting, heat colouring and export take one path.
pub struct Built {
    /// The hierarchy and its current cut.
    pub live: LiveCut,
    /// The parameters it was built with.
    pub params: BuildParams,
    /// Time for the method itself (without preparing the view).
    pub seconds: f32,
    pub rows: Vec<Row>,
    pub plots: Vec<Plot>,
    /// A voxel build's level (the surface nearest the 0.5 density) and its
    /// topology; the finest level of a pyramid.
    pub voxel: Option<Box<VoxelLevel>>,
}

impl Built {
    /// A finished hierarchy build, cut live from a first view of `bounds`
    /// (the studio re-cuts it for its own camera at the next frame).
    pub fn live(
        hierarchy: Box<dyn lodstudio_core::lod::Hierarchy>,
        bounds: lodstudio_core::Aabb,
        params: BuildParams,
        seconds: f32,
        rows: Vec<Row>,
        plots: Vec<Plot>,
    ) -> Built {
        let view = View::orbit(bounds.center(), bounds.diagonal(), 0.6, 0.4);
        Built {
            live: LiveCut::new(hierarchy, &view, Tolerance::Pixels(1.0)),
            params,
            seconds,
            rows,
            plots,
            voxel: None,
        }
    }

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

/// Whether `method` can build the model opened from `path`.
///
/// # Errors
/// A one-line message for the user saying why not.
pub fn check(method: Method, path: &Path, model: &Model) -> Result<(), String> {
    match method {
        Method::EdgeCollapse | Method::MergeTree | Method::Hybrid => mesh_of(model).map(|_| ()),
        Method::Amg => lodstudio_core::amg::point_set(model)
            .map(|_| ())
            .ok_or_else(|| {
                "AMG simplification needs points: a point set or a mesh's vertices.".to_string()
            }),
        Method::Voxel => voxel_source(path, model).map(|_| ()),
    }
}

/// What voxel simplification works on.
#[derive(Debug, Clone, Copy)]
pub enum VoxelSource<'a> {
    /// The name of a built-in implicit solid, sampled on a grid of its own.
    Implicit(&'a str),
    /// A scalar volume (CT, MRI), thresholded on its own grid.
    Volume(&'a Volume),
    /// A triangle mesh, inside where its generalised winding number is ≥ ½.
    Mesh(&'a TriMesh),
}

/// What voxel simplification samples of the model opened from `path`, or why
/// there is nothing.
///
/// # Errors
/// A message for the user naming what the model is instead.
pub fn voxel_source<'a>(path: &'a Path, model: &'a Model) -> Result<VoxelSource<'a>, String> {
    if let Some(name) = path.to_str().and_then(|p| p.strip_prefix("builtin:"))
        && builtins::implicit(name).is_some()
    {
        return Ok(VoxelSource::Implicit(name));
    }
    match model {
        Model::Volume(volume) => Ok(VoxelSource::Volume(volume)),
        Model::Mesh(mesh) if !mesh.triangles.is_empty() => Ok(VoxelSource::Mesh(mesh)),
        Model::Mesh(_) => {
            Err("Voxel simplification needs a solid: this mesh has no triangles.".into())
        }
        Model::Points(points) => Err(format!(
            "Voxel simplification samples solids (meshes, implicit built-ins, volumes); this model is a point set ({} points) with no inside.",
            points.positions.len()
        )),
    }
}

/// The triangle mesh edge collapse works on, or why there is none.
///
/// # Errors
/// A message for the user naming what the model is instead.
pub fn mesh_of(model: &Model) -> Result<&TriMesh, String> {
    let what = match model {
        Model::Mesh(mesh) if !mesh.triangles.is_empty() => return Ok(mesh),
        Model::Mesh(_) => "a mesh without triangles".to_string(),
        Model::Points(points) => format!("a point set ({} points)", points.positions.len()),
        Model::Volume(_) => "a volume".to_string(),
    };
    Err(format!(
        "Edge collapse needs a triangle mesh, and this model is {what}."
    ))
}

/// Records `model`'s edge collapses down to the floor, each step with its
/// certified bound, as a hierarchy the studio cuts live (the target and the
/// threshold choose the step).
///
/// # Errors
/// `Err(Cancelled)` when `progress` was cancelled; `Ok(Err(message))` when the
/// model does not allow a build.
pub fn run(
    model: &Model,
    collapse: CollapseOptions,
    progress: &Progress,
) -> Result<Result<Built, String>, Cancelled> {
    let mesh = match mesh_of(model) {
        Ok(mesh) => mesh,
        Err(message) => return Ok(Err(message)),
    };
    let start = Instant::now();
    let floor = EdgeCollapseSettings::floor(mesh.triangles.len());
    let recorded = Arc::new(progressive::record(mesh, collapse, floor, progress)?);
    let seconds = start.elapsed().as_secs_f32();
    progress.check()?;
    progress.stage("preparing the view");
    let rows = rows(&recorded, seconds);
    let plots = vec![bound_curve(&recorded)];
    Ok(Ok(Built::live(
        Box::new(ProgressiveCut::new(recorded)),
        mesh.bounds(),
        BuildParams::EdgeCollapse(collapse),
        seconds,
        rows,
        plots,
    )))
}

/// Samples a solid (a built-in implicit or a mesh's winding number), filters
/// and extracts its surface (voxel paper §2), and prepares everything the
/// studio shows of it.
///
/// # Errors
/// `Err(Cancelled)` when `progress` was cancelled.
pub fn run_voxel(
    solid: &dyn Implicit,
    settings: VoxelSettings,
    progress: &Progress,
) -> Result<Result<Built, String>, Cancelled> {
    let settings = settings.for_implicit();
    let start = Instant::now();
    let source = Source::Solid(solid);
    if settings.pyramid {
        return voxel_pyramid(source, settings.resolution, settings, start, progress);
    }
    let f = density(
        source,
        settings.resolution,
        1,
        settings.radius,
        settings.filter.filter(),
        progress,
    )?;
    voxel_built(f, source, settings.resolution, settings, start, progress)
}

/// Thresholds the volume `model` (whose grid is `grid`) into S, filters it and
/// extracts its surface on the volume's own grid (voxel paper §2), and prepares
/// everything the studio shows of it. Only the filter, the radius and the
/// threshold of `settings` take effect.
///
/// # Errors
/// `Err(Cancelled)` when `progress` was cancelled; `Ok(Err(message))` when
/// `model` is no volume.
pub fn run_voxel_volume(
    model: &Model,
    grid: &VolumeGrid,
    settings: VoxelSettings,
    progress: &Progress,
) -> Result<Result<Built, String>, Cancelled> {
    let Model::Volume(volume) = model else {
        return Ok(Err("this model is no volume".to_string()));
    };
    let settings = settings.for_volume(grid);
    let threshold = grid.threshold(settings.threshold);
    let start = Instant::now();
    let source = Source::Volume(volume, threshold);
    if settings.pyramid {
        return voxel_pyramid(source, 0, settings, start, progress);
    }
    let f = density(
        source,
        0,
        1,
        settings.radius,
        settings.filter.filter(),
        progress,
    )?;
    let resolution = volume.dims.into_iter().max().unwrap_or(0);
    voxel_built(f, source, resolution, settings, start, progress)
}

/// Extracts a voxel build from the filtered density `f` (one surface at the
/// iso-density, or the layers of §3 when δ asks for more than one) and
/// prepares its scene and inspector rows.
fn voxel_built(
    f: Volume,
    source: Source,
    resolution: usize,
    settings: VoxelSettings,
    start: Instant,
    progress: &Progress,
) -> Result<Result<Built, String>, Cancelled> {
    let iso = match settings.threshold {
        Some(_) => DENSITY_ISO,
        None => settings.iso,
    };
    let layers::LayeredLevel { level, layers, .. } = layers::layered_level(
        &f,
        (resolution, settings.radius),
        settings.filter.filter(),
        settings.layers_error,
        iso,
        settings.post(),
        progress,
    )?;
    // One surface, or the translucent layers ordered for the camera; a mesh's
    // level is certified against it like the pyramid's levels.
    let mut hierarchy = Layered::new(layers, &f);
    if let Some(surface) = source.surface() {
        hierarchy.certify(surface, progress)?;
    }
    let seconds = start.elapsed().as_secs_f32();
    progress.check()?;
    progress.stage("preparing the view");
    let mut rows = voxel_rows(&level, settings, seconds);
    rows.insert(
        rows.len() - 1,
        Row {
            label: "layers",
            value: hierarchy.layers.len().to_string(),
            hint: "Translucent iso-surfaces of §3 (eq. 4-6): the fewest whose fit of the \
                   density fall-off meets the layers error δ; drawn back to front.",
        },
    );
    let mut built = Built::live(
        Box::new(hierarchy),
        f.bounds(),
        BuildParams::Voxel(settings),
        seconds,
        rows,
        Vec::new(),
    );
    built.voxel = Some(Box::new(level));
    Ok(Ok(built))
}

/// Builds the whole pyramid (§2, Tables 1–3) for browsing at any position
/// (§5), with its levels' topology in the inspector.
fn voxel_pyramid(
    source: Source,
    resolution: usize,
    settings: VoxelSettings,
    start: Instant,
    progress: &Progress,
) -> Result<Result<Built, String>, Cancelled> {
    let mut pyramid = Pyramid::build(
        source,
        resolution,
        settings.radius,
        settings.filter.filter(),
        progress,
    )?;
    pyramid.post = settings.post();
    pyramid.certify(source.surface(), progress)?;
    progress.stage("extracting the levels");
    let mut levels = Vec::with_capacity(pyramid.levels.len());
    for i in 0..pyramid.levels.len() {
        levels.push(pyramid.level(i, progress)?);
        progress.set_fraction((i + 1) as f32 / pyramid.levels.len() as f32);
    }
    let seconds = start.elapsed().as_secs_f32();
    let series = |f: fn(&VoxelLevel) -> f64| -> Vec<[f64; 2]> {
        levels
            .iter()
            .enumerate()
            .map(|(i, l)| [i as f64, f(l)])
            .collect()
    };
    let plots = vec![
        Plot {
            title: "genus per pyramid level",
            x_label: "level (0 = finest)",
            y_label: "genus",
            log_y: false,
            series: vec![
                ("genus".to_string(), series(|l| l.genus as f64)),
                ("components".to_string(), series(|l| l.components as f64)),
            ],
        },
        Plot {
            title: "triangles per pyramid level",
            x_label: "level (0 = finest)",
            y_label: "triangles",
            log_y: true,
            series: vec![(
                "triangles".to_string(),
                series(|l| l.mesh.triangles.len() as f64),
            )],
        },
    ];
    let mut rows = voxel_rows(&levels[0], settings, seconds);
    rows.insert(
        rows.len() - 1,
        Row {
            label: "pyramid",
            value: levels
                .iter()
                .map(|l| format!("{}:{}", l.resolution, l.genus))
                .collect::<Vec<_>>()
                .join(" "),
            hint: "Resolution:genus of each level, finest first (Tables 1-3).",
        },
    );
    let finest = levels.swap_remove(0);
    let mut built = Built::live(
        Box::new(PyramidCut::new(pyramid, settings.runtime_position())),
        finest.mesh.bounds(),
        BuildParams::Voxel(settings),
        seconds,
        rows,
        plots,
    );
    built.voxel = Some(Box::new(finest));
    Ok(Ok(built))
}

/// The rows of a voxel build; `settings.threshold` is set for volumes only.
fn voxel_rows(level: &VoxelLevel, settings: VoxelSettings, seconds: f32) -> Vec<Row> {
    let (resolution_hint, radius_hint) = if settings.threshold.is_some() {
        (
            "Largest dimension of the volume's own grid, whose thresholded samples \
             are the volume buffer S of §2.",
            "Support radius R of the low-pass filter h, in voxels of the volume's \
             smallest spacing.",
        )
    } else {
        (
            "Voxels of the sampling grid along the longest side of the solid's \
             bounds (the volume buffer S of §2).",
            "Support radius R of the low-pass filter h, in voxels of the \
             sampling grid.",
        )
    };
    let surface = match settings.threshold {
        Some(threshold) => Row {
            label: "threshold",
            value: length(threshold),
            hint: "Samples at or above this value (the volume's own units) formed the \
                   solid S; the surface is the density 0.5 of the filtered S.",
        },
        None => Row {
            label: "iso-density",
            value: format!("{}", settings.iso),
            hint: "The density f at which marching cubes extracted the surface.",
        },
    };
    vec![
        Row {
            label: "resolution",
            value: level.resolution.to_string(),
            hint: resolution_hint,
        },
        Row {
            label: "filter",
            value: settings.filter.name().to_string(),
            hint: "The low-pass filter h of f = h * S: the Gaussian or the hyper-cone \
                   of eq. 3.",
        },
        Row {
            label: "filter radius",
            value: format!("{:.1} voxels", level.radius),
            hint: radius_hint,
        },
        surface,
        Row {
            label: "LOD triangles",
            value: level.mesh.triangles.len().to_string(),
            hint: "Triangles of the extracted iso-surface.",
        },
        Row {
            label: "LOD components",
            value: level.components.to_string(),
            hint: "Connected pieces of the extracted surface.",
        },
        Row {
            label: "LOD genus",
            value: level.genus.to_string(),
            hint: "Holes (tunnels) through the extracted surface: a wider filter closes \
                   the small ones, so the genus falls as the radius grows.",
        },
        Row {
            label: "build time",
            value: format!("{seconds:.2} s"),
            hint: "Time to sample, filter and extract, without preparing the view.",
        },
    ]
}

fn rows(p: &Progressive, seconds: f32) -> Vec<Row> {
    let floor = p.collapses();
    let bound = p.bound_at(floor);
    vec![
        Row {
            label: "original triangles",
            value: p.triangles_at(0).to_string(),
            hint: "Triangles of the model as opened (after repair).",
        },
        Row {
            label: "recorded collapses",
            value: floor.to_string(),
            hint: "Edge collapses recorded, each with the certified bound of the triangles \
                   it made; the target and the threshold choose how many are shown.",
        },
        Row {
            label: "floor triangles",
            value: p.triangles_at(floor).to_string(),
            hint: "Triangles after every recorded collapse: the coarsest step.",
        },
        Row {
            label: "bound at the floor",
            value: format!(
                "{} ({:.3} %)",
                length(bound),
                100.0 * bound / p.diagonal().max(f32::MIN_POSITIVE)
            ),
            hint: "Guaranteed upper bound on the two-sided Hausdorff distance between the \
                   original and the coarsest step: no point of either lies farther than \
                   this from the other (hybrid paper §5.2).",
        },
        Row {
            label: "build time",
            value: format!("{seconds:.2} s"),
            hint: "Time to collapse and bound every step, without preparing the view.",
        },
    ]
}

/// The certified bound of each step against its triangle count.
fn bound_curve(p: &Progressive) -> Plot {
    let n = p.collapses();
    let stride = (n / 256).max(1);
    let diagonal = p.diagonal().max(f32::MIN_POSITIVE);
    let points = (0..=n)
        .step_by(stride)
        .chain(std::iter::once(n))
        .map(|k| {
            let bound = 100.0 * p.bound_at(k) / diagonal;
            [p.triangles_at(k) as f64, f64::from(bound)]
        })
        .collect();
    Plot {
        title: "certified bound per step",
        x_label: "triangles",
        y_label: "bound (% of the diagonal)",
        log_y: true,
        series: vec![("bound".to_string(), points)],
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

#[cfg(test)]
mod tests {
    use super::*;
    use lodstudio_core::builtins::torus;
    use lodstudio_core::geom::PointSet;
    use lodstudio_core::implicit::MeshSolid;
    use lodstudio_core::simplify::CollapseOptions;

    #[test]
    fn lengths_keep_four_significant_digits() {
        assert_eq!(length(0.012_345_6), "0.01235");
        assert_eq!(length(12.345_67), "12.35");
        assert_eq!(length(12_345.6), "12346");
        assert_eq!(length(0.0), "0");
        assert_eq!(length(f32::INFINITY), "unbounded");
    }

    #[test]
    fn builds_a_torus_and_explains_points() {
        let options = CollapseOptions::default();
        let model = Model::Mesh(torus(1.0, 0.35, 32, 16));
        let mut built = run(&model, options, &Progress::new())
            .expect("not cancelled")
            .expect("a mesh builds");
        assert_eq!(built.method(), Method::EdgeCollapse);
        // The target moves the cut without a rebuild: a quarter of the triangles.
        let live = &mut built.live;
        let knobs = |n| lodstudio_core::lod::Knobs {
            collapse: Some(lodstudio_core::lod::PrefixTarget::Triangles(n)),
            ..Default::default()
        };
        live.set_knobs(&knobs(256));
        let view = View::orbit(glam::Vec3::ZERO, 3.0, 0.2, 0.3);
        assert!(live.update(&view, Tolerance::Pixels(1.0)));
        let (n, bound) = (live.stats.triangles, live.stats.error_bound);
        assert!((250..=256).contains(&n), "{n}");
        assert!(bound > 0.0 && bound.is_finite());
        live.set_knobs(&knobs(900));
        live.update(&view, Tolerance::Pixels(1.0));
        assert!(live.stats.triangles > n && live.stats.error_bound <= bound);
        assert!(live.has_errors(), "per-triangle bounds for the heat map");
        // Down to the floor, or as far as the torus's topology lets it go.
        assert!(built.rows.iter().any(
            |r| r.label == "floor triangles" && r.value.parse::<usize>().is_ok_and(|f| f < 64)
        ));

        let points = Model::Points(PointSet::default());
        let message = run(&points, options, &Progress::new())
            .expect("not cancelled")
            .err()
            .expect("points do not build");
        assert!(message.contains("needs a triangle mesh"), "{message}");

        let cancelled = Progress::new();
        cancelled.cancel();
        assert!(run(&model, options, &cancelled).is_err());
    }

    #[test]
    fn voxel_builds_solids_and_meshes_but_not_points() {
        let settings = VoxelSettings {
            resolution: 24,
            radius: 1.0,
            ..Default::default()
        };
        let solid = builtins::implicit("csg-part").expect("csg-part is implicit");
        let built = run_voxel(solid.as_ref(), settings, &Progress::new())
            .expect("not cancelled")
            .expect("csg-part builds");
        let level = built.voxel.as_deref().expect("a voxel result");
        assert!(!level.mesh.triangles.is_empty());
        assert_eq!(built.mesh().triangles.len(), level.mesh.triangles.len());
        assert_eq!(built.method(), Method::Voxel);
        // A single level is a hierarchy of one; an implicit solid has no
        // surface to certify it against.
        assert!(!built.live.has_levels());
        assert!(built.live.stats.error_bound.is_infinite());

        let mesh = Model::Mesh(torus(1.0, 0.35, 8, 4));
        assert!(check(Method::EdgeCollapse, Path::new("builtin:torus"), &mesh).is_ok());
        assert!(check(Method::Voxel, Path::new("builtin:torus"), &mesh).is_ok());
        let Model::Mesh(torus_mesh) = &mesh else {
            unreachable!()
        };
        let built = run_voxel(&MeshSolid::new(torus_mesh), settings, &Progress::new())
            .expect("not cancelled")
            .expect("a closed mesh builds");
        let level = built.voxel.as_deref().expect("a voxel result");
        let bound = built.live.stats.error_bound;
        assert!(
            bound > 0.0 && bound < 0.2,
            "certified against the torus: {bound}"
        );
        assert_eq!(
            (level.components, level.genus),
            (1, 1),
            "the torus keeps its hole"
        );
        let points = Model::Points(lodstudio_core::builtins::octahedron_points(100, 1));
        let message =
            check(Method::Voxel, Path::new("p.ply"), &points).expect_err("points have no inside");
        assert!(message.contains("a point set"), "{message}");
    }

    #[test]
    fn voxel_builds_volumes_at_their_threshold() {
        // A ball of radius 8 voxels: values fall from 10 at the centre outwards.
        let n = 24;
        let data = (0..n * n * n)
            .map(|i| {
                let p = glam::Vec3::new((i % n) as f32, (i / n % n) as f32, (i / (n * n)) as f32);
                10.0 - p.distance(glam::Vec3::splat(11.5))
            })
            .collect();
        let model = Model::Volume(Volume {
            dims: [n; 3],
            spacing: glam::Vec3::ONE,
            origin: glam::Vec3::ZERO,
            data,
        });
        assert!(check(Method::Voxel, Path::new("ball.nrrd"), &model).is_ok());
        let Model::Volume(volume) = &model else {
            unreachable!()
        };
        let grid = VolumeGrid::of(volume);
        let settings = VoxelSettings {
            radius: 1.0,
            threshold: Some(2.0),
            ..Default::default()
        };
        let built = run_voxel_volume(&model, &grid, settings, &Progress::new())
            .expect("not cancelled")
            .expect("a volume builds");
        let level = built.voxel.as_deref().expect("a voxel result");
        assert_eq!((level.resolution, level.components, level.genus), (n, 1, 0));
        assert_eq!(built.params, BuildParams::Voxel(settings.for_volume(&grid)));
        let threshold = built.rows.iter().find(|r| r.label == "threshold");
        assert_eq!(threshold.map(|r| r.value.as_str()), Some("2.000"));

        let mesh = Model::Mesh(torus(1.0, 0.35, 8, 4));
        let message = run_voxel_volume(&mesh, &grid, settings, &Progress::new())
            .expect("not cancelled")
            .err()
            .expect("a mesh is no volume");
        assert!(message.contains("no volume"), "{message}");
    }
}
