//! Cancel stops the worker (issue 31): for every method and every stage of
//! its build, a build cancelled as it enters the stage returns a
//! cancellation (not any error) within a deadline, and its progress stops.
//! A build that ignored Cancel would run on to its end (seconds here) or
//! return a result.

use std::sync::Arc;
use std::sync::mpsc;
use std::time::{Duration, Instant};

use lodstudio_core::{Progress, io};
use lodstudio_tests::{shared_mesh, shared_model};

/// Runs of a build before one that finished counts against it: the bunny's
/// "hybrid: merging points" takes ~15 ms, and with the other tests on both
/// cores the watching thread missed it three times in a row (CI, b9cdcc9).
const ATTEMPTS: usize = 6;

/// How a build ended: `Some(true)` cancelled, `Some(false)` another error,
/// `None` finished.
type Outcome = Option<bool>;

/// Runs `work` on a worker, cancels it as it enters `stage`, and checks it
/// stops with a cancellation within the deadline, its progress frozen. A
/// stage of a few milliseconds can end before Cancel lands on a loaded
/// machine, so a finished build is run again, up to [`ATTEMPTS`] times; a
/// build that ignored Cancel finishes every time and fails.
fn cancels_at(stage: &str, work: impl Fn(&Progress) -> Outcome + Send + Sync + 'static) {
    let work = Arc::new(work);
    for attempt in 1..=ATTEMPTS {
        let progress = Arc::new(Progress::new());
        let (tx, rx) = mpsc::channel();
        let worker = {
            let (progress, work) = (Arc::clone(&progress), Arc::clone(&work));
            std::thread::spawn(move || {
                let _ = tx.send(work(&progress));
            })
        };
        let deadline = Instant::now() + Duration::from_secs(120);
        while progress.stage_name() != stage {
            if let Ok(outcome) = rx.try_recv() {
                panic!("ended ({outcome:?}) before stage {stage:?}");
            }
            assert!(Instant::now() < deadline, "never reached {stage:?}");
            std::thread::sleep(Duration::from_micros(50));
        }
        progress.cancel();
        let cancelled = Instant::now();
        let outcome = rx
            .recv_timeout(Duration::from_secs(5))
            .unwrap_or_else(|_| panic!("{stage:?}: still running 5 s after Cancel"));
        let took = cancelled.elapsed();
        worker.join().unwrap();
        if outcome.is_none() && attempt < ATTEMPTS {
            eprintln!("{stage:?}: finished before Cancel landed (attempt {attempt}); again");
            continue;
        }
        assert_eq!(
            outcome,
            Some(true),
            "{stage:?}: a cancellation, not a result or another error"
        );
        let (fraction, name) = (progress.fraction(), progress.stage_name());
        std::thread::sleep(Duration::from_millis(20));
        assert_eq!(
            (progress.fraction(), progress.stage_name()),
            (fraction, name),
            "{stage:?}: progress stopped"
        );
        eprintln!(
            "{stage:?}: stopped {:.1} ms after Cancel",
            took.as_secs_f64() * 1e3
        );
        return;
    }
}

#[test]
fn edge_collapse_stops_at_every_stage() {
    use lodstudio_core::simplify::{self, SimplifyError, SimplifyOptions, Target};
    for stage in ["collapsing edges", "certifying the error bound"] {
        let horse = shared_mesh("horse.ply");
        cancels_at(stage, move |p| {
            let opts = SimplifyOptions {
                target: Target::Ratio(0.02),
                collapse: Default::default(),
                per_triangle_bounds: true,
            };
            match simplify::simplify(&horse, &opts, p) {
                Ok(_) => None,
                Err(e) => Some(e == SimplifyError::Cancelled),
            }
        });
    }
    // The studio's build: the collapses recorded with their bounds.
    for stage in ["collapsing edges", "bounding collapses"] {
        let horse = shared_mesh("horse.ply");
        cancels_at(stage, move |p| {
            let r = simplify::progressive::record(&horse, Default::default(), 100, p);
            r.err().map(|_| true)
        });
    }
}

