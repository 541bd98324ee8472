//! `export FOLDER|GLOB|--manifest M -o DIR`: one GLB per model, each built
//! by a child `lodstudio export FILE --recipe R` (so a crash, an abort, an
//! out-of-memory kill or a `--timeout-per-model` kill fails that model
//! alone, and its peak memory is its own), on workers within a memory
//! budget, skipping what the output folder's cache says is done, for the
//! shard this process is.
//!
//! Untrusted input (DESIGN.md): every input, and every file a glTF names,
//! must lie in the asset root (`--asset-root`, else the manifest's folder,
//! the folder given, or a glob's leading folder); the children are confined
//! to the same root with the same limits. Outputs are plain names in the
//! output folder, and an output folder that holds an input is refused before
//! anything is written.
//!
//! Reports: `report[.shard-I-of-N].jsonl` is append-only. Each model's line
//! is appended whole (one `write` of the line and its newline, on a file
//! opened with O_APPEND, under an exclusive `flock`), so batches sharing a
//! folder never tear or lose each other's lines; a rerun adds its lines
//! after those of earlier runs, each line carrying `run` (the process
//! token) to tell runs apart. The summary holds this run's models alone.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::Mutex;
use std::time::Duration;

use super::*;
use crate::cli::shard::{ShardArgs, tool_id};
use lodstudio_core::batch::{
    Cache, Entry, Lookup, Record, assign, cache, estimate_peak, manifest, run_within_budget,
    schedule,
};
use lodstudio_core::io::confine::{self, Refused};

#[derive(Args, Debug)]
pub struct BatchArgs {
    #[command(flatten)]
    shard: ShardArgs,
    /// Batch: models built at once [default: the machine's cores].
    #[arg(long, value_name = "T")]
    threads: Option<usize>,
    /// Batch: memory the models running at once may use by their estimated
    /// peaks, e.g. 8G; a model that does not fit waits [default: half the
    /// machine's memory].
    #[arg(long, value_name = "SIZE", value_parser = io::limits::parse_size)]
    memory: Option<u64>,
    /// Batch: a model still building after this many seconds is stopped
    /// (its process killed) and reported failed with "timeout after S s";
    /// the others still run.
    #[arg(long, value_name = "SECONDS", value_parser = parse_timeout)]
    timeout_per_model: Option<f64>,
}

/// `--timeout-per-model`: seconds, finite and above zero.
fn parse_timeout(text: &str) -> Result<f64, String> {
    let bad = || format!("expected a number of seconds above 0, such as 600, got {text:?}");
    let seconds: f64 = text.trim().parse().map_err(|_| bad())?;
    if seconds > 0.0 && Duration::try_from_secs_f64(seconds).is_ok() {
        Ok(seconds)
    } else {
        Err(bad())
    }
}

/// One model of the batch, planned.
struct Job {
    entry: Entry,
    output: String,
    /// Its recipe, or why the manifest's overrides give none (bad input).
    recipe: Result<Recipe, CliError>,
    /// Why the input may not be read at all (a link out of the asset root,
    /// a special file, a glTF naming a file outside it): bad input, and
    /// nothing of it is read.
    refused: Option<String>,
    /// The canonical paths of the input and of the files it names.
    paths: Vec<PathBuf>,
    size: u64,
}

/// What became of one model.
enum Outcome {
    Built(serde_json::Value),
    Skipped(serde_json::Value),
    Failed { error: String, bad_input: bool },
}

/// What every child is started with besides its model.
struct ChildOptions<'a> {
    /// Rayon threads.
    threads: usize,
    /// `--timeout-per-model`.
    timeout: Option<f64>,
    /// The asset root (canonical) the child is confined to.
    root: &'a Path,
}

use crate::cli::outputs::io_error;

/// How a batch that ran ended.
#[derive(Debug)]
pub enum Ran {
    /// Every model of this shard was exported (or found in the cache).
    AllExported,
    /// Some failed: the error the command exits with.
    Failed(CliError),
}

impl Ran {
    pub fn into_result(self) -> Result<(), CliError> {
        match self {
            Ran::AllExported => Ok(()),
            Ran::Failed(e) => Err(e),
        }
    }
}

