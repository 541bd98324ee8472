//! Issue 28: builds use both cores, and their output does not depend on how
//! many threads there are. Every method's hierarchy is built on fandisk in a
//! pool of one thread and in a pool of two, saved, and compared byte for byte
//! (the saved file holds every float bit-exact).

use std::sync::Arc;

use lodstudio_core::lod::{Hierarchy, Method};
use lodstudio_core::{Progress, TriMesh, io};
use lodstudio_tests::shared_model;

fn fandisk() -> TriMesh {
    let path = shared_model("fandisk.obj");
    match io::load(&path, &Default::default(), &Progress::new())
        .unwrap()
        .model
    {
        lodstudio_core::Model::Mesh(m) => m,
        _ => panic!("fandisk is a mesh"),
    }
}

fn build(method: Method, mesh: &TriMesh) -> Box<dyn Hierarchy> {
    let p = Progress::new();
    match method {
        Method::EdgeCollapse => {
            let floor = mesh.triangles.len() / 100;
            let r =
                lodstudio_core::simplify::progressive::record(mesh, Default::default(), floor, &p);
            Box::new(lodstudio_core::simplify::progressive::ProgressiveCut::new(
                Arc::new(r.unwrap()),
            ))
        }
        Method::Hybrid => {
            let mrg = lodstudio_core::hybrid::build(mesh, &Default::default(), &p).unwrap();
            Box::new(lodstudio_core::hybrid::HybridCut::new(Arc::new(mrg)))
        }
        Method::MergeTree => {
            let tree = lodstudio_core::mergetree::build(mesh, &Default::default(), &p).unwrap();
            Box::new(lodstudio_core::mergetree::MergeTreeView::new(
                Arc::new(tree),
                Default::default(),
            ))
        }
        Method::Voxel => {
            use lodstudio_core::voxel::{Filter, Pyramid, Source, pyramid::PyramidCut};
            let solid = lodstudio_core::implicit::MeshSolid::new(mesh);
            let source = Source::Solid(&solid);
            let mut pyramid = Pyramid::build(source, 48, 1.5, Filter::Gaussian, &p).unwrap();
            pyramid.certify(source.surface(), &p).unwrap();
            Box::new(PyramidCut::new(pyramid, None))
        }
        Method::Amg => {
            let model = lodstudio_core::Model::Mesh(mesh.clone());
            let points = lodstudio_core::amg::point_set(&model).unwrap();
            let ms = lodstudio_core::amg::decompose(&points, &Default::default(), &p).unwrap();
            let texel = ms.default_texel();
            Box::new(lodstudio_core::amg::AmgHierarchy::new(ms, texel))
        }
    }
}

#[test]
fn every_method_builds_the_same_bits_on_one_thread_and_on_two() {
    let mesh = fandisk();
    let in_pool = |threads: usize, method: Method| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            build(method, &mesh)
                .save(&serde_json::json!({}))
                .expect("saves")
        })
    };
    for method in Method::ALL {
        let (one, two) = (in_pool(1, method), in_pool(2, method));
        assert!(
            one == two,
            "{method:?}: {} vs {} bytes, differing",
            one.len(),
            two.len()
        );
    }
}
