//! Hard limits on what untrusted bytes may make lodstudio allocate: how far a
//! gzip stream may inflate, and a memory budget that counts read from headers
//! are checked against before anything is reserved. An input over a limit is
//! an error naming the limit and how to raise it, never an abort.
//!
//! Process-wide, like the thread pool: the CLI sets them once from
//! `--max-decompressed` / `--max-memory` or the environment; the defaults come
//! from the machine's memory.

use std::sync::atomic::{AtomicU64, Ordering};

use super::ParseError;

/// Environment variable overriding the decompression cap (a size such as `512M`).
pub const MAX_DECOMPRESSED_ENV: &str = "LODSTUDIO_MAX_DECOMPRESSED";
/// Environment variable overriding the memory budget (a size such as `8G`).
pub const MAX_MEMORY_ENV: &str = "LODSTUDIO_MAX_MEMORY";

/// A gzip stream may inflate to at most this many times its own size
/// (above [`RATIO_FLOOR`]), besides the absolute cap: a 2 MB bomb of 2 GB
/// is refused, where a model (2–10×) never comes near it.
pub const MAX_RATIO: u64 = 100;
/// What any gzip stream may inflate to whatever its ratio.
pub const RATIO_FLOOR: u64 = 256 << 20;

/// Assumed when the machine's memory cannot be read.
const FALLBACK_MEMORY: u64 = 8 << 30;

/// The limits in force.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Limits {
    /// Most bytes a gzip stream may inflate to.
    pub max_decompressed: u64,
    /// Most bytes a reader may reserve for what one file's headers announce.
    pub memory_budget: u64,
    /// Whether a gzip stream is also held to [`MAX_RATIO`] times its size
    /// (the default; a cap the user names is taken as it is).
    pub ratio_limited: bool,
}

impl Limits {
    /// From the machine: half its memory as the budget, a quarter as the
    /// decompression cap (the inflated bytes and what is parsed from them
    /// must both fit).
    pub fn machine() -> Limits {
        let total = machine_total();
        Limits {
            max_decompressed: total / 4,
            memory_budget: total / 2,
            ratio_limited: true,
        }
    }

    /// [`Limits::machine`] with the environment's overrides.
    pub fn from_env() -> Result<Limits, String> {
        let mut limits = Limits::machine();
        if let Some(v) = env_size(MAX_DECOMPRESSED_ENV)? {
            limits.max_decompressed = v;
            limits.ratio_limited = false;
        }
        if let Some(v) = env_size(MAX_MEMORY_ENV)? {
            limits.memory_budget = v;
        }
        Ok(limits)
    }
}

fn env_size(name: &str) -> Result<Option<u64>, String> {
    match std::env::var(name) {
        Ok(v) => parse_size(&v).map(Some).map_err(|e| format!("{name}: {e}")),
        Err(_) => Ok(None),
    }
}

/// The machine's memory (or a guess where it cannot be read), in bytes.
pub fn machine_total() -> u64 {
    machine_memory().unwrap_or(FALLBACK_MEMORY)
}

