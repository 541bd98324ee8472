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
//!
//! A manifest is untrusted input (DESIGN.md, "Untrusted input"): every path
//! it names, models and recipes alike, must lie inside the asset root (the
//! manifest's folder, or `--asset-root`) after `..` and links are followed
//! ([`crate::io::confine::resolve_path`]); an absolute path is taken only
//! where it lies inside that root. A path that leaves it, or names a FIFO,
//! a device or a folder, refuses the whole manifest with `FILE:LINE: ` and
//! the policy's message. A file that does not exist (yet) inside the root is
//! kept: that model fails alone when it is built. The manifest itself is
//! read as a regular file within the memory budget (`/dev/zero` or a FIFO
//! is refused at once), and a value is quoted in messages only as an
//! [`excerpt`](crate::io::confine::excerpt).

use std::path::{Component, Path, PathBuf};

use crate::io::confine::{self, Refused, excerpt};

/// One model of a batch with its overrides.
#[derive(Debug, Clone, PartialEq)]
pub struct Entry {
    /// The input as named (relative to the manifest's folder, joined).
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
    /// (`horse.ply.gz` -> `horse.glb`). Always a plain file name, so an
    /// output never leaves the output folder: an input whose stem is empty,
    /// `.` or `..`, or holds a path separator, is refused (naming it).
    pub fn output_name(&self) -> Result<String, String> {
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
        let output = format!("{stem}.glb");
        if stem.is_empty() || stem == "." || stem == ".." {
            return Err(format!(
                "{}: cannot name an output after it (its name has no stem)",
                excerpt(&self.input.to_string_lossy())
            ));
        }
        check_file_name(&output).map_err(|why| {
            format!(
                "{}: cannot name an output after it ({why})",
                excerpt(&self.input.to_string_lossy())
            )
        })?;
        Ok(output)
    }
}

/// Whether `name` is a plain file name: not empty, not `.` or `..`, and
/// without a separator (`/`, `\`) or NUL, so joining it to a folder stays
/// in that folder.
pub fn check_file_name(name: &str) -> Result<(), &'static str> {
    if name.is_empty() || name == "." || name == ".." {
        return Err("not a file name");
    }
    if name.contains(['/', '\\', '\0']) {
        return Err("a path separator in the name");
    }
    Ok(())
}

/// Reads a manifest; an error names the line (`FILE:LINE: ...`). Every path
/// is confined to the asset root (module doc). Bad input ([`Refused::Input`],
/// exit 2) is told from an environment failure ([`Refused::Io`], exit 1).
pub fn read_manifest(path: &Path) -> Result<Vec<Entry>, Refused> {
    let budget = crate::io::limits::current().memory_budget;
    let bytes = confine::read_regular(path, budget)?;
    let text = String::from_utf8(bytes).map_err(|e| {
        Refused::Input(format!(
            "{}: the manifest is not UTF-8 text (at byte {})",
            path.display(),
            e.utf8_error().valid_up_to()
        ))
    })?;
    let base = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    let mut entries = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let at = |e: Refused| match e {
            Refused::Input(m) => Refused::Input(format!("{}:{}: {m}", path.display(), i + 1)),
            Refused::Io(m) => Refused::Io(format!("{}:{}: {m}", path.display(), i + 1)),
        };
        let bad = |m: String| at(Refused::Input(m));
        let mut rest = line;
        let (mut recipe, mut lods) = (None, None);
        // Overrides are the trailing words of the form key=value.
        while let Some((head, word)) = rest.rsplit_once(char::is_whitespace) {
            let Some((key, value)) = word.split_once('=') else {
                break;
            };
            match key {
                "recipe" => recipe = Some(confined(base, Path::new(value), "recipe").map_err(at)?),
                "lods" => lods = Some(value.to_string()),
                _ => {
                    return Err(bad(format!(
                        "unknown override {} (recipe=, lods=)",
                        excerpt(key)
                    )));
                }
            }
            rest = head.trim_end();
        }
        if rest.contains('=') && !base.join(rest).exists() {
            return Err(bad(format!(
                "{}: an override needs a path before it",
                excerpt(rest)
            )));
        }
        confined(base, Path::new(rest), "input").map_err(at)?;
        entries.push(Entry {
            input: base.join(rest),
            recipe,
            lods,
        });
    }
    if entries.is_empty() {
        return Err(Refused::Input(format!(
            "{}: the manifest lists no models",
            path.display()
        )));
    }
    Ok(entries)
}