/// Runs the batch: `Err` when it was refused before any model ran (bad
/// options, a clash of outputs, an output folder holding inputs), else how
/// the run ended.
pub fn run(args: &ExportArgs, recipe: &Recipe, entries: Vec<Entry>) -> Result<Ran, CliError> {
    let b = &args.shards;
    let shard = b.shard.shard()?;
    let threads = b
        .threads
        .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
    if threads == 0 {
        return Err(CliError::BadInput("--threads must be at least 1".into()));
    }
    if recipe.layout == lodstudio_core::scene::Layout::Files {
        return Err(CliError::BadInput(
            "--layout files writes a file per level, a batch one file per model: use msft_lod or nodes".into(),
        ));
    }
    let budget = b
        .memory
        .unwrap_or_else(|| io::limits::current().memory_budget);
    // One root for the inputs, what they name, and every child.
    let root = batch_root(args)?;
    let policy = confine::current();
    confine::set(confine::Policy {
        asset_root: Some(root.clone()),
        allow_outside: policy.allow_outside,
    });
    let jobs = plan(recipe, entries)?;
    let dir = &args.output;
    let report_path = dir.join(format!("report{}.jsonl", shard.suffix()));
    let summary_path = dir.join(format!("summary{}.json", shard.suffix()));
    refuse_overwriting_inputs(args, &jobs, &[&report_path, &summary_path])?;
    if dir.metadata().is_ok_and(|m| !m.is_dir()) {
        return Err(CliError::BadInput(format!(
            "{}: is not a folder (a batch writes one GLB per model into a folder)",
            dir.display()
        )));
    }
    std::fs::create_dir_all(dir).map_err(|e| io_error(dir, "create", &e))?;
    let cache = Cache::open(dir).map_err(|e| io_error(dir, "make its cache", &e))?;
    // What killed runs left (never what a live run is writing).
    cache.clean(dir);
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
    let estimates: Vec<u64> = mine.iter().map(|j| estimate(j)).collect();
    let report_file = std::fs::OpenOptions::new()
        .append(true)
        .create(true)
        .open(&report_path)
        .map_err(|e| io_error(&report_path, "write", &e))?;
    let lines = Mutex::new(report_file);
    let report_error: Mutex<Option<String>> = Mutex::new(None);
    let bar = indicatif::ProgressBar::new(mine.len() as u64).with_style(
        indicatif::ProgressStyle::with_template("{bar:30} {pos}/{len} {elapsed} {msg}")
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    // Each child gets its share of the cores (outputs do not depend on it).
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let child = ChildOptions {
        threads: (cores / threads).max(1),
        timeout: b.timeout_per_model,
        root: &root,
    };
    let start = std::time::Instant::now();
    let outcomes = run_within_budget(&estimates, threads, budget, |i| {
        let job = mine[i];
        bar.set_message(job.output.clone());
        let t = std::time::Instant::now();
        let outcome = build(args, &cache, job, &child);
        let line = model_line(job, &outcome, t.elapsed().as_secs_f64(), estimates[i]);
        if let Err(e) = append_line(&lines, &line) {
            let mut first = report_error.lock().unwrap_or_else(|e| e.into_inner());
            first.get_or_insert_with(|| {
                format!("{}: cannot add a report line: {e}", report_path.display())
            });
        }
        bar.inc(1);
        (outcome, line)
    });
    bar.finish_and_clear();
    let report_error = report_error.into_inner().unwrap_or_else(|e| e.into_inner());
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
        "timeout_per_model": b.timeout_per_model,
        "asset_root": root.display().to_string(),
        "seconds": seconds,
        "report": report_path.display().to_string(),
        "report_error": report_error,
        "run": io::process_token(),
    });
    let mut text = serde_json::to_vec_pretty(&summary).expect("a summary serializes");
    text.push(b'\n');
    io::write_atomic(&summary_path, &text).map_err(|e| io_error(&summary_path, "write", &e))?;
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
                    .or(line["error"].as_str())
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
    if failed == 0 && report_error.is_none() {
        return Ok(Ran::AllExported);
    }
    let mut message = String::new();
    if let Some(first) = failures.first() {
        // A child's error names its file already.
        let error = first["error"].as_str().unwrap_or_default();
        let file = first["file"].as_str().unwrap_or_default();
        message = if error.starts_with(file) {
            format!("{failed} of {} models failed; first: {error}", mine.len())
        } else {
            format!(
                "{failed} of {} models failed; first: {file}: {error}",
                mine.len()
            )
        };
    }
    if let Some(e) = &report_error {
        message = if message.is_empty() {
            e.clone()
        } else {
            format!("{message}; {e}")
        };
    }
    let any_bad = outcomes.iter().any(|(o, _)| {
        matches!(
            o,
            Outcome::Failed {
                bad_input: true,
                ..
            }
        )
    });
    Ok(Ran::Failed(if any_bad {
        CliError::BadInput(message)
    } else {
        CliError::Failure(message)
    }))
}

