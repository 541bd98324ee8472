//! The content-addressed cache of a batch, kept in the output folder (so a
//! shared volume shares it between machines). An output's key hashes the
//! bytes of its input and of the files the input names (a glTF's buffers
//! and images), the recipe it was built with and the tool; a record per key
//! says which output it made and the output's own hash. A rerun skips an
//! output whose record matches and whose file is unchanged; anything else is
//! rebuilt, with the reason. A file's time stamp is not content: touching an
//! input without changing it rebuilds nothing.
//!
//! # Untrusted inputs
//!
//! What a glTF names is resolved through the asset-root policy
//! ([`crate::io::confine`]): a reference out of the root fails that model as
//! bad input and is never read or hashed. Every file is read as a regular
//! file within the memory budget (a FIFO or a device never blocks or fills
//! memory).
//!
//! # Layout
//!
//! ```text
//! DIR/.lodstudio-cache/
//!   records/OUTPUT/KEY.json   what KEY made of DIR/OUTPUT
//!   tmp/TOKEN/OUTPUT/         a build's scratch (the recipe, the child's GLB)
//!   locks/TOKEN.lock          held (flock) by the batch process TOKEN while it lives
//! ```
//!
//! Records are found by their output's name, so "was DIR/OUTPUT made by a
//! batch here?" is answered when it is asked, by whether any record of
//! OUTPUT exists (whatever its key, damaged or not). Two batches with
//! different recipes on one folder, started together, thus never refuse
//! each other's outputs, and a damaged record (cut short, edited) is a miss
//! with the reason `cache record damaged`, rebuilt and rewritten, never a
//! refusal that every rerun repeats. Records of the first layout
//! (`HASH.json` beside `records/`) still count as made (read once when the
//! cache opens: nothing writes them any more).
//!
//! # Temporaries of killed runs
//!
//! A run killed at any moment leaves temporaries: its scratch folder
//! `tmp/TOKEN/`, and the hidden `.NAME.tmpTOKEN-N` files of
//! [`crate::io::write_temporary`] in the output folder (the summary), the
//! cache folder and the records. TOKEN is [`crate::io::process_token`]:
//! the process id and 64 random bits, so it names one process however pids
//! repeat (pid 1 in every container of a job on one shared volume).
//! [`Cache::clean`], called as a run starts, removes them, and never a live
//! run's:
//!
//! - each batch process holds an exclusive `flock` on `locks/TOKEN.lock`
//!   from [`Cache::open`] until its cache is dropped; the kernel releases it
//!   when the process ends, however it ends (SIGKILL, the OOM killer, a node
//!   lost), and the build processes it starts inherit it (a child left
//!   running by a killed batch keeps its scratch alive until it exits);
//! - a cleaner removes TOKEN's temporaries only while it holds TOKEN's lock
//!   itself, which it can take only when no process holding it is alive;
//!   TOKEN is never reused, so no new temporary of TOKEN can appear after
//!   that. It then removes the lock file, still holding it;
//! - the owner takes its lock before it makes any temporary, and checks
//!   after locking that the path still names the file it locked (a cleaner
//!   may have locked and removed a fresh lock file before its owner locked
//!   it), starting again if not;
//! - a temporary with no lock file (a single `export` writing into the
//!   folder, a file system without `flock`, an older lodstudio) is removed
//!   only once it is an hour old, as any temporary is written in seconds.
//!
//! On Linux over NFS, `flock` is carried out with POSIX byte-range locks,
//! which the server arbitrates between machines; where locking fails
//! (ENOLCK), the owner removes its lock file and its temporaries fall under
//! the hour rule.

use std::collections::{BTreeMap, HashSet};
use std::io::Read;
use std::path::{Component, Path, PathBuf};
use std::sync::{Arc, Mutex, Weak};

use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};

use super::manifest::check_file_name;
use crate::io::confine::{self, Refused};

/// The cache's folder inside the output folder.
pub const DIR_NAME: &str = ".lodstudio-cache";

