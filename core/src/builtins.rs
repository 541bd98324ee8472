//! Built-in models generated in code, addressable as `builtin:NAME`.

use glam::{Vec2, Vec3};

use crate::geom::Model;
use crate::geom::{PointSet, TriMesh};
use crate::implicit::{self, Implicit, Sphereflake};
use crate::io::LoadError;
use crate::progress::Progress;
use crate::rng::Rng;

/// Name and description of every built-in model.
pub const NAMES: &[(&str, &str)] = &[
    ("sphere", "icosphere, 5,120 triangles"),
    ("torus", "torus of genus 1, 4,096 triangles"),
    (
        "octahedron-points",
        "16,000 points on an octahedron's surface, a colour per face (AMG paper, Fig. 1)",
    ),
    (
        "sphereflake",
        "fractal of 820 spheres (voxel paper) as separate sphere meshes; also an implicit solid",
    ),
    (
        "csg-part",
        "mechanical part from boolean operations: plate, boss, five holes (genus 5)",
    ),
];

pub fn build(name: &str, progress: &Progress) -> Result<Model, LoadError> {
    Ok(match name {
        "sphere" => Model::Mesh(icosphere(Vec3::ZERO, 1.0, 4)),
        "torus" => Model::Mesh(torus(1.0, 0.35, 64, 32)),
        "octahedron-points" => Model::Points(octahedron_points(16_000, 1)),
        "sphereflake" => Model::Mesh(sphereflake_mesh(&Sphereflake::new(3))),
        "csg-part" => {
            let field =
                crate::voxel::sampling::sample_field(&implicit::csg_part(), 0.04, progress)?;
            Model::Mesh(crate::voxel::marching_cubes(&field, 0.0, progress)?)
        }
        _ => {
            return Err(LoadError::UnknownBuiltin {
                name: name.to_string(),
            });
        }
    })
}

/// The implicit form of a built-in solid, for methods that sample volumes.
pub fn implicit(name: &str) -> Option<Box<dyn Implicit>> {
    match name {
        "sphereflake" => Some(Box::new(Sphereflake::new(3))),
        "csg-part" => Some(Box::new(implicit::csg_part())),
        _ => None,
    }
}

