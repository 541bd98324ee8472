//! `export FOLDER|GLOB|--manifest M -o DIR`: one GLB per model, each built
//! by a child `lodstudio export FILE --recipe R` (so a crash, an abort or an
//! out-of-memory kill fails that model alone, and its peak memory is its
//! own), on workers within a memory budget, skipping what the output
//! folder's cache says is done, for the shard this process is.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::{Mutex, OnceLock};

use super::*;
use lodstudio_core::batch::{
    Cache, Entry, Lookup, Record, Shard, assign, cache, estimate_peak, run_within_budget, shard,
};

#[derive(Args, Debug)]
pub struct BatchArgs {
    /// Batch: run shard I of N (0-based) of the inputs, e.g. 2/8.
    #[arg(long, value_name = "I/N", value_parser = Shard::parse, conflicts_with = "shards")]
    shard: Option<Shard>,
    /// Batch: N shards, this one's index read from JOB_COMPLETION_INDEX (a
    /// Kubernetes Indexed Job) or the variable --shard-index-env names.
    #[arg(long, value_name = "N")]
    shards: Option<usize>,
    /// Batch: the variable holding the 0-based shard index with --shards
    /// (a Slurm array: SLURM_ARRAY_TASK_ID; a CI matrix: its index variable).
    #[arg(long, value_name = "VAR", default_value = shard::INDEX_ENV, requires = "shards")]
    shard_index_env: String,
    /// Batch: models built at once [default: the machine's cores].
    #[arg(long, value_name = "T")]
    threads: Option<usize>,
    /// Batch: memory the models running at once may use by their estimated
    /// peaks, e.g. 8G; a model that does not fit waits [default: half the
    /// machine's memory].
    #[arg(long, value_name = "SIZE", value_parser = io::limits::parse_size)]
    memory: Option<u64>,
}

impl BatchArgs {
    fn shard(&self) -> Result<Shard, CliError> {
        match (self.shard, self.shards) {
            (Some(s), _) => Ok(s),
            (None, Some(n)) => {
                Shard::from_env(&self.shard_index_env, n).map_err(CliError::BadInput)
            }
            (None, None) => Ok(Shard::ALL),
        }
    }
}

/// One model of the batch, planned.
struct Job {
    entry: Entry,
    output: String,
    recipe: Result<Recipe, String>,
    size: u64,
}

/// What became of one model.
enum Outcome {
    Built(serde_json::Value),
    Skipped(serde_json::Value),
    Failed { error: String, bad_input: bool },
}

