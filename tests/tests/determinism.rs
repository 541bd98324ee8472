//! Issue 28: builds use both cores, and their output does not depend on how
//! many threads there are. Every method's hierarchy is built on fandisk in a
//! pool of one thread and in a pool of two, saved, and compared byte for byte
//! (the saved file holds every float bit-exact).

use lodstudio_core::lod::Method;
use lodstudio_tests::{build_hierarchy, shared_mesh};

#[test]
fn every_method_builds_the_same_bits_on_one_thread_and_on_two() {
    let mesh = shared_mesh("fandisk.obj");
    let in_pool = |threads: usize, method: Method| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            build_hierarchy(method, &mesh)
                .0
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
