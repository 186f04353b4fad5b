//! The zero set of a [`Field`] as a closed triangle mesh: surface nets on a sparse narrow-band
//! grid. One vertex per cell the surface crosses, one quad per grid edge with a sign change
//! (the four cells around it), so the result is closed and consistently oriented by
//! construction and never folds: folds of a moved-vertex offset in concave regions simply do
//! not exist on a level set. Cells whose corner signs make two sheets meet in them (the
//! ambiguous patterns that leave naive surface nets with edges of four triangles and pinched
//! vertices) are resolved towards the inside first, so the surface is also a manifold.
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
    let mut corners = corner_values(field, &kept, h, keep + half_diagonal);
    let cells = cells_of(&kept);
    make_cells_manifold(&cells, &mut corners);
    surface_nets(&cells, &corners, h)
}

/// Every cell of the kept blocks, in block order.
fn cells_of(blocks: &[Key]) -> Vec<[i64; 3]> {
    blocks
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
        .collect()
}

/// Whether the corners in `mask` (bit i = corner i of [`CORNERS`]) are connected along the
/// cube's edges. Corner i's neighbours differ from it in one coordinate bit.
const fn corners_connected(mask: u8) -> bool {
    if mask == 0 {
        return true;
    }
    let mut reached = 1u8 << mask.trailing_zeros();
    loop {
        let mut grown = reached;
        let mut i = 0;
        while i < 8 {
            if reached & (1 << i) != 0 {
                grown |= (1 << (i ^ 1)) | (1 << (i ^ 2)) | (1 << (i ^ 4));
            }
            i += 1;
        }
        grown &= mask;
        if grown == reached {
            return reached == mask;
        }
        reached = grown;
    }
}

/// Sign patterns whose surface-nets vertex is a manifold disc: the inside corners and the
/// outside corners each connected. Both connected makes the sign changes one cycle around the
/// cube (a cut of a planar graph whose two sides are connected is a single dual cycle), which
/// also rules out a face with alternating signs (its edge would be shared by four quads).
const MANIFOLD_PATTERN: [bool; 256] = {
    let mut table = [false; 256];
    let mut mask = 0;
    while mask < 256 {
        table[mask] = corners_connected(mask as u8) && corners_connected(!(mask as u8));
        mask += 1;
    }
    table
};

/// Which corners of `cell` are inside (bit i = corner i of [`CORNERS`]) and where their values
/// are; `None` where a corner lies outside the kept blocks.
fn inside_mask(cell: [i64; 3], corners: &SortedValues<f64>) -> Option<(u8, [usize; 8])> {
    let mut mask = 0u8;
    let mut index = [0usize; 8];
    for (i, offset) in CORNERS.iter().enumerate() {
        index[i] = corners.index(add(cell, *offset))?;
        if inside(corners.values[index[i]]) {
            mask |= 1 << i;
        }
    }
    Some((mask, index))
}