/// Runs the batch: `Err` when it was refused before any model ran (bad
/// options, a clash of outputs), else the run's outcome (failed models).
pub fn run(
    args: &ExportArgs,
    recipe: &Recipe,
    entries: Vec<Entry>,
) -> Result<Result<(), CliError>, CliError> {
    let b = &args.shards;
    let shard = b.shard()?;
    let threads = b
        .threads
        .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
    if threads == 0 {
        return Err(CliError::BadInput("--threads must be at least 1".into()));
    }
    let budget = b
        .memory
        .unwrap_or_else(|| io::limits::current().memory_budget);
    let dir = &args.output;
    std::fs::create_dir_all(dir)
        .map_err(|e| CliError::BadInput(format!("{}: cannot create: {e}", dir.display())))?;
    let cache = Cache::open(dir).map_err(|e| {
        CliError::BadInput(format!("{}: cannot make its cache: {e}", dir.display()))
    })?;
    // Scratch files of killed runs; a live write is seconds old.
    cache.clean_scratch(std::time::Duration::from_secs(3600));
    let jobs = plan(recipe, entries)?;
    let sizes: Vec<u64> = jobs.iter().map(|j| j.size).collect();
    let shards = assign(&sizes, shard.count);
    let mut mine: Vec<&Job> = jobs
        .iter()
        .zip(&shards)
        .filter(|(_, s)| **s == shard.index)
        .map(|(j, _)| j)
        .collect();
    // Largest first: the long ones start early, the small ones fill in.
    mine.sort_by(|a, b| b.size.cmp(&a.size).then(a.entry.input.cmp(&b.entry.input)));
    let estimates: Vec<u64> = mine
        .iter()
        .map(|j| {
            let gz = j.entry.input.extension().is_some_and(|e| e == "gz");
            j.recipe
                .as_ref()
                .map_or(0, |r| estimate_peak(j.size, gz, r))
        })
        .collect();
    let report_path = dir.join(format!("report{}.jsonl", shard.suffix()));
    let report_file = std::fs::File::create(&report_path)
        .map_err(|e| CliError::BadInput(format!("{}: cannot write: {e}", report_path.display())))?;
    let lines = Mutex::new(report_file);
    let bar = indicatif::ProgressBar::new(mine.len() as u64).with_style(
        indicatif::ProgressStyle::with_template("{bar:30} {pos}/{len} {elapsed} {msg}")
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    // Each child gets its share of the cores (outputs do not depend on it).
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let child_threads = (cores / threads).max(1);
    let start = std::time::Instant::now();
    let outcomes = run_within_budget(&estimates, threads, budget, |i| {
        let job = mine[i];
        bar.set_message(job.output.clone());
        let t = std::time::Instant::now();
        let outcome = build(args, &cache, job, child_threads);
        let line = model_line(job, &outcome, t.elapsed().as_secs_f64());
        if let Ok(mut f) = lines.lock() {
            let _ = writeln!(f, "{line}");
        }
        bar.inc(1);
        (outcome, line)
    });
    bar.finish_and_clear();
    let seconds = start.elapsed().as_secs_f64();
    let count = |f: fn(&Outcome) -> bool| outcomes.iter().filter(|(o, _)| f(o)).count();
    let built = count(|o| matches!(o, Outcome::Built(_)));
    let skipped = count(|o| matches!(o, Outcome::Skipped(_)));
    let failed = count(|o| matches!(o, Outcome::Failed { .. }));
    let mut outputs: Vec<String> = mine
        .iter()
        .zip(&outcomes)
        .filter(|(_, (o, _))| !matches!(o, Outcome::Failed { .. }))
        .map(|(j, _)| dir.join(&j.output).display().to_string())
        .collect();
    outputs.sort();
    let failures: Vec<serde_json::Value> = mine
        .iter()
        .zip(&outcomes)
        .filter_map(|(j, (o, _))| match o {
            Outcome::Failed { error, .. } => Some(serde_json::json!({
                "file": j.entry.input.display().to_string(),
                "error": error,
            })),
            _ => None,
        })
        .collect();
    let reports: Vec<&serde_json::Value> = outcomes.iter().map(|(_, l)| l).collect();
    let summary = serde_json::json!({
        "models": mine.len(),
        "built": built,
        "skipped": skipped,
        "failed": failed,
        "outputs": outputs,
        "failures": failures,
        "reports": reports,
        "shard": format!("{}/{}", shard.index, shard.count),
        "inputs_in_all_shards": jobs.len(),
        "threads": threads,
        "memory_budget": budget,
        "seconds": seconds,
        "report": report_path.display().to_string(),
    });
    let summary_path = dir.join(format!("summary{}.json", shard.suffix()));
    let mut text = serde_json::to_vec_pretty(&summary).expect("a summary serializes");
    text.push(b'\n');
    io::write_atomic(&summary_path, &text).map_err(|e| {
        CliError::BadInput(format!("{}: cannot write: {e}", summary_path.display()))
    })?;
    if args.report.json {
        println!("{summary}");
    } else {
        for (_, line) in &outcomes {
            println!(
                "{:>8} {}{}",
                line["status"].as_str().unwrap_or_default(),
                line["input"].as_str().unwrap_or_default(),
                line["reason"]
                    .as_str()
                    .map_or(String::new(), |r| format!(" ({r})"))
            );
        }
        println!(
            "shard {}/{}: {} models: {built} built, {skipped} skipped, {failed} failed, in {seconds:.1} s; reports in {}",
            shard.index,
            shard.count,
            mine.len(),
            report_path.display()
        );
    }
    if failed == 0 {
        return Ok(Ok(()));
    }
    let first = &failures[0];
    // A child's error names its file already.
    let error = first["error"].as_str().unwrap_or_default();
    let file = first["file"].as_str().unwrap_or_default();
    let message = if error.starts_with(file) {
        format!("{failed} of {} models failed; first: {error}", mine.len())
    } else {
        format!(
            "{failed} of {} models failed; first: {file}: {error}",
            mine.len()
        )
    };
    let any_bad = outcomes.iter().any(|(o, _)| {
        matches!(
            o,
            Outcome::Failed {
                bad_input: true,
                ..
            }
        )
    });
    Ok(Err(if any_bad {
        CliError::BadInput(message)
    } else {
        CliError::Failure(message)
    }))
}

/// Every entry with its output name, recipe (overrides applied) and size;
/// two inputs that would write one output are refused before anything runs.
fn plan(recipe: &Recipe, entries: Vec<Entry>) -> Result<Vec<Job>, CliError> {
    let mut seen: std::collections::HashMap<String, PathBuf> = Default::default();
    let mut jobs = Vec::with_capacity(entries.len());
    for entry in entries {
        let output = entry.output_name();
        if let Some(other) = seen.insert(output.clone(), entry.input.clone()) {
            return Err(CliError::BadInput(format!(
                "{} and {} would both write {output}: rename one",
                other.display(),
                entry.input.display()
            )));
        }
        let recipe = entry_recipe(recipe, &entry);
        let size = cache::input_size(&entry.input);
        jobs.push(Job {
            entry,
            output,
            recipe,
            size,
        });
    }
    Ok(jobs)
}

/// The recipe of one entry: the batch's, or the manifest's overrides.
fn entry_recipe(recipe: &Recipe, entry: &Entry) -> Result<Recipe, String> {
    let mut r = match &entry.recipe {
        Some(path) => read_recipe(path).map_err(|e| e.message().to_string())?,
        None => recipe.clone(),
    };
    if let Some(lods) = &entry.lods {
        r.rows = parse_lods(lods, Some(r.rows[0].method))?;
        r.check().map_err(|e| format!("lods={lods}: {e}"))?;
    }
    Ok(r)
}

/// The tool's identity in cache keys: its version and the hash of its own
/// executable, so a rebuilt lodstudio never reuses another build's outputs.
fn tool_id() -> &'static str {
    static ID: OnceLock<String> = OnceLock::new();
    ID.get_or_init(|| {
        let exe = std::env::current_exe()
            .ok()
            .and_then(|p| std::fs::read(p).ok())
            .map_or_else(|| "unknown".into(), |b| cache::sha256_hex(&b));
        format!("lodstudio {} {exe}", env!("CARGO_PKG_VERSION"))
    })
}

