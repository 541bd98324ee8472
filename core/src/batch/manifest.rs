//! The inputs of a batch: a manifest lists one model a line, optionally
//! with per-asset overrides of the recipe:
//!
//! ```text
//! # comment
//! models/truck.glb
//! models/rock.obj        lods=simplify:1%,amg:15%
//! models/engine.gltf     recipe=recipes/hero.json
//! ```
//!
//! Relative paths are taken from the manifest's folder; `key=value` words
//! at the end of a line are overrides (`recipe=` a whole recipe, `lods=` its
//! rows), the rest of the line is the path.

use std::path::{Path, PathBuf};

/// One model of a batch with its overrides.
#[derive(Debug, Clone, PartialEq)]
pub struct Entry {
    pub input: PathBuf,
    /// A recipe file used instead of the batch's.
    pub recipe: Option<PathBuf>,
    /// `--lods` rows used instead of the recipe's.
    pub lods: Option<String>,
}

impl Entry {
    pub fn new(input: PathBuf) -> Entry {
        Entry {
            input,
            recipe: None,
            lods: None,
        }
    }

    /// The output's name in the output folder: the input's stem and `.glb`
    /// (`horse.ply.gz` -> `horse.glb`).
    pub fn output_name(&self) -> String {
        let name = self
            .input
            .file_name()
            .unwrap_or_default()
            .to_string_lossy()
            .into_owned();
        let name = name.strip_suffix(".gz").unwrap_or(&name);
        let stem = Path::new(name)
            .file_stem()
            .unwrap_or_default()
            .to_string_lossy();
        format!("{stem}.glb")
    }
}

/// Reads a manifest; an error names the line.
pub fn read_manifest(path: &Path) -> Result<Vec<Entry>, String> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| format!("{}: cannot read the manifest: {e}", path.display()))?;
    let base = path.parent().unwrap_or(Path::new("."));
    let mut entries = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let at = |m: String| format!("{}:{}: {m}", path.display(), i + 1);
        let mut rest = line;
        let (mut recipe, mut lods) = (None, None);
        // Overrides are the trailing words of the form key=value.
        while let Some((head, word)) = rest.rsplit_once(char::is_whitespace) {
            let Some((key, value)) = word.split_once('=') else {
                break;
            };
            match key {
                "recipe" => recipe = Some(base.join(value)),
                "lods" => lods = Some(value.to_string()),
                _ => return Err(at(format!("unknown override {key:?} (recipe=, lods=)"))),
            }
            rest = head.trim_end();
        }
        if rest.contains('=') && !Path::new(rest).exists() {
            return Err(at(format!("{rest:?}: an override needs a path before it")));
        }
        entries.push(Entry {
            input: base.join(rest),
            recipe,
            lods,
        });
    }
    if entries.is_empty() {
        return Err(format!("{}: the manifest lists no models", path.display()));
    }
    Ok(entries)
}

/// The model files a folder or glob names, sorted; `None` for one file or
/// a built-in.
pub fn folder_or_glob(arg: &Path) -> Result<Option<Vec<PathBuf>>, String> {
    let text = arg.to_string_lossy();
    let mut files: Vec<PathBuf> = if arg.is_dir() {
        let entries =
            std::fs::read_dir(arg).map_err(|e| format!("{}: cannot list: {e}", arg.display()))?;
        entries
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.is_file() && crate::io::is_model_path(p))
            .collect()
    } else if !arg.exists() && text.contains(['*', '?', '[']) {
        let paths = glob::glob(&text).map_err(|e| format!("{text}: bad pattern: {e}"))?;
        paths
            .filter_map(Result::ok)
            .filter(|p| p.is_file())
            .collect()
    } else {
        return Ok(None);
    };
    if files.is_empty() {
        return Err(format!("{text}: no model files there"));
    }
    files.sort();
    Ok(Some(files))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn manifests_take_paths_overrides_and_comments() {
        let dir = std::env::temp_dir().join(format!("lodstudio-manifest-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let m = dir.join("m.txt");
        std::fs::write(
            &m,
            "# models\n\na.obj\n  with space.ply   lods=simplify:1%,amg:15%\n/abs/b.glb recipe=r.json lods=2%\n",
        )
        .unwrap();
        let e = read_manifest(&m).unwrap();
        assert_eq!(e.len(), 3);
        assert_eq!(e[0], Entry::new(dir.join("a.obj")));
        assert_eq!(e[1].input, dir.join("with space.ply"));
        assert_eq!(e[1].lods.as_deref(), Some("simplify:1%,amg:15%"));
        assert_eq!(e[2].input, PathBuf::from("/abs/b.glb"));
        assert_eq!(e[2].recipe, Some(dir.join("r.json")));
        std::fs::write(&m, "a.obj colour=red\n").unwrap();
        assert!(read_manifest(&m).unwrap_err().contains("m.txt:1"));
        std::fs::write(&m, "# nothing\n").unwrap();
        assert!(read_manifest(&m).is_err());
        assert_eq!(
            Entry::new("x/horse.ply.gz".into()).output_name(),
            "horse.glb"
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
