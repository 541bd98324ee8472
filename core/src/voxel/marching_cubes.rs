//! Marching cubes (§2 of the voxel paper, after Lorensen and Cline): the iso-density
//! surface of a filtered volume buffer as an indexed, watertight triangle mesh.
//!
//! The case table covers all 256 corner classifications, but instead of the classic
//! hand-written table (whose fixed choices in ambiguous faces leave cracks between
//! neighbouring cells) it is derived from face segments: on every cube face the
//! crossings are joined in pairs, and the segments of the six faces close into
//! oriented loops that are triangulated. An ambiguous face (two diagonal corners
//! inside) is resolved by the asymptotic decider, which reads only the four values of
//! that face in a fixed global order, so both cells sharing the face agree on it and
//! every interior mesh edge is used by exactly two triangles.

use std::sync::OnceLock;
use std::sync::atomic::{AtomicUsize, Ordering};

use glam::Vec3;
use rayon::prelude::*;

use crate::geom::{TriMesh, Volume};
use crate::progress::{Cancelled, Progress};

/// The iso value for densities in 0..=1 (§4: "an isodensity of 0.5").
pub const DENSITY_ISO: f32 = 0.5;

/// The 12 cube edges as (lower corner, axis); the upper corner is `lower + 1 << axis`.
/// Cube corner `i` sits at offset `(i & 1, i >> 1 & 1, i >> 2 & 1)`.
const EDGES: [(usize, usize); 12] = [
    (0, 0),
    (2, 0),
    (4, 0),
    (6, 0),
    (0, 1),
    (1, 1),
    (4, 1),
    (5, 1),
    (0, 2),
    (1, 2),
    (2, 2),
    (3, 2),
];

fn edge_between(a: usize, b: usize) -> usize {
    let (lo, hi) = (a.min(b), a.max(b));
    let axis = (hi - lo).trailing_zeros() as usize;
    EDGES
        .iter()
        .position(|&e| e == (lo, axis))
        .expect("corners of a cube edge")
}

/// Corners of face `f` (normal axis `f / 2`, side `f % 2`) in the face's canonical
/// order: (u0v0, u1v0, u1v1, u0v1) with u < v the two other axes. Both cells that
/// share the face list its values in this same order.
fn face_corners(f: usize) -> [usize; 4] {
    let (k, side) = (f / 2, f % 2);
    let (u, v) = match k {
        0 => (1, 2),
        1 => (0, 2),
        _ => (0, 1),
    };
    let base = side << k;
    [base, base | 1 << u, base | 1 << u | 1 << v, base | 1 << v]
}

/// Face corners in counter-clockwise order seen from outside the cube.
fn face_corners_ccw(f: usize) -> [usize; 4] {
    let c = face_corners(f);
    // (u, v, k) is a right-handed cycle for k = x and k = z, so the canonical order
    // runs counter-clockwise around +k; the outward normal is +k on side 1.
    let ccw_around_plus_k = f / 2 != 1;
    if ccw_around_plus_k == (f % 2 == 1) {
        c
    } else {
        [c[3], c[2], c[1], c[0]]
    }
}

/// Bit mask of the faces an edge lies on.
fn edge_faces(e: usize) -> u8 {
    let (lo, axis) = EDGES[e];
    let hi = lo | 1 << axis;
    (0..6)
        .filter(|&f| {
            let c = face_corners(f);
            c.contains(&lo) && c.contains(&hi)
        })
        .fold(0, |m, f| m | 1 << f)
}

/// Faces whose corners alternate inside/outside around the face.
fn ambiguous_faces(case: usize) -> u8 {
    (0..6)
        .filter(|&f| {
            let c = face_corners(f).map(|i| case >> i & 1);
            c[0] == c[2] && c[1] == c[3] && c[0] != c[1]
        })
        .fold(0, |m, f| m | 1 << f)
}

/// Triangles of one configuration. Vertex slots 0..12 are crossings on the cube
/// edges; slot `12 + j` is the centre of `centres[j]`, a loop whose fan would reuse
/// a pair of vertices that also share a face (and so a neighbouring cell).
#[derive(Debug, Clone, Default, PartialEq)]
struct CaseEntry {
    triangles: Vec<[u8; 3]>,
    centres: Vec<Vec<u8>>,
}