/// Builds one model unless the cache has it: a child process writes the
/// chain to a scratch file in the cache, which is renamed into the folder.
fn build(args: &ExportArgs, cache: &Cache, job: &Job, child_threads: usize) -> Outcome {
    let bad = |error: String| Outcome::Failed {
        error,
        bad_input: true,
    };
    let recipe = match &job.recipe {
        Ok(r) => r,
        Err(e) => return bad(e.clone()),
    };
    let files = match cache::input_files(&job.entry.input) {
        Ok(f) => f,
        Err(e) => return bad(format!("{}: cannot read: {e}", job.entry.input.display())),
    };
    let recipe_bytes = recipe.to_json();
    let key = cache::key(&files, &recipe_bytes, tool_id());
    let dir = &args.output;
    let reason = match cache.lookup(&key, dir, &job.output) {
        Lookup::Hit(record) if !args.report.force => return Outcome::Skipped(record.report),
        Lookup::Hit(_) => "--force",
        Lookup::Miss(reason) => reason,
    };
    if dir.join(&job.output).exists() && !args.report.force && !cache.made(&job.output) {
        return bad(format!(
            "{} exists and was not made by a batch here (use --force to overwrite)",
            dir.join(&job.output).display()
        ));
    }
    // This job's own recipe file and scratch output: no other job or
    // machine shares them.
    let recipe_path = cache.scratch(&job.output, "json");
    if let Err(e) = io::write_atomic(&recipe_path, &recipe_bytes) {
        return Outcome::Failed {
            error: format!("{}: cannot write: {e}", recipe_path.display()),
            bad_input: false,
        };
    }
    let scratch = cache.scratch(&job.output, "glb");
    let child = run_child(&job.entry.input, &recipe_path, &scratch, child_threads);
    let _ = std::fs::remove_file(&recipe_path);
    let (mut report, peak) = match child {
        Ok(r) => r,
        Err(e) => {
            let _ = std::fs::remove_file(&scratch);
            return e;
        }
    };
    report["output"] = dir.join(&job.output).display().to_string().into();
    report["peak_memory_bytes"] = peak.into();
    report["reason"] = reason.into();
    // The record first, then the output: a kill between the two leaves a
    // record whose output is missing (rebuilt next time), never an output
    // without a record (which a rerun would take for the user's own file).
    let placed = std::fs::read(&scratch).and_then(|bytes| {
        let record = Record {
            key,
            output: job.output.clone(),
            output_sha256: cache::sha256_hex(&bytes),
            report: report.clone(),
        };
        cache.store(&record)?;
        std::fs::rename(&scratch, dir.join(&job.output))
    });
    if let Err(e) = placed {
        let _ = std::fs::remove_file(&scratch);
        return Outcome::Failed {
            error: format!("{}: cannot place the output: {e}", job.output),
            bad_input: false,
        };
    }
    Outcome::Built(report)
}

