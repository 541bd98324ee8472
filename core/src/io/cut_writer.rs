//! One writer for a cut ([`DrawSet`]): every subcommand and the studio's
//! Export write here, so no primitive type is dropped on the way out.
//!
//! GLB holds everything (triangles with their materials, points, textured
//! splats, translucent layers). A mesh format (OBJ, PLY) gets the triangles;
//! the points go to the `.points.ply` beside it (DESIGN.md: vertex
//! properties `x y z radius` and `red green blue`), written beside a GLB too;
//! layers after the first go to `.layerK.EXT` (the first is the file itself
//! when there are no triangles). Splats need their textures: a mesh format
//! is refused for them with a message, never written without them.

use std::path::{Path, PathBuf};

use super::{encode_mesh, extension, ply, write_atomic};
use crate::geom::PointSet;
use crate::lod::DrawSet;

/// The `.points.ply` beside a cut's file.
pub fn points_path(path: &Path) -> PathBuf {
    path.with_extension("points.ply")
}

/// The points of `set` as a point set (centre, normal, colour, radius).
fn points(set: &DrawSet) -> PointSet {
    PointSet {
        positions: set.points.iter().map(|p| p.center).collect(),
        normals: Some(set.points.iter().map(|p| p.normal).collect()),
        colors: Some(set.points.iter().map(|p| p.color).collect()),
        radii: Some(set.points.iter().map(|p| p.radius).collect()),
    }
}

/// The files `set` becomes at `path`, each with its bytes (module doc).
///
/// # Errors
/// An unknown extension, or splats asked of a mesh format.
pub fn encode(path: &Path, set: &DrawSet) -> Result<Vec<(PathBuf, Vec<u8>)>, String> {
    let mut files = Vec::new();
    if extension(path) == "glb" {
        files.push((
            path.to_path_buf(),
            super::gltf_writer::write_draw_set_glb(set),
        ));
    } else {
        if !set.splats.is_empty() {
            return Err(format!(
                "{}: {} textured splats need a .glb (OBJ and PLY cannot hold their textures)",
                path.display(),
                set.splats.len()
            ));
        }
        let layers_only = set.mesh.triangles.is_empty() && !set.layers.is_empty();
        if !layers_only {
            files.push((path.to_path_buf(), encode_mesh(path, &set.mesh)?));
        }
        let ext = extension(path);
        for (k, layer) in set.layers.iter().enumerate() {
            let k = k + usize::from(!layers_only);
            let file = if k == 0 {
                path.to_path_buf()
            } else {
                path.with_extension(format!("layer{k}.{ext}"))
            };
            let bytes = encode_mesh(&file, &layer.mesh)?;
            files.push((file, bytes));
        }
    }
    if !set.points.is_empty() {
        let bytes = ply::write_points(&points(set), ply::Encoding::BinaryLittleEndian);
        files.push((points_path(path), bytes));
    }
    Ok(files)
}

/// Writes `set` at `path` as [`encode`] lays it out, each file atomically;
/// the files written and their sizes.
///
/// # Errors
/// As [`encode`] (before anything is written), or a file that cannot be written.
pub fn write(path: &Path, set: &DrawSet) -> Result<Vec<(PathBuf, usize)>, String> {
    let files = encode(path, set)?;
    files
        .into_iter()
        .map(|(file, bytes)| {
            write_atomic(&file, &bytes)
                .map(|()| (file.clone(), bytes.len()))
                .map_err(|e| format!("{}: cannot write: {e}", file.display()))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lod::{CutPoint, Layer, Splat};
    use glam::Vec3;

    fn set() -> DrawSet {
        let mesh = crate::builtins::torus(1.0, 0.3, 8, 4);
        DrawSet {
            points: vec![CutPoint {
                center: Vec3::ONE,
                radius: 0.5,
                color: Vec3::X,
                normal: Vec3::Z,
                error: 0.1,
            }],
            layers: vec![Layer {
                mesh: mesh.clone(),
                alpha: 0.5,
                isodensity: 0.3,
            }],
            mesh,
            ..Default::default()
        }
    }

    #[test]
    fn mesh_formats_get_sidecars_and_glb_holds_all() {
        let out = Path::new("/x/cut.obj");
        let files: Vec<PathBuf> = encode(out, &set())
            .unwrap()
            .into_iter()
            .map(|f| f.0)
            .collect();
        let want = ["/x/cut.obj", "/x/cut.layer1.obj", "/x/cut.points.ply"].map(PathBuf::from);
        assert_eq!(files, want);
        let glb = encode(Path::new("/x/cut.glb"), &set()).unwrap();
        assert_eq!(glb.len(), 2, "the GLB, and the points beside it");
        let points = ply::read(&glb[1].1, &crate::Progress::new()).unwrap();
        assert!(matches!(points, crate::Model::Points(p) if p.positions == vec![Vec3::ONE]));
    }

    #[test]
    fn splats_are_refused_by_mesh_formats_not_dropped() {
        let mut s = set();
        s.splats.push(Splat {
            center: Vec3::ZERO,
            axes: [Vec3::X, Vec3::Y],
            normal: Vec3::Z,
            texture: 0,
            domain: 0,
            neighbours: Vec::new(),
        });
        let e = encode(Path::new("/x/cut.ply"), &s).unwrap_err();
        assert!(e.contains("splats need a .glb"), "{e}");
        assert!(encode(Path::new("/x/cut.glb"), &s).is_ok());
        assert!(encode(Path::new("/x/cut.xyz"), &set()).is_err());
    }
}
