//! meshoptimizer (the `meshopt` crate, a dev-dependency) as the benches'
//! peer, and the dragon at n/4, n/2, n reduced by it (for costs against n).

use lodstudio_core::TriMesh;
use lodstudio_core::geom::{RepairOptions, repair::repair_mesh};

/// meshoptimizer's simplification of `mesh` to `target` triangles (indices).
pub fn meshopt_to(mesh: &TriMesh, target: usize) -> Vec<u32> {
    meshopt_with(mesh, target, meshopt::SimplifyOptions::None)
}

/// [`meshopt_to`] with meshoptimizer's `options` (e.g. `LockBorder`).
pub fn meshopt_with(mesh: &TriMesh, target: usize, options: meshopt::SimplifyOptions) -> Vec<u32> {
    let bytes: Vec<u8> = mesh
        .positions
        .iter()
        .flat_map(|p| p.to_array())
        .flat_map(f32::to_ne_bytes)
        .collect();
    let vertices = meshopt::VertexDataAdapter::new(&bytes, 12, 0).expect("vertex adapter");
    let indices: Vec<u32> = mesh.triangles.iter().flatten().copied().collect();
    meshopt::simplify(&indices, &vertices, 3 * target, 1.0, options, None)
}

/// `mesh` itself for `quarters` = 4, else reduced by meshopt to that many
/// quarters of its triangles and repaired as lodstudio loads meshes.
pub fn quarters_of(mesh: &TriMesh, quarters: usize) -> TriMesh {
    if quarters >= 4 {
        return mesh.clone();
    }
    let reduced = meshopt_to(mesh, mesh.triangles.len() * quarters / 4);
    let mut out = TriMesh::new(mesh.positions.clone(), Vec::new());
    out.triangles = reduced
        .chunks_exact(3)
        .map(|t| [t[0], t[1], t[2]])
        .collect();
    repair_mesh(out, &RepairOptions::default()).0
}