const RECORDS: &str = "records";
const TMP: &str = "tmp";
const LOCKS: &str = "locks";
/// A record is a small JSON file; a larger one is damaged.
const RECORD_LIMIT: u64 = 16 << 20;
/// A temporary with no owner to ask is left alone this long.
const UNOWNED_AGE: std::time::Duration = std::time::Duration::from_secs(3600);

/// Hex SHA-256 of `bytes`.
pub fn sha256_hex(bytes: &[u8]) -> String {
    hex(&Sha256::digest(bytes))
}

fn hex(digest: &[u8]) -> String {
    digest.iter().map(|b| format!("{b:02x}")).collect()
}

/// `e` with `input` named first.
fn naming(input: &Path, e: Refused) -> Refused {
    let at = |m: String| {
        if m.starts_with(&input.display().to_string()) {
            m
        } else {
            format!("{}: {m}", input.display())
        }
    };
    match e {
        Refused::Input(m) => Refused::Input(at(m)),
        Refused::Io(m) => Refused::Io(at(m)),
    }
}

/// The files a model file names, resolved through the asset-root policy
/// (canonical): a glTF's buffers and images (a gzipped one's, inflated
/// within the decompression cap); none for other formats, or for a document
/// that does not parse (it fails when loaded). `bytes`: the file's content.
fn named_in(input: &Path, bytes: &[u8]) -> Result<Vec<PathBuf>, Refused> {
    let ext = crate::io::extension(input);
    if ext != "gltf" && ext != "glb" {
        return Ok(Vec::new());
    }
    let inflated;
    let mut data = bytes;
    if crate::io::is_gzip(data) {
        match crate::io::gunzip(data, u64::MAX) {
            Ok(d) => inflated = d,
            Err(_) => return Ok(Vec::new()),
        }
        data = &inflated;
    }
    crate::io::gltf::referenced_files(input, data).map_err(|e| naming(input, e))
}

/// The files an input is made of: itself (canonical), then what it names
/// (a glTF's buffers and images), each read as a regular file within the
/// memory budget. A reference the asset-root policy refuses is an error
/// (bad input) and nothing it names is read.
pub fn input_files(input: &Path) -> Result<Vec<(PathBuf, Vec<u8>)>, Refused> {
    let budget = crate::io::limits::current().memory_budget;
    let bytes = confine::read_regular(input, budget).map_err(|e| naming(input, e))?;
    let named = named_in(input, &bytes)?;
    let own = input.canonicalize().unwrap_or_else(|_| input.to_path_buf());
    let mut files = vec![(own, bytes)];
    for path in named {
        let b = confine::read_regular(&path, budget).map_err(|e| naming(input, e))?;
        files.push((path, b));
    }
    Ok(files)
}

/// The files a `.gltf` names, for sharding and planning (other formats:
/// none, so a large GLB is not read): resolved through the asset-root
/// policy, which may refuse one.
pub fn named_files(input: &Path) -> Result<Vec<PathBuf>, Refused> {
    if crate::io::extension(input) != "gltf" {
        return Ok(Vec::new());
    }
    let budget = crate::io::limits::current().memory_budget;
    let bytes = confine::read_regular(input, budget).map_err(|e| naming(input, e))?;
    named_in(input, &bytes)
}

/// An input's size for sharding, from file metadata: itself and, for a
/// `.gltf`, the files its JSON names (through the policy; a refused one
/// counts nothing, as the model fails). 0 for a file that cannot be listed
/// (it fails when built, on whichever shard has it).
pub fn input_size(input: &Path) -> u64 {
    size_with(input, &named_files(input).unwrap_or_default())
}

/// `input`'s length and those of `named`, from metadata.
pub fn size_with(input: &Path, named: &[PathBuf]) -> u64 {
    let len = |p: &Path| std::fs::metadata(p).map_or(0, |m| m.len());
    len(input) + named.iter().map(|p| len(p)).sum::<u64>()
}

/// `path` relative to `base` (both canonical), climbing with `..` where
/// needed: the same on every machine whatever the volume's mount point.
fn relative(path: &Path, base: &Path) -> PathBuf {
    let p: Vec<Component> = path.components().collect();
    let b: Vec<Component> = base.components().collect();
    let common = p.iter().zip(&b).take_while(|(x, y)| x == y).count();
    let mut out = PathBuf::new();
    for _ in common..b.len() {
        out.push("..");
    }
    for c in &p[common..] {
        out.push(c);
    }
    out
}