/// Runs `lodstudio export --recipe R -o OUT --force --json -- INPUT`; its
/// report and peak resident memory (bytes), or the failure it ended with.
fn run_child(
    input: &Path,
    recipe: &Path,
    out: &Path,
    threads: usize,
) -> Result<(serde_json::Value, u64), Outcome> {
    let exe = std::env::current_exe().map_err(|e| Outcome::Failed {
        error: format!("cannot find the lodstudio executable: {e}"),
        bad_input: false,
    })?;
    let mut cmd = Command::new(exe);
    cmd.arg("export")
        .arg("--recipe")
        .arg(recipe)
        .arg("-o")
        .arg(out)
        .args(["--force", "--json", "--"])
        .arg(input)
        .env("RAYON_NUM_THREADS", threads.to_string())
        .stdin(std::process::Stdio::null())
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped());
    let child = cmd.spawn().map_err(|e| Outcome::Failed {
        error: format!("cannot start a build: {e}"),
        bad_input: false,
    })?;
    let (output, peak) = wait_with_peak(child).map_err(|e| Outcome::Failed {
        error: format!("waiting for a build: {e}"),
        bad_input: false,
    })?;
    let stderr = String::from_utf8_lossy(&output.stderr);
    let message = stderr
        .lines()
        .last()
        .unwrap_or_default()
        .trim_start_matches("lodstudio: ")
        .to_string();
    match output.status.code() {
        Some(0) => serde_json::from_slice(&output.stdout)
            .map(|j| (j, peak))
            .map_err(|e| Outcome::Failed {
                error: format!("a build printed no report: {e}"),
                bad_input: false,
            }),
        Some(2) => Err(Outcome::Failed {
            error: message,
            bad_input: true,
        }),
        code => Err(Outcome::Failed {
            error: match code {
                Some(c) => format!("failed (exit {c}): {message}"),
                None => format!("killed by a signal: {message}"),
            },
            bad_input: false,
        }),
    }
}

/// Waits for a child, returning its output and its peak resident memory.
#[cfg(target_os = "linux")]
fn wait_with_peak(child: std::process::Child) -> std::io::Result<(std::process::Output, u64)> {
    let pid = child.id() as libc::pid_t;
    // Read the pipes on threads while this one waits with wait4 for the rusage.
    let mut child = child;
    let mut stdout = child.stdout.take().expect("piped");
    let mut stderr = child.stderr.take().expect("piped");
    let out = std::thread::spawn(move || {
        let mut b = Vec::new();
        let _ = std::io::Read::read_to_end(&mut stdout, &mut b);
        b
    });
    let err = std::thread::spawn(move || {
        let mut b = Vec::new();
        let _ = std::io::Read::read_to_end(&mut stderr, &mut b);
        b
    });
    let mut status: libc::c_int = 0;
    // SAFETY: rusage is plain data; wait4 fills it for our own child.
    let mut usage: libc::rusage = unsafe { std::mem::zeroed() };
    let r = unsafe { libc::wait4(pid, &mut status, 0, &mut usage) };
    if r < 0 {
        return Err(std::io::Error::last_os_error());
    }
    use std::os::unix::process::ExitStatusExt;
    let output = std::process::Output {
        status: std::process::ExitStatus::from_raw(status),
        stdout: out.join().unwrap_or_default(),
        stderr: err.join().unwrap_or_default(),
    };
    // ru_maxrss is in kilobytes on Linux.
    Ok((output, usage.ru_maxrss.max(0) as u64 * 1024))
}

#[cfg(not(target_os = "linux"))]
fn wait_with_peak(child: std::process::Child) -> std::io::Result<(std::process::Output, u64)> {
    Ok((child.wait_with_output()?, 0))
}

/// The report line of one model.
fn model_line(job: &Job, outcome: &Outcome, seconds: f64) -> serde_json::Value {
    let input = job.entry.input.display().to_string();
    match outcome {
        Outcome::Built(r) => serde_json::json!({
            "input": input, "status": "built", "cache_hit": false, "output": r["output"],
            "reason": r["reason"], "lods": r["lods"], "seconds": seconds,
            "peak_memory_bytes": r["peak_memory_bytes"], "bytes": r["bytes"],
            "input_triangles": r["input_triangles"],
        }),
        Outcome::Skipped(r) => serde_json::json!({
            "input": input, "status": "skipped", "cache_hit": true, "output": r["output"],
            "reason": "cached: the same input, recipe and lodstudio built it",
            "lods": r["lods"], "seconds": seconds, "bytes": r["bytes"],
            "input_triangles": r["input_triangles"],
        }),
        Outcome::Failed { error, .. } => serde_json::json!({
            "input": input, "status": "failed", "cache_hit": false, "error": error,
            "seconds": seconds,
        }),
    }
}