/// `path` (named by `what` in a file of `folder`) through the asset-root
/// policy: the canonical file when it exists and may be read; the path as
/// joined when nothing is there yet but its place lies inside the root (the
/// model then fails alone when built); else the policy's refusal.
fn confined(folder: &Path, path: &Path, what: &str) -> Result<PathBuf, Refused> {
    let refused = match confine::resolve_path(folder, path, what) {
        Ok(p) => return Ok(p),
        Err(e) => e,
    };
    let joined = folder.join(path);
    let nothing_there = joined
        .symlink_metadata()
        .is_err_and(|e| e.kind() == std::io::ErrorKind::NotFound);
    if path.as_os_str().is_empty() || !nothing_there {
        // Something is there (a special file, a folder, a link out), or the
        // name cannot be looked up at all (too long): refused.
        return Err(refused);
    }
    // Nothing there: the nearest folder that exists must lie in the root,
    // and the missing rest must not climb.
    let Some(existing) = joined.ancestors().skip(1).find(|a| {
        let a = if a.as_os_str().is_empty() {
            Path::new(".")
        } else {
            a
        };
        a.symlink_metadata().is_ok()
    }) else {
        return Err(refused);
    };
    let existing = if existing.as_os_str().is_empty() {
        Path::new(".")
    } else {
        existing
    };
    let missing = joined.strip_prefix(existing).unwrap_or(&joined);
    if !missing
        .components()
        .all(|c| matches!(c, Component::Normal(_)))
    {
        return Err(refused);
    }
    let inside = match (existing.canonicalize(), confine::root_for(folder)) {
        (Ok(e), Ok(root)) => confine::current().allow_outside || e.starts_with(root),
        _ => false,
    };
    if inside { Ok(joined) } else { Err(refused) }
}

/// The model files a folder or glob names, sorted; `None` for one file or
/// a built-in. Only regular files are listed (links followed): a FIFO, a
/// device or a folder named like a model is skipped.
pub fn folder_or_glob(arg: &Path) -> Result<Option<Vec<PathBuf>>, String> {
    let text = arg.to_string_lossy();
    let regular = |p: &Path| std::fs::metadata(p).is_ok_and(|m| m.is_file());
    let mut files: Vec<PathBuf> = if arg.is_dir() {
        let entries =
            std::fs::read_dir(arg).map_err(|e| format!("{}: cannot list: {e}", arg.display()))?;
        entries
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| crate::io::is_model_path(p) && regular(p))
            .collect()
    } else if !arg.exists() && text.contains(['*', '?', '[']) {
        let paths =
            glob::glob(&text).map_err(|e| format!("{}: bad pattern: {e}", excerpt(&text)))?;
        paths
            .filter_map(Result::ok)
            .filter(|p| regular(p))
            .collect()
    } else {
        return Ok(None);
    };
    if files.is_empty() {
        return Err(format!("{}: no model files there", excerpt(&text)));
    }
    files.sort();
    Ok(Some(files))
}