/// Surface nets puts one vertex in each cell the surface crosses; where the signs at a cell's
/// corners make two sheets meet there (two diagonal inside corners, a face with alternating
/// signs) that vertex or its edges become non-manifold. Such ambiguities are resolved towards
/// the inside: the outside corner closest to the level set is taken in, which only grows the
/// region (conservative for a shape that must enclose the part; the verification still
/// measures the result), until every crossed cell has a manifold pattern. Each round takes in
/// at least one corner, so it ends; the rounds after the first look only at the cells around
/// the corners just taken in. Sorted corner lists keep the result independent of the threads.
fn make_cells_manifold(cells: &[[i64; 3]], corners: &mut SortedValues<f64>) {
    // Inside, but as close to the level set as a corner can be: the crossing is put at it.
    let taken_in = -f64::MIN_POSITIVE;
    let mut suspects: Vec<[i64; 3]> = cells.to_vec();
    loop {
        let snapshot = &*corners;
        let mut fixes: Vec<usize> = suspects
            .par_iter()
            .filter_map(|&cell| {
                let (mask, index) = inside_mask(cell, snapshot)?;
                if MANIFOLD_PATTERN[mask as usize] {
                    return None;
                }
                (0..8)
                    .filter(|i| mask & (1 << i) == 0)
                    .map(|i| index[i])
                    .min_by(|&a, &b| {
                        snapshot.values[a]
                            .total_cmp(&snapshot.values[b])
                            .then(a.cmp(&b))
                    })
            })
            .collect();
        if fixes.is_empty() {
            return;
        }
        fixes.sort_unstable();
        fixes.dedup();
        let mut next = Vec::with_capacity(fixes.len() * 8);
        for &corner in &fixes {
            corners.values[corner] = taken_in;
            let c = unpack(corners.keys[corner]);
            for offset in CORNERS {
                next.push(pack([c[0] - offset[0], c[1] - offset[1], c[2] - offset[2]]));
            }
        }
        next.sort_unstable();
        next.dedup();
        suspects = next.into_iter().map(unpack).collect();
    }
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

/// Surface nets over `cells` with corner values `corners`.
fn surface_nets(cells: &[[i64; 3]], corners: &SortedValues<f64>, h: f64) -> Result<Mesh, String> {
    let cell_vertex = |cell: [i64; 3]| -> Option<Point3> {
        let (mask, index) = inside_mask(cell, corners)?;
        if mask == 0 || mask == u8::MAX {
            return None;
        }
        let f = index.map(|i| corners.values[i]);
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

#[cfg(test)]
mod tests {
    use super::super::field::{Field, Term};
    use super::*;
    use crate::geom::Vector3;
    use crate::mesh::SurfaceDistance;
    use crate::mesh::fixtures::uv_sphere;

    /// The table against an independent count: walk the sign changes around the cube's faces
    /// (each face with two of them joins those two edges; a face with four is ambiguous) and
    /// count the cycles they close. Manifold means exactly one cycle and no ambiguous face.
    #[test]
    fn manifold_patterns_are_the_single_cycles() {
        const FACES: [[usize; 4]; 6] = [
            [0, 1, 3, 2],
            [4, 5, 7, 6],
            [0, 1, 5, 4],
            [2, 3, 7, 6],
            [0, 2, 6, 4],
            [1, 3, 7, 5],
        ];
        let edge_of = |a: usize, b: usize| {
            EDGES
                .iter()
                .position(|&(x, y)| (x, y) == (a.min(b), a.max(b)))
                .unwrap()
        };
        let mut manifold = 0;
        for (mask, &tabled) in MANIFOLD_PATTERN.iter().enumerate() {
            let inside = |c: usize| mask & (1 << c) != 0;
            let mut links: Vec<Vec<usize>> = vec![Vec::new(); 12];
            let mut ambiguous = false;
            for face in FACES {
                let crossed: Vec<usize> = (0..4)
                    .filter(|&i| inside(face[i]) != inside(face[(i + 1) % 4]))
                    .map(|i| edge_of(face[i], face[(i + 1) % 4]))
                    .collect();
                match crossed.len() {
                    0 => {}
                    2 => {
                        links[crossed[0]].push(crossed[1]);
                        links[crossed[1]].push(crossed[0]);
                    }
                    _ => ambiguous = true,
                }
            }
            let crossed_edges: Vec<usize> = (0..12).filter(|&e| !links[e].is_empty()).collect();
            let mut seen = [false; 12];
            let mut cycles = 0;
            for &start in &crossed_edges {
                if seen[start] {
                    continue;
                }
                cycles += 1;
                let mut stack = vec![start];
                while let Some(e) = stack.pop() {
                    if !std::mem::replace(&mut seen[e], true) {
                        stack.extend(&links[e]);
                    }
                }
            }
            let expected = mask == 0 || mask == 255 || (!ambiguous && cycles == 1);
            assert_eq!(tabled, expected, "pattern {mask:08b}");
            manifold += usize::from(expected);
        }
        // Not every pattern: the diagonal pairs and alternating faces must be left out.
        assert!(manifold < 256 && manifold > 100, "{manifold}");
    }

    /// Two spheres closer than a grid cell, side by side along a diagonal: corners in the gap
    /// are outside while the cells across it hold inside corners of both spheres, the patterns
    /// that make naive surface nets non-manifold. Resolved, the surface is a closed manifold whatever the lattice's
    /// phase, and it still holds both spheres.
    #[test]
    fn a_gap_narrower_than_a_cell_gives_a_manifold_surface() {
        let (radius, h) = (3.0, 0.4);
        let mut exercised = 0;
        for (step, gap) in [0.05, 0.1, 0.17, 0.23, 0.31].into_iter().enumerate() {
            // Along a diagonal, so that the gap's thin slab cuts the cells slantwise.
            let direction = Vector3::new(1.0, 0.9 + 0.02 * step as f64, 0.7).normalize();
            let shift = (radius + gap / 2.0) * direction;
            let sphere = uv_sphere(radius, 24, 48);
            let moved = |sign: f64| {
                let mut m = sphere.clone();
                for p in &mut m.positions {
                    *p += sign * shift;
                }
                m
            };
            let (left, right) = (moved(-1.0), moved(1.0));
            let surfaces = [SurfaceDistance::new(&left), SurfaceDistance::new(&right)];
            let field = Field {
                terms: surfaces
                    .iter()
                    .map(|surface| Term {
                        surface,
                        closed: true,
                        level: 0.0,
                    })
                    .collect(),
            };
            let mut seeds = left.positions.clone();
            seeds.extend_from_slice(&right.positions);
            let mesh = extract(&field, &seeds, h).unwrap();
            let topology = Topology::analyse(&mesh.triangles, mesh.positions.len());
            assert!(topology.is_closed_manifold(), "gap {gap}: {topology:?}");
            assert_eq!(topology.inconsistent_edges, 0, "gap {gap}");
            // Count what the fix had to do, from the raw corner signs of the same lattice.
            let blocks: Vec<Key> = {
                let mut b: Vec<Key> = mesh
                    .positions
                    .iter()
                    .map(|p| pack([p.x, p.y, p.z].map(|x| (x / (BLOCK as f64 * h)).floor() as i64)))
                    .collect();
                b.sort_unstable();
                b.dedup();
                b
            };
            let corners = corner_values(&field, &blocks, h, f64::INFINITY);
            exercised += cells_of(&blocks)
                .iter()
                .filter_map(|&c| inside_mask(c, &corners))
                .filter(|(mask, _)| !MANIFOLD_PATTERN[*mask as usize])
                .count();
            // Taking corners in stays local: the volume is the two spheres' to the surface
            // nets' chord error (a few per cent at 0.4 mm cells on 3 mm spheres).
            let (volume, spheres) = (mesh.signed_volume(), 2.0 * sphere.signed_volume());
            assert!(
                (volume - spheres).abs() <= 0.03 * spheres,
                "gap {gap}: {volume} against {spheres}"
            );
        }
        assert!(
            exercised > 0,
            "no ambiguous cell: the test does not exercise the fix"
        );
    }
}
