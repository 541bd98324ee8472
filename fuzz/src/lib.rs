//! What every fuzz target shares: limits small enough that no input can make a
//! reader allocate past libFuzzer's memory limit without being refused first.

use lodstudio_core::io::limits::{self, Limits};

/// Puts the fuzzing limits in force (idempotent; cheap enough per input).
pub fn setup() {
    limits::set(Limits {
        max_decompressed: 64 << 20,
        memory_budget: 256 << 20,
        ratio_limited: true,
    });
}
