//! Whatever mesh or point set a reader lets through, the methods must not
//! panic on it (degenerate, non-manifold, huge coordinates, 1e-30 scales):
//! the whole loader (detection and repair) on the bytes, then a tiny
//! simplify, hybrid MRG, voxel level and AMG decomposition.
#![no_main]
use std::path::Path;

use lodstudio_core::amg::{self, AmgOptions};
use lodstudio_core::hybrid::{self, HybridOptions};
use lodstudio_core::implicit::MeshSolid;
use lodstudio_core::io::{self, LoadOptions, Model};
use lodstudio_core::simplify::{self, CollapseOptions, SimplifyOptions, Target};
use lodstudio_core::voxel::{self, Filter};
use lodstudio_core::Progress;

/// The name only hints the format when the content does not say (OBJ).
const NAMES: [&str; 3] = ["fuzz.obj", "fuzz.off", "fuzz.ply"];
const MAX_TRIANGLES: usize = 400;
const MAX_POINTS: usize = 300;

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    lodstudio_fuzz::setup();
    let Some((&pick, file)) = data.split_first() else {
        return;
    };
    let path = Path::new(NAMES[pick as usize % NAMES.len()]);
    let progress = Progress::new();
    let Ok(loaded) = io::load_bytes(path, file, &LoadOptions::default(), &progress) else {
        return;
    };
    match loaded.model {
        Model::Mesh(mesh) if mesh.triangles.len() <= MAX_TRIANGLES => {
            let opts = SimplifyOptions {
                target: Target::Ratio(0.5),
                collapse: CollapseOptions::default(),
                per_triangle_bounds: false,
            };
            let _ = simplify::simplify(&mesh, &opts, &progress);
            let _ = hybrid::build(&mesh, &HybridOptions::default(), &progress);
            let solid = MeshSolid::new(&mesh);
            let _ = voxel::simplify_implicit(&solid, 8, 1.0, Filter::Gaussian, 0.5, &progress);
        }
        Model::Points(points) if points.positions.len() <= MAX_POINTS => {
            let opts = AmgOptions {
                k: 8,
                ..Default::default()
            };
            let _ = amg::decompose(&points, &opts, &progress);
        }
        _ => {}
    }
});
