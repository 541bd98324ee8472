//! The models of one machine on a few workers within a memory budget:
//! largest first, and a model whose estimated peak does not fit what the
//! running ones leave waits (one that fits no budget runs alone).

use std::io::Read;
use std::path::Path;
use std::sync::{Condvar, Mutex};

use crate::recipe::Recipe;

/// Bytes of memory the heaviest row of `recipe` may reach at its peak
/// ([`Params::peak_bytes`](crate::lod::Params::peak_bytes)), and what the
/// process holds besides. `parsed_bytes`: what the readers parse, a gzip
/// input's inflated size ([`parsed_size`]), not the bytes on disk.
pub fn estimate_peak(parsed_bytes: u64, recipe: &Recipe) -> u64 {
    let heaviest = (0..recipe.rows.len())
        .map(|j| recipe.row_params(j).peak_bytes(parsed_bytes))
        .max()
        .unwrap_or(parsed_bytes);
    (64u64 << 20).saturating_add(heaviest)
}

/// The bytes a reader parses from the file at `path`: its length, or for a
/// gzip file (known by its first bytes, as the loader knows it) the length
/// it inflates to, measured by inflating it as a stream and counting (no
/// more than a buffer is held) up to `cap`. A stream that runs past the cap,
/// or whose size cannot be learned (corrupt, unreadable after its start),
/// counts as `cap`: the most a reader may be made to parse. A file that
/// cannot be opened, or is not a regular file, counts 0 (it fails when
/// built, alone).
pub fn parsed_size(path: &Path, cap: u64) -> u64 {
    let Ok(file) = crate::io::confine::open_regular(path) else {
        return 0;
    };
    let len = file.metadata().map_or(0, |m| m.len());
    let mut reader = std::io::BufReader::with_capacity(1 << 16, file);
    let mut magic = [0u8; 2];
    if reader.read_exact(&mut magic).is_err() || !crate::io::is_gzip(&magic) {
        return len;
    }
    let stream = std::io::Cursor::new(magic).chain(reader);
    let mut inflate = flate2::read::MultiGzDecoder::new(stream).take(cap.saturating_add(1));
    match std::io::copy(&mut inflate, &mut std::io::sink()) {
        Ok(n) if n <= cap => n,
        _ => cap,
    }
}

/// Runs its closure when dropped.
struct Release<'a>(&'a dyn Fn());

impl Drop for Release<'_> {
    fn drop(&mut self) {
        (self.0)();
    }
}