/// The key of an output: the input files' names (relative to the input's
/// folder) and bytes, the recipe's bytes and the tool's identity.
pub fn key(files: &[(PathBuf, Vec<u8>)], recipe: &[u8], tool: &str) -> String {
    let mut h = Sha256::new();
    let mut field = |bytes: &[u8]| {
        h.update((bytes.len() as u64).to_le_bytes());
        h.update(bytes);
    };
    field(b"lodstudio-batch-key 2");
    field(tool.as_bytes());
    field(recipe);
    let base = files.first().and_then(|(p, _)| p.parent());
    for (i, (path, bytes)) in files.iter().enumerate() {
        // The input's own name does not matter; what it names does.
        let name = match (i, base) {
            (0, _) => String::new(),
            (_, Some(b)) => relative(path, b).to_string_lossy().into(),
            _ => path.to_string_lossy().into(),
        };
        field(name.as_bytes());
        field(bytes);
    }
    hex(&h.finalize())
}

/// [`key`] of an input read as a stream (with the files a `.gltf` names),
/// each file standing in by its SHA-256: for inputs too large to hold.
pub fn streamed_key(input: &Path, recipe: &[u8], tool: &str) -> std::io::Result<String> {
    let named = named_files(input).map_err(|e| std::io::Error::other(e.to_string()))?;
    let files = std::iter::once(input.to_path_buf())
        .chain(named)
        .map(|p| Ok((p.clone(), hash_file(&p)?.into_bytes())))
        .collect::<std::io::Result<Vec<_>>>()?;
    Ok(key(&files, recipe, tool))
}

/// What the cache knows of one output.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Record {
    pub key: String,
    /// The output's file name in the output folder.
    pub output: String,
    /// SHA-256 of the output's bytes as written.
    pub output_sha256: String,
    /// The model's report when it was built (counts, bounds).
    pub report: serde_json::Value,
}

/// Whether an output can be skipped.
#[derive(Debug, Clone, PartialEq)]
pub enum Lookup {
    /// Built before from the same content: skip, with its record.
    Hit(Box<Record>),
    /// Build it, for this reason.
    Miss(&'static str),
}

/// The cache of one output folder.
#[derive(Debug, Clone)]
pub struct Cache {
    dir: PathBuf,
    /// Outputs named by records of the first layout (module doc).
    legacy_made: HashSet<String>,
    /// This process's hold on its temporaries (module doc).
    claim: Arc<Claim>,
}

impl Cache {
    /// The cache of `out_dir` (made if missing), held by this process
    /// until it is dropped (module doc).
    pub fn open(out_dir: &Path) -> std::io::Result<Cache> {
        let dir = out_dir.join(DIR_NAME);
        for sub in [RECORDS, TMP, LOCKS] {
            std::fs::create_dir_all(dir.join(sub))?;
        }
        let legacy_made = std::fs::read_dir(&dir)?
            .filter_map(Result::ok)
            .filter(|e| e.path().extension().is_some_and(|x| x == "json"))
            .filter_map(|e| confine::read_regular(&e.path(), RECORD_LIMIT).ok())
            .filter_map(|b| serde_json::from_slice::<Record>(&b).ok())
            .map(|r| r.output)
            .collect();
        let claim = Claim::take(&dir)?;
        Ok(Cache {
            dir,
            legacy_made,
            claim,
        })
    }

    /// Where the records of `output` are (`None`: not a plain file name).
    fn record_dir(&self, output: &str) -> Option<PathBuf> {
        check_file_name(output).ok()?;
        Some(self.dir.join(RECORDS).join(output))
    }

    /// A record per key and output: two inputs with the same bytes (copies
    /// under two names) make two outputs, each with its record.
    fn record_path(&self, key: &str, output: &str) -> Option<PathBuf> {
        let plain_key = !key.is_empty() && key.bytes().all(|b| b.is_ascii_hexdigit());
        plain_key
            .then(|| self.record_dir(output))?
            .map(|d| d.join(format!("{key}.json")))
    }