/// Builds the entry for corner classification `case` (bit i: corner i inside) and
/// face decisions `joined` (bit f: the inside corners of ambiguous face f connect).
fn build_entry(case: usize, joined: u8) -> CaseEntry {
    let inside = |i: usize| case >> i & 1 == 1;
    // next[e]: the crossing that follows the crossing on edge e in its loop.
    let mut next = [usize::MAX; 12];
    for f in 0..6 {
        let c = face_corners_ccw(f);
        // Crossings in counter-clockwise order; `up` when entering an inside corner.
        let mut crossings = Vec::with_capacity(4);
        for i in 0..4 {
            let (a, b) = (c[i], c[(i + 1) % 4]);
            if inside(a) != inside(b) {
                crossings.push((edge_between(a, b), inside(b)));
            }
        }
        let n = crossings.len();
        // With the surface normal towards the outside (lower density), each segment
        // runs from an "up" crossing to a "down" one. Two inside corners across a
        // diagonal are cut off separately by pairing each up crossing with the next
        // down crossing, or joined by pairing it with the previous one.
        let step = if n == 4 && joined >> f & 1 == 1 {
            n - 1
        } else {
            1
        };
        for i in 0..n {
            if crossings[i].1 {
                let down = crossings[(i + step) % n];
                debug_assert!(!down.1);
                next[crossings[i].0] = down.0;
            }
        }
    }
    let faces: [u8; 12] = std::array::from_fn(edge_faces);
    let mut entry = CaseEntry::default();
    let mut seen = [false; 12];
    for start in 0..12 {
        if next[start] == usize::MAX || seen[start] {
            continue;
        }
        let mut ring = Vec::new();
        let mut e = start;
        while !seen[e] {
            seen[e] = true;
            ring.push(e as u8);
            e = next[e];
        }
        let n = ring.len();
        // A fan apex whose diagonals never join two crossings of one face: such a
        // diagonal could also appear in the neighbouring cell.
        let apex = (0..n).find(|&a| {
            (2..n - 1).all(|i| faces[ring[a] as usize] & faces[ring[(a + i) % n] as usize] == 0)
        });
        match apex {
            Some(a) => {
                for i in 1..n - 1 {
                    entry
                        .triangles
                        .push([ring[a], ring[(a + i) % n], ring[(a + i + 1) % n]]);
                }
            }
            None => {
                let centre = 12 + entry.centres.len() as u8;
                for i in 0..n {
                    entry.triangles.push([centre, ring[i], ring[(i + 1) % n]]);
                }
                entry.centres.push(ring);
            }
        }
    }
    entry
}

/// The case table: entry `case | joined << 8`, filled for the `joined` bits of
/// ambiguous faces only (other bits are masked off before lookup).
struct CaseTable {
    ambiguous: [u8; 256],
    /// Bit e: cube edge e joins an inside and an outside corner.
    crossings: [u16; 256],
    entries: Vec<CaseEntry>,
}

fn table() -> &'static CaseTable {
    static TABLE: OnceLock<CaseTable> = OnceLock::new();
    TABLE.get_or_init(|| {
        let ambiguous: [u8; 256] = std::array::from_fn(ambiguous_faces);
        let mut entries = vec![CaseEntry::default(); 256 * 64];
        for case in 1..255 {
            let amb = ambiguous[case];
            for joined in 0..64u8 {
                if joined & !amb == 0 {
                    entries[case | (joined as usize) << 8] = build_entry(case, joined);
                }
            }
        }
        let crossings = std::array::from_fn(|case| {
            EDGES.iter().enumerate().fold(0, |m, (e, &(lo, axis))| {
                let crosses = (case >> lo & 1) != (case >> (lo | 1 << axis) & 1);
                m | (crosses as u16) << e
            })
        });
        CaseTable {
            ambiguous,
            crossings,
            entries,
        }
    })
}

/// Side bits of a row of samples: some sample inside (≥ iso), some outside.
const INSIDE: u8 = 1;
const OUTSIDE: u8 = 2;
const MIXED: u8 = INSIDE | OUTSIDE;

/// Corner `i` of a cell reads sample row `i >> 1` of its four rows (y, z offsets
/// (0,0), (1,0), (0,1), (1,1)); `SPREAD` moves the four rows' bits at one x to the
/// even case bits, so `SPREAD[col(x)] | SPREAD[col(x + 1)] << 1` is the case.
const SPREAD: [u8; 16] = {
    let mut t = [0u8; 16];
    let mut c = 0;
    while c < 16 {
        t[c] = (c & 1 | (c & 2) << 1 | (c & 4) << 2 | (c & 8) << 3) as u8;
        c += 1;
    }
    t
};

