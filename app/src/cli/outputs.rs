//! The files one command writes, as one transaction: each is claimed before
//! any work (an existing file needs `--force`; two outputs, or an output and
//! an input, never share a path), written to a temporary beside its place
//! as it is made, and put in place together when the command succeeds. A
//! command that fails leaves no file behind (`simplify -o ok.ply --save
//! ro/x.lodh` wrote ok.ply before the save failed; `-o X.glb --save X.glb`
//! kept the hierarchy and lost the mesh).
//!
//! Write failures are told apart: a path the user named wrongly (no such
//! folder, a folder where a file goes) is bad input (exit 2); the
//! environment failing (permission denied, a full disk) is exit 1.

use std::path::{Path, PathBuf};
use std::sync::Mutex;

use super::CliError;

#[derive(Default)]
struct Transaction {
    /// Paths claimed as outputs (as identified by [`identity`]).
    claimed: Vec<PathBuf>,
    /// Inputs read: no output may replace one.
    inputs: Vec<PathBuf>,
    /// Written temporaries and where each goes.
    staged: Vec<(PathBuf, PathBuf)>,
}

static RUN: Mutex<Option<Transaction>> = Mutex::new(None);

fn with<T>(f: impl FnOnce(&mut Transaction) -> T) -> T {
    let mut guard = RUN.lock().unwrap_or_else(|e| e.into_inner());
    f(guard.get_or_insert_with(Transaction::default))
}

/// A path as the file system will resolve it: its folder made canonical
/// (links followed), its name kept, so `a/../x.glb` and `./x.glb` are one.
pub fn identity(path: &Path) -> PathBuf {
    if let Ok(p) = path.canonicalize() {
        return p;
    }
    let name = path.file_name().map(PathBuf::from).unwrap_or_default();
    let folder = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    match folder.canonicalize() {
        Ok(f) => f.join(name),
        Err(_) => std::path::absolute(path).unwrap_or_else(|_| path.to_path_buf()),
    }
}

/// Claims `path` as an output: refused when it exists (without `force`),
/// when another output of this run claimed it, or when it is an input.
pub fn claim(path: &Path, force: bool) -> Result<(), CliError> {
    let id = identity(path);
    with(|t| {
        if t.inputs.contains(&id) {
            return Err(same_as_input(path));
        }
        if t.claimed.contains(&id) {
            return Err(CliError::BadInput(format!(
                "{}: named for two outputs of one run (say --output and --save): give each its own file",
                path.display(),
            )));
        }
        if path.exists() && !force {
            return Err(CliError::BadInput(format!(
                "{} exists (use --force to overwrite)",
                path.display()
            )));
        }
        t.claimed.push(id);
        Ok(())
    })
}

fn same_as_input(path: &Path) -> CliError {
    CliError::BadInput(format!(
        "{}: is an input of this run and cannot be written as its output",
        path.display()
    ))
}

/// Records an input: no output of this run may be written over it.
pub fn input(path: &Path) -> Result<(), CliError> {
    let id = identity(path);
    with(|t| {
        if t.claimed.contains(&id) {
            return Err(same_as_input(path));
        }
        t.inputs.push(id);
        Ok(())
    })
}

/// Writes `bytes` for `path`: to a temporary beside it now (so a full disk
/// fails here), put in place by [`commit`].
pub fn write(path: &Path, bytes: &[u8]) -> Result<(), CliError> {
    let id = identity(path);
    let clash = with(|t| {
        if t.inputs.contains(&id) {
            return Some(same_as_input(path));
        }
        t.staged.iter().any(|(_, p)| identity(p) == id).then(|| {
            CliError::BadInput(format!(
                "{}: two outputs of this run would be written there",
                path.display()
            ))
        })
    });
    if let Some(e) = clash {
        return Err(e);
    }
    let tmp =
        lodstudio_core::io::write_temporary(path, bytes).map_err(|e| write_error(path, &e))?;
    with(|t| t.staged.push((tmp, path.to_path_buf())));
    Ok(())
}

/// The error of a failed write.
pub fn write_error(path: &Path, e: &std::io::Error) -> CliError {
    io_error(path, "write", e)
}

/// A failed file operation (`what`: "write", "create", …) on `path`: bad
/// input where the path named is wrong (no such folder, a folder where a
/// file goes), an environment failure otherwise (permission denied, a full
/// disk: DESIGN.md's exit 1).
pub fn io_error(path: &Path, what: &str, e: &std::io::Error) -> CliError {
    use std::io::ErrorKind as K;
    let message = format!("{}: cannot {what}: {e}", path.display());
    match e.kind() {
        K::NotFound | K::NotADirectory | K::IsADirectory | K::InvalidInput | K::InvalidFilename => {
            CliError::BadInput(message)
        }
        _ => CliError::Failure(message),
    }
}

/// Puts every staged file in place (a rename each, in the order written).
pub fn commit() -> Result<(), CliError> {
    let staged = with(|t| std::mem::take(&mut t.staged));
    let mut result = Ok(());
    for (tmp, path) in staged {
        if result.is_err() {
            let _ = std::fs::remove_file(&tmp);
            continue;
        }
        if let Err(e) = std::fs::rename(&tmp, &path) {
            let _ = std::fs::remove_file(&tmp);
            result = Err(write_error(&path, &e));
        }
    }
    result
}

/// Removes every staged temporary: the command failed, nothing is written.
pub fn discard() {
    for (tmp, _) in with(|t| std::mem::take(&mut t.staged)) {
        let _ = std::fs::remove_file(tmp);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn outputs_are_written_together_or_not_at_all() {
        let dir = tempfile::tempdir().unwrap();
        let (a, b) = (dir.path().join("a.obj"), dir.path().join("sub/../b.ply"));
        std::fs::create_dir(dir.path().join("sub")).unwrap();
        std::fs::write(dir.path().join("in.obj"), b"v").unwrap();
        input(&dir.path().join("in.obj")).unwrap();
        assert!(
            claim(&dir.path().join("./in.obj"), true).is_err(),
            "an input"
        );
        claim(&a, false).unwrap();
        claim(&b, false).unwrap();
        let twice = claim(&dir.path().join("b.ply"), true);
        assert!(matches!(twice, Err(CliError::BadInput(m)) if m.contains("two outputs")));
        write(&a, b"a").unwrap();
        assert!(!a.exists(), "staged, not in place");
        assert!(write(&dir.path().join("a.obj"), b"again").is_err());
        discard();
        let left: Vec<_> = std::fs::read_dir(dir.path()).unwrap().collect();
        assert_eq!(left.len(), 2, "only in.obj and sub: no temporary left");
        write(&a, b"a").unwrap();
        write(&b, b"b").unwrap();
        commit().unwrap();
        assert_eq!(std::fs::read(&a).unwrap(), b"a");
        assert_eq!(std::fs::read(dir.path().join("b.ply")).unwrap(), b"b");
        let e = write(&dir.path().join("missing/x.obj"), b"x").unwrap_err();
        assert!(
            matches!(e, CliError::BadInput(_)),
            "no such folder: bad input"
        );
    }
}
