//! A tileset's input read out of core (issue 47, item 2): a PLY (binary or
//! ascii, gzip too) streamed once, its vertices kept (12 bytes each, and
//! their normals and colours where it has them) and its
//! faces written to a file as they come; then the file streamed again,
//! each triangle repaired as loading repairs it (`geom::repair`: triangles
//! on non-finite vertices dropped, vertices of equal coordinates welded,
//! triangles with a repeated vertex or no area dropped) and written as the
//! partition's root cell. The triangles are never all in memory, and the
//! kept ones are numbered as the loaded mesh numbers them, so the partition
//! and every tile are the in-memory build's.

use std::io::{BufReader, BufWriter, Read, Write};
use std::path::Path;

use glam::Vec3;

use super::partition::{CellWriter, Items, Rec};
use crate::geom::Aabb;
use crate::geom::repair::{Weld, is_zero_area, weld_exact};
use crate::io::LoadError;
use crate::progress::Progress;

/// A mesh streamed to disk: its vertices, and its triangles as a cell file.
#[derive(Debug)]
pub struct Streamed {
    pub positions: Vec<Vec3>,
    pub normals: Option<Vec<Vec3>>,
    pub colors: Option<Vec<Vec3>>,
    /// The kept triangles, in input order, numbered from 0.
    pub root: Items,
    pub triangles: usize,
    /// The box of the vertices the kept triangles use.
    pub bounds: Aabb,
}

