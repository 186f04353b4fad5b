//! Neighbouring faces made to share their boundary vertices.
//!
//! An IGES file has no topology: two faces meeting along an edge each carry their own trim
//! curve, sampled here independently, so their vertices differ and their chords miss each
//! other by up to the file's trim accuracy. Two steps make one welded mesh of them: every
//! boundary vertex that lies on another boundary's edge (within the weld distance, away from
//! that edge's ends) is inserted into that edge, so both sides carry the same vertices; then
//! vertices closer than the weld distance become one vertex at their mean.

use std::collections::HashMap;

use nalgebra::{Point2, Point3};

use super::FaceTriangles;
use super::trim::{BoundaryLoop, LoopVertex, chord_distance};
use crate::mesh::Mesh;
use crate::mesh::weld::weld;

/// Where a boundary vertex is: face, loop, index in the loop.
type VertexKey = (usize, usize, usize);

/// A uniform hash grid over points.
struct Grid {
    cell: f64,
    cells: HashMap<[i64; 3], Vec<u32>>,
}

impl Grid {
    fn new(cell: f64) -> Grid {
        Grid {
            cell,
            cells: HashMap::new(),
        }
    }
    fn key(&self, p: &Point3<f64>) -> [i64; 3] {
        [p.x, p.y, p.z].map(|c| (c / self.cell).floor() as i64)
    }
    fn insert(&mut self, p: &Point3<f64>, id: u32) {
        self.cells.entry(self.key(p)).or_default().push(id);
    }
    /// Ids in the 27 cells around `p`: every point within one cell size of `p`, and others.
    fn around(&self, p: &Point3<f64>, out: &mut Vec<u32>) {
        let [x, y, z] = self.key(p);
        for dx in -1..=1 {
            for dy in -1..=1 {
                for dz in -1..=1 {
                    if let Some(ids) = self.cells.get(&[x + dx, y + dy, z + dz]) {
                        out.extend_from_slice(ids);
                    }
                }
            }
        }
    }
}

/// Inserts into every boundary edge the boundary vertices (of any face, its own included) that
/// lie within `weld` of its interior and farther than `weld` from both its ends. Returns how
/// many were inserted.
pub(super) fn insert_junctions(faces: &mut [Vec<BoundaryLoop>], weld: f64) -> usize {
    let (with_junctions, total) = junctions_of(faces, weld);
    for (face, loops) in faces.iter_mut().zip(with_junctions) {
        *face = loops;
    }
    total
}

/// The loops with their junction vertices, and how many there are; found from the vertices as
/// they were, so the order in which edges are visited does not matter.
fn junctions_of(faces: &[Vec<BoundaryLoop>], weld: f64) -> (Vec<Vec<BoundaryLoop>>, usize) {
    let keys: Vec<VertexKey> = faces
        .iter()
        .enumerate()
        .flat_map(|(f, loops)| {
            loops
                .iter()
                .enumerate()
                .flat_map(move |(l, lp)| (0..lp.len()).map(move |i| (f, l, i)))
        })
        .collect();
    let position = |(f, l, i): VertexKey| faces[f][l][i].position;
    // Cells at least twice the weld distance: a segment walked in steps of half a cell has
    // every point within half a cell of a step, so within a cell of it lie all vertices
    // within `weld` of the segment.
    let cell = (4.0 * weld).max(0.5);
    let mut grid = Grid::new(cell);
    for (id, &k) in keys.iter().enumerate() {
        grid.insert(&position(k), id as u32);
    }
    let mut total = 0;
    let mut candidates = Vec::new();
    let mut inserts: Vec<(f64, Point3<f64>)> = Vec::new();
    let mut result = Vec::with_capacity(faces.len());
    for (f, loops) in faces.iter().enumerate() {
        let mut face_loops = Vec::with_capacity(loops.len());
        for (l, lp) in loops.iter().enumerate() {
            let n = lp.len();
            let mut out: BoundaryLoop = Vec::with_capacity(n);
            for i in 0..n {
                let (a, b) = (lp[i], lp[(i + 1) % n]);
                out.push(a);
                let ab = b.position - a.position;
                let length = ab.norm();
                if length <= 2.0 * weld {
                    continue;
                }
                candidates.clear();
                let steps = (length / (0.5 * cell)).ceil() as usize;
                for k in 0..=steps {
                    grid.around(
                        &(a.position + ab * (k as f64 / steps as f64)),
                        &mut candidates,
                    );
                }
                candidates.sort_unstable();
                candidates.dedup();
                inserts.clear();
                for &id in &candidates {
                    let key = keys[id as usize];
                    if key == (f, l, i) || key == (f, l, (i + 1) % n) {
                        continue;
                    }
                    let q = position(key);
                    let t = (q - a.position).dot(&ab) / (length * length);
                    if !(0.0..=1.0).contains(&t)
                        || (q - a.position).norm() <= weld
                        || (q - b.position).norm() <= weld
                        || chord_distance(&q, &a.position, &b.position) > weld
                    {
                        continue;
                    }
                    inserts.push((t, q));
                }
                inserts.sort_by(|x, y| x.0.total_cmp(&y.0));
                // One vertex per place: candidates from several faces meeting here weld anyway.
                let mut last: Option<Point3<f64>> = None;
                for &(t, q) in &inserts {
                    if last.is_some_and(|p| (p - q).norm() <= weld) {
                        continue;
                    }
                    last = Some(q);
                    out.push(LoopVertex {
                        uv: Point2::from(a.uv.coords * (1.0 - t) + b.uv.coords * t),
                        position: q,
                    });
                    total += 1;
                }
            }
            face_loops.push(out);
        }
        result.push(face_loops);
    }
    (result, total)
}

