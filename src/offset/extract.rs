//! The zero set of a [`Field`] as a closed triangle mesh: surface nets on a sparse narrow-band
//! grid. One vertex per cell the surface crosses, one quad per grid edge with a sign change
//! (the four cells around it), so the result is closed and consistently oriented by
//! construction and never folds: folds of a moved-vertex offset in concave regions simply do
//! not exist on a level set.
//!
//! Only blocks of 4³ cells near the level set are visited. They are found by a breadth-first
//! walk from the blocks holding the surfaces' vertices through the tube around them, one
//! distance query per block centre: f is 1-Lipschitz, so a block whose centre is farther from
//! the level set than its half-diagonal (plus the reach of a sign-change edge) holds no cell
//! that matters. Every set is sorted before use: the output does not depend on the thread count.

use std::collections::HashSet;

use rayon::prelude::*;

use super::field::Field;
use crate::geom::Point3;
use crate::mesh::Mesh;
use crate::mesh::topology::Topology;

/// Cells per block edge.
const BLOCK: i64 = 4;
/// Lattice coordinates are packed 21 bits per axis.
const COORDINATE_LIMIT: i64 = 1 << 20;

type Key = u64;

fn pack(c: [i64; 3]) -> Key {
    let field = |x: i64| (x + COORDINATE_LIMIT) as u64;
    (field(c[0]) << 42) | (field(c[1]) << 21) | field(c[2])
}

fn unpack(k: Key) -> [i64; 3] {
    let mask = (1u64 << 21) - 1;
    [
        ((k >> 42) & mask) as i64 - COORDINATE_LIMIT,
        ((k >> 21) & mask) as i64 - COORDINATE_LIMIT,
        (k & mask) as i64 - COORDINATE_LIMIT,
    ]
}

