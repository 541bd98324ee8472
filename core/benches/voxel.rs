//! Benchmark of issue 6: the voxel method's stages (sampling S, the low-pass
//! filter, marching cubes) on the dragon (a mesh, sampled through its winding
//! number) and on the MRI head (a volume), at 64³, 128³ and 256³; and marching
//! cubes alone on a 256³ density, which it also writes out so that
//! `scripts/bench-voxel.sh` can time scikit-image's `marching_cubes` on the
//! very same data in the same run.
//!
//! Run with `cargo bench -p lodstudio-core --bench voxel` (or the script).
//! Prints a Markdown table on stdout. `LODSTUDIO_BENCH_RAW=PATH` sets where
//! the 256³ density goes (default: the system temp folder).

use std::path::PathBuf;
use std::time::Instant;

use lodstudio_core::implicit::MeshSolid;
use lodstudio_core::voxel::{Filter, Source, density, marching_cubes};
use lodstudio_core::{Model, Progress, io};

fn model(name: &str) -> Model {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../shared/models")
        .join(name);
    io::load(&path, &Default::default(), &Progress::new())
        .unwrap_or_else(|e| panic!("{name}: {e}"))
        .model
}

fn main() {
    let p = Progress::new();
    let Model::Mesh(dragon) = model("dragon_vrip.ply.gz") else {
        panic!("dragon is a mesh")
    };
    let Model::Volume(head) = model("ch2.nii.gz") else {
        panic!("ch2 is a volume")
    };
    let solid = MeshSolid::new(&dragon);
    println!("| input | grid | sample + filter (s) | marching cubes (s) | triangles |");
    println!("|---|---|---|---|---|");
    let mut finest = None;
    for n in [64usize, 128, 256] {
        let t = Instant::now();
        let f = density(Source::Solid(&solid), n, 1, 1.0, Filter::Gaussian, &p).unwrap();
        let sample = t.elapsed().as_secs_f64();
        let t = Instant::now();
        let mesh = marching_cubes(&f, 0.5, &p).unwrap();
        let mc = t.elapsed().as_secs_f64();
        println!(
            "| dragon ({} triangles) | {}×{}×{} | {sample:.2} | {mc:.3} | {} |",
            dragon.triangles.len(),
            f.dims[0],
            f.dims[1],
            f.dims[2],
            mesh.triangles.len()
        );
        finest = Some(f);
    }
    // The head's own grid is 181×217×181; pooling by 4, 2, 1 gives ~64³..256³-class grids.
    let iso = 0.5 * (head.value_range().0 + head.value_range().1);
    for factor in [4usize, 2, 1] {
        let t = Instant::now();
        let f = density(
            Source::Volume(&head, iso),
            0,
            factor,
            1.0,
            Filter::Gaussian,
            &p,
        )
        .unwrap();
        let sample = t.elapsed().as_secs_f64();
        let t = Instant::now();
        let mesh = marching_cubes(&f, 0.5, &p).unwrap();
        let mc = t.elapsed().as_secs_f64();
        println!(
            "| MRI head ch2 | {}×{}×{} | {sample:.2} | {mc:.3} | {} |",
            f.dims[0],
            f.dims[1],
            f.dims[2],
            mesh.triangles.len()
        );
    }
    let f = finest.expect("three grids");
    let best = (0..3)
        .map(|_| {
            let t = Instant::now();
            let m = marching_cubes(&f, 0.5, &p).unwrap();
            (t.elapsed().as_secs_f64(), m.triangles.len())
        })
        .min_by(|a, b| a.0.total_cmp(&b.0))
        .unwrap();
    let raw = std::env::var_os("LODSTUDIO_BENCH_RAW")
        .map(PathBuf::from)
        .unwrap_or_else(|| std::env::temp_dir().join("lodstudio-dragon-density.f32"));
    let bytes: Vec<u8> = f.data.iter().flat_map(|v| v.to_le_bytes()).collect();
    std::fs::write(&raw, bytes).expect("write the density");
    println!();
    println!(
        "marching cubes alone, dragon density {}×{}×{} (best of 3): {:.3} s, {} triangles; raw f32 volume in {} (dims {} {} {})",
        f.dims[0],
        f.dims[1],
        f.dims[2],
        best.0,
        best.1,
        raw.display(),
        f.dims[0],
        f.dims[1],
        f.dims[2]
    );
}
