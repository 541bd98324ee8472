//! The models of one machine on a few workers within a memory budget:
//! largest first, and a model whose estimated peak does not fit what the
//! running ones leave waits (one that fits no budget runs alone).

use std::sync::{Condvar, Mutex};

use crate::lod::Method;
use crate::recipe::Recipe;

/// Bytes of memory per input byte that the heaviest method of `recipe`
/// may reach at its peak, from BENCHMARKS.md's dragon figures (peak RSS
/// over the PLY's bytes: hybrid 2.0 GB, AMG 0.8 GB, edge collapse 0.33 GB,
/// merge tree 0.24 GB of a 32 MB file), plus the voxel grids.
pub fn estimate_peak(input_bytes: u64, compressed: bool, recipe: &Recipe) -> u64 {
    let bytes = input_bytes.saturating_mul(if compressed { 4 } else { 1 });
    let per_byte = |m: Method| -> u64 {
        match m {
            Method::Hybrid => 64,
            Method::Amg => 26,
            Method::EdgeCollapse => 11,
            Method::MergeTree => 8,
            Method::Voxel => 8,
        }
    };
    let heaviest = recipe
        .rows
        .iter()
        .map(|r| per_byte(r.method))
        .max()
        .unwrap_or(1);
    // A voxel pyramid keeps a few float grids of resolution³ (sampled,
    // filtered, and the coarser levels).
    let grids = recipe
        .rows
        .iter()
        .filter(|r| r.method == Method::Voxel)
        .map(|r| (r.resolution() as u64).pow(3) * 4 * 4)
        .max()
        .unwrap_or(0);
    64 * 1024 * 1024 + bytes.saturating_mul(heaviest) + grids
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
        assert!(estimate_peak(1 << 20, false, &r) > estimate_peak(1 << 20, false, &light));
        assert!(estimate_peak(1 << 20, true, &light) > estimate_peak(1 << 20, false, &light));
    }
}