/// Total memory from /proc/meminfo (Linux), in bytes.
fn machine_memory() -> Option<u64> {
    let info = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = info.lines().find(|l| l.starts_with("MemTotal:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    kib.checked_mul(1024)
}

/// 0: not set yet (the environment's or the machine's limits on first use).
static MAX_DECOMPRESSED: AtomicU64 = AtomicU64::new(0);
static MEMORY_BUDGET: AtomicU64 = AtomicU64::new(0);
static RATIO_LIMITED: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(true);

/// Puts `limits` in force for the rest of the process.
pub fn set(limits: Limits) {
    MAX_DECOMPRESSED.store(limits.max_decompressed.max(1), Ordering::Relaxed);
    MEMORY_BUDGET.store(limits.memory_budget.max(1), Ordering::Relaxed);
    RATIO_LIMITED.store(limits.ratio_limited, Ordering::Relaxed);
}

/// The limits in force: those [`set`], else the environment's (a bad value
/// there falls back to the machine's; the CLI reports it before any read).
pub fn current() -> Limits {
    let (d, m) = (
        MAX_DECOMPRESSED.load(Ordering::Relaxed),
        MEMORY_BUDGET.load(Ordering::Relaxed),
    );
    if d != 0 && m != 0 {
        return Limits {
            max_decompressed: d,
            memory_budget: m,
            ratio_limited: RATIO_LIMITED.load(Ordering::Relaxed),
        };
    }
    let limits = Limits::from_env().unwrap_or_else(|_| Limits::machine());
    set(limits);
    limits
}

/// Refuses to reserve `bytes` for `what` (e.g. "4000000000 vertices") when
/// that is over the memory budget.
pub fn check_budget(what: &str, bytes: u64) -> Result<(), ParseError> {
    let budget = current().memory_budget;
    if bytes <= budget {
        return Ok(());
    }
    Err(ParseError::file(format!(
        "{what} would need about {} of memory, over the budget of {} \
         (raise it with --max-memory or {MAX_MEMORY_ENV})",
        format_size(bytes),
        format_size(budget)
    )))
}

/// `count` items of `each` bytes against the budget (overflow is over it).
pub fn check_items(what: &str, count: usize, each: usize) -> Result<(), ParseError> {
    let bytes = (count as u64).saturating_mul(each as u64);
    check_budget(&format!("{count} {what}"), bytes)
}

/// Parses a size: bytes, or a number with K, M, G or T (powers of 1024; an
/// optional `B` or `iB` after the letter), e.g. `512M`, `1.5G`, `8GiB`.
pub fn parse_size(text: &str) -> Result<u64, String> {
    let t = text.trim();
    let digits = t
        .find(|c: char| !(c.is_ascii_digit() || c == '.'))
        .unwrap_or(t.len());
    let (number, unit) = t.split_at(digits);
    let value: f64 = number
        .parse()
        .map_err(|_| format!("expected a size such as 512M or 8G, got {text:?}"))?;
    let unit = unit.trim().to_ascii_uppercase();
    let unit = unit
        .strip_suffix("IB")
        .or_else(|| unit.strip_suffix('B'))
        .unwrap_or(&unit);
    let scale: u64 = match unit {
        "" => 1,
        "K" => 1 << 10,
        "M" => 1 << 20,
        "G" => 1 << 30,
        "T" => 1 << 40,
        _ => return Err(format!("unknown size unit in {text:?} (use K, M, G or T)")),
    };
    let bytes = value * scale as f64;
    if !(bytes >= 1.0 && bytes < u64::MAX as f64) {
        return Err(format!(
            "expected a size of at least one byte, got {text:?}"
        ));
    }
    Ok(bytes as u64)
}

/// A size for messages, in the largest binary unit that keeps it ≥ 1.
pub fn format_size(bytes: u64) -> String {
    const UNITS: [&str; 5] = ["bytes", "KiB", "MiB", "GiB", "TiB"];
    let mut value = bytes as f64;
    let mut unit = 0;
    while value >= 1024.0 && unit + 1 < UNITS.len() {
        value /= 1024.0;
        unit += 1;
    }
    if unit == 0 {
        format!("{bytes} bytes")
    } else {
        format!("{value:.1} {}", UNITS[unit])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_parse_with_binary_units_and_bad_ones_are_errors() {
        assert_eq!(parse_size("1000"), Ok(1000));
        assert_eq!(parse_size("512M"), Ok(512 << 20));
        assert_eq!(parse_size("8G"), Ok(8 << 30));
        assert_eq!(parse_size("8GiB"), Ok(8 << 30));
        assert_eq!(parse_size("2kb"), Ok(2048));
        assert_eq!(parse_size("1.5G"), Ok(3 << 29));
        for bad in ["", "G", "-1", "0", "12X", "1e400", "nan"] {
            assert!(parse_size(bad).is_err(), "{bad:?}");
        }
        assert_eq!(format_size(512), "512 bytes");
        assert_eq!(format_size(3 << 29), "1.5 GiB");
    }

    #[test]
    fn the_machine_limits_leave_room_for_what_is_parsed() {
        let l = Limits::machine();
        assert!(l.max_decompressed > 0 && l.max_decompressed < l.memory_budget);
    }
}
