//! Saving a built LOD: the save dialog and the writing both run on a worker
//! thread (see `job.rs`), so neither a slow disk nor a dialog blocks the UI.

use std::path::{Path, PathBuf};

use lodstudio_core::io::{cut_writer, write_atomic};
use lodstudio_core::lod::DrawSet;
use lodstudio_core::scene::Layout;

/// Extensions the cut writer writes, the dialog's default (it holds every
/// primitive type) first.
const MESH_EXTENSIONS: &[&str] = &["glb", "obj", "ply"];

/// How an export ended.
#[derive(Debug)]
pub enum Saved {
    Written {
        path: PathBuf,
        bytes: usize,
        /// Files written beside it (a cut's points, more layers).
        beside: Vec<PathBuf>,
    },
    /// The dialog was closed without a choice (or there is no dialog service).
    NoFile,
    Failed(String),
}

/// Asks where to save (suggesting `file_name`); the dialog itself asks before
/// replacing a file. Then writes as [`write`] does.
pub fn choose_and_write(set: &DrawSet, file_name: &str) -> Saved {
    let filters: [(&str, &[&str]); 2] = [
        ("glTF binary: everything (glb)", &MESH_EXTENSIONS[..1]),
        (
            "Meshes: triangles, points beside (obj, ply)",
            &MESH_EXTENSIONS[1..],
        ),
    ];
    save_dialog("Export the LOD", file_name, &filters).map_or(Saved::NoFile, |p| write(set, &p))
}

/// A save dialog (which asks before replacing a file): the desktop's or the
/// in-app one; `None` when it was closed without a choice.
fn save_dialog(title: &str, file_name: &str, filters: &[(&str, &[&str])]) -> Option<PathBuf> {
    crate::file_dialog::save_file(title, file_name, filters)
}

/// Asks where to save a built hierarchy (suggesting `file_name`), then
/// writes its encoded `bytes`.
pub fn choose_and_write_hierarchy(bytes: &[u8], file_name: &str) -> Saved {
    let filters: [(&str, &[&str]); 1] = [("Saved hierarchies (lodh)", &["lodh"])];
    save_dialog("Save hierarchy", file_name, &filters)
        .map_or(Saved::NoFile, |p| write_bytes(bytes, &p))
}

/// Asks where to save an LOD chain's GLB (suggesting `file_name`), then
/// writes it as [`write_chain`] does.
pub fn choose_and_write_chain(glb: &[u8], file_name: &str) -> Saved {
    let filters: [(&str, &[&str]); 2] = [
        ("glTF binary (glb)", &["glb"]),
        ("glTF with its buffer beside (gltf)", &["gltf"]),
    ];
    save_dialog("Export the LOD chain", file_name, &filters)
        .map_or(Saved::NoFile, |p| write_chain(glb, &p))
}

/// Writes a chain's GLB through the writer `lodstudio export` uses (`.gltf`
/// names get the buffer in a `.bin` beside), atomically.
pub fn write_chain(glb: &[u8], path: &Path) -> Saved {
    match lodstudio_core::io::gltf_writer::write_file(path, glb) {
        Ok(bytes) => Saved::Written {
            path: path.to_path_buf(),
            bytes,
            beside: Vec::new(),
        },
        Err(e) => Saved::Failed(e),
    }
}

/// Asks where to save a scene's LODs (suggesting `file_name`), then writes
/// them as [`write_scene`] does.
pub fn choose_and_write_scene(glbs: &[Vec<u8>], layout: Layout, file_name: &str) -> Saved {
    let filters: [(&str, &[&str]); 2] = [
        ("glTF binary (glb)", &["glb"]),
        ("glTF with its buffer beside (gltf)", &["gltf"]),
    ];
    save_dialog("Export the scene's LODs", file_name, &filters)
        .map_or(Saved::NoFile, |p| write_scene(glbs, layout, &p))
}

/// Writes a scene's GLBs at `path` as `lodstudio export` does (`files`:
/// `OUT_LOD1.glb`… beside it), each atomically.
pub fn write_scene(glbs: &[Vec<u8>], layout: Layout, path: &Path) -> Saved {
    let paths = layout.outputs(path, glbs.len());
    let mut bytes = 0;
    for (p, glb) in paths.iter().zip(glbs) {
        match lodstudio_core::io::gltf_writer::write_file(p, glb) {
            Ok(n) => bytes += n,
            Err(e) => return Saved::Failed(e),
        }
    }
    Saved::Written {
        path: path.to_path_buf(),
        bytes,
        beside: paths[1..].to_vec(),
    }
}

/// Asks where to save a recipe (suggesting `file_name`), then writes it.
pub fn choose_and_write_recipe(bytes: &[u8], file_name: &str) -> Saved {
    let filters: [(&str, &[&str]); 1] = [("Recipes (json)", &["json"])];
    save_dialog("Save the chain's recipe", file_name, &filters)
        .map_or(Saved::NoFile, |p| write_bytes(bytes, &p))
}

/// Writes the cut `set` at `path` through the one cut writer (GLB holds it
/// all; OBJ and PLY get the points beside them, and refuse splats),
/// atomically: a failed write leaves any existing file as it was.
pub fn write(set: &DrawSet, path: &Path) -> Saved {
    match cut_writer::write(path, set) {
        Ok(files) => {
            let bytes = files.iter().map(|f| f.1).sum();
            let mut paths = files.into_iter().map(|f| f.0);
            Saved::Written {
                path: paths.next().unwrap_or_else(|| path.to_path_buf()),
                bytes,
                beside: paths.collect(),
            }
        }
        Err(e) => Saved::Failed(e),
    }
}

/// Writes `bytes` to `path` atomically.
pub fn write_bytes(bytes: &[u8], path: &Path) -> Saved {
    match write_atomic(path, bytes) {
        Ok(()) => Saved::Written {
            path: path.to_path_buf(),
            bytes: bytes.len(),
            beside: Vec::new(),
        },
        Err(e) => Saved::Failed(format!("{}: cannot write: {e}", path.display())),
    }
}

/// A file name for the export of `source` (a path or `builtin:NAME`) with
/// `triangles` triangles, in the dialog's default format.
pub fn suggested_name(source: &Path, triangles: usize) -> String {
    let text = source.to_string_lossy();
    let stem = match text.strip_prefix("builtin:") {
        Some(name) => name.to_string(),
        None => source
            .file_stem()
            .map_or_else(|| "model".to_string(), |s| s.to_string_lossy().into_owned()),
    };
    format!("{stem}-{triangles}.{}", MESH_EXTENSIONS[0])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_and_bad_extensions() {
        assert_eq!(
            suggested_name(Path::new("/x/couplingdown.off"), 929),
            "couplingdown-929.glb"
        );
        assert_eq!(suggested_name(Path::new("builtin:torus"), 5), "torus-5.glb");
        let set = DrawSet {
            mesh: lodstudio_core::builtins::torus(1.0, 0.3, 8, 4),
            ..Default::default()
        };
        let dir = tempfile::tempdir().unwrap();
        match write(&set, &dir.path().join("lodstudio-export-test.xyz")) {
            Saved::Failed(message) => assert!(message.contains("xyz"), "{message}"),
            other => panic!("expected a failure, got {other:?}"),
        }
    }
}
