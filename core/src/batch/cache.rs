//! The content-addressed cache of a batch, kept in the output folder (so a
//! shared volume shares it between machines). An output's key hashes the
//! bytes of its input and of the files the input names (a glTF's buffers
//! and images), the recipe it was built with and the tool; a record per key
//! says which output it made and the output's own hash. A rerun skips an
//! output whose record matches and whose file is unchanged; anything else is
//! rebuilt, with the reason. A file's time stamp is not content: touching an
//! input without changing it rebuilds nothing.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};

/// The cache's folder inside the output folder.
pub const DIR_NAME: &str = ".lodstudio-cache";

/// Hex SHA-256 of `bytes`.
pub fn sha256_hex(bytes: &[u8]) -> String {
    hex(&Sha256::digest(bytes))
}

fn hex(digest: &[u8]) -> String {
    digest.iter().map(|b| format!("{b:02x}")).collect()
}

/// The files an input is made of: itself, then what it names (glTF).
pub fn input_files(input: &Path) -> std::io::Result<Vec<(PathBuf, Vec<u8>)>> {
    let bytes = std::fs::read(input)?;
    let ext = crate::io::extension(input);
    let named = if ext == "gltf" || ext == "glb" {
        crate::io::gltf::referenced_files(input, &bytes)
    } else {
        Vec::new()
    };
    let mut files = vec![(input.to_path_buf(), bytes)];
    for path in named {
        // A missing file changes nothing here: the model fails to load.
        if let Ok(b) = std::fs::read(&path) {
            files.push((path, b));
        }
    }
    Ok(files)
}

/// An input's size for sharding, from file metadata (no reads): itself and,
/// for a `.gltf`, the files its JSON names. 0 for a file that cannot be
/// listed (it fails when built, on whichever shard has it).
pub fn input_size(input: &Path) -> u64 {
    let len = |p: &Path| std::fs::metadata(p).map_or(0, |m| m.len());
    let named = match crate::io::extension(input).as_str() {
        "gltf" => std::fs::read(input)
            .map(|bytes| crate::io::gltf::referenced_files(input, &bytes))
            .unwrap_or_default(),
        _ => Vec::new(),
    };
    len(input) + named.iter().map(|p| len(p)).sum::<u64>()
}

/// The key of an output: the input files' names (relative to the input's
/// folder) and bytes, the recipe's bytes and the tool's identity.
pub fn key(files: &[(PathBuf, Vec<u8>)], recipe: &[u8], tool: &str) -> String {
    let mut h = Sha256::new();
    let mut field = |bytes: &[u8]| {
        h.update((bytes.len() as u64).to_le_bytes());
        h.update(bytes);
    };
    field(b"lodstudio-batch-key 1");
    field(tool.as_bytes());
    field(recipe);
    let base = files.first().and_then(|(p, _)| p.parent());
    for (i, (path, bytes)) in files.iter().enumerate() {
        // The input's own name does not matter; what it names does.
        let name = match (i, base) {
            (0, _) => String::new(),
            (_, Some(b)) => path
                .strip_prefix(b)
                .unwrap_or(path)
                .to_string_lossy()
                .into(),
            _ => path.to_string_lossy().into(),
        };
        field(name.as_bytes());
        field(bytes);
    }
    hex(&h.finalize())
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
    /// The outputs some record names, read once when opened.
    made: std::collections::HashSet<String>,
}

impl Cache {
    /// The cache of `out_dir` (made if missing).
    pub fn open(out_dir: &Path) -> std::io::Result<Cache> {
        let dir = out_dir.join(DIR_NAME);
        std::fs::create_dir_all(dir.join("tmp"))?;
        let made = std::fs::read_dir(&dir)?
            .filter_map(Result::ok)
            .filter(|e| e.path().extension().is_some_and(|x| x == "json"))
            .filter_map(|e| std::fs::read(e.path()).ok())
            .filter_map(|b| serde_json::from_slice::<Record>(&b).ok())
            .map(|r| r.output)
            .collect();
        Ok(Cache { dir, made })
    }

    /// A record per key and output: two inputs with the same bytes (copies
    /// under two names) make two outputs, each with its record.
    fn record_path(&self, key: &str, output: &str) -> PathBuf {
        let name = sha256_hex(format!("{key}\0{output}").as_bytes());
        self.dir.join(format!("{name}.json"))
    }