/// The folder a batch's inputs are confined to (unless `--asset-root`
/// names one): a folder argument itself, a glob's longest leading part
/// without a wildcard (`assets/*/m.gltf` -> `assets`, `*.obj` -> `.`), a
/// manifest's folder.
pub fn folder_of(arg: &Path) -> PathBuf {
    if arg.is_dir() {
        return arg.to_path_buf();
    }
    let components: Vec<Component> = arg.components().collect();
    let mut base = PathBuf::new();
    for c in components.iter().take(components.len().saturating_sub(1)) {
        if c.as_os_str().to_string_lossy().contains(['*', '?', '[']) {
            break;
        }
        base.push(c);
    }
    if base.as_os_str().is_empty() {
        PathBuf::from(".")
    } else {
        base
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn manifests_take_paths_overrides_and_comments() {
        let tmp = tempfile::tempdir().unwrap();
        let dir = tmp.path().join("assets");
        std::fs::create_dir_all(dir.join("sub")).unwrap();
        std::fs::write(dir.join("b.glb"), b"glb").unwrap();
        std::fs::write(dir.join("r.json"), b"{}").unwrap();
        std::fs::write(tmp.path().join("outside.obj"), b"v").unwrap();
        let m = dir.join("m.txt");
        // An absolute path is taken where it lies inside the manifest's folder.
        let abs = dir.join("b.glb");
        std::fs::write(
            &m,
            format!(
                "# models\n\na.obj\n  with space.ply   lods=simplify:1%,amg:15%\n{} recipe=r.json lods=2%\nsub/../missing.off\n",
                abs.display()
            ),
        )
        .unwrap();
        let e = read_manifest(&m).unwrap();
        assert_eq!(e.len(), 4);
        assert_eq!(e[0], Entry::new(dir.join("a.obj")));
        assert_eq!(e[1].input, dir.join("with space.ply"));
        assert_eq!(e[1].lods.as_deref(), Some("simplify:1%,amg:15%"));
        assert_eq!(e[2].input, abs);
        assert_eq!(
            e[2].recipe,
            Some(dir.join("r.json").canonicalize().unwrap())
        );
        std::fs::write(&m, "a.obj colour=red\n").unwrap();
        assert!(read_manifest(&m).unwrap_err().message().contains("m.txt:1"));
        std::fs::write(&m, "# nothing\n").unwrap();
        assert!(read_manifest(&m).is_err());
        // Out of the folder: by .., by an absolute path, by a link; a recipe too.
        let outside = tmp.path().join("outside.obj");
        #[cfg(unix)]
        std::os::unix::fs::symlink(&outside, dir.join("link.obj")).unwrap();
        for (line, n, why) in [
            ("../outside.obj", 2, "climbs out"),
            ("../nothing/x.obj", 2, "climbs out"),
            (outside.to_str().unwrap(), 2, "an absolute path"),
            ("/abs/b.glb", 2, "an absolute path"),
            ("b.glb recipe=../outside.obj", 2, "climbs out"),
            #[cfg(unix)]
            ("link.obj", 2, "a link leads out"),
            ("sub", 2, "a folder"),
        ] {
            std::fs::write(&m, format!("a.obj\n{line}\n")).unwrap();
            let e = read_manifest(&m).unwrap_err().to_string();
            assert!(e.contains(&format!("m.txt:{n}: ")), "{line}: {e}");
            assert!(e.contains(why), "{line}: {e}");
        }
        // A line of megabytes is quoted as an excerpt.
        let long = "x".repeat(1 << 20);
        for line in [format!("{long}.obj"), format!("a.obj {long}=1")] {
            std::fs::write(&m, &line).unwrap();
            let e = read_manifest(&m).unwrap_err().to_string();
            assert!(e.len() < 400, "{} characters", e.len());
        }
        #[cfg(unix)]
        {
            let e = read_manifest(Path::new("/dev/zero"))
                .unwrap_err()
                .to_string();
            assert!(e.contains("not a regular file"), "{e}");
        }
        assert_eq!(
            Entry::new("x/horse.ply.gz".into()).output_name(),
            Ok("horse.glb".into())
        );
        for bad in ["x/.gz", "x/..", "/", "x/a\\b.obj"] {
            let e = Entry::new(bad.into()).output_name().unwrap_err();
            assert!(e.contains("cannot name an output"), "{bad}: {e}");
        }
        assert_eq!(
            folder_of(Path::new("assets/*/m.gltf")),
            PathBuf::from("assets")
        );
        assert_eq!(folder_of(Path::new("*.obj")), PathBuf::from("."));
        assert_eq!(folder_of(&dir), dir);
    }
}