/// The welded boundary vertices: their positions, and for every face, loop and vertex the
/// index of the welded vertex it became. Vertices join the earliest (in face order) within
/// `weld_distance`, and a welded vertex sits at the mean of those that joined it, so that the
/// two sides of a seam the file gives a few micrometres apart each move by half of that.
pub(super) fn weld_boundaries(
    faces: &[Vec<BoundaryLoop>],
    weld_distance: f64,
) -> (Vec<Point3<f64>>, Vec<Vec<Vec<u32>>>) {
    let positions: Vec<Point3<f64>> = positions_of(faces).collect();
    let welded = weld(
        &Mesh {
            positions,
            triangles: Vec::new(),
        },
        weld_distance,
    );
    let mut next = welded.vertex_map.iter().copied();
    let ids = faces
        .iter()
        .map(|loops| {
            loops
                .iter()
                .map(|lp| next.by_ref().take(lp.len()).collect())
                .collect()
        })
        .collect();
    let mut sums = vec![(nalgebra::Vector3::zeros(), 0usize); welded.mesh.positions.len()];
    for (p, &k) in positions_of(faces).zip(&welded.vertex_map) {
        let slot = &mut sums[k as usize];
        slot.0 += p.coords;
        slot.1 += 1;
    }
    let positions = sums
        .into_iter()
        .map(|(sum, n)| Point3::from(sum / n.max(1) as f64))
        .collect();
    (positions, ids)
}

fn positions_of(faces: &[Vec<BoundaryLoop>]) -> impl Iterator<Item = Point3<f64>> + '_ {
    faces.iter().flatten().flatten().map(|v| v.position)
}

/// What sewing did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(super) struct Sewing {
    /// Open-edge vertices merged with another.
    pub merged_vertices: usize,
    /// Open edges split at a vertex of the other side.
    pub split_edges: usize,
    /// Widest gap closed, mm.
    pub widest_gap: f64,
}

