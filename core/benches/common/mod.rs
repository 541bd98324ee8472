//! What the benchmarks share: loading a model as `lodstudio` loads it.

use std::path::Path;

use lodstudio_core::{Model, Progress, TriMesh, io};

/// The triangle mesh in the file at `path`, loaded and repaired.
pub fn load_mesh(path: impl AsRef<Path>) -> TriMesh {
    let path = path.as_ref();
    let loaded = io::load(path, &Default::default(), &Progress::new())
        .unwrap_or_else(|e| panic!("cannot load {}: {e}", path.display()));
    match loaded.model {
        Model::Mesh(m) => m,
        _ => panic!("{} is not a triangle mesh", path.display()),
    }
}