fn add(a: [i64; 3], b: [i64; 3]) -> [i64; 3] {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

/// A sorted key set with values, looked up by binary search.
struct SortedValues<T> {
    keys: Vec<Key>,
    values: Vec<T>,
}

impl<T> SortedValues<T> {
    fn index(&self, c: [i64; 3]) -> Option<usize> {
        self.keys.binary_search(&pack(c)).ok()
    }
}

/// Extracts the zero set of `field` on the lattice of spacing `h` (anchored at the origin),
/// walking from the blocks that hold `seeds` (every vertex of every surface of the field).
pub(super) fn extract(field: &Field, seeds: &[Point3], h: f64) -> Result<Mesh, String> {
    if !(h.is_finite() && h > 0.0) {
        return Err(format!("grid spacing {h} mm is not positive"));
    }
    let block_size = BLOCK as f64 * h;
    let half_diagonal = block_size * 3f64.sqrt() / 2.0;
    // Every point of a cell around a sign-change edge is within √3·h of the level set, so the
    // centre of its block is within √3·h + half-diagonal: keep blocks within 3h + that.
    let keep = 3.0 * h + half_diagonal;
    let tube = keep + 2.0 * half_diagonal;
    let lattice = |p: &Point3| -> Result<[i64; 3], String> {
        let c = [p.x, p.y, p.z].map(|x| (x / block_size).floor());
        if c.iter()
            .all(|x| x.abs() < (COORDINATE_LIMIT / BLOCK - 2) as f64)
        {
            Ok(c.map(|x| x as i64))
        } else {
            Err(format!(
                "a point at ({}, {}, {}) mm is too far from the origin for a grid of {h} mm",
                p.x, p.y, p.z
            ))
        }
    };
    let centre = |b: [i64; 3]| {
        Point3::new(
            (b[0] as f64 + 0.5) * block_size,
            (b[1] as f64 + 0.5) * block_size,
            (b[2] as f64 + 0.5) * block_size,
        )
    };
    let mut frontier: Vec<Key> = seeds
        .iter()
        .map(|p| lattice(p).map(pack))
        .collect::<Result<_, _>>()?;
    frontier.sort_unstable();
    frontier.dedup();
    let mut visited: HashSet<Key> = frontier.iter().copied().collect();
    let mut kept: Vec<Key> = Vec::new();
    while !frontier.is_empty() {
        let judged: Vec<(bool, bool)> = frontier
            .par_iter()
            .map(|&k| {
                let c = centre(unpack(k));
                (
                    field.value(&c, keep).abs() <= keep,
                    field.tube_value(&c, tube) <= tube - half_diagonal,
                )
            })
            .collect();
        let mut next = Vec::new();
        for (&k, &(keep_it, in_tube)) in frontier.iter().zip(&judged) {
            if keep_it {
                kept.push(k);
            }
            if in_tube {
                let b = unpack(k);
                for dx in -1..=1 {
                    for dy in -1..=1 {
                        for dz in -1..=1 {
                            let n = add(b, [dx, dy, dz]);
                            if n.iter().any(|x| x.abs() >= COORDINATE_LIMIT / BLOCK - 2) {
                                return Err("the offset reaches the edge of the grid".into());
                            }
                            let nk = pack(n);
                            if visited.insert(nk) {
                                next.push(nk);
                            }
                        }
                    }
                }
            }
        }
        next.sort_unstable();
        frontier = next;
    }
    kept.sort_unstable();
    let corners = corner_values(field, &kept, h, keep + half_diagonal);
    surface_nets(&kept, &corners, h)
}

/// f at every corner of the kept blocks.
fn corner_values(field: &Field, blocks: &[Key], h: f64, reach: f64) -> SortedValues<f64> {
    let mut keys: Vec<Key> = Vec::with_capacity(blocks.len() * 125);
    for &b in blocks {
        let origin = unpack(b).map(|x| x * BLOCK);
        for i in 0..=BLOCK {
            for j in 0..=BLOCK {
                for k in 0..=BLOCK {
                    keys.push(pack(add(origin, [i, j, k])));
                }
            }
        }
    }
    keys.sort_unstable();
    keys.dedup();
    let values = keys
        .par_iter()
        .map(|&k| {
            let c = unpack(k);
            field.value(
                &Point3::new(c[0] as f64 * h, c[1] as f64 * h, c[2] as f64 * h),
                reach,
            )
        })
        .collect();
    SortedValues { keys, values }
}

/// The eight corner offsets of a cell, and its twelve edges as corner pairs.
const CORNERS: [[i64; 3]; 8] = [
    [0, 0, 0],
    [1, 0, 0],
    [0, 1, 0],
    [1, 1, 0],
    [0, 0, 1],
    [1, 0, 1],
    [0, 1, 1],
    [1, 1, 1],
];
const EDGES: [(usize, usize); 12] = [
    (0, 1),
    (2, 3),
    (4, 5),
    (6, 7),
    (0, 2),
    (1, 3),
    (4, 6),
    (5, 7),
    (0, 4),
    (1, 5),
    (2, 6),
    (3, 7),
];

fn inside(value: f64) -> bool {
    value < 0.0
}

/// Surface nets over the cells of `blocks` with corner values `corners`.
fn surface_nets(blocks: &[Key], corners: &SortedValues<f64>, h: f64) -> Result<Mesh, String> {
    let cell_vertex = |cell: [i64; 3]| -> Option<Point3> {
        let mut f = [0.0; 8];
        for (slot, offset) in f.iter_mut().zip(CORNERS) {
            *slot = corners.values[corners.index(add(cell, offset))?];
        }
        if f.iter().all(|&v| inside(v)) || f.iter().all(|&v| !inside(v)) {
            return None;
        }
        let mut sum = nalgebra::Vector3::zeros();
        let mut count = 0.0;
        for (a, b) in EDGES {
            if inside(f[a]) != inside(f[b]) {
                let s = f[a] / (f[a] - f[b]);
                let pa = add(cell, CORNERS[a]).map(|x| x as f64);
                let pb = add(cell, CORNERS[b]).map(|x| x as f64);
                sum += nalgebra::Vector3::from_fn(|i, _| pa[i] + s * (pb[i] - pa[i]));
                count += 1.0;
            }
        }
        Some(Point3::from(sum / count * h))
    };
    let cells: Vec<[i64; 3]> = blocks
        .iter()
        .flat_map(|&b| {
            let origin = unpack(b).map(|x| x * BLOCK);
            (0..BLOCK * BLOCK * BLOCK).map(move |n| {
                add(
                    origin,
                    [n % BLOCK, (n / BLOCK) % BLOCK, n / (BLOCK * BLOCK)],
                )
            })
        })
        .collect();
    let mut crossing: Vec<(Key, Point3)> = cells
        .par_iter()
        .filter_map(|&c| cell_vertex(c).map(|p| (pack(c), p)))
        .collect();
    crossing.sort_unstable_by_key(|&(k, _)| k);
    let vertices = SortedValues {
        keys: crossing.iter().map(|&(k, _)| k).collect(),
        values: crossing.iter().map(|&(_, p)| p).collect(),
    };
    let mut triangles = Vec::new();
    for &key in &vertices.keys {
        let p = unpack(key);
        let Some(fp) = corners.index(p).map(|i| corners.values[i]) else {
            continue;
        };
        for (a, b, c) in [(0, 1, 2), (1, 2, 0), (2, 0, 1)] {
            let mut step = [0; 3];
            step[a] = 1;
            let Some(fq) = corners.index(add(p, step)).map(|i| corners.values[i]) else {
                continue;
            };
            if inside(fp) == inside(fq) {
                continue;
            }
            let (mut eb, mut ec) = ([0; 3], [0; 3]);
            eb[b] = -1;
            ec[c] = -1;
            let around = [add(add(p, eb), ec), add(p, ec), p, add(p, eb)];
            let mut quad = [0u32; 4];
            for (slot, cell) in quad.iter_mut().zip(around) {
                *slot = vertices.index(cell).ok_or_else(|| {
                    "a sign change at the edge of the narrow band (grid too coarse for the \
                     surface)"
                        .to_string()
                })? as u32;
            }
            if !inside(fp) {
                quad.swap(1, 3);
            }
            let [qa, qb, qc, qd] = quad.map(|v| vertices.values[v as usize]);
            if (qa - qc).norm_squared() <= (qb - qd).norm_squared() {
                triangles.push([quad[0], quad[1], quad[2]]);
                triangles.push([quad[0], quad[2], quad[3]]);
            } else {
                triangles.push([quad[0], quad[1], quad[3]]);
                triangles.push([quad[1], quad[2], quad[3]]);
            }
        }
    }
    let mesh = Mesh {
        positions: vertices.values,
        triangles,
    };
    let topology = Topology::analyse(&mesh.triangles, mesh.positions.len());
    if topology.boundary_edges > 0 {
        return Err(format!(
            "the extracted surface has {} open edges (a sign change left the narrow band)",
            topology.boundary_edges
        ));
    }
    Ok(outer_components(mesh, &topology))
}

/// The components of a closed surface that bound the region from outside (positive volume).
/// A negative one is a cavity inside the part (where a pseudo-normal sign of a level surface
/// that touches itself went wrong, or a void of the part) that no cutter can reach.
fn outer_components(mesh: Mesh, topology: &Topology) -> Mesh {
    let centre = mesh.aabb().center();
    let mut volume = vec![0.0; topology.component_count];
    for (t, &c) in topology.face_component.iter().enumerate() {
        let [a, b, d] = mesh.corners(t);
        volume[c as usize] += (a - centre).dot(&(b - centre).cross(&(d - centre))) / 6.0;
    }
    let mut index = vec![u32::MAX; mesh.positions.len()];
    let mut positions = Vec::new();
    let mut triangles = Vec::new();
    for (t, tri) in mesh.triangles.iter().enumerate() {
        if volume[topology.face_component[t] as usize] <= 0.0 {
            continue;
        }
        triangles.push(tri.map(|v| {
            if index[v as usize] == u32::MAX {
                index[v as usize] = positions.len() as u32;
                positions.push(mesh.positions[v as usize]);
            }
            index[v as usize]
        }));
    }
    Mesh {
        positions,
        triangles,
    }
}