#[test]
fn hybrid_stops_at_every_stage() {
    for stage in [
        "hybrid: collapsing edges",
        "hybrid: replacing triangles by points",
        "hybrid: merging points",
    ] {
        let bunny = shared_mesh("stanford-bunny.obj");
        cancels_at(stage, move |p| {
            let opts = lodstudio_core::hybrid::HybridOptions::default();
            lodstudio_core::hybrid::build(&bunny, &opts, p)
                .err()
                .map(|_| true)
        });
    }
}

#[test]
fn merge_tree_stops_at_every_stage() {
    for stage in ["merge tree levels", "merge tree dependencies"] {
        let horse = shared_mesh("horse.ply");
        cancels_at(stage, move |p| {
            lodstudio_core::mergetree::build(&horse, &Default::default(), p)
                .err()
                .map(|_| true)
        });
    }
}

#[test]
fn voxel_stops_at_every_stage() {
    use lodstudio_core::voxel::{Filter, Pyramid, Source};
    for (stage, filter) in [
        ("sampling", Filter::Gaussian),
        ("gaussian filter", Filter::Gaussian),
        ("hyper-cone filter", Filter::Cone),
        ("certifying the levels' bounds", Filter::Gaussian),
        // Each level's edge collapse after its extraction (§5).
        ("collapsing edges", Filter::Gaussian),
    ] {
        let horse = shared_mesh("horse.ply");
        cancels_at(stage, move |p| {
            let solid = lodstudio_core::implicit::MeshSolid::new(&horse);
            let source = Source::Solid(&solid);
            let mut pyramid = match Pyramid::build(source, 96, 3.0, filter, p) {
                Ok(pyramid) => pyramid,
                Err(_) => return Some(true),
            };
            pyramid.certify(source.surface(), p).err().map(|_| true)
        });
    }
    // The signed field of an implicit solid (the built-in CSG part's mesh).
    cancels_at("sampling the solid", move |p| {
        let part = lodstudio_core::implicit::csg_part();
        lodstudio_core::voxel::sampling::sample_field(&part, 0.015, p)
            .err()
            .map(|_| true)
    });
    // Marching cubes of a dense grid (a volume's surface).
    cancels_at("marching cubes", move |p| {
        let n = 160;
        let data = (0..n * n * n)
            .map(|i| {
                let q = glam::Vec3::new((i % n) as f32, (i / n % n) as f32, (i / (n * n)) as f32);
                // A wavy ball: many surface cells.
                70.0 - q.distance(glam::Vec3::splat(80.0)) + 4.0 * (q.x * 0.3).sin()
            })
            .collect();
        let v = lodstudio_core::Volume {
            dims: [n; 3],
            spacing: glam::Vec3::ONE,
            origin: glam::Vec3::ZERO,
            data,
        };
        lodstudio_core::voxel::marching_cubes(&v, 0.0, p)
            .err()
            .map(|_| true)
    });
}

#[test]
fn amg_stops_at_every_stage() {
    use lodstudio_core::amg::{self, AmgError};
    for stage in [
        "neighbourhoods",
        "classifier",
        "stiffness matrix",
        "AMG coarsening",
    ] {
        let ball = shared_model("ball.ply");
        cancels_at(stage, move |p| {
            let loaded = io::load(&ball, &Default::default(), &Progress::new()).unwrap();
            let points = amg::point_set(&loaded.model).unwrap();
            match amg::decompose(&points, &Default::default(), p) {
                Ok(_) => None,
                Err(e) => Some(matches!(e, AmgError::Cancelled)),
            }
        });
    }
    let ball = shared_model("ball.ply");
    let loaded = io::load(&ball, &Default::default(), &Progress::new()).unwrap();
    let points = amg::point_set(&loaded.model).unwrap();
    let ms = Arc::new(amg::decompose(&points, &Default::default(), &Progress::new()).unwrap());
    cancels_at("domain primitives", move |p| {
        let texel = 0.1
            * ms.radii
                .iter()
                .copied()
                .fold(f32::INFINITY, f32::min)
                .max(1e-4);
        amg::primitives(&ms, 1, texel, p).err().map(|_| true)
    });
}