    /// Whether `output` (in `out_dir`) is already what `key` makes.
    pub fn lookup(&self, key: &str, out_dir: &Path, output: &str) -> Lookup {
        let Some(path) = self.record_path(key, output) else {
            return Lookup::Miss("new");
        };
        // None: no record; Some(None): one that cannot be read as this key's.
        let record: Option<Option<Record>> = match path.symlink_metadata() {
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => None,
            _ => Some(
                confine::read_regular(&path, RECORD_LIMIT)
                    .ok()
                    .and_then(|b| serde_json::from_slice::<Record>(&b).ok())
                    .filter(|r| r.key == key && r.output == output),
            ),
        };
        let out = out_dir.join(output);
        match record {
            Some(None) => Lookup::Miss("cache record damaged"),
            None if out.exists() => Lookup::Miss("input, recipe or lodstudio changed"),
            None => Lookup::Miss("new"),
            Some(Some(r)) => match hash_file(&out) {
                Err(_) => Lookup::Miss("output missing"),
                Ok(h) if h == r.output_sha256 => Lookup::Hit(Box::new(r)),
                Ok(_) => Lookup::Miss("output changed since it was cached"),
            },
        }
    }

    /// Whether a batch here made `output`: any record of it exists now
    /// (whatever its key, even a damaged one), so an existing file there is
    /// a batch's own, not the user's. Asked at the time of the check, so
    /// a concurrent batch's new outputs count.
    pub fn made(&self, output: &str) -> bool {
        if self.legacy_made.contains(output) {
            return true;
        }
        let Some(dir) = self.record_dir(output) else {
            return false;
        };
        std::fs::read_dir(dir).is_ok_and(|entries| {
            entries.filter_map(Result::ok).any(|e| {
                let name = e.file_name();
                let name = name.to_string_lossy();
                name.ends_with(".json") && !name.starts_with('.')
            })
        })
    }

    /// Records `record` (atomically; after its output is in place).
    pub fn store(&self, record: &Record) -> std::io::Result<()> {
        let path = self
            .record_path(&record.key, &record.output)
            .ok_or_else(|| {
                std::io::Error::new(
                    std::io::ErrorKind::InvalidInput,
                    format!("{:?}: not a plain output name", record.output),
                )
            })?;
        if let Some(dir) = path.parent() {
            std::fs::create_dir_all(dir)?;
        }
        let bytes = serde_json::to_vec_pretty(record).expect("a record serializes");
        crate::io::write_atomic(&path, &bytes)
    }

    /// A private, empty folder for a build of `output` to write to (its
    /// recipe, the child's GLB) before its output is renamed into the
    /// folder (same file system, so the rename is atomic and the folder only
    /// ever holds whole outputs). This process's own (`tmp/TOKEN/OUTPUT`),
    /// so no other job or machine shares it; remove it when the build ends.
    pub fn scratch_dir(&self, output: &str) -> std::io::Result<PathBuf> {
        check_file_name(output).map_err(|why| {
            std::io::Error::new(
                std::io::ErrorKind::InvalidInput,
                format!("{output:?}: {why}"),
            )
        })?;
        let dir = self.claim.scratch.join(output);
        if dir.exists() {
            std::fs::remove_dir_all(&dir)?;
        }
        std::fs::create_dir_all(&dir)?;
        Ok(dir)
    }

