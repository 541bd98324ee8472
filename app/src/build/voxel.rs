//! What the inspector shows of a voxel build (voxel paper §2–§5): the
//! level's grid, filter and topology, its layers (§3), or the pyramid's
//! genus and triangles per level (Tables 1–3).

use lodstudio_core::lod::{BuildError, Hierarchy};
use lodstudio_core::progress::Progress;
use lodstudio_core::voxel::layers::Layered;
use lodstudio_core::voxel::pyramid::PyramidCut;
use lodstudio_core::voxel::{VoxelLevel, VoxelParams};

use super::{Inspection, Plot, Row, build_time, concrete_mut, internal, length};

/// A level's (or the pyramid's) rows, and the pyramid's plots, whose levels
/// are extracted here, on the worker.
///
/// # Errors
/// `BuildError::Cancelled` when `progress` was cancelled.
pub fn inspect(
    hierarchy: &mut dyn Hierarchy,
    params: &VoxelParams,
    seconds: f32,
    progress: &Progress,
) -> Result<Inspection, BuildError> {
    if params.pyramid {
        return pyramid(concrete_mut(hierarchy)?, params, seconds, progress);
    }
    let layered: &mut Layered = concrete_mut(hierarchy)?;
    // Reports only: the hierarchy draws its layers.
    let level = layered
        .level
        .take()
        .ok_or_else(|| internal(lodstudio_core::lod::Method::Voxel))?;
    let mut rows = rows(&level, params, seconds);
    rows.insert(
        rows.len() - 1,
        Row {
            label: "layers",
            value: layered.layers.len().to_string(),
            hint: "Translucent iso-surfaces of §3 (eq. 4-6): the fewest whose fit of the \
                   density fall-off meets the layers error δ; drawn back to front.",
        },
    );
    Ok(Inspection {
        rows,
        plots: Vec::new(),
        voxel: Some(level),
    })
}

/// The whole pyramid (§2, Tables 1–3), browsed at any position (§5), with
/// its levels' topology.
fn pyramid(
    cut: &mut PyramidCut,
    params: &VoxelParams,
    seconds: f32,
    progress: &Progress,
) -> Result<Inspection, BuildError> {
    let pyramid = &cut.pyramid;
    progress.stage("extracting the levels");
    let mut levels = Vec::with_capacity(pyramid.levels.len());
    for i in 0..pyramid.levels.len() {
        levels.push(pyramid.level(i, progress)?);
        progress.set_fraction((i + 1) as f32 / pyramid.levels.len() as f32);
    }
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
    let mut rows = rows(&levels[0], params, seconds);
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
    Ok(Inspection {
        rows,
        plots,
        voxel: Some(Box::new(levels.swap_remove(0))),
    })
}

/// The rows of a voxel build; `params.threshold` is set for volumes only.
fn rows(level: &VoxelLevel, params: &VoxelParams, seconds: f32) -> Vec<Row> {
    let (resolution_hint, radius_hint) = if params.threshold.is_some() {
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
    let surface = match params.threshold {
        Some(threshold) => Row {
            label: "threshold",
            value: length(threshold),
            hint: "Samples at or above this value (the volume's own units) formed the \
                   solid S; the surface is the density 0.5 of the filtered S.",
        },
        None => Row {
            label: "iso-density",
            value: format!("{}", params.iso),
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
            value: params.filter.name().to_string(),
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
        build_time(
            seconds,
            "Time to sample, filter, extract and certify, without preparing the view.",
        ),
    ]
}

#[cfg(test)]
mod tests {
    use std::sync::Arc;

    use lodstudio_core::builtins::{self, torus};
    use lodstudio_core::geom::Volume;
    use lodstudio_core::io::Model;
    use lodstudio_core::lod::{Knobs, Params};
    use lodstudio_core::progress::Progress;

    use crate::build::{Built, Source, check, run, tests::source};
    use crate::settings::Method;
    use crate::settings::voxel::{VolumeGrid, VoxelSettings};

    fn build(settings: &VoxelSettings, source: &Source, grid: Option<&VolumeGrid>) -> Built {
        let params = Params::Voxel(settings.params(grid));
        run(&params, source, &Knobs::default(), &Progress::new()).expect("builds")
    }

    #[test]
    fn voxel_builds_solids_and_meshes_but_not_points() {
        let settings = VoxelSettings {
            resolution: 24,
            radius: 1.0,
            ..Default::default()
        };
        let solid: Arc<dyn lodstudio_core::implicit::Implicit> =
            Arc::from(builtins::implicit("csg-part").expect("csg-part is implicit"));
        let mut csg = source(Model::Mesh(torus(1.0, 0.35, 8, 4)));
        csg.solid = Some(solid);
        let built = build(&settings, &csg, None);
        let level = built.voxel.as_deref().expect("a voxel result");
        assert!(!level.mesh.triangles.is_empty());
        assert_eq!(built.mesh().triangles.len(), level.mesh.triangles.len());
        assert_eq!(built.method(), Method::Voxel);
        // A single level is a hierarchy of one; an implicit solid has no
        // surface to certify it against.
        assert!(!built.live.has_levels());
        assert!(built.live.stats.error_bound.is_infinite());
        // Edge collapse takes the tessellation, voxel the solid.
        assert!(check(Method::EdgeCollapse, &csg).is_ok());
        assert!(check(Method::Voxel, &csg).is_ok());

        let mesh = source(Model::Mesh(torus(1.0, 0.35, 8, 4)));
        let built = build(&settings, &mesh, None);
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
        let points = source(Model::Points(builtins::octahedron_points(100, 1)));
        let message = check(Method::Voxel, &points)
            .expect_err("points have no inside")
            .to_string();
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
        let volume = Volume {
            dims: [n; 3],
            spacing: glam::Vec3::ONE,
            origin: glam::Vec3::ZERO,
            data,
        };
        let grid = VolumeGrid::of(&volume);
        let model = source(Model::Volume(volume));
        assert!(check(Method::Voxel, &model).is_ok());
        let settings = VoxelSettings {
            radius: 1.0,
            threshold: Some(2.0),
            ..Default::default()
        };
        let built = build(&settings, &model, Some(&grid));
        let level = built.voxel.as_deref().expect("a voxel result");
        assert_eq!((level.resolution, level.components, level.genus), (n, 1, 0));
        assert_eq!(built.params, Params::Voxel(settings.params(Some(&grid))));
        let threshold = built.rows.iter().find(|r| r.label == "threshold");
        assert_eq!(threshold.map(|r| r.value.as_str()), Some("2.000"));
        // The same settings on a mesh are a solid's build: no threshold row.
        let mesh = source(Model::Mesh(torus(1.0, 0.35, 8, 4)));
        let built = build(&settings, &mesh, None);
        assert!(built.rows.iter().all(|r| r.label != "threshold"));
    }
}
