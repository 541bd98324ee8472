//! The spatial partition of a tileset: a k-d tree over the triangles'
//! centroids, each cell split at the median of its longest axis until it
//! holds at most the tile budget. Balanced by count, so every leaf holds
//! between half the budget and the budget (the tree's levels stay even),
//! and the tree's shape and numbering depend on the count alone.
//!
//! Out of core (issue 47, item 2): a cell larger than the memory it may use
//! stays in a file of [`Rec`]ords, its extent and its exact median found by
//! streaming it (a radix select over `(coordinate, index)` keys, four
//! passes of 16 bits), and split into two files; a cell that fits is split
//! in memory. The median rule is the same either way (the lower half by
//! coordinate, ties by triangle index), so a partition on disk is the one
//! in memory, cell for cell, whatever memory it was given.

use std::io::{BufReader, BufWriter, Read, Write};
use std::path::{Path, PathBuf};

use glam::Vec3;

use crate::geom::TriMesh;
use crate::progress::{Cancelled, Progress};

/// One triangle as the partition moves it: its index in the input and its
/// vertices.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Rec {
    pub index: u32,
    pub vertices: [u32; 3],
}

/// Bytes of a record in a cell's file.
pub const REC_BYTES: usize = 16;

impl Rec {
    fn bytes(&self) -> [u8; REC_BYTES] {
        let mut b = [0; REC_BYTES];
        b[..4].copy_from_slice(&self.index.to_le_bytes());
        for (k, v) in self.vertices.iter().enumerate() {
            b[4 + 4 * k..8 + 4 * k].copy_from_slice(&v.to_le_bytes());
        }
        b
    }

    fn from_bytes(b: &[u8]) -> Rec {
        let u = |k: usize| u32::from_le_bytes([b[4 * k], b[4 * k + 1], b[4 * k + 2], b[4 * k + 3]]);
        Rec {
            index: u(0),
            vertices: [u(1), u(2), u(3)],
        }
    }

    fn centroid(&self, positions: &[Vec3]) -> Vec3 {
        self.vertices
            .iter()
            .map(|v| positions[*v as usize])
            .sum::<Vec3>()
            / 3.0
    }
}

/// A node of the partition: a leaf with its triangles (input order), or
/// two children (indices into the node list).
#[derive(Debug, Clone, PartialEq)]
pub enum Cell {
    Leaf(Vec<u32>),
    Split([usize; 2]),
}

/// The partition of `mesh`'s triangles into cells of at most `budget`
/// (≥ 1), in memory; node 0 is the root.
pub fn partition(mesh: &TriMesh, budget: usize) -> Vec<Cell> {
    let mut leaves = Vec::new();
    let tree = split(
        &mesh.positions,
        Items::Memory(records(mesh)),
        budget,
        &Spill::none(),
        &Progress::new(),
        |at, recs| {
            leaves.push((at, recs.iter().map(|r| r.index).collect()));
            Ok(())
        },
    )
    .expect("in memory: no I/O, never cancelled");
    let mut cells: Vec<Cell> = tree
        .into_iter()
        .map(|k| k.map_or(Cell::Leaf(Vec::new()), Cell::Split))
        .collect();
    for (at, tris) in leaves {
        cells[at] = Cell::Leaf(tris);
    }
    cells
}

/// Every triangle of `mesh` as a record, in input order.
pub fn records(mesh: &TriMesh) -> Vec<Rec> {
    mesh.triangles
        .iter()
        .enumerate()
        .map(|(i, t)| Rec {
            index: i as u32,
            vertices: *t,
        })
        .collect()
}

/// Where cells too large for memory go, and what memory cells may use.
#[derive(Debug, Clone)]
pub struct Spill {
    /// A folder for cell files (removed as they are split).
    pub dir: Option<PathBuf>,
    /// Most records held in memory at once: larger cells stay on disk.
    pub in_memory: usize,
}

impl Spill {
    /// Everything in memory.
    pub fn none() -> Spill {
        Spill {
            dir: None,
            in_memory: usize::MAX,
        }
    }
}

/// A cell's triangles: in memory, or in a file of `count` records.
#[derive(Debug)]
pub enum Items {
    Memory(Vec<Rec>),
    Disk { path: PathBuf, count: usize },
}

impl Items {
    fn len(&self) -> usize {
        match self {
            Items::Memory(r) => r.len(),
            Items::Disk { count, .. } => *count,
        }
    }
}