/// The folder the batch's inputs (and what they name) must lie in, canonical:
/// `--asset-root`, else the manifest's folder, the folder given, or the
/// leading folder of a glob.
fn batch_root(args: &ExportArgs) -> Result<PathBuf, CliError> {
    let folder = match (&args.manifest, &args.file) {
        (Some(m), _) => m
            .parent()
            .filter(|p| !p.as_os_str().is_empty())
            .map_or_else(|| PathBuf::from("."), Path::to_path_buf),
        (None, Some(f)) => manifest::folder_of(f),
        (None, None) => PathBuf::from("."),
    };
    Ok(confine::root_for(&folder)?)
}

/// Refuses, before anything is written, an output folder that holds an
/// input or a file one names (`export DIR -o DIR --force` would replace the
/// models with their LODs), and a file the batch writes (its report, its
/// summary, an output, its cache) that is the manifest or a recipe it reads.
fn refuse_overwriting_inputs(
    args: &ExportArgs,
    jobs: &[Job],
    written: &[&Path],
) -> Result<(), CliError> {
    // A folder that is not there yet holds nothing.
    let Ok(out) = args.output.canonicalize() else {
        return Ok(());
    };
    for job in jobs {
        if let Some(p) = job.paths.iter().find(|p| p.starts_with(&out)) {
            let what = if *p == job.paths[0] {
                format!("{}", job.entry.input.display())
            } else {
                format!("{} (named by {})", p.display(), job.entry.input.display())
            };
            return Err(CliError::BadInput(format!(
                "{what}: is inside the output folder {}: the batch would write over its inputs (choose another -o)",
                args.output.display()
            )));
        }
    }
    let mut writes: Vec<PathBuf> = written
        .iter()
        .filter_map(|p| p.file_name().map(|n| out.join(n)))
        .collect();
    writes.extend(jobs.iter().map(|j| out.join(&j.output)));
    let cache_dir = out.join(cache::DIR_NAME);
    let read = args
        .manifest
        .iter()
        .chain(&args.recipe)
        .chain(jobs.iter().filter_map(|j| j.entry.recipe.as_ref()));
    for path in read {
        let Ok(c) = path.canonicalize() else {
            continue;
        };
        if writes.contains(&c) || c.starts_with(&cache_dir) {
            return Err(CliError::BadInput(format!(
                "{}: is read by the batch and would be written by it in {} (move it or choose another -o)",
                path.display(),
                args.output.display()
            )));
        }
    }
    Ok(())
}

/// Every entry with its output name, recipe (overrides applied), what it
/// is made of and its size; an output name that is no plain file name, and
/// two inputs that would write one output, are refused before anything runs.
fn plan(recipe: &Recipe, entries: Vec<Entry>) -> Result<Vec<Job>, CliError> {
    let mut seen: std::collections::HashMap<String, PathBuf> = Default::default();
    let mut jobs = Vec::with_capacity(entries.len());
    for entry in entries {
        let output = entry.output_name().map_err(CliError::BadInput)?;
        if let Some(other) = seen.insert(output.clone(), entry.input.clone()) {
            return Err(CliError::BadInput(format!(
                "{} and {} would both write {output}: rename one",
                other.display(),
                entry.input.display()
            )));
        }
        let recipe = entry_recipe(recipe, &entry);
        let missing = entry
            .input
            .symlink_metadata()
            .is_err_and(|e| e.kind() == std::io::ErrorKind::NotFound);
        // A missing input fails alone when built (it cannot be read);
        // anything else must be a regular file inside the root.
        let (refused, paths) = if missing {
            (None, Vec::new())
        } else {
            match confine::resolve_path(Path::new("."), &entry.input, "input") {
                Err(e) => (Some(e.message().to_string()), Vec::new()),
                Ok(own) => match cache::named_files(&entry.input) {
                    Ok(named) => (None, std::iter::once(own).chain(named).collect()),
                    Err(e) => (Some(e.message().to_string()), vec![own]),
                },
            }
        };
        let size = cache::size_with(&entry.input, paths.get(1..).unwrap_or_default());
        jobs.push(Job {
            entry,
            output,
            recipe,
            refused,
            paths,
            size,
        });
    }
    Ok(jobs)
}