/// Edge crossings of one grid plane z = k: x- and y-edges in the plane and z-edges
/// from it to the next, with keys `(y * nx + x) * 3 + axis` in increasing order and
/// a sentinel key after the last. Row y's crossings start at `row_start[y]`, so a
/// cell finds its crossings with a forward-only cursor instead of a search.
struct PlaneCrossings {
    row_start: Vec<u32>,
    keys: Vec<u64>,
    positions: Vec<Vec3>,
}

/// A forward-only reader of one row's crossings, advanced as cells move along x.
struct RowCursor<'a> {
    /// The plane's keys and positions from the row's first crossing on.
    keys: &'a [u64],
    positions: &'a [Vec3],
    /// Global vertex index of `keys[0]`.
    base: u32,
    at: usize,
}

impl RowCursor<'_> {
    /// The vertex and position of the crossing `key` of the cell whose keys start
    /// at `floor`. Keys below `floor` are passed for good, so cells are visited in
    /// increasing x; a cell's up to six keys on the row follow one another.
    fn find(&mut self, floor: u64, key: u64) -> (u32, Vec3) {
        while self.keys[self.at] < floor {
            self.at += 1;
        }
        let i = self.at
            + self.keys[self.at..]
                .iter()
                .take(6)
                .position(|&k| k == key)
                .expect("a crossing of this cell");
        (self.base + i as u32, self.positions[i])
    }
}

/// Triangles of one layer of cells; indices with `CENTRE` set point into `centres`.
struct LayerTriangles {
    triangles: Vec<[u32; 3]>,
    centres: Vec<Vec3>,
}

const CENTRE: u32 = 1 << 31;

