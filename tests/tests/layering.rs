//! The layering the README promises, checked on the sources: core imports
//! no GUI crate; core's top-level modules form no cycle, and geometry, I/O
//! and distances know no method; the studio's builds and settings import no
//! UI. Comments and `#[cfg(test)]` modules are left out of the scan.
//!
//! `lod` is the interface every method implements, and `lod::build` the one
//! build path above the methods: the scan counts `lod/build.rs` as a module
//! of its own (`lod::build`), and no method may name it.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

const GUI_CRATES: [&str; 8] = [
    "egui",
    "eframe",
    "egui_wgpu",
    "egui_kittest",
    "egui_plot",
    "wgpu",
    "winit",
    "rfd",
];
const METHODS: [&str; 5] = ["simplify", "hybrid", "mergetree", "voxel", "amg"];

fn workspace() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// Every `.rs` file under `dir`, sorted.
fn sources(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p);
            } else if p.extension().is_some_and(|x| x == "rs") {
                out.push(p);
            }
        }
    }
    out.sort();
    out
}

/// A file's code: without comments, and cut where its test module starts.
fn code(path: &Path) -> String {
    let text = std::fs::read_to_string(path).unwrap();
    let mut out = String::new();
    let mut lines = text.lines().peekable();
    while let Some(line) = lines.next() {
        let trimmed = line.trim_start();
        if trimmed.starts_with("#[cfg(test)]")
            && lines.peek().is_some_and(|l| {
                let l = l.trim_start();
                ["mod ", "pub mod ", "pub(crate) mod "]
                    .iter()
                    .any(|m| l.starts_with(m))
            })
        {
            break;
        }
        let line = line.split("//").next().unwrap_or_default();
        out.push_str(line);
        out.push('\n');
    }
    out
}

/// The names a path prefix (`crate::`, `use egui`…) reaches first in `code`:
/// `crate::io::x` gives `io`; `crate::{geom::A, io}` gives `geom` and `io`.
fn after(code: &str, prefix: &str) -> BTreeSet<String> {
    let ident = |s: &str| -> String {
        s.chars()
            .take_while(|c| c.is_alphanumeric() || *c == '_')
            .collect()
    };
    let mut out = BTreeSet::new();
    for (at, _) in code.match_indices(prefix) {
        let before = code[..at].chars().next_back();
        if before.is_some_and(|c| c.is_alphanumeric() || c == '_') {
            continue; // part of a longer name
        }
        let rest = &code[at + prefix.len()..];
        if let Some(group) = rest.strip_prefix('{') {
            // Names at the group's top level.
            let mut depth = 0;
            let mut start = true;
            for (i, c) in group.char_indices() {
                match c {
                    '{' => depth += 1,
                    '}' if depth == 0 => break,
                    '}' => depth -= 1,
                    ',' if depth == 0 => start = true,
                    c if start && depth == 0 && !c.is_whitespace() => {
                        out.insert(ident(&group[i..]));
                        start = false;
                    }
                    _ => {}
                }
            }
        } else {
            out.insert(ident(rest));
        }
    }
    out.retain(|n| !n.is_empty());
    out
}

/// Core's top-level modules and the others each one names.
fn core_graph() -> BTreeMap<String, BTreeSet<String>> {
    let src = workspace().join("core/src");
    let mut files: BTreeMap<String, Vec<PathBuf>> = BTreeMap::new();
    for f in sources(&src) {
        let rel = f.strip_prefix(&src).unwrap();
        let top = rel
            .components()
            .next()
            .unwrap()
            .as_os_str()
            .to_string_lossy();
        let mut top = top.trim_end_matches(".rs").to_string();
        if rel == Path::new("lod/build.rs") {
            top = "lod::build".to_string();
        }
        if top != "lib" {
            files.entry(top).or_default().push(f);
        }
    }
    let names: BTreeSet<String> = files.keys().cloned().collect();
    files
        .iter()
        .map(|(m, fs)| {
            let mut uses = BTreeSet::new();
            for f in fs {
                uses.extend(after(&code(f), "crate::"));
            }
            uses.retain(|u| u != m && names.contains(u));
            (m.clone(), uses)
        })
        .collect()
}