/// A job's estimated peak memory: what its input parses to (a gzip file's
/// inflated size, measured) with the files it names, by the recipe.
fn estimate(job: &Job) -> u64 {
    let Ok(recipe) = &job.recipe else {
        return 0;
    };
    if job.refused.is_some() {
        return 0;
    }
    let own = std::fs::metadata(&job.entry.input).map_or(0, |m| m.len());
    let parsed = schedule::parsed_size(&job.entry.input, io::decompression_cap(own));
    estimate_peak(job.size.saturating_sub(own).saturating_add(parsed), recipe)
}

/// Appends one report line whole: a single `write` of the line and its
/// newline on the O_APPEND file, under an exclusive `flock` (other
/// batches on the folder; on NFS, where O_APPEND is not atomic between
/// machines, the lock is what keeps lines whole).
fn append_line(file: &Mutex<std::fs::File>, line: &serde_json::Value) -> std::io::Result<()> {
    let mut buf = serde_json::to_vec(line).expect("a report line serializes");
    buf.push(b'\n');
    let file = file.lock().unwrap_or_else(|e| e.into_inner());
    let _locked = FileLock::exclusive(&file);
    let written = loop {
        match (&*file).write(&buf) {
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
            r => break r?,
        }
    };
    if written != buf.len() {
        return Err(std::io::Error::new(
            std::io::ErrorKind::WriteZero,
            format!(
                "{written} of {} bytes written (is the disk full?)",
                buf.len()
            ),
        ));
    }
    Ok(())
}

/// An exclusive `flock` on a file, released when dropped (none where
/// locking fails: O_APPEND alone then).
struct FileLock<'a>(#[allow(dead_code)] &'a std::fs::File);

