//! What the commands that split their work over machines share: which
//! shard this process is (`--shard I/N`, or `--shards N` with the index
//! from the environment), and the tool's identity in the keys that say
//! whether work done before can be reused.

use std::sync::OnceLock;

use super::*;
use lodstudio_core::batch::{Shard, cache, shard};

#[derive(Args, Debug)]
pub struct ShardArgs {
    /// Run shard I of N (0-based), e.g. 2/8.
    #[arg(long, value_name = "I/N", value_parser = Shard::parse, conflicts_with = "shards")]
    shard: Option<Shard>,
    /// N shards, this one's index read from JOB_COMPLETION_INDEX (a
    /// Kubernetes Indexed Job) or the variable --shard-index-env names.
    #[arg(long, value_name = "N")]
    shards: Option<usize>,
    /// The variable holding the 0-based shard index with --shards (a Slurm
    /// array: SLURM_ARRAY_TASK_ID; a CI matrix: its index variable).
    #[arg(long, value_name = "VAR", default_value = shard::INDEX_ENV, requires = "shards")]
    shard_index_env: String,
}

impl ShardArgs {
    pub fn shard(&self) -> Result<Shard, CliError> {
        match (self.shard, self.shards) {
            (Some(s), _) => Ok(s),
            (None, Some(n)) => {
                Shard::from_env(&self.shard_index_env, n).map_err(CliError::BadInput)
            }
            (None, None) => Ok(Shard::ALL),
        }
    }
}

/// The tool's identity in cache keys: its version and the hash of its own
/// executable, so a rebuilt lodstudio never reuses another build's outputs.
pub fn tool_id() -> &'static str {
    static ID: OnceLock<String> = OnceLock::new();
    ID.get_or_init(|| {
        let exe = std::env::current_exe()
            .ok()
            .and_then(|p| std::fs::read(p).ok())
            .map_or_else(|| "unknown".into(), |b| cache::sha256_hex(&b));
        format!("lodstudio {} {exe}", env!("CARGO_PKG_VERSION"))
    })
}
