//! Opening what a user names, in one place above the readers, the
//! built-in models and the methods: a model file (`io`), a `builtin:` name
//! (`builtins`), one level of an exported LOD chain (`FILE.glb#lodN`), or a
//! saved hierarchy (decoded through its [`Method`]; as a model it opens as
//! its finest cut).

use std::path::Path;
use std::sync::Arc;

use crate::io::hierarchy_file::{self, Header, HierarchyFileError, load, peek};
use crate::io::{Format, LoadError, LoadOptions, Loaded, Location, ParseError};
use crate::lod::{Hierarchy, Method};
use crate::progress::Progress;
use crate::view::{Tolerance, View};

/// Opens a model file, a `builtin:NAME`, LOD N of a glTF's `MSFT_lod` chain
/// (`FILE#lodN`, see [`crate::io::gltf::read_lod`]) or a saved hierarchy
/// (its finest cut), detecting the format and repairing meshes as `io::load` does.
pub fn open(path: &Path, opts: &LoadOptions, progress: &Progress) -> Result<Loaded, LoadError> {
    if let Some(name) = path.to_str().and_then(|s| s.strip_prefix("builtin:")) {
        let model = crate::builtins::build(name, progress)?;
        return crate::io::prepared(path, model, Format::Builtin, opts);
    }
    if let Some((file, lod)) = lod_of(path) {
        let bytes = crate::io::read_file(file, progress)?;
        let mesh = crate::io::gltf::read_lod(&bytes, file.parent(), lod)
            .map_err(|e| LoadError::malformed(path, e))?;
        let format = match bytes.starts_with(b"glTF") {
            true => Format::Glb,
            false => Format::Gltf,
        };
        return crate::io::prepared(path, crate::io::Model::Mesh(mesh), format, opts);
    }
    let bytes = crate::io::read_file(path, progress)?;
    open_bytes(path, &bytes, opts, progress)
}

/// `FILE#lodN` as the file and N.
fn lod_of(path: &Path) -> Option<(&Path, usize)> {
    let (file, lod) = path.to_str()?.rsplit_once("#lod")?;
    let digits = !lod.is_empty() && lod.bytes().all(|b| b.is_ascii_digit());
    Some((Path::new(file), lod.parse().ok().filter(|_| digits)?))
}

/// [`open`] for bytes already in memory (`path` names them in errors).
pub fn open_bytes(
    path: &Path,
    bytes: &[u8],
    opts: &LoadOptions,
    progress: &Progress,
) -> Result<Loaded, LoadError> {
    if !hierarchy_file::is_hierarchy(bytes) {
        return crate::io::load_bytes(path, bytes, opts, progress);
    }
    let malformed = |e: String| LoadError::malformed(path, ParseError::new(Location::File, e));
    let (_, mut h) = reopen(bytes).map_err(|e| malformed(e.to_string()))?;
    let view = View::orbit(glam::Vec3::ZERO, 1.0, 0.0, 0.0);
    let model = crate::io::Model::Mesh(h.select(&view, Tolerance::Relative(0.0)).mesh);
    crate::io::prepared(path, model, Format::Hierarchy, opts)
}

/// Reopens any saved hierarchy, ready to cut: a progressive edge collapse,
/// a hybrid MRG, a merge tree
/// (with the default criteria; the studio sets its own), a voxel pyramid or
/// an AMG multiscale.
pub fn reopen(bytes: &[u8]) -> Result<(Header, Box<dyn Hierarchy>), HierarchyFileError> {
    let header = peek(bytes)?;
    // Impostors are never saved: they have no hierarchy to cut.
    let Some(method) = Method::from_tag(&header.method).filter(|m| Method::ALL.contains(m)) else {
        return Err(HierarchyFileError::WrongMethod {
            found: header.method,
            expected: Method::ALL.map(Method::tag).join(", "),
        });
    };
    let tag = method.tag();
    let hierarchy: Box<dyn Hierarchy> = match method {
        Method::EdgeCollapse => {
            use crate::simplify::progressive::{Progressive, ProgressiveCut, Record};
            let (_, record) = load::<Record>(bytes, tag)?;
            let progressive =
                Progressive::new(record).map_err(|why| HierarchyFileError::Corrupt {
                    what: "collapse sequence",
                    why,
                })?;
            Box::new(ProgressiveCut::new(Arc::new(progressive)))
        }
        Method::Hybrid => {
            let (_, mrg) = load::<crate::hybrid::Mrg>(bytes, tag)?;
            // The graph's invariants (ids in range, arcs consistent) before any cut.
            mrg.check()
                .map_err(|why| HierarchyFileError::Corrupt { what: "graph", why })?;
            Box::new(crate::hybrid::HybridCut::new(Arc::new(mrg)))
        }
        Method::MergeTree => {
            let (_, tree) = load::<crate::mergetree::MergeTree>(bytes, tag)?;
            tree.check()
                .map_err(|why| HierarchyFileError::Corrupt { what: "tree", why })?;
            Box::new(crate::mergetree::MergeTreeView::new(
                Arc::new(tree),
                Default::default(),
            ))
        }
        Method::Voxel => {
            let (_, pyramid) = load::<crate::voxel::Pyramid>(bytes, tag)?;
            let grids_fit = pyramid.levels.iter().all(|l| {
                let d = l.density.dims;
                d.iter().all(|&n| n >= 2)
                    && d.iter().try_fold(1usize, |a, &n| a.checked_mul(n))
                        == Some(l.density.data.len())
            });
            if pyramid.levels.is_empty() || !grids_fit {
                return Err(HierarchyFileError::Corrupt {
                    what: "pyramid",
                    why: "levels missing or grids not matching their samples".into(),
                });
            }
            let bounds_fit = [0, pyramid.levels.len()].contains(&pyramid.error_bounds.len())
                && pyramid.error_bounds.iter().all(|b| *b >= 0.0)
                && pyramid.diagonal.is_finite()
                && pyramid.diagonal >= 0.0;
            if !bounds_fit {
                return Err(HierarchyFileError::Corrupt {
                    what: "pyramid",
                    why: "level bounds not one non-negative number per level".into(),
                });
            }
            Box::new(crate::voxel::pyramid::PyramidCut::new(pyramid, None))
        }
        Method::Impostor => unreachable!("refused above"),
        Method::Amg => {
            let (_, ms) = load::<crate::amg::Multiscale>(bytes, tag)?;
            if !ms.is_consistent() {
                return Err(HierarchyFileError::Corrupt {
                    what: "multiscale",
                    why: "points, radii and operators disagree in size or are not finite".into(),
                });
            }
            let texel = header
                .params
                .get("texel")
                .and_then(|t| t.as_f64())
                .unwrap_or(0.0) as f32;
            let texel = if texel.is_finite() && texel > 0.0 {
                texel
            } else {
                ms.default_texel()
            };
            Box::new(crate::amg::AmgHierarchy::new(ms, texel))
        }
    };
    Ok((header, hierarchy))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_lod_suffix_names_a_file_and_a_level() {
        let lod = |s: &str| lod_of(Path::new(s)).map(|(f, n)| (f.to_str().unwrap().to_owned(), n));
        assert_eq!(lod("out/x.glb#lod12"), Some(("out/x.glb".into(), 12)));
        assert_eq!(lod("x.glb#lod0"), Some(("x.glb".into(), 0)));
        for plain in [
            "x.glb",
            "x.glb#lod",
            "x.glb#lod+1",
            "x.glb#lod1a",
            "builtin:torus",
        ] {
            assert_eq!(lod(plain), None, "{plain}");
        }
    }
}