    /// Removes the temporaries of runs that ended without removing them
    /// (killed), never a live run's (module doc), in `out_dir` and the
    /// cache; returns how many it removed.
    pub fn clean(&self, out_dir: &Path) -> usize {
        let own = crate::io::process_token();
        let mut by_token: BTreeMap<String, Vec<PathBuf>> = BTreeMap::new();
        let mut unowned = Vec::new();
        let list = |dir: &Path| -> Vec<(String, PathBuf)> {
            std::fs::read_dir(dir).map_or_else(
                |_| Vec::new(),
                |d| {
                    d.filter_map(Result::ok)
                        .map(|e| (e.file_name().to_string_lossy().into_owned(), e.path()))
                        .collect()
                },
            )
        };
        let mut folders = vec![out_dir.to_path_buf(), self.dir.clone()];
        folders.extend(
            list(&self.dir.join(RECORDS))
                .into_iter()
                .map(|(_, p)| p)
                .filter(|p| p.is_dir()),
        );
        for folder in &folders {
            for (name, path) in list(folder) {
                if let Some(token) = temporary_token(&name) {
                    by_token.entry(token.to_string()).or_default().push(path);
                }
            }
        }
        for (name, path) in list(&self.dir.join(TMP)) {
            if is_token(&name) {
                by_token.entry(name).or_default().push(path);
            } else {
                unowned.push(path);
            }
        }
        for (name, _) in list(&self.dir.join(LOCKS)) {
            if let Some(token) = name.strip_suffix(".lock").filter(|t| is_token(t)) {
                by_token.entry(token.to_string()).or_default();
            }
        }
        let mut removed = 0;
        for (token, paths) in by_token {
            if token == own {
                continue;
            }
            let lock = self.dir.join(LOCKS).join(format!("{token}.lock"));
            match owner(&lock) {
                Owner::Live => {}
                Owner::Dead(held) => {
                    removed += paths.iter().filter(|p| remove(p)).count();
                    // Still held: no owner can have taken it anew meanwhile.
                    let _ = std::fs::remove_file(&lock);
                    drop(held);
                }
                Owner::Unknown => unowned.extend(paths),
            }
        }
        for path in unowned {
            let old = path
                .symlink_metadata()
                .and_then(|m| m.modified())
                .ok()
                .and_then(|t| t.elapsed().ok())
                .is_some_and(|a| a >= UNOWNED_AGE);
            if old && remove(&path) {
                removed += 1;
            }
        }
        removed
    }
}

/// Removes a file or a folder with its content; whether it is gone.
fn remove(path: &Path) -> bool {
    match path.symlink_metadata() {
        Ok(m) if m.is_dir() => std::fs::remove_dir_all(path).is_ok(),
        Ok(_) => std::fs::remove_file(path).is_ok(),
        Err(_) => false,
    }
}

/// SHA-256 of a regular file's bytes, read as a stream.
fn hash_file(path: &Path) -> std::io::Result<String> {
    let mut file = crate::io::confine::open_regular(path)?;
    let mut h = Sha256::new();
    let mut buf = vec![0u8; 1 << 16];
    loop {
        match file.read(&mut buf) {
            Ok(0) => break,
            Ok(n) => h.update(&buf[..n]),
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
            Err(e) => return Err(e),
        }
    }
    Ok(hex(&h.finalize()))
}

/// Whether `s` is a [`crate::io::process_token`]: digits, `-`, 16 hex digits.
fn is_token(s: &str) -> bool {
    let Some((pid, random)) = s.split_once('-') else {
        return false;
    };
    !pid.is_empty()
        && pid.bytes().all(|b| b.is_ascii_digit())
        && random.len() == 16
        && random.bytes().all(|b| b.is_ascii_hexdigit())
}

/// The token of a temporary of [`crate::io::write_temporary`]
/// (`.NAME.tmpTOKEN-N`), if `name` is one.
fn temporary_token(name: &str) -> Option<&str> {
    let rest = name.strip_prefix('.')?;
    let tail = &rest[rest.rfind(".tmp")? + 4..];
    let (token, n) = tail.rsplit_once('-')?;
    let counter = !n.is_empty() && n.bytes().all(|b| b.is_ascii_digit());
    (counter && is_token(token)).then_some(token)
}

/// Who owns a token's temporaries.
enum Owner {
    /// A process that holds the token's lock: keep them.
    Live,
    /// Nobody: remove them while holding this (the lock, taken).
    #[cfg_attr(not(unix), allow(dead_code))]
    Dead(std::fs::File),
    /// No lock to ask (none there, or locks do not work here).
    Unknown,
}

#[cfg(unix)]
fn owner(lock: &Path) -> Owner {
    use std::os::fd::AsRawFd;
    let file = match std::fs::File::open(lock) {
        Ok(f) => f,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Owner::Unknown,
        Err(_) => return Owner::Live,
    };
    // SAFETY: flock on a descriptor this function owns.
    if unsafe { libc::flock(file.as_raw_fd(), libc::LOCK_EX | libc::LOCK_NB) } != 0 {
        let e = std::io::Error::last_os_error();
        return if e.raw_os_error() == Some(libc::EWOULDBLOCK) {
            Owner::Live
        } else {
            Owner::Unknown
        };
    }
    // Taken; but if another cleaner removed this file meanwhile, it has
    // dealt with the token already.
    if same_file(&file, lock) {
        Owner::Dead(file)
    } else {
        Owner::Live
    }
}

#[cfg(not(unix))]
fn owner(_lock: &Path) -> Owner {
    Owner::Unknown
}

#[cfg(unix)]
fn same_file(file: &std::fs::File, path: &Path) -> bool {
    use std::os::unix::fs::MetadataExt;
    match (file.metadata(), std::fs::metadata(path)) {
        (Ok(a), Ok(b)) => a.dev() == b.dev() && a.ino() == b.ino(),
        _ => false,
    }
}

/// This process's hold on its temporaries in one cache: its scratch folder
/// and its lock (module doc). One per cache folder and process, shared by
/// every [`Cache`] opened on it; dropping the last removes the scratch
/// folder and the lock file.
#[derive(Debug)]
struct Claim {
    /// `tmp/TOKEN`.
    scratch: PathBuf,
    /// `locks/TOKEN.lock`.
    lock: PathBuf,
    /// The locked file (None where locks do not work: the hour rule).
    held: Option<std::fs::File>,
}

static CLAIMS: Mutex<Vec<(PathBuf, Weak<Claim>)>> = Mutex::new(Vec::new());

impl Claim {
    fn take(dir: &Path) -> std::io::Result<Arc<Claim>> {
        let token = crate::io::process_token();
        let id = dir.canonicalize()?;
        let mut claims = CLAIMS.lock().unwrap_or_else(|e| e.into_inner());
        claims.retain(|(_, c)| c.strong_count() > 0);
        if let Some(c) = claims
            .iter()
            .find(|(d, _)| *d == id)
            .and_then(|(_, c)| c.upgrade())
        {
            return Ok(c);
        }
        let lock = dir.join(LOCKS).join(format!("{token}.lock"));
        let held = lock_own(&lock);
        let scratch = dir.join(TMP).join(token);
        std::fs::create_dir_all(&scratch)?;
        let claim = Arc::new(Claim {
            scratch,
            lock,
            held,
        });
        claims.push((id, Arc::downgrade(&claim)));
        Ok(claim)
    }
}

impl Drop for Claim {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.scratch);
        if self.held.is_some() {
            // Removed while still held (the file closes after this).
            let _ = std::fs::remove_file(&self.lock);
        }
    }
}