#[test]
fn the_scanner_reads_paths_groups_and_skips_comments() {
    let snippet = "use crate::{geom::A, io, lod::{B, C}};\nlet x = crate::view::f(); // crate::amg\nmycrate::x";
    let got: Vec<String> = after(snippet, "crate::").into_iter().collect();
    assert_eq!(
        got,
        ["amg", "geom", "io", "lod", "view"],
        "before comments are cut"
    );
    let dir = tempfile::tempdir().unwrap();
    let f = dir.path().join("m.rs");
    std::fs::write(
        &f,
        format!("{snippet}\n#[cfg(test)]\npub(crate) mod tests {{ use crate::hybrid; }}\n"),
    )
    .unwrap();
    let got: Vec<String> = after(&code(&f), "crate::").into_iter().collect();
    assert_eq!(got, ["geom", "io", "lod", "view"]);
}

#[test]
fn core_imports_no_gui_crate() {
    let manifest = std::fs::read_to_string(workspace().join("core/Cargo.toml")).unwrap();
    for line in manifest.lines() {
        let name = line.split(['=', ' ', '.']).next().unwrap_or_default();
        assert!(
            !GUI_CRATES.contains(&name.replace('-', "_").as_str()),
            "core/Cargo.toml depends on {name}"
        );
    }
    for f in sources(&workspace().join("core/src")) {
        let code = code(&f);
        for gui in GUI_CRATES {
            assert!(
                after(&code, &format!("{gui}::")).is_empty()
                    && !code.contains(&format!("use {gui}")),
                "{} uses {gui}",
                f.display()
            );
        }
    }
}

#[test]
fn core_modules_form_no_cycle_and_lower_layers_know_no_method() {
    let graph = core_graph();
    assert!(graph.len() > 15, "{graph:?}");
    // Depth-first search for a back edge, naming the cycle found.
    fn visit(
        m: &str,
        graph: &BTreeMap<String, BTreeSet<String>>,
        path: &mut Vec<String>,
        done: &mut BTreeSet<String>,
    ) {
        if done.contains(m) {
            return;
        }
        if let Some(at) = path.iter().position(|p| p == m) {
            panic!("core modules import in a cycle: {:?} -> {m}", &path[at..]);
        }
        path.push(m.to_string());
        for next in &graph[m] {
            visit(next, graph, path, done);
        }
        path.pop();
        done.insert(m.to_string());
    }
    let mut done = BTreeSet::new();
    for m in graph.keys() {
        visit(m, &graph, &mut Vec::new(), &mut done);
    }
    assert!(graph.contains_key("lod::build"), "{graph:?}");
    for method in METHODS {
        for f in sources(&workspace().join("core/src").join(method)) {
            let code = code(&f);
            for above in ["lod::build", "lod::Params", "BuildError"] {
                assert!(!code.contains(above), "{} names {above}", f.display());
            }
        }
    }
    for lower in ["geom", "io", "distance", "view", "progress"] {
        let methods: Vec<&String> = graph[lower]
            .iter()
            .filter(|u| METHODS.contains(&u.as_str()))
            .collect();
        assert!(
            methods.is_empty(),
            "{lower} imports the methods {methods:?}"
        );
    }
}

#[test]
fn builds_and_settings_import_no_ui() {
    for folder in ["app/src/build", "app/src/settings"] {
        for f in sources(&workspace().join(folder)) {
            let code = code(&f);
            let mut ui: Vec<String> = GUI_CRATES
                .iter()
                .filter(|g| !after(&code, &format!("{g}::")).is_empty())
                .map(|g| g.to_string())
                .collect();
            ui.extend(
                after(&code, "crate::")
                    .into_iter()
                    .filter(|m| ["studio", "panels", "render", "job"].contains(&m.as_str())),
            );
            assert!(ui.is_empty(), "{} imports UI: {ui:?}", f.display());
        }
    }
}