/// Splits `root` into cells of at most `budget` triangles; each leaf's
/// records (in input order) go to `leaf` with its node index. Returns each
/// node's children (`None`: a leaf). Node 0 is the root; children are
/// numbered when their parent splits, depth first, the lower half first.
pub fn split(
    positions: &[Vec3],
    root: Items,
    budget: usize,
    spill: &Spill,
    progress: &Progress,
    mut leaf: impl FnMut(usize, &[Rec]) -> std::io::Result<()>,
) -> Result<Vec<Option<[usize; 2]>>, SplitError> {
    let budget = budget.max(1);
    let total = root.len().max(1);
    let mut placed = 0usize;
    let mut tree = vec![None];
    let mut stack = vec![(0usize, root)];
    let mut files = 0usize;
    while let Some((at, items)) = stack.pop() {
        progress.check()?;
        if items.len() <= budget {
            let mut recs = load(items)?;
            recs.sort_unstable_by_key(|r| r.index);
            leaf(at, &recs)?;
            placed += recs.len();
            progress.set_fraction(placed as f32 / total as f32);
            continue;
        }
        let half = items.len() / 2;
        let [lower, upper] = match items {
            Items::Memory(recs) => split_in_memory(positions, recs, half),
            Items::Disk { path, count } => {
                let halves = split_on_disk(positions, &path, count, half, spill, &mut files)?;
                std::fs::remove_file(&path)?;
                halves
            }
        };
        let kids = [tree.len(), tree.len() + 1];
        tree.extend([None, None]);
        tree[at] = Some(kids);
        stack.push((kids[1], upper));
        stack.push((kids[0], lower));
    }
    Ok(tree)
}