/// Icosahedron subdivided `level` times and projected to the sphere
/// (20·4^level triangles), with normals.
pub fn icosphere(center: Vec3, radius: f32, level: u32) -> TriMesh {
    let t = (1.0 + 5f32.sqrt()) / 2.0;
    let mut pos: Vec<Vec3> = [
        [-1.0, t, 0.0],
        [1.0, t, 0.0],
        [-1.0, -t, 0.0],
        [1.0, -t, 0.0],
        [0.0, -1.0, t],
        [0.0, 1.0, t],
        [0.0, -1.0, -t],
        [0.0, 1.0, -t],
        [t, 0.0, -1.0],
        [t, 0.0, 1.0],
        [-t, 0.0, -1.0],
        [-t, 0.0, 1.0],
    ]
    .iter()
    .map(|p| Vec3::from_array(*p).normalize())
    .collect();
    let mut tris: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..level {
        let mut mid = std::collections::HashMap::new();
        let mut midpoint = |a: u32, b: u32, pos: &mut Vec<Vec3>| -> u32 {
            *mid.entry((a.min(b), a.max(b))).or_insert_with(|| {
                pos.push((pos[a as usize] + pos[b as usize]).normalize());
                pos.len() as u32 - 1
            })
        };
        let mut next = Vec::with_capacity(tris.len() * 4);
        for [a, b, c] in tris {
            let ab = midpoint(a, b, &mut pos);
            let bc = midpoint(b, c, &mut pos);
            let ca = midpoint(c, a, &mut pos);
            next.extend([[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        tris = next;
    }
    let normals = pos.clone();
    let mut m = TriMesh::new(pos.iter().map(|p| center + *p * radius).collect(), tris);
    m.normals = Some(normals);
    m
}

/// Torus around z with major radius `r_major`, tube radius `r_minor`, and UVs.
pub fn torus(r_major: f32, r_minor: f32, n_major: u32, n_minor: u32) -> TriMesh {
    let mut pos = Vec::new();
    let mut normals = Vec::new();
    let mut uvs = Vec::new();
    let tau = std::f32::consts::TAU;
    for i in 0..n_major {
        let u = i as f32 / n_major as f32;
        let (su, cu) = (u * tau).sin_cos();
        for j in 0..n_minor {
            let v = j as f32 / n_minor as f32;
            let (sv, cv) = (v * tau).sin_cos();
            let n = Vec3::new(cu * cv, su * cv, sv);
            pos.push(Vec3::new(cu * r_major, su * r_major, 0.0) + n * r_minor);
            normals.push(n);
            uvs.push(Vec2::new(u, v));
        }
    }
    let idx = |i: u32, j: u32| (i % n_major) * n_minor + (j % n_minor);
    let mut tris = Vec::new();
    for i in 0..n_major {
        for j in 0..n_minor {
            let (a, b, c, d) = (idx(i, j), idx(i + 1, j), idx(i + 1, j + 1), idx(i, j + 1));
            tris.push([a, b, c]);
            tris.push([a, c, d]);
        }
    }
    let mut m = TriMesh::new(pos, tris);
    m.normals = Some(normals);
    m.uvs = Some(uvs);
    m
}

/// `n` points spread uniformly over the surface of the unit octahedron, coloured
/// by face, with normals and a radius that covers the surface.
pub fn octahedron_points(n: usize, seed: u64) -> PointSet {
    const FACE_COLORS: [[f32; 3]; 8] = [
        [0.90, 0.20, 0.20],
        [0.20, 0.70, 0.25],
        [0.20, 0.35, 0.90],
        [0.95, 0.80, 0.15],
        [0.80, 0.30, 0.85],
        [0.15, 0.80, 0.85],
        [0.95, 0.55, 0.15],
        [0.55, 0.55, 0.55],
    ];
    let mut rng = Rng::new(seed);
    let mut positions = Vec::with_capacity(n);
    let mut normals = Vec::with_capacity(n);
    let mut colors = Vec::with_capacity(n);
    for i in 0..n {
        // Equal-area faces: the same number of points on each.
        let face = i % 8;
        let s = Vec3::new(
            if face & 1 == 0 { 1.0 } else { -1.0 },
            if face & 2 == 0 { 1.0 } else { -1.0 },
            if face & 4 == 0 { 1.0 } else { -1.0 },
        );
        let (mut a, mut b) = (rng.f32(), rng.f32());
        if a + b > 1.0 {
            (a, b) = (1.0 - a, 1.0 - b);
        }
        let p = Vec3::new(a, b, 1.0 - a - b) * s;
        positions.push(p);
        normals.push(s.normalize());
        colors.push(Vec3::from_array(FACE_COLORS[face]));
    }
    // Radius so that discs of n points cover the area 4√3: π r² n ≈ 2 · area.
    let r = (2.0 * 4.0 * 3f32.sqrt() / (std::f32::consts::PI * n as f32)).sqrt();
    PointSet {
        positions,
        normals: Some(normals),
        colors: Some(colors),
        radii: Some(vec![r; n]),
    }
}

/// One icosphere per sphere of the flake (a part each), finer for larger spheres.
pub fn sphereflake_mesh(flake: &Sphereflake) -> TriMesh {
    let mut mesh = TriMesh::default();
    for s in &flake.spheres {
        let level = if s.radius > 0.5 {
            3
        } else if s.radius > 0.2 {
            2
        } else {
            1
        };
        // A generic rotation keeps mesh vertices off the tangent points, where
        // they would coincide with the neighbour's and weld the spheres together.
        let mut sphere = icosphere(Vec3::ZERO, s.radius, level);
        let rot = glam::Quat::from_euler(glam::EulerRot::XYZ, 0.31, 0.17, 0.23);
        for (p, n) in sphere
            .positions
            .iter_mut()
            .zip(sphere.normals.iter_mut().flatten())
        {
            *n = rot * *n;
            *p = s.center + rot * *p;
        }
        mesh.append(&sphere);
    }
    mesh
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::Topology;

    #[test]
    fn every_builtin_builds_with_the_expected_topology() {
        let p = Progress::new();
        let mesh = |name| match build(name, &p).unwrap() {
            Model::Mesh(m) => m,
            _ => panic!("{name} is a mesh"),
        };
        let sphere = Topology::of(&mesh("sphere"));
        assert_eq!(
            (sphere.triangles, sphere.genus, sphere.components.len()),
            (5120, 0, 1)
        );
        let torus = Topology::of(&mesh("torus"));
        assert_eq!(
            (torus.triangles, torus.genus, torus.boundary_loops),
            (4096, 1, 0)
        );
        let flake = mesh("sphereflake");
        assert_eq!(flake.part_count(), 820);
        assert_eq!(Topology::of(&flake).components.len(), 820);
        let part = Topology::of(&mesh("csg-part"));
        assert_eq!(part.components.len(), 1);
        assert_eq!(part.boundary_loops, 0);
        assert_eq!(part.non_manifold_edges, 0);
        assert_eq!(part.genus, 5);
        match build("octahedron-points", &p).unwrap() {
            Model::Points(pts) => {
                assert_eq!(pts.positions.len(), 16_000);
                // Every point lies on the octahedron |x|+|y|+|z| = 1.
                assert!(
                    pts.positions
                        .iter()
                        .all(|q| (q.abs().element_sum() - 1.0).abs() < 1e-5)
                );
            }
            _ => panic!("points"),
        }
        assert!(matches!(
            build("nope", &p),
            Err(LoadError::UnknownBuiltin { .. })
        ));
    }
}
