//! Mutation test: thousands of random corruptions (bit flips, truncations,
//! altered header counts, spliced bytes) of real files of every format. Every one
//! must load or fail with an error: no panic, and no allocation beyond a fixed
//! limit (a header count must never be trusted). Bounded in time per format.

use std::alloc::{GlobalAlloc, Layout, System};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::{Duration, Instant};

use lodstudio_core::Progress;
use lodstudio_core::io::{self, LoadOptions};
use lodstudio_core::rng::Rng;
use lodstudio_tests::shared_model;

/// Largest single allocation any mutated file may cause.
const ALLOC_LIMIT: usize = 1 << 30;

struct Guarded;
static LARGEST: AtomicUsize = AtomicUsize::new(0);

unsafe impl GlobalAlloc for Guarded {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        LARGEST.fetch_max(layout.size(), Ordering::Relaxed);
        if layout.size() > ALLOC_LIMIT {
            return std::ptr::null_mut();
        }
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        LARGEST.fetch_max(new_size, Ordering::Relaxed);
        if new_size > ALLOC_LIMIT {
            return std::ptr::null_mut();
        }
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Guarded = Guarded;

/// One random corruption of `data`.
fn mutate(data: &[u8], rng: &mut Rng) -> Vec<u8> {
    let mut out = data.to_vec();
    match rng.below(5) {
        0 => {
            for _ in 0..1 + rng.below(8) {
                let i = rng.below(out.len());
                out[i] ^= 1 << rng.below(8);
            }
        }
        1 => out.truncate(rng.below(out.len())),
        2 => {
            // Alter a number in the header region: the counts live there.
            let head = out.len().min(1024);
            let digits: Vec<usize> = (0..head).filter(|i| out[*i].is_ascii_digit()).collect();
            if let Some(&i) = digits.get(rng.below(digits.len().max(1))) {
                let replacement: &[u8] = match rng.below(4) {
                    0 => b"999999999999",
                    1 => b"0",
                    2 => b"-1",
                    _ => b"4294967296",
                };
                out.splice(i..i + 1, replacement.iter().copied());
            }
        }
        3 => {
            // Overwrite a binary word with an extreme value (binary counts, offsets).
            let i = rng.below(out.len().saturating_sub(4).max(1));
            let v: [u8; 4] = [0xff, 0xff, 0xff, 0x7f];
            for (k, b) in v.iter().enumerate() {
                if let Some(x) = out.get_mut(i + k) {
                    *x = *b;
                }
            }
        }
        _ => {
            // Splice: duplicate or delete a random run.
            let a = rng.below(out.len());
            let b = (a + rng.below(64)).min(out.len());
            if rng.below(2) == 0 {
                out.drain(a..b);
            } else {
                let run: Vec<u8> = out[a..b].to_vec();
                out.splice(a..a, run);
            }
        }
    }
    out
}

/// Mutates `data` repeatedly for `budget`; returns how many variants were tried.
fn hammer(name: &Path, data: &[u8], opts: &LoadOptions, budget: Duration, seed: u64) -> usize {
    let mut rng = Rng::new(seed);
    let start = Instant::now();
    let mut tried = 0;
    while start.elapsed() < budget && tried < 1500 {
        let bad = mutate(data, &mut rng);
        let result = std::panic::catch_unwind(|| {
            let _ = io::load_bytes(name, &bad, opts, &Progress::new());
        });
        assert!(
            result.is_ok(),
            "{}: panic on mutation #{tried}",
            name.display()
        );
        tried += 1;
    }
    tried
}

fn read(name: &str) -> Vec<u8> {
    std::fs::read(shared_model(name)).unwrap()
}

#[test]
fn random_corruptions_never_panic_or_over_allocate() {
    let budget = Duration::from_secs(4);
    let opts = LoadOptions::default();
    // (label, the name the loader sees, bytes, seed)
    let mut jobs: Vec<(String, PathBuf, Vec<u8>, u64)> = [
        "couplingdown.off",
        "fandisk.obj",
        "CesiumMilkTruck.glb",
        "2CylinderEngine.gltf",
        "ball.ply",
        "horse.ply",
        "skull_2.9.inr",
        "ch2.nii.gz",
    ]
    .iter()
    .enumerate()
    .map(|(i, name)| (name.to_string(), shared_model(name), read(name), i as u64))
    .collect();

    // Formats without a real file here are made from real data.
    let skull = match io::load(&shared_model("skull_2.9.inr"), &opts, &Progress::new())
        .unwrap()
        .model
    {
        io::Model::Volume(v) => v,
        _ => unreachable!(),
    };
    let mut nrrd = format!(
        "NRRD0004\ntype: float\ndimension: 3\nsizes: {} {} {}\nspacings: {} {} {}\nendian: big\nencoding: raw\n\n",
        skull.dims[0], skull.dims[1], skull.dims[2], skull.spacing.x, skull.spacing.y, skull.spacing.z
    )
    .into_bytes();
    nrrd.extend(skull.data.iter().flat_map(|v| v.to_be_bytes()));
    let dir = std::env::temp_dir();
    jobs.push((
        "skull.nrrd (big-endian)".into(),
        dir.join("skull.nrrd"),
        nrrd,
        100,
    ));

    let ball = match io::load(&shared_model("ball.ply"), &opts, &Progress::new())
        .unwrap()
        .model
    {
        io::Model::Points(p) => p,
        _ => unreachable!(),
    };
    let be = io::ply::write_points(&ball, io::ply::Encoding::BinaryBigEndian);
    jobs.push((
        "ball.ply (binary big-endian)".into(),
        dir.join("ball_be.ply"),
        be,
        101,
    ));

    // gzip: the NIfTI head is large, so mutate a smaller gzipped PLY.
    let gz = {
        use std::io::Write;
        let mut enc = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
        enc.write_all(&read("couplingdown.off")).unwrap();
        enc.finish().unwrap()
    };
    jobs.push((
        "couplingdown.off.gz".into(),
        dir.join("couplingdown.off.gz"),
        gz,
        102,
    ));

    // The formats are hammered two at a time (each for its own time budget),
    // so the test takes half the wall time on two cores.
    let next = AtomicUsize::new(0);
    let per_format = std::sync::Mutex::new(Vec::new());
    std::thread::scope(|scope| {
        for _ in 0..2 {
            scope.spawn(|| {
                while let Some((label, path, data, seed)) =
                    jobs.get(next.fetch_add(1, Ordering::Relaxed))
                {
                    let n = hammer(path, data, &opts, budget, *seed);
                    per_format.lock().unwrap().push((label.clone(), n));
                }
            });
        }
    });
    let per_format = per_format.into_inner().unwrap();
    let total: usize = per_format.iter().map(|(_, n)| n).sum();
    assert_eq!(per_format.len(), jobs.len());
    eprintln!("mutations per format: {per_format:?}");
    assert!(total >= 2000, "thousands of mutations: {total}");
    assert!(per_format.iter().all(|(_, n)| *n >= 20), "{per_format:?}");
    assert!(LARGEST.load(Ordering::Relaxed) <= ALLOC_LIMIT);
}