/// Extracts the iso-surface `value = iso` of `volume` (corners with value ≥ iso are
/// inside). Normals point towards lower values; a volume whose border samples are
/// all below `iso` gives a closed, edge-manifold mesh. Runs in parallel over z
/// slabs; vertices are numbered by plane and grid-edge order, so the result is
/// deterministic. Rows of samples entirely on one side are classified once and
/// skipped, so empty space costs one comparison per sample.
pub fn marching_cubes(
    volume: &Volume,
    iso: f32,
    progress: &Progress,
) -> Result<TriMesh, Cancelled> {
    let [nx, ny, nz] = volume.dims;
    if nx < 2 || ny < 2 || nz < 2 {
        return Ok(TriMesh::default());
    }
    progress.stage("marching cubes");
    let table = table();
    let data = &volume.data;
    let row = |r: usize| &data[r * nx..(r + 1) * nx];
    let point = |x: usize, y: usize, z: usize| {
        volume.origin + volume.spacing * Vec3::new(x as f32, y as f32, z as f32)
    };
    let done = AtomicUsize::new(0);
    let total = (2 * nz - 1) as f32;
    let tick = || {
        let d = done.fetch_add(1, Ordering::Relaxed) + 1;
        progress.set_fraction(d as f32 / total);
    };

    // Row r = y + ny * z: which sides of the iso level its samples lie on.
    let sides: Vec<u8> = data
        .par_chunks(nx)
        .map(|samples| {
            samples
                .iter()
                .fold(0, |s, &v| s | if v >= iso { INSIDE } else { OUTSIDE })
        })
        .collect();

    let planes: Vec<PlaneCrossings> = (0..nz)
        .into_par_iter()
        .map(|z| {
            progress.check()?;
            let mut plane = PlaneCrossings {
                row_start: Vec::with_capacity(ny + 1),
                keys: Vec::new(),
                positions: Vec::new(),
            };
            for y in 0..ny {
                plane.row_start.push(plane.keys.len() as u32);
                let r = y + ny * z;
                let row_key = (y * nx * 3) as u64;
                // A grid edge can cross only between rows that are not all on one side.
                let along = [
                    (sides[r] == MIXED).then_some(r),
                    (y + 1 < ny && sides[r] | sides[r + 1] == MIXED).then_some(r + 1),
                    (z + 1 < nz && sides[r] | sides[r + ny] == MIXED).then_some(r + ny),
                ];
                if along.iter().all(Option::is_none) {
                    continue;
                }
                for (x, &v0) in row(r).iter().enumerate() {
                    for (axis, other) in along.iter().enumerate() {
                        let Some(other) = *other else { continue };
                        let (x1, y1, z1) = match axis {
                            0 if x + 1 < nx => (x + 1, y, z),
                            0 => continue,
                            1 => (x, y + 1, z),
                            _ => (x, y, z + 1),
                        };
                        let v1 = row(other)[x1];
                        if (v0 >= iso) != (v1 >= iso) {
                            // Clamped so vertices of different edges stay apart when
                            // a sample equals the iso value exactly.
                            let t = ((iso - v0) / (v1 - v0)).clamp(1e-4, 1.0 - 1e-4);
                            plane.keys.push(row_key + (x * 3 + axis) as u64);
                            plane
                                .positions
                                .push(point(x, y, z).lerp(point(x1, y1, z1), t));
                        }
                    }
                }
            }
            plane.row_start.push(plane.keys.len() as u32);
            // Above every key, so a cursor stops at the end of the plane.
            plane.keys.push(u64::MAX);
            tick();
            Ok(plane)
        })
        .collect::<Result<_, Cancelled>>()?;
    let mut plane_offset = Vec::with_capacity(nz + 1);
    let mut edge_vertices = 0u32;
    plane_offset.push(edge_vertices);
    for p in &planes {
        edge_vertices += p.positions.len() as u32;
        plane_offset.push(edge_vertices);
    }

    let layers: Vec<LayerTriangles> = (0..nz - 1)
        .into_par_iter()
        .map(|z| {
            progress.check()?;
            let mut out = LayerTriangles {
                triangles: Vec::new(),
                centres: Vec::new(),
            };
            let mut slots = [0u32; 12];
            let mut slot_positions = [Vec3::ZERO; 12];
            let row_key = |r: usize| ((r % ny) * nx * 3) as u64;
            for y in 0..ny - 1 {
                // The cell row's four sample rows, in corner order (i >> 1).
                let r = y + ny * z;
                let rows = [r, r + 1, r + ny, r + ny + 1];
                if rows.iter().fold(0, |s, &r| s | sides[r]) != MIXED {
                    continue;
                }
                let samples = rows.map(row);
                let mut cursors = rows.map(|r| {
                    let plane = &planes[r / ny];
                    let start = plane.row_start[r % ny] as usize;
                    RowCursor {
                        keys: &plane.keys[start..],
                        positions: &plane.positions[start..],
                        base: plane_offset[r / ny] + start as u32,
                        at: 0,
                    }
                });
                let column =
                    |x: usize| (0..4).fold(0, |c, j| c | ((samples[j][x] >= iso) as usize) << j);
                let mut left = column(0);
                for x in 0..nx - 1 {
                    let right = column(x + 1);
                    let case = (SPREAD[left] | SPREAD[right] << 1) as usize;
                    left = right;
                    if case == 0 || case == 255 {
                        continue;
                    }
                    let amb = table.ambiguous[case];
                    let mut joined = 0u8;
                    if amb != 0 {
                        let values: [f32; 8] =
                            std::array::from_fn(|i| samples[i >> 1][x + (i & 1)]);
                        for f in 0..6 {
                            if amb >> f & 1 == 1 {
                                let [a, b, c, d] = face_corners(f).map(|i| values[i]);
                                // Asymptotic decider: the bilinear saddle of the face.
                                let saddle = (a * c - b * d) / (a + c - b - d);
                                joined |= ((saddle >= iso) as u8) << f;
                            }
                        }
                    }
                    let entry = &table.entries[case | (joined as usize) << 8];
                    let mut crossing = table.crossings[case];
                    while crossing != 0 {
                        let e = crossing.trailing_zeros() as usize;
                        crossing &= crossing - 1;
                        let (lo, axis) = EDGES[e];
                        let j = lo >> 1;
                        let key = row_key(rows[j]) + ((x + (lo & 1)) * 3 + axis) as u64;
                        (slots[e], slot_positions[e]) =
                            cursors[j].find(row_key(rows[j]) + (x * 3) as u64, key);
                    }
                    let centre_base = out.centres.len() as u32;
                    for ring in &entry.centres {
                        let sum: Vec3 = ring.iter().map(|&e| slot_positions[e as usize]).sum();
                        out.centres.push(sum / ring.len() as f32);
                    }
                    for t in &entry.triangles {
                        out.triangles.push(t.map(|s| {
                            if s < 12 {
                                slots[s as usize]
                            } else {
                                CENTRE | (centre_base + s as u32 - 12)
                            }
                        }));
                    }
                }
            }
            tick();
            Ok(out)
        })
        .collect::<Result<_, Cancelled>>()?;

    let mut positions = Vec::with_capacity(
        edge_vertices as usize + layers.iter().map(|l| l.centres.len()).sum::<usize>(),
    );
    for p in planes {
        positions.extend(p.positions);
    }
    let mut triangles = Vec::with_capacity(layers.iter().map(|l| l.triangles.len()).sum());
    for layer in layers {
        let base = positions.len() as u32;
        triangles.extend(layer.triangles.into_iter().map(|t| {
            t.map(|i| {
                if i & CENTRE != 0 {
                    base + (i & !CENTRE)
                } else {
                    i
                }
            })
        }));
        positions.extend(layer.centres);
    }
    Ok(TriMesh::new(positions, triangles))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::Topology;
    use crate::rng::Rng;

    fn volume(dims: [usize; 3], spacing: Vec3, origin: Vec3, f: impl Fn(Vec3) -> f32) -> Volume {
        let mut data = Vec::with_capacity(dims[0] * dims[1] * dims[2]);
        for z in 0..dims[2] {
            for y in 0..dims[1] {
                for x in 0..dims[0] {
                    data.push(f(origin + spacing * Vec3::new(x as f32, y as f32, z as f32)));
                }
            }
        }
        Volume {
            dims,
            spacing,
            origin,
            data,
        }
    }

    /// A smooth density: 1 deep inside, 0 outside, 0.5 on the surface `sd = 0`.
    fn density(sd: f32, width: f32) -> f32 {
        (0.5 - sd / width).clamp(0.0, 1.0)
    }

    fn signed_volume(m: &TriMesh) -> f64 {
        m.triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| m.positions[i as usize].as_dvec3());
                a.dot(b.cross(c)) / 6.0
            })
            .sum()
    }

    fn assert_closed_manifold(m: &TriMesh) -> Topology {
        let topo = Topology::of(m);
        assert_eq!(topo.boundary_loops, 0, "no cracks");
        assert_eq!(topo.non_manifold_edges, 0, "every edge in two triangles");
        assert_eq!(topo.inconsistent_edges, 0, "consistent orientation");
        topo
    }

    #[test]
    fn case_table_loops_close_and_match_classic_triangle_counts() {
        let t = table();
        // The classic cases without ambiguous faces, by a representative bit set
        // and the triangle count of the Lorensen–Cline table.
        for (case, tris) in [
            (0b0000_0001usize, 1),
            (0b0000_0011, 2),
            (0b1000_0001, 2),
            (0b0000_1110, 3),
            (0b0000_1111, 2),
            (0b0001_0111, 4),
            (0b0100_1101, 4),
        ] {
            assert_eq!(t.ambiguous[case], 0);
            for c in [case, 255 ^ case] {
                assert_eq!(t.entries[c].triangles.len(), tris, "case {c:#010b}");
                assert!(t.entries[c].centres.is_empty());
            }
        }
        // Joined ambiguous faces make long loops whose fans would need a diagonal
        // inside a face; those get a centre vertex.
        assert!(t.entries.iter().any(|e| !e.centres.is_empty()));
        for e in &t.entries {
            assert!(e.centres.iter().all(|ring| ring.len() >= 6));
        }
        // Every configuration: each crossing edge is used, and each triangle side
        // on a face boundary is matched in reverse by the complementary config.
        for case in 1..255usize {
            let amb = t.ambiguous[case];
            for joined in 0..64u8 {
                if joined & !amb != 0 {
                    continue;
                }
                let e = &t.entries[case | (joined as usize) << 8];
                let crossing = |k: usize| {
                    let (lo, axis) = EDGES[k];
                    (case >> lo & 1) != (case >> (lo | 1 << axis) & 1)
                };
                for k in 0..12 {
                    assert_eq!(t.crossings[case] >> k & 1 == 1, crossing(k));
                    let used = e.triangles.iter().any(|tri| tri.contains(&(k as u8)));
                    assert_eq!(used, crossing(k), "case {case:#b} edge {k}");
                }
                // Complement with the complementary face decisions flips orientation.
                let comp = &t.entries[(255 ^ case) | ((!joined & amb) as usize) << 8];
                let sides = |entry: &CaseEntry| {
                    let mut s: Vec<(u8, u8)> = entry
                        .triangles
                        .iter()
                        .flat_map(|t| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])])
                        .filter(|&(a, b)| {
                            a < 12 && b < 12 && edge_faces(a as usize) & edge_faces(b as usize) != 0
                        })
                        .collect();
                    s.sort();
                    s
                };
                let mut reversed: Vec<(u8, u8)> =
                    sides(comp).into_iter().map(|(a, b)| (b, a)).collect();
                reversed.sort();
                assert_eq!(sides(e), reversed, "case {case:#b} joined {joined:#b}");
            }
        }
    }

    #[test]
    fn random_noise_is_watertight_and_deterministic() {
        let mut rng = Rng::new(11);
        let n = 24;
        let mut vol = volume([n; 3], Vec3::ONE, Vec3::ZERO, |_| 0.0);
        for z in 1..n - 1 {
            for y in 1..n - 1 {
                for x in 1..n - 1 {
                    vol.data[x + n * (y + n * z)] = rng.f32();
                }
            }
        }
        let p = Progress::new();
        for iso in [0.3, 0.5, 0.7] {
            let m = marching_cubes(&vol, iso, &p).unwrap();
            assert!(m.triangles.len() > 5000);
            assert_closed_manifold(&m);
            assert_eq!(m, marching_cubes(&vol, iso, &p).unwrap(), "deterministic");
        }
    }

    #[test]
    fn sphere_density_gives_a_closed_genus_0_surface_of_the_right_area() {
        let r = 1.0f32;
        let n = 48;
        let h = 2.6 / (n - 1) as f32;
        let vol = volume([n; 3], Vec3::splat(h), Vec3::splat(-1.3), |p| {
            density(p.length() - r, 0.2)
        });
        let m = marching_cubes(&vol, DENSITY_ISO, &Progress::new()).unwrap();
        let topo = assert_closed_manifold(&m);
        assert_eq!(topo.components.len(), 1);
        assert_eq!(topo.genus, 0);
        let area = m.area() as f32;
        let exact = 4.0 * std::f32::consts::PI * r * r;
        assert!(
            (area - exact).abs() < 0.01 * exact,
            "area {area} vs {exact}"
        );
        // Outward normals: positive enclosed volume close to 4/3 π r³.
        let v = signed_volume(&m) as f32;
        assert!((v - exact / 3.0).abs() < 0.01 * exact / 3.0, "volume {v}");
        for p in &m.positions {
            assert!((p.length() - r).abs() < 0.01);
        }
    }

    #[test]
    fn torus_density_on_an_anisotropic_offset_grid_has_genus_1() {
        let (big, small) = (1.0f32, 0.35f32);
        let spacing = Vec3::new(0.05, 0.06, 0.04);
        let origin = Vec3::new(2.0, -3.0, 0.5);
        let dims = [56, 48, 28];
        let centre = origin + spacing * Vec3::new(27.5, 23.5, 13.5);
        let vol = volume(dims, spacing, origin, |p| {
            let q = p - centre;
            let ring = (glam::Vec2::new(q.x, q.y).length() - big).hypot(q.z);
            density(ring - small, 0.1)
        });
        let m = marching_cubes(&vol, DENSITY_ISO, &Progress::new()).unwrap();
        let topo = assert_closed_manifold(&m);
        assert_eq!(topo.components.len(), 1);
        assert_eq!(topo.genus, 1);
        let exact = 4.0 * std::f32::consts::PI.powi(2) * big * small;
        let area = m.area() as f32;
        assert!(
            (area - exact).abs() < 0.02 * exact,
            "area {area} vs {exact}"
        );
        assert!(signed_volume(&m) > 0.0);
    }

    #[test]
    fn cancelling_stops_extraction() {
        let vol = volume([8; 3], Vec3::ONE, Vec3::ZERO, |p| {
            density(p.distance(Vec3::splat(3.5)) - 2.0, 1.0)
        });
        let p = Progress::new();
        p.cancel();
        assert_eq!(marching_cubes(&vol, 0.5, &p), Err(Cancelled));
    }
}