    /// Whether `output` (in `out_dir`) is already what `key` makes.
    pub fn lookup(&self, key: &str, out_dir: &Path, output: &str) -> Lookup {
        let out = out_dir.join(output);
        let record: Option<Record> = std::fs::read(self.record_path(key, output))
            .ok()
            .and_then(|b| serde_json::from_slice(&b).ok());
        let Ok(bytes) = std::fs::read(&out) else {
            return Lookup::Miss(if record.is_some() {
                "output missing"
            } else {
                "new"
            });
        };
        match record {
            Some(r) if r.output == output && r.output_sha256 == sha256_hex(&bytes) => {
                Lookup::Hit(Box::new(r))
            }
            Some(r) if r.output == output => Lookup::Miss("output changed since it was cached"),
            _ => Lookup::Miss("input, recipe or lodstudio changed"),
        }
    }

    /// Whether a record named `output` when the cache was opened (so an
    /// existing file there is a batch's own, not the user's; each output
    /// belongs to one shard, so no other shard makes it meanwhile).
    pub fn made(&self, output: &str) -> bool {
        self.made.contains(output)
    }

    /// Records `record` (atomically; after its output is in place).
    pub fn store(&self, record: &Record) -> std::io::Result<()> {
        let bytes = serde_json::to_vec_pretty(record).expect("a record serializes");
        crate::io::write_atomic(&self.record_path(&record.key, &record.output), &bytes)
    }

    /// A private place for a build of `output` to write to (`extension`:
    /// the GLB, or the recipe it is built with) before its output is renamed
    /// into the folder (same file system, so the rename is atomic and the
    /// folder only ever holds whole outputs). Unique to this process and
    /// output, so no other job or machine shares it.
    pub fn scratch(&self, output: &str, extension: &str) -> PathBuf {
        self.dir.join("tmp").join(format!(
            "{output}.{}.{extension}",
            crate::io::process_token()
        ))
    }

    /// Removes scratch files older than `age` (left by runs that were killed).
    pub fn clean_scratch(&self, age: std::time::Duration) {
        let Ok(entries) = std::fs::read_dir(self.dir.join("tmp")) else {
            return;
        };
        for e in entries.filter_map(Result::ok) {
            let old = e
                .metadata()
                .and_then(|m| m.modified())
                .ok()
                .and_then(|t| t.elapsed().ok())
                .is_some_and(|a| a >= age);
            if old {
                let _ = std::fs::remove_file(e.path());
            }
        }
    }
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
        let mut bin = a.clone();
        bin[1].1.push(0);
        for other in [
            key(&bin, b"recipe", "tool"),
            key(&a, b"recipe2", "tool"),
            key(&a, b"recipe", "tool2"),
        ] {
            assert_ne!(k, other);
        }
        let dir = std::env::temp_dir().join(format!("lodstudio-cache-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let cache = Cache::open(&dir).unwrap();
        assert_eq!(cache.lookup(&k, &dir, "a.glb"), Lookup::Miss("new"));
        std::fs::write(dir.join("a.glb"), b"glb").unwrap();
        assert_eq!(
            cache.lookup(&k, &dir, "a.glb"),
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
        assert!(Cache::open(&dir).unwrap().made("a.glb"), "read when opened");
        // A copy of the input under another name has its own record.
        std::fs::write(dir.join("b.glb"), b"glb").unwrap();
        assert_eq!(
            cache.lookup(&k, &dir, "b.glb"),
            Lookup::Miss("input, recipe or lodstudio changed")
        );
        assert_eq!(
            cache.lookup(&k, &dir, "a.glb"),
            Lookup::Hit(Box::new(record))
        );
        std::fs::write(dir.join("a.glb"), b"glb!").unwrap();
        assert_eq!(
            cache.lookup(&k, &dir, "a.glb"),
            Lookup::Miss("output changed since it was cached")
        );
        std::fs::remove_file(dir.join("a.glb")).unwrap();
        assert_eq!(
            cache.lookup(&k, &dir, "a.glb"),
            Lookup::Miss("output missing")
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
