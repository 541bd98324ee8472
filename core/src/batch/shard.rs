//! Shards: which machine runs which model. Every shard computes the same
//! assignment from the same inputs, so an engine that hands out an index
//! (`JOB_COMPLETION_INDEX` of a Kubernetes Indexed Job, a CI matrix, a Slurm
//! array's `SLURM_ARRAY_TASK_ID`) is all the coordination there is.

/// The environment variable a Kubernetes Indexed Job sets in each pod.
pub const INDEX_ENV: &str = "JOB_COMPLETION_INDEX";

/// Shard `index` of `count` (0-based).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Shard {
    pub index: usize,
    pub count: usize,
}

impl Shard {
    /// The whole batch on one machine.
    pub const ALL: Shard = Shard { index: 0, count: 1 };

    /// `I/N` as `--shard` writes it.
    pub fn parse(text: &str) -> Result<Shard, String> {
        let bad = || format!("--shard {text:?}: expected I/N with 0 <= I < N, e.g. 0/3");
        let (i, n) = text.split_once('/').ok_or_else(bad)?;
        let index = i.trim().parse::<usize>().map_err(|_| bad())?;
        let count = n.trim().parse::<usize>().map_err(|_| bad())?;
        Shard::new(index, count).ok_or_else(bad)
    }

    pub fn new(index: usize, count: usize) -> Option<Shard> {
        (count > 0 && index < count).then_some(Shard { index, count })
    }

    /// Shard I of `count` where I is `JOB_COMPLETION_INDEX` (or the
    /// variable `var` names).
    pub fn from_env(var: &str, count: usize) -> Result<Shard, String> {
        let text = std::env::var(var)
            .map_err(|_| format!("--shards {count}: {var} is not set (the shard index)"))?;
        let index = text
            .trim()
            .parse::<usize>()
            .map_err(|_| format!("{var}={text:?} is not a shard index"))?;
        Shard::new(index, count)
            .ok_or_else(|| format!("{var}={index} is not below --shards {count}"))
    }

    /// How reports of this shard are named: "" or ".shard-1-of-3".
    pub fn suffix(&self) -> String {
        if self.count == 1 {
            String::new()
        } else {
            format!(".shard-{}-of-{}", self.index, self.count)
        }
    }
}

/// The shard of each input: largest first, each to the shard with the
/// least work so far (ties: the lower index), work counted in input bytes.
/// Equal sizes keep input order, so the assignment depends only on the list.
pub fn assign(sizes: &[u64], shards: usize) -> Vec<usize> {
    let shards = shards.max(1);
    let mut order: Vec<usize> = (0..sizes.len()).collect();
    order.sort_by(|&a, &b| sizes[b].cmp(&sizes[a]).then(a.cmp(&b)));
    let mut load = vec![0u64; shards];
    let mut out = vec![0; sizes.len()];
    for i in order {
        let s = (0..shards).min_by_key(|&s| (load[s], s)).expect("a shard");
        load[s] += sizes[i].max(1);
        out[i] = s;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_input_goes_to_one_shard_balanced_by_size() {
        let sizes = [100, 1, 50, 50, 2, 98, 0];
        let a = assign(&sizes, 3);
        let load = |s| {
            (0..sizes.len())
                .filter(|&i| a[i] == s)
                .map(|i| sizes[i])
                .sum::<u64>()
        };
        // 100 | 98 + 1 | 50 + 50 ... greedy: 100 / 98+2 / 50+50+1+0 or close.
        let loads: Vec<u64> = (0..3).map(load).collect();
        assert_eq!(loads.iter().sum::<u64>(), 301);
        assert!(
            loads.iter().max().unwrap() - loads.iter().min().unwrap() <= 2,
            "{loads:?}"
        );
        assert_eq!(a, assign(&sizes, 3), "the same list, the same shards");
        assert!(assign(&sizes, 1).iter().all(|&s| s == 0));
        assert_eq!(Shard::parse("1/3"), Ok(Shard { index: 1, count: 3 }));
        for bad in ["3/3", "1", "-1/3", "a/b", "0/0"] {
            assert!(Shard::parse(bad).is_err(), "{bad}");
        }
        assert_eq!(Shard::ALL.suffix(), "");
        assert_eq!(Shard::parse("0/2").unwrap().suffix(), ".shard-0-of-2");
    }
}