#[derive(Debug, thiserror::Error)]
pub enum SplitError {
    #[error(transparent)]
    Cancelled(#[from] Cancelled),
    #[error(transparent)]
    Io(#[from] std::io::Error),
}

/// The longest axis of the centroids' extent.
fn axis_of(lo: Vec3, hi: Vec3) -> usize {
    let extent = hi - lo;
    if extent.x >= extent.y && extent.x >= extent.z {
        0
    } else if extent.y >= extent.z {
        1
    } else {
        2
    }
}

/// A record's place in the median's order: its centroid's coordinate
/// (f32 bits turned to sort as `total_cmp` does), then its index.
fn key(r: &Rec, positions: &[Vec3], axis: usize) -> u64 {
    let bits = r.centroid(positions)[axis].to_bits();
    let ordered = if bits >> 31 == 1 {
        !bits
    } else {
        bits | 1 << 31
    };
    (ordered as u64) << 32 | r.index as u64
}

fn extent(recs: impl Iterator<Item = Vec3>) -> (Vec3, Vec3) {
    recs.fold(
        (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
        |(lo, hi), c| (lo.min(c), hi.max(c)),
    )
}

fn split_in_memory(positions: &[Vec3], mut recs: Vec<Rec>, half: usize) -> [Items; 2] {
    let (lo, hi) = extent(recs.iter().map(|r| r.centroid(positions)));
    let axis = axis_of(lo, hi);
    recs.select_nth_unstable_by_key(half, |r| key(r, positions, axis));
    let upper = recs.split_off(half);
    [Items::Memory(recs), Items::Memory(upper)]
}

/// Streams a cell file's records.
fn each(path: &Path, mut f: impl FnMut(Rec)) -> std::io::Result<()> {
    let mut reader = BufReader::with_capacity(1 << 20, std::fs::File::open(path)?);
    let mut buf = [0u8; REC_BYTES * 4096];
    loop {
        let mut filled = 0;
        while filled < buf.len() {
            match reader.read(&mut buf[filled..])? {
                0 => break,
                n => filled += n,
            }
        }
        if filled % REC_BYTES != 0 {
            return Err(std::io::Error::other(format!(
                "{}: a cell file cut short",
                path.display()
            )));
        }
        buf[..filled]
            .chunks_exact(REC_BYTES)
            .for_each(|b| f(Rec::from_bytes(b)));
        if filled < buf.len() {
            return Ok(());
        }
    }
}

fn load(items: Items) -> std::io::Result<Vec<Rec>> {
    match items {
        Items::Memory(r) => Ok(r),
        Items::Disk { path, count } => {
            let mut recs = Vec::with_capacity(count);
            each(&path, |r| recs.push(r))?;
            std::fs::remove_file(&path)?;
            Ok(recs)
        }
    }
}

/// Writes records to a new cell file, returning its items.
pub struct CellWriter {
    path: PathBuf,
    out: BufWriter<std::fs::File>,
    count: usize,
}

impl CellWriter {
    pub fn create(path: PathBuf) -> std::io::Result<CellWriter> {
        let out = BufWriter::with_capacity(1 << 20, std::fs::File::create(&path)?);
        Ok(CellWriter {
            path,
            out,
            count: 0,
        })
    }

    pub fn push(&mut self, r: &Rec) -> std::io::Result<()> {
        self.count += 1;
        self.out.write_all(&r.bytes())
    }

    pub fn finish(mut self) -> std::io::Result<Items> {
        self.out.flush()?;
        Ok(Items::Disk {
            path: self.path,
            count: self.count,
        })
    }
}

/// The exact median split of a cell on disk: its extent, then the key of
/// rank `half` by four 16-bit radix passes, then the records below it to
/// one half and the rest to the other (in file order), each half to
/// memory when it fits.
fn split_on_disk(
    positions: &[Vec3],
    path: &Path,
    count: usize,
    half: usize,
    spill: &Spill,
    files: &mut usize,
) -> std::io::Result<[Items; 2]> {
    let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
    each(path, |r| {
        let c = r.centroid(positions);
        lo = lo.min(c);
        hi = hi.max(c);
    })?;
    let axis = axis_of(lo, hi);
    // The key of rank `half`: digit by digit from the top, counting only
    // the keys that share the digits found so far.
    let (mut prefix, mut rank) = (0u64, half);
    for pass in 0..4 {
        let shift = 48 - 16 * pass;
        let mut counts = vec![0usize; 1 << 16];
        each(path, |r| {
            let k = key(&r, positions, axis);
            if pass == 0 || k >> (shift + 16) == prefix >> (shift + 16) {
                counts[(k >> shift & 0xffff) as usize] += 1;
            }
        })?;
        let mut digit = 0;
        while rank >= counts[digit] {
            rank -= counts[digit];
            digit += 1;
        }
        prefix |= (digit as u64) << shift;
    }
    let median = prefix;
    let sides = [half, count - half];
    let mut out: Vec<Result<Vec<Rec>, CellWriter>> = Vec::with_capacity(2);
    for n in sides {
        out.push(if n <= spill.in_memory {
            Ok(Vec::with_capacity(n))
        } else {
            let dir = spill.dir.as_ref().ok_or_else(|| {
                std::io::Error::other("a cell larger than memory and no folder to spill it to")
            })?;
            *files += 1;
            Err(CellWriter::create(dir.join(format!("cell-{files}.bin")))?)
        });
    }
    let mut failed = None;
    each(path, |r| {
        let side = &mut out[usize::from(key(&r, positions, axis) >= median)];
        match side {
            Ok(v) => v.push(r),
            Err(w) => {
                if let Err(e) = w.push(&r) {
                    failed.get_or_insert(e);
                }
            }
        }
    })?;
    if let Some(e) = failed {
        return Err(e);
    }
    let mut halves = out.into_iter().map(|side| match side {
        Ok(v) => Ok(Items::Memory(v)),
        Err(w) => w.finish(),
    });
    let lower = halves.next().expect("two halves")?;
    let upper = halves.next().expect("two halves")?;
    Ok([lower, upper])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::builtins::icosphere;

    /// Every triangle in exactly one leaf, in input order, every leaf
    /// within the budget and at least half of it.
    #[test]
    fn leaves_cover_every_triangle_once_within_the_budget() {
        let mesh = icosphere(Vec3::ZERO, 1.0, 4);
        let budget = 300;
        let cells = partition(&mesh, budget);
        let mut seen = vec![0u32; mesh.triangles.len()];
        for c in &cells {
            if let Cell::Leaf(tris) = c {
                assert!(
                    tris.len() <= budget && 2 * tris.len() >= budget,
                    "{}",
                    tris.len()
                );
                assert!(tris.windows(2).all(|w| w[0] < w[1]), "input order");
                for t in tris {
                    seen[*t as usize] += 1;
                }
            }
        }
        assert!(seen.iter().all(|s| *s == 1));
        assert_eq!(partition(&mesh, budget), cells, "the same partition again");
    }

    /// Cells split on disk (any memory, down to a few records) give the
    /// partition made in memory, node for node; the spill folder is left
    /// empty.
    #[test]
    fn a_partition_on_disk_is_the_one_in_memory() {
        let mesh = icosphere(Vec3::ZERO, 1.0, 4);
        let budget = 300;
        let want = partition(&mesh, budget);
        for in_memory in [0, 700, 2000] {
            let dir = tempfile::tempdir().unwrap();
            let mut root = CellWriter::create(dir.path().join("root.bin")).unwrap();
            for (i, t) in mesh.triangles.iter().enumerate() {
                let r = Rec {
                    index: i as u32,
                    vertices: *t,
                };
                root.push(&r).unwrap();
            }
            let spill = Spill {
                dir: Some(dir.path().to_path_buf()),
                in_memory,
            };
            let mut got = Vec::new();
            let tree = split(
                &mesh.positions,
                root.finish().unwrap(),
                budget,
                &spill,
                &Progress::new(),
                |at, recs| {
                    got.push((at, recs.iter().map(|r| r.index).collect::<Vec<_>>()));
                    Ok(())
                },
            )
            .unwrap();
            assert_eq!(tree.len(), want.len());
            for (at, tris) in got {
                assert_eq!(want[at], Cell::Leaf(tris), "memory {in_memory}, node {at}");
            }
            for (i, kids) in tree.iter().enumerate() {
                if let Some(k) = kids {
                    assert_eq!(want[i], Cell::Split(*k));
                }
            }
            assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
        }
    }
}