/// Creates and locks this process's lock file, inherited by the processes
/// it starts; None where locking does not work (the file is then removed).
#[cfg(unix)]
fn lock_own(path: &Path) -> Option<std::fs::File> {
    use std::os::fd::AsRawFd;
    for _ in 0..64 {
        let file = std::fs::OpenOptions::new()
            .read(true)
            .write(true)
            .create(true)
            .truncate(false)
            .open(path)
            .ok()?;
        let fd = file.as_raw_fd();
        // SAFETY: flock on a descriptor this function owns. Blocking: a
        // cleaner that took it first holds it for a moment only.
        if unsafe { libc::flock(fd, libc::LOCK_EX) } != 0 {
            if std::io::Error::last_os_error().kind() == std::io::ErrorKind::Interrupted {
                continue;
            }
            let _ = std::fs::remove_file(path);
            return None;
        }
        if same_file(&file, path) {
            // Children inherit the descriptor, and the lock with it.
            // SAFETY: clears FD_CLOEXEC on a descriptor this function owns.
            unsafe { libc::fcntl(fd, libc::F_SETFD, 0) };
            return Some(file);
        }
        // A cleaner removed the file before this process locked it: again.
    }
    None
}

#[cfg(not(unix))]
fn lock_own(_path: &Path) -> Option<std::fs::File> {
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keys_follow_content_and_records_say_what_to_skip() {
        let a = vec![
            (PathBuf::from("/m/a.gltf"), b"json".to_vec()),
            (PathBuf::from("/m/a.bin"), b"bin".to_vec()),
        ];
        let k = key(&a, b"recipe", "tool");
        let renamed = vec![
            (PathBuf::from("/n/b.gltf"), b"json".to_vec()),
            (PathBuf::from("/n/a.bin"), b"bin".to_vec()),
        ];
        assert_eq!(
            k,
            key(&renamed, b"recipe", "tool"),
            "the input's own name is not content"
        );
        // A file beside the input's folder: named relatively, so another
        // mount point of the same volume gives the same key.
        let beside = |root: &str| {
            vec![
                (PathBuf::from(format!("{root}/x/a.gltf")), b"json".to_vec()),
                (PathBuf::from(format!("{root}/t/a.png")), b"png".to_vec()),
            ]
        };
        assert_eq!(
            key(&beside("/mnt/v"), b"r", "t"),
            key(&beside("/data"), b"r", "t")
        );
        assert_eq!(
            relative(Path::new("/a/t/p.png"), Path::new("/a/x")),
            PathBuf::from("../t/p.png")
        );
        let mut bin = a.clone();
        bin[1].1.push(0);
        for other in [
            key(&bin, b"recipe", "tool"),
            key(&a, b"recipe2", "tool"),
            key(&a, b"recipe", "tool2"),
        ] {
            assert_ne!(k, other);
        }
        let tmp = tempfile::tempdir().unwrap();
        let dir = tmp.path();
        let cache = Cache::open(dir).unwrap();
        assert_eq!(cache.lookup(&k, dir, "a.glb"), Lookup::Miss("new"));
        std::fs::write(dir.join("a.glb"), b"glb").unwrap();
        assert_eq!(
            cache.lookup(&k, dir, "a.glb"),
            Lookup::Miss("input, recipe or lodstudio changed")
        );
        assert!(!cache.made("a.glb"));
        let record = Record {
            key: k.clone(),
            output: "a.glb".into(),
            output_sha256: sha256_hex(b"glb"),
            report: serde_json::json!({}),
        };
        cache.store(&record).unwrap();
        assert!(cache.made("a.glb"), "known when asked, not when opened");
        // A copy of the input under another name has its own record.
        std::fs::write(dir.join("b.glb"), b"glb").unwrap();
        assert_eq!(
            cache.lookup(&k, dir, "b.glb"),
            Lookup::Miss("input, recipe or lodstudio changed")
        );
        assert_eq!(
            cache.lookup(&k, dir, "a.glb"),
            Lookup::Hit(Box::new(record.clone()))
        );
        std::fs::write(dir.join("a.glb"), b"glb!").unwrap();
        assert_eq!(
            cache.lookup(&k, dir, "a.glb"),
            Lookup::Miss("output changed since it was cached")
        );
        std::fs::remove_file(dir.join("a.glb")).unwrap();
        assert_eq!(
            cache.lookup(&k, dir, "a.glb"),
            Lookup::Miss("output missing")
        );
        // A damaged record is a miss (rebuilt), and its output still the batch's.
        let path = cache.record_path(&k, "a.glb").unwrap();
        for damage in [&b"{\"key\": 1"[..], b"{}", b"[1, 2]"] {
            std::fs::write(&path, damage).unwrap();
            assert_eq!(
                cache.lookup(&k, dir, "a.glb"),
                Lookup::Miss("cache record damaged")
            );
            assert!(cache.made("a.glb"));
        }
        let mut wrong = record.clone();
        wrong.output = "b.glb".into();
        std::fs::write(&path, serde_json::to_vec(&wrong).unwrap()).unwrap();
        assert_eq!(
            cache.lookup(&k, dir, "a.glb"),
            Lookup::Miss("cache record damaged")
        );
        cache.store(&record).unwrap();
        std::fs::write(dir.join("a.glb"), b"glb").unwrap();
        assert_eq!(
            cache.lookup(&k, dir, "a.glb"),
            Lookup::Hit(Box::new(record))
        );
        // Names that would leave the folder are never records.
        for bad in ["../x.glb", "a/b.glb", ".."] {
            assert!(!cache.made(bad));
            assert_eq!(cache.lookup(&k, dir, bad), Lookup::Miss("new"));
            assert!(cache.scratch_dir(bad).is_err());
        }
    }

    #[test]
    fn temporaries_are_named_by_their_process() {
        assert!(is_token("12-0123456789abcdef"));
        assert!(!is_token("12-0123456789abcde"));
        assert!(!is_token("-0123456789abcdef"));
        assert!(is_token(crate::io::process_token()));
        assert_eq!(
            temporary_token(".a.tmp.glb.tmp7-0123456789abcdef-12"),
            Some("7-0123456789abcdef")
        );
        for not in [
            "a.glb",
            ".a.glb",
            ".a.glb.tmp7-0123456789abcdef",
            "x.tmp7-0123456789abcdef-1",
        ] {
            assert_eq!(temporary_token(not), None, "{not}");
        }
    }

    /// A dead process's temporaries go, a live one's (its lock held) stay,
    /// and ones with no lock to ask go only once they are an hour old.
    #[cfg(unix)]
    #[test]
    fn clean_removes_what_dead_runs_left_only() {
        use std::os::fd::AsRawFd;
        let tmp = tempfile::tempdir().unwrap();
        let out = tmp.path();
        let cache = Cache::open(out).unwrap();
        let c = out.join(DIR_NAME);
        let (dead, live, none) = (
            "4000001-00000000000000d1",
            "4000002-00000000000000a1",
            "4000003-00000000000000e1",
        );
        std::fs::write(c.join(LOCKS).join(format!("{dead}.lock")), b"").unwrap();
        let held = std::fs::File::create(c.join(LOCKS).join(format!("{live}.lock"))).unwrap();
        // SAFETY: flock on a descriptor this test owns.
        assert_eq!(unsafe { libc::flock(held.as_raw_fd(), libc::LOCK_EX) }, 0);
        std::fs::create_dir_all(c.join(RECORDS).join("x.glb")).unwrap();
        let made = |token: &str| {
            let files = [
                out.join(format!(".summary.json.tmp{token}-0")),
                c.join(RECORDS)
                    .join("x.glb")
                    .join(format!(".k.json.tmp{token}-3")),
                c.join(TMP).join(token).join("x.glb").join("model.glb"),
            ];
            for f in &files {
                std::fs::create_dir_all(f.parent().unwrap()).unwrap();
                std::fs::write(f, b"partial").unwrap();
            }
            files
        };
        let (dead_files, live_files, none_files) = (made(dead), made(live), made(none));
        let own = cache.scratch_dir("y.glb").unwrap().join("model.glb");
        std::fs::write(&own, b"mine").unwrap();
        std::fs::write(out.join("user.glb"), b"the user's").unwrap();
        cache.clean(out);
        for f in &dead_files {
            assert!(!f.exists(), "{}", f.display());
        }
        assert!(!c.join(TMP).join(dead).exists());
        assert!(!c.join(LOCKS).join(format!("{dead}.lock")).exists());
        for f in live_files.iter().chain(&none_files).chain([&own]) {
            assert!(f.exists(), "{}", f.display());
        }
        assert!(out.join("user.glb").exists());
        // An hour later, the ones with no lock go too.
        let old = std::time::SystemTime::now() - std::time::Duration::from_secs(7200);
        for f in &none_files[..2] {
            std::fs::File::options()
                .append(true)
                .open(f)
                .unwrap()
                .set_modified(old)
                .unwrap();
        }
        let tmp_dir = std::fs::File::open(c.join(TMP).join(none)).unwrap();
        tmp_dir.set_modified(old).unwrap();
        cache.clean(out);
        assert!(none_files[..2].iter().all(|f| !f.exists()));
        assert!(!c.join(TMP).join(none).exists());
        assert!(live_files.iter().all(|f| f.exists()));
        drop(held);
        drop(cache);
        assert!(
            !c.join(TMP).join(crate::io::process_token()).exists(),
            "own scratch removed"
        );
        let lock = c
            .join(LOCKS)
            .join(format!("{}.lock", crate::io::process_token()));
        assert!(!lock.exists(), "own lock removed");
    }
}