/// Closes what welding left open where the file's faces miss each other by more than the
/// weld distance but less than `distance`: vertices of open edges within `distance` of each
/// other become one (at their mean), and an open edge with another open edge's vertex near
/// its middle is split there. Only open edges take part, so nothing already closed moves.
///
/// Only edges between boundary vertices (below `boundary_count`) can be open: a face's
/// interior vertices are surrounded by its own triangles.
pub(super) fn sew(mesh: &mut FaceTriangles, boundary_count: u32, distance: f64) -> Sewing {
    let mut sewing = Sewing::default();
    for _ in 0..2 {
        let open = open_edges(mesh, boundary_count);
        if open.is_empty() {
            break;
        }
        // Merge open vertices.
        let mut vertices: Vec<u32> = open.iter().flat_map(|(e, _)| *e).collect();
        vertices.sort_unstable();
        vertices.dedup();
        let points: Vec<Point3<f64>> = vertices
            .iter()
            .map(|&v| mesh.positions[v as usize])
            .collect();
        let welded = weld(
            &Mesh {
                positions: points.clone(),
                triangles: Vec::new(),
            },
            distance,
        );
        let mut groups: Vec<Vec<usize>> = vec![Vec::new(); welded.mesh.positions.len()];
        for (i, &k) in welded.vertex_map.iter().enumerate() {
            groups[k as usize].push(i);
        }
        let mut remap: HashMap<u32, u32> = HashMap::new();
        for group in groups.iter().filter(|g| g.len() > 1) {
            let mean = group
                .iter()
                .map(|&i| points[i].coords)
                .sum::<nalgebra::Vector3<f64>>()
                / group.len() as f64;
            let keep = vertices[group[0]];
            for &i in group {
                sewing.widest_gap = sewing.widest_gap.max((points[i] - points[group[0]]).norm());
                if i != group[0] {
                    remap.insert(vertices[i], keep);
                    sewing.merged_vertices += 1;
                }
            }
            mesh.positions[keep as usize] = Point3::from(mean);
        }
        for t in &mut mesh.triangles {
            for v in t.iter_mut() {
                if let Some(&k) = remap.get(v) {
                    *v = k;
                }
            }
        }
        mesh.drop_collapsed();

        // Split open edges at the other side's vertices.
        let open = open_edges(mesh, boundary_count);
        let mut open_vertices: Vec<u32> = open.iter().flat_map(|(e, _)| *e).collect();
        open_vertices.sort_unstable();
        open_vertices.dedup();
        let cell = (4.0 * distance).max(0.5);
        let mut grid = Grid::new(cell);
        for &q in &open_vertices {
            grid.insert(&mesh.positions[q as usize], q);
        }
        let mut splits: Vec<(usize, [u32; 2], u32)> = Vec::new();
        let mut candidates = Vec::new();
        for &([a, b], t) in &open {
            let (pa, pb) = (mesh.positions[a as usize], mesh.positions[b as usize]);
            let ab = pb - pa;
            let len2 = ab.norm_squared();
            if len2 <= 4.0 * distance * distance {
                continue;
            }
            candidates.clear();
            let steps = (len2.sqrt() / (0.5 * cell)).ceil() as usize;
            for k in 0..=steps {
                grid.around(&(pa + ab * (k as f64 / steps as f64)), &mut candidates);
            }
            candidates.sort_unstable();
            candidates.dedup();
            let mut best: Option<(f64, u32)> = None;
            for &q in &candidates {
                if q == a || q == b {
                    continue;
                }
                let pq = mesh.positions[q as usize];
                let s = (pq - pa).dot(&ab) / len2;
                let d = chord_distance(&pq, &pa, &pb);
                if (0.0..=1.0).contains(&s)
                    && d <= distance
                    && (pq - pa).norm() > distance
                    && (pq - pb).norm() > distance
                    && best.is_none_or(|(bd, _)| d < bd)
                {
                    best = Some((d, q));
                }
            }
            if let Some((d, q)) = best {
                sewing.widest_gap = sewing.widest_gap.max(d);
                splits.push((t, [a, b], q));
            }
        }
        // One split per triangle and pass; a second open side waits for the next pass.
        splits.sort_unstable();
        splits.dedup_by_key(|s| s.0);
        for &(t, [ea, eb], q) in &splits {
            let tri = mesh.triangles[t];
            // The corner where the open edge starts, in the triangle's own order.
            let Some(k) = (0..3).find(|&k| {
                let (x, y) = (tri[k], tri[(k + 1) % 3]);
                (x == ea && y == eb) || (x == eb && y == ea)
            }) else {
                continue;
            };
            let (x, y, z) = (k, (k + 1) % 3, (k + 2) % 3);
            let uv = mesh.corner_uv[t];
            let (px, py) = (
                mesh.positions[tri[x] as usize],
                mesh.positions[tri[y] as usize],
            );
            let along = px - py;
            let s = ((mesh.positions[q as usize] - py).dot(&along) / along.norm_squared())
                .clamp(0.0, 1.0);
            let uv_q = Point2::from(uv[y].coords + (uv[x].coords - uv[y].coords) * s);
            mesh.triangles[t] = [tri[x], q, tri[z]];
            mesh.corner_uv[t] = [uv[x], uv_q, uv[z]];
            mesh.triangles.push([q, tri[y], tri[z]]);
            mesh.corner_uv.push([uv_q, uv[y], uv[z]]);
            mesh.face_of_triangle.push(mesh.face_of_triangle[t]);
            sewing.split_edges += 1;
        }
    }
    sewing
}

/// Edges with one triangle: their vertices (in the triangle's order) and the triangle.
fn open_edges(mesh: &FaceTriangles, boundary_count: u32) -> Vec<([u32; 2], usize)> {
    let mut count: HashMap<[u32; 2], (usize, [u32; 2], usize)> = HashMap::new();
    for (t, tri) in mesh.triangles.iter().enumerate() {
        for k in 0..3 {
            let (a, b) = (tri[k], tri[(k + 1) % 3]);
            if a >= boundary_count || b >= boundary_count {
                continue;
            }
            let entry = count.entry([a.min(b), a.max(b)]).or_insert((0, [a, b], t));
            entry.0 += 1;
        }
    }
    let mut open: Vec<([u32; 2], usize)> = count
        .into_values()
        .filter(|(n, _, _)| *n == 1)
        .map(|(_, e, t)| (e, t))
        .collect();
    open.sort_unstable();
    open
}