impl<'a> FileLock<'a> {
    #[cfg(target_os = "linux")]
    fn exclusive(file: &'a std::fs::File) -> Option<FileLock<'a>> {
        use std::os::fd::AsRawFd;
        // SAFETY: flock on a descriptor that outlives the guard.
        (unsafe { libc::flock(file.as_raw_fd(), libc::LOCK_EX) } == 0).then_some(FileLock(file))
    }

    #[cfg(not(target_os = "linux"))]
    fn exclusive(_file: &'a std::fs::File) -> Option<FileLock<'a>> {
        None
    }
}

#[cfg(target_os = "linux")]
impl Drop for FileLock<'_> {
    fn drop(&mut self) {
        use std::os::fd::AsRawFd;
        // SAFETY: unlocks what `exclusive` locked.
        unsafe { libc::flock(self.0.as_raw_fd(), libc::LOCK_UN) };
    }
}

/// The recipe of one entry: the batch's, or the manifest's overrides.
fn entry_recipe(recipe: &Recipe, entry: &Entry) -> Result<Recipe, CliError> {
    let mut r = match &entry.recipe {
        Some(path) => read_recipe(path)?,
        None => recipe.clone(),
    };
    if let Some(lods) = &entry.lods {
        r.rows = parse_lods(lods, Some(r.rows[0].method)).map_err(CliError::BadInput)?;
        r.check()
            .map_err(|e| CliError::BadInput(format!("lods={lods}: {e}")))?;
    }
    Ok(r)
}

/// Removes a folder when dropped (a build's scratch, whatever became of it).
struct RemoveDir(PathBuf);

impl Drop for RemoveDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// Builds one model unless the cache has it: a child process writes the
/// chain to this build's scratch folder in the cache, from which it is
/// renamed into the output folder.
fn build(args: &ExportArgs, cache: &Cache, job: &Job, child: &ChildOptions) -> Outcome {
    let bad = |error: String| Outcome::Failed {
        error,
        bad_input: true,
    };
    let failure = |error: String| Outcome::Failed {
        error,
        bad_input: false,
    };
    let recipe = match &job.recipe {
        Ok(r) => r,
        Err(e) => return bad(e.message().to_string()),
    };
    if let Some(e) = &job.refused {
        return bad(e.clone());
    }
    let files = match cache::input_files(&job.entry.input) {
        Ok(f) => f,
        Err(Refused::Input(e)) => return bad(e),
        Err(Refused::Io(e)) => return failure(e),
    };
    let recipe_bytes = recipe.to_json();
    let key = cache::key(&files, &recipe_bytes, tool_id());
    drop(files);
    let dir = &args.output;
    let reason = match cache.lookup(&key, dir, &job.output) {
        Lookup::Hit(record) if !args.report.force => return Outcome::Skipped(record.report),
        Lookup::Hit(_) => "--force",
        Lookup::Miss(reason) => reason,
    };
    // Whether a batch made the file there is asked now (a concurrent
    // batch's output counts), by the records named after it.
    if dir.join(&job.output).exists() && !args.report.force && !cache.made(&job.output) {
        return bad(format!(
            "{} exists and was not made by a batch here (use --force to overwrite)",
            dir.join(&job.output).display()
        ));
    }
    // This build's own folder: no other job or machine shares it, and it
    // is removed however the build ends.
    let scratch_dir = match cache.scratch_dir(&job.output) {
        Ok(d) => d,
        Err(e) => return failure(format!("{}: cannot make a scratch folder: {e}", job.output)),
    };
    let _scratch = RemoveDir(scratch_dir.clone());
    let recipe_path = scratch_dir.join("recipe.json");
    if let Err(e) = io::write_atomic(&recipe_path, &recipe_bytes) {
        return failure(format!("{}: cannot write: {e}", recipe_path.display()));
    }
    let scratch = scratch_dir.join("model.glb");
    let (mut report, peak) = match run_child(&job.entry.input, &recipe_path, &scratch, child) {
        Ok(r) => r,
        Err(e) => return e,
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
        return failure(format!("{}: cannot place the output: {e}", job.output));
    }
    Outcome::Built(report)
}

/// Runs `lodstudio export --recipe R -o OUT --force --json --asset-root
/// ROOT [--allow-outside-uris] --max-memory M [--max-decompressed D] --
/// INPUT`: the child is confined as this process is. Its report and peak
/// resident memory (bytes), or the failure it ended with.
fn run_child(
    input: &Path,
    recipe: &Path,
    out: &Path,
    options: &ChildOptions,
) -> Result<(serde_json::Value, u64), Outcome> {
    let exe = std::env::current_exe().map_err(|e| Outcome::Failed {
        error: format!("cannot find the lodstudio executable: {e}"),
        bad_input: false,
    })?;
    let limits = io::limits::current();
    let mut cmd = Command::new(exe);
    cmd.arg("export")
        .arg("--recipe")
        .arg(recipe)
        .arg("-o")
        .arg(out)
        .args(["--force", "--json"])
        .arg("--asset-root")
        .arg(options.root);
    // Never wider than this run's own command line made it.
    if confine::current().allow_outside {
        cmd.arg("--allow-outside-uris");
    }
    cmd.arg("--max-memory")
        .arg(limits.memory_budget.to_string());
    // A cap the user named (else the child derives the same one, with
    // its ratio rule, as this process did).
    if !limits.ratio_limited {
        cmd.arg("--max-decompressed")
            .arg(limits.max_decompressed.to_string());
    }
    cmd.arg("--")
        .arg(input)
        .env("RAYON_NUM_THREADS", options.threads.to_string())
        .stdin(std::process::Stdio::null())
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped());
    let child = cmd.spawn().map_err(|e| Outcome::Failed {
        error: format!("cannot start a build: {e}"),
        bad_input: false,
    })?;
    let timeout = options.timeout.map(Duration::from_secs_f64);
    let (output, peak, timed_out) =
        wait_with_peak(child, timeout).map_err(|e| Outcome::Failed {
            error: format!("waiting for a build: {e}"),
            bad_input: false,
        })?;
    if timed_out {
        return Err(Outcome::Failed {
            error: format!("timeout after {} s", options.timeout.unwrap_or_default()),
            bad_input: false,
        });
    }
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

/// The pipes of a child read on threads, so it never blocks on a full one.
type Pipes = (
    std::thread::JoinHandle<Vec<u8>>,
    std::thread::JoinHandle<Vec<u8>>,
);

fn read_pipes(child: &mut std::process::Child) -> Pipes {
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
    (out, err)
}

/// Waits for a child, killing it (SIGKILL) once it has run `timeout`;
/// returns its output, its peak resident memory, and whether it was killed
/// for the timeout.
#[cfg(target_os = "linux")]
fn wait_with_peak(
    mut child: std::process::Child,
    timeout: Option<Duration>,
) -> std::io::Result<(std::process::Output, u64, bool)> {
    let pid = child.id() as libc::pid_t;
    let (out, err) = read_pipes(&mut child);
    let start = std::time::Instant::now();
    let mut status: libc::c_int = 0;
    // SAFETY: rusage is plain data; wait4 fills it for our own child.
    let mut usage: libc::rusage = unsafe { std::mem::zeroed() };
    let mut timed_out = false;
    let mut pause = Duration::from_millis(1);
    loop {
        // With a timeout, poll (WNOHANG) until it passes; the child is not
        // reaped before wait4 returns it, so its pid is never another's.
        let flags = if timeout.is_some() && !timed_out {
            libc::WNOHANG
        } else {
            0
        };
        // SAFETY: as above.
        let r = unsafe { libc::wait4(pid, &mut status, flags, &mut usage) };
        if r == pid {
            break;
        }
        if r < 0 {
            let e = std::io::Error::last_os_error();
            if e.kind() == std::io::ErrorKind::Interrupted {
                continue;
            }
            return Err(e);
        }
        if timeout.is_some_and(|t| start.elapsed() >= t) {
            // SAFETY: our own child, not yet reaped.
            unsafe { libc::kill(pid, libc::SIGKILL) };
            timed_out = true;
            continue;
        }
        std::thread::sleep(pause);
        pause = (pause * 2).min(Duration::from_millis(50));
    }
    use std::os::unix::process::ExitStatusExt;
    let output = std::process::Output {
        status: std::process::ExitStatus::from_raw(status),
        stdout: out.join().unwrap_or_default(),
        stderr: err.join().unwrap_or_default(),
    };
    // ru_maxrss is in kilobytes on Linux.
    Ok((output, usage.ru_maxrss.max(0) as u64 * 1024, timed_out))
}

#[cfg(not(target_os = "linux"))]
fn wait_with_peak(
    mut child: std::process::Child,
    timeout: Option<Duration>,
) -> std::io::Result<(std::process::Output, u64, bool)> {
    let (out, err) = read_pipes(&mut child);
    let start = std::time::Instant::now();
    let mut timed_out = false;
    let status = loop {
        if let Some(status) = child.try_wait()? {
            break status;
        }
        if !timed_out && timeout.is_some_and(|t| start.elapsed() >= t) {
            child.kill()?;
            timed_out = true;
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    let output = std::process::Output {
        status,
        stdout: out.join().unwrap_or_default(),
        stderr: err.join().unwrap_or_default(),
    };
    Ok((output, 0, timed_out))
}

/// The report line of one model.
fn model_line(job: &Job, outcome: &Outcome, seconds: f64, estimate: u64) -> serde_json::Value {
    let input = job.entry.input.display().to_string();
    let run = io::process_token();
    match outcome {
        Outcome::Built(r) => serde_json::json!({
            "input": input, "status": "built", "cache_hit": false, "output": r["output"],
            "reason": r["reason"], "lods": r["lods"], "seconds": seconds,
            "peak_memory_bytes": r["peak_memory_bytes"], "bytes": r["bytes"],
            "input_triangles": r["input_triangles"], "estimated_peak_bytes": estimate,
            "run": run,
        }),
        Outcome::Skipped(r) => serde_json::json!({
            "input": input, "status": "skipped", "cache_hit": true, "output": r["output"],
            "reason": "cached: the same input, recipe and lodstudio built it",
            "lods": r["lods"], "seconds": seconds, "bytes": r["bytes"],
            "input_triangles": r["input_triangles"], "estimated_peak_bytes": estimate,
            "run": run,
        }),
        Outcome::Failed { error, .. } => serde_json::json!({
            "input": input, "status": "failed", "cache_hit": false, "error": error,
            "seconds": seconds, "estimated_peak_bytes": estimate, "run": run,
        }),
    }
}