#[derive(Debug, thiserror::Error)]
pub enum StreamError {
    /// The file is not a mesh this reader streams, or is malformed.
    #[error("{0}")]
    Input(String),
    #[error(transparent)]
    Io(#[from] std::io::Error),
}

/// Streams the PLY `path` into `dir` (the work folder), welding as `weld`
/// says (`Exact` or `Off`; a tolerance needs every vertex's neighbours and
/// is refused).
pub fn stream_ply(
    path: &Path,
    dir: &Path,
    weld: Weld,
    progress: &Progress,
) -> Result<Streamed, StreamError> {
    let shown = path.display();
    let bad_input = |why: String| StreamError::Input(format!("{shown}: {why}"));
    if matches!(weld, Weld::Tolerance(_)) {
        return Err(bad_input(
            "welding within a tolerance is not done out of core".into(),
        ));
    }
    progress.stage("tiles: streaming the input");
    let mut file = crate::io::confine::open_regular(path)?;
    let mut magic = [0u8; 2];
    let gz = file.read(&mut magic)? == 2 && magic == [0x1f, 0x8b];
    let file = crate::io::confine::open_regular(path)?;
    // A gzip bomb is stopped where loading stops it (the faces would fill
    // the disk rather than memory).
    let cap = crate::io::decompression_cap(file.metadata()?.len());
    let capped = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
    let (reader, total): (Box<dyn std::io::BufRead>, usize) = if gz {
        let inflate = Capped {
            inner: flate2::read::MultiGzDecoder::new(BufReader::new(file)),
            left: cap,
            hit: std::sync::Arc::clone(&capped),
        };
        (
            Box::new(BufReader::with_capacity(1 << 20, inflate)),
            usize::MAX,
        )
    } else {
        let len = file.metadata()?.len() as usize;
        (Box::new(BufReader::with_capacity(1 << 20, file)), len)
    };
    let raw_path = dir.join("faces.bin");
    let mut raw = BufWriter::with_capacity(1 << 20, std::fs::File::create(&raw_path)?);
    let mut written = 0usize;
    let mut sink = |tris: &[[u32; 3]]| -> Result<(), String> {
        for t in tris {
            for v in t {
                raw.write_all(&v.to_le_bytes()).map_err(|e| e.to_string())?;
            }
        }
        written += tris.len();
        Ok(())
    };
    let vertices =
        crate::io::ply::stream_mesh(reader, total, progress, &mut sink).map_err(|e| {
            if capped.load(std::sync::atomic::Ordering::Relaxed) {
                return bad_input(format!(
                    "inflates past {cap} bytes ({} raises the cap)",
                    crate::io::limits::MAX_DECOMPRESSED_ENV
                ));
            }
            StreamError::Input(LoadError::malformed(path, e).to_string())
        })?;
    raw.flush()?;
    drop(raw);
    let positions = vertices.positions;
    progress.stage("tiles: repairing the triangles");
    let bad: Vec<bool> = positions.iter().map(|p| !p.is_finite()).collect();
    let remap = match weld {
        Weld::Off => None,
        _ => Some(weld_exact(&positions, &bad)),
    };
    // Welded records whose normals or colours differ keep them per corner
    // in memory (`Wedges::of_welded`, over the records triangles use);
    // out of core each vertex keeps its own, so such a file is refused.
    let attributes = [&vertices.normals, &vertices.colors];
    let has_attributes = attributes.iter().any(|a| a.is_some());
    let mut merged = vec![false; if has_attributes { positions.len() } else { 0 }];
    if let Some(r) = remap.as_ref().filter(|_| has_attributes) {
        for (i, w) in r.iter().enumerate() {
            if *w as usize != i {
                merged[*w as usize] = true;
            }
        }
    }
    // +0 and −0 are one value, as `of_welded` has it.
    let bits = |r: usize| -> Vec<u32> {
        attributes
            .iter()
            .filter_map(|a| a.as_ref())
            .flat_map(|a| a[r].to_array().map(|x| (x + 0.0).to_bits()))
            .collect()
    };
    let mut seen: std::collections::HashMap<u32, Vec<u32>> = std::collections::HashMap::new();
    let mut root = CellWriter::create(dir.join("cell-root.bin"))?;
    let mut bounds = Aabb::EMPTY;
    let mut kept = 0u32;
    let mut reader = BufReader::with_capacity(1 << 20, std::fs::File::open(&raw_path)?);
    let mut buf = [0u8; 12];
    for _ in 0..written {
        reader.read_exact(&mut buf)?;
        let t: [u32; 3] = std::array::from_fn(|k| {
            u32::from_le_bytes([buf[4 * k], buf[4 * k + 1], buf[4 * k + 2], buf[4 * k + 3]])
        });
        if t.iter().any(|v| bad[*v as usize]) {
            continue;
        }
        let records = t;
        let t = remap.as_ref().map_or(t, |r| t.map(|v| r[v as usize]));
        for (r, w) in records.iter().zip(t) {
            if merged.get(w as usize) == Some(&true) {
                let own = bits(*r as usize);
                if *seen.entry(w).or_insert_with(|| own.clone()) != own {
                    let _ = std::fs::remove_file(&raw_path);
                    return Err(bad_input(format!(
                        "vertex {r} is welded to one of the same position with another normal or colour, which out of core does not carry (give it the memory to be tiled in memory)"
                    )));
                }
            }
        }
        if t[0] == t[1] || t[1] == t[2] || t[0] == t[2] || is_zero_area(&positions, &t) {
            continue;
        }
        for v in t {
            bounds = bounds.grow(positions[v as usize]);
        }
        root.push(&Rec {
            index: kept,
            vertices: t,
        })?;
        kept = kept
            .checked_add(1)
            .ok_or_else(|| bad_input(format!("more than {} triangles", u32::MAX)))?;
    }
    drop(reader);
    std::fs::remove_file(&raw_path)?;
    if kept == 0 {
        return Err(bad_input("no valid triangles".into()));
    }
    if !bounds.diagonal().is_finite() {
        return Err(bad_input(format!(
            "expected coordinates within f32 range of each other, found a bounding box from {} to {} whose diagonal overflows",
            bounds.min, bounds.max
        )));
    }
    Ok(Streamed {
        positions,
        normals: vertices.normals,
        colors: vertices.colors,
        root: root.finish()?,
        triangles: kept as usize,
        bounds,
    })
}

/// A reader that fails past `left` bytes, and says so in `hit`.
struct Capped<R> {
    inner: R,
    left: u64,
    hit: std::sync::Arc<std::sync::atomic::AtomicBool>,
}

impl<R: Read> Read for Capped<R> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        if self.left == 0 {
            let mut probe = [0u8; 1];
            if self.inner.read(&mut probe)? == 0 {
                return Ok(0);
            }
            self.hit.store(true, std::sync::atomic::Ordering::Relaxed);
            return Err(std::io::Error::other("past the decompression cap"));
        }
        let n = buf.len().min(self.left.min(usize::MAX as u64) as usize);
        let got = self.inner.read(&mut buf[..n])?;
        self.left -= got as u64;
        Ok(got)
    }
}