/// Runs `job(i)` for every job on `workers` threads, taking jobs in the
/// order given (largest first) as the budget allows: job i starts when its
/// `estimates[i]` fits what the running jobs leave of `budget`, or when
/// nothing runs. Results come in job order, whatever order they ran in.
pub fn run_within_budget<T: Send>(
    estimates: &[u64],
    workers: usize,
    budget: u64,
    job: impl Fn(usize) -> T + Sync,
) -> Vec<T> {
    struct State {
        pending: Vec<usize>,
        in_use: u64,
        running: usize,
    }
    let state = Mutex::new(State {
        pending: (0..estimates.len()).collect(),
        in_use: 0,
        running: 0,
    });
    let changed = Condvar::new();
    let results: Mutex<Vec<Option<T>>> = Mutex::new((0..estimates.len()).map(|_| None).collect());
    std::thread::scope(|scope| {
        for _ in 0..workers.max(1) {
            scope.spawn(|| {
                loop {
                    let i = {
                        let mut s = state.lock().expect("scheduler lock");
                        loop {
                            if s.pending.is_empty() {
                                return;
                            }
                            let left = budget.saturating_sub(s.in_use);
                            let fits = s.pending.iter().position(|&i| estimates[i] <= left);
                            let pick = fits.or((s.running == 0).then_some(0));
                            if let Some(at) = pick {
                                let i = s.pending.remove(at);
                                s.in_use += estimates[i];
                                s.running += 1;
                                break i;
                            }
                            s = changed.wait(s).expect("scheduler lock");
                        }
                    };
                    // Released even if the job panics, so no worker waits forever
                    // (the panic then ends the scope).
                    let _release = Release(&|| {
                        if let Ok(mut s) = state.lock() {
                            s.in_use -= estimates[i];
                            s.running -= 1;
                        }
                        changed.notify_all();
                    });
                    let out = job(i);
                    results.lock().expect("results lock")[i] = Some(out);
                }
            });
        }
    });
    results
        .into_inner()
        .expect("results lock")
        .into_iter()
        .map(|r| r.expect("every job ran"))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::atomic::{AtomicU64, Ordering};

    /// The running jobs' estimates never add up past the budget (a job
    /// larger than it runs alone), and every job runs once.
    #[test]
    fn jobs_run_once_within_the_budget() {
        let estimates = [900, 500, 400, 300, 200, 100, 100];
        let (in_use, worst) = (AtomicU64::new(0), AtomicU64::new(0));
        let out = run_within_budget(&estimates, 3, 1000, |i| {
            let now = in_use.fetch_add(estimates[i], Ordering::SeqCst) + estimates[i];
            worst.fetch_max(now, Ordering::SeqCst);
            std::thread::sleep(std::time::Duration::from_millis(5));
            in_use.fetch_sub(estimates[i], Ordering::SeqCst);
            i * 10
        });
        assert_eq!(out, [0, 10, 20, 30, 40, 50, 60]);
        assert!(worst.load(Ordering::SeqCst) <= 1000);
        let alone = run_within_budget(&[5000, 10], 2, 1000, |i| i);
        assert_eq!(alone, [0, 1]);
        let r = Recipe::new(crate::recipe::parse_lods("hybrid:1%,simplify:2%", None).unwrap());
        let light = Recipe::new(crate::recipe::parse_lods("simplify:2%", None).unwrap());
        assert!(estimate_peak(1 << 20, &r) > estimate_peak(1 << 20, &light));
        assert!(estimate_peak(4 << 20, &light) >= (4 << 20) * 11);
    }

    /// A gzip input counts as what it inflates to (or the cap, when that is
    /// over it or cannot be learned), not as its compressed bytes.
    #[test]
    fn gzip_inputs_count_their_inflated_size() {
        use std::io::Write;
        let dir = tempfile::tempdir().unwrap();
        let gz = |name: &str, bytes: &[u8]| {
            let path = dir.path().join(name);
            let mut e = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
            e.write_all(bytes).unwrap();
            std::fs::write(&path, e.finish().unwrap()).unwrap();
            path
        };
        let zeros = gz("zeros.obj.gz", &vec![0u8; 3 << 20]);
        assert!(std::fs::metadata(&zeros).unwrap().len() < 64 << 10);
        assert_eq!(parsed_size(&zeros, 1 << 30), 3 << 20);
        assert_eq!(parsed_size(&zeros, 1 << 20), 1 << 20, "at the cap");
        // Two members, as MultiGzDecoder (the loader) reads them.
        let mut two = std::fs::read(&zeros).unwrap();
        two.extend(std::fs::read(&zeros).unwrap());
        let twice = dir.path().join("twice.ply.gz");
        std::fs::write(&twice, &two).unwrap();
        assert_eq!(parsed_size(&twice, 1 << 30), 6 << 20);
        // Corrupt after its header: its size cannot be learned.
        let mut broken = std::fs::read(&zeros).unwrap();
        broken.truncate(broken.len() / 2);
        broken.extend([0xff; 64]);
        let broken_path = dir.path().join("broken.off.gz");
        std::fs::write(&broken_path, broken).unwrap();
        assert_eq!(parsed_size(&broken_path, 5 << 20), 5 << 20);
        let plain = dir.path().join("plain.obj");
        std::fs::write(&plain, b"v 0 0 0\n").unwrap();
        assert_eq!(parsed_size(&plain, 1), 8, "not gzip: its length");
        assert_eq!(parsed_size(&dir.path().join("missing.obj"), 1 << 20), 0);
        assert_eq!(parsed_size(dir.path(), 1 << 20), 0, "a folder");
    }
}
