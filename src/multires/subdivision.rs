//! Loop subdivision with boundaries, creases and corners (DESIGN.md §3.1; seed 004 eq. 5.1),
//! plus dihedral-angle crease detection.
//!
//! One level ([`loop_step`]) is the 1-to-4 split of [`crate::multires::split()`] with positions:
//! * odd vertex of an interior edge `(a, b)` with opposite vertices `c, d`:
//!   `(3a + 3b + c + d)/8`; of a crease or boundary edge: `(a + b)/2`;
//! * even vertex, by [`VertexClass`]: smooth of valence n: `(1 − nβ)v + βΣ neighbours`,
//!   `β = a(n)/n`, `a(n) = 5/8 − (3 + 2cos(2π/n))²/64` (Loop's original weights); crease or
//!   boundary with sharp neighbours `v₋, v₊`: `(v₋ + 6v + v₊)/8`; corner: stays.
//!
//! Each level costs O(V + T) (bucket-sorted edge table, no hashing) and is deterministic.

use std::borrow::Cow;

use nalgebra::{Point3, Vector3};
use thiserror::Error;

use super::split::{
    Creases, EdgeTable, NO_HALFEDGE, Split, VertexClass, classify, mark_sharp, normalized,
    split_triangles,
};
use crate::mesh::Mesh;

/// Why a mesh (or its crease list) cannot be Loop-subdivided.
#[derive(Clone, Debug, Error, PartialEq)]
pub enum SubdivisionError {
    /// A triangle refers to a vertex that does not exist.
    #[error(
        "triangle {triangle} refers to vertex {index}, but the mesh has {vertex_count} vertices"
    )]
    IndexOutOfRange {
        /// Triangle index.
        triangle: usize,
        /// The offending vertex index.
        index: u32,
        /// Number of vertices of the mesh.
        vertex_count: usize,
    },
    /// A triangle uses the same vertex twice.
    #[error("triangle {triangle} {vertices:?} repeats a vertex")]
    DegenerateTriangle {
        /// Triangle index.
        triangle: usize,
        /// Its vertex indices.
        vertices: [u32; 3],
    },
    /// An edge is shared by more than two triangles.
    #[error("non-manifold edge {edge:?}: shared by {faces} triangles (at most 2 allowed)")]
    NonManifoldEdge {
        /// The edge `[min, max]`.
        edge: [u32; 2],
        /// How many triangle sides lie on it (saturates at 255).
        faces: usize,
    },
    /// A listed crease is not an edge of the mesh.
    #[error("crease {edge:?} is not an edge of the mesh")]
    UnknownCrease {
        /// The crease `[min, max]`.
        edge: [u32; 2],
    },
    /// A vertex position is NaN or infinite.
    #[error("vertex {vertex} has a non-finite position")]
    NonFinitePosition {
        /// Vertex index.
        vertex: usize,
    },
    /// The subdivided level would not fit in `u32` indices.
    #[error(
        "level {level} would have {vertices} vertices and {triangles} triangles: too large for u32 indices"
    )]
    TooLarge {
        /// The level that does not fit (input = 0).
        level: u32,
        /// Its vertex count.
        vertices: usize,
        /// Its triangle count.
        triangles: usize,
    },
}

/// Subdivides `mesh` `levels` times with Loop's rules; `creases` (edges of `mesh`) stay sharp,
/// and so do boundary edges. Returns the finest mesh and its creases (each crease edge split
/// in two, see [`Creases`]). `levels = 0` validates and returns a copy.
///
/// Errors: see [`SubdivisionError`] (invalid input is never a panic).
pub fn loop_subdivide(
    mesh: &Mesh,
    creases: &Creases,
    levels: u32,
) -> Result<(Mesh, Creases), SubdivisionError> {
    if levels == 0 {
        let level = Level::new(mesh, creases, 0)?;
        return Ok((mesh.clone(), level.creases.into_owned()));
    }
    let (mut mesh, mut creases) = step(mesh, creases, 0)?;
    for level in 1..levels {
        (mesh, creases) = step(&mesh, &creases, level)?;
    }
    Ok((mesh, creases))
}

/// One level of Loop subdivision: returns level j+1 and its creases. The connectivity is
/// exactly [`crate::multires::split()`] of `mesh.triangles` (even vertices first, then one odd
/// vertex per sorted edge).
pub fn loop_step(mesh: &Mesh, creases: &Creases) -> Result<(Mesh, Creases), SubdivisionError> {
    step(mesh, creases, 0)
}

/// Detects creases: the interior edges whose two face normals make an angle greater than
/// `dihedral_angle_deg` degrees (0 = coplanar). Boundary and non-manifold edges, and edges of
/// triangles that are degenerate or refer to missing vertices, are never reported. If the two
/// faces of an edge are inconsistently oriented, one normal is flipped first. Never panics; a
/// NaN threshold reports nothing.
pub fn detect_creases(mesh: &Mesh, dihedral_angle_deg: f64) -> Creases {
    let threshold = dihedral_angle_deg.to_radians();
    // Keep only usable triangles, so that bad indices cannot blow up the edge table.
    let normal = |t: &[u32; 3]| -> Option<Vector3<f64>> {
        let p = |i: u32| mesh.positions.get(i as usize);
        let (a, b, c) = (p(t[0])?, p(t[1])?, p(t[2])?);
        (t[0] != t[1] && t[1] != t[2] && t[2] != t[0]).then(|| (b - a).cross(&(c - a)))
    };
    let (triangles, normals): (Vec<[u32; 3]>, Vec<Vector3<f64>>) = mesh
        .triangles
        .iter()
        .filter_map(|t| normal(t).map(|n| (*t, n)))
        .unzip();
    let table = EdgeTable::build(&triangles, mesh.positions.len());
    let mut edges = Vec::new();
    for (k, &[h0, h1]) in table.halfedges.iter().enumerate() {
        if table.face_count[k] != 2 {
            continue;
        }
        let (t0, t1) = (h0 as usize / 3, h1 as usize / 3);
        let mut n1 = normals[t1];
        // Consistent orientation: the two faces traverse the edge in opposite directions.
        let start = |h: u32| triangles[h as usize / 3][h as usize % 3];
        if start(h0) == start(h1) {
            n1 = -n1;
        }
        let n0 = normals[t0];
        let angle = n0.cross(&n1).norm().atan2(n0.dot(&n1));
        if angle > threshold {
            edges.push(table.edges[k]);
        }
    }
    Creases { edges }
}

/// A validated level: its edge table, sharp flags and normalized creases.
struct Level<'a> {
    table: EdgeTable,
    sharp: Vec<bool>,
    creases: Cow<'a, Creases>,
}

impl<'a> Level<'a> {
    /// Validates `mesh` and `creases` (indices, degeneracy, finiteness, manifold edges,
    /// crease existence, sizes) and builds the edge table.
    fn new(mesh: &Mesh, creases: &'a Creases, level: u32) -> Result<Self, SubdivisionError> {
        let vertex_count = mesh.positions.len();
        let too_large = SubdivisionError::TooLarge {
            level,
            vertices: vertex_count,
            triangles: mesh.triangles.len(),
        };
        if mesh.triangles.len() > (u32::MAX / 3) as usize || vertex_count > u32::MAX as usize {
            return Err(too_large);
        }
        for (triangle, t) in mesh.triangles.iter().enumerate() {
            if let Some(&index) = t.iter().find(|&&i| i as usize >= vertex_count) {
                return Err(SubdivisionError::IndexOutOfRange {
                    triangle,
                    index,
                    vertex_count,
                });
            }
            if t[0] == t[1] || t[1] == t[2] || t[2] == t[0] {
                return Err(SubdivisionError::DegenerateTriangle {
                    triangle,
                    vertices: *t,
                });
            }
        }
        if let Some(vertex) = mesh
            .positions
            .iter()
            .position(|p| !p.coords.iter().all(|x| x.is_finite()))
        {
            return Err(SubdivisionError::NonFinitePosition { vertex });
        }
        let table = EdgeTable::build(&mesh.triangles, vertex_count);
        if let Some(k) = table.face_count.iter().position(|&c| c > 2) {
            return Err(SubdivisionError::NonManifoldEdge {
                edge: table.edges[k],
                faces: table.face_count[k] as usize,
            });
        }
        let creases = normalized(creases);
        let (sharp, unknown) = mark_sharp(&table, &creases.edges);
        if let Some(&edge) = unknown.first() {
            return Err(SubdivisionError::UnknownCrease { edge });
        }
        Ok(Level {
            table,
            sharp,
            creases,
        })
    }
}

/// Loop's ring weight β(n) = a(n)/n, a(n) = 5/8 − (3 + 2cos(2π/n))²/64.
fn beta(n: u32) -> f64 {
    let n = f64::from(n);
    let c = 3.0 + 2.0 * (2.0 * std::f64::consts::PI / n).cos();
    (5.0 / 8.0 - c * c / 64.0) / n
}

/// One level; `level` only labels errors.
fn step(mesh: &Mesh, creases: &Creases, level: u32) -> Result<(Mesh, Creases), SubdivisionError> {
    let Level {
        table,
        sharp,
        creases,
    } = Level::new(mesh, creases, level)?;
    let p = &mesh.positions;
    let nv = p.len();
    let ne = table.edges.len();
    if nv + ne > u32::MAX as usize || mesh.triangles.len() > (u32::MAX / 12) as usize {
        return Err(SubdivisionError::TooLarge {
            level: level + 1,
            vertices: nv + ne,
            triangles: 4 * mesh.triangles.len(),
        });
    }

    // Even vertices: one pass over the edges for ring sums and valences.
    let mut ring = vec![Vector3::<f64>::zeros(); nv];
    let mut valence = vec![0u32; nv];
    for &[a, b] in &table.edges {
        let (a, b) = (a as usize, b as usize);
        ring[a] += p[b].coords;
        ring[b] += p[a].coords;
        valence[a] += 1;
        valence[b] += 1;
    }
    let classes = classify(nv, &table.edges, &sharp);
    let betas: Vec<f64> = (0..16).map(beta).collect();
    let mut positions: Vec<Point3<f64>> = Vec::with_capacity(nv + ne);
    for v in 0..nv {
        let pv = p[v];
        positions.push(match classes[v] {
            VertexClass::Smooth if valence[v] > 0 => {
                let n = valence[v];
                let b = betas.get(n as usize).copied().unwrap_or_else(|| beta(n));
                Point3::from(ring[v] * b + pv.coords * (1.0 - f64::from(n) * b))
            }
            VertexClass::Crease([l, r]) => {
                Point3::from((p[l as usize].coords + pv.coords * 6.0 + p[r as usize].coords) / 8.0)
            }
            VertexClass::Smooth | VertexClass::Corner => pv,
        });
    }

    // Odd vertices, in edge order.
    for (k, &[a, b]) in table.edges.iter().enumerate() {
        let (pa, pb) = (p[a as usize].coords, p[b as usize].coords);
        let [h0, h1] = table.halfedges[k];
        positions.push(if sharp[k] || h1 == NO_HALFEDGE {
            Point3::from((pa + pb) * 0.5)
        } else {
            let c = p[EdgeTable::opposite(&mesh.triangles, h0) as usize].coords;
            let d = p[EdgeTable::opposite(&mesh.triangles, h1) as usize].coords;
            Point3::from((pa + pb) * 0.375 + (c + d) * 0.125)
        });
    }

    let split = Split {
        coarse_vertices: nv,
        triangles: split_triangles(&mesh.triangles, &table.tri_edges, nv),
        edges: table.edges,
    };
    let fine_creases = split.fine_creases(&creases);
    Ok((
        Mesh {
            positions,
            triangles: split.triangles,
        },
        fine_creases,
    ))
}

#[cfg(test)]
mod tests {
    use nalgebra::{Rotation3, Translation3};

    use super::*;
    use crate::multires::split::EdgeTable;
    use crate::multires::test_meshes::{self, reference_obj};

    fn diagonal(m: &Mesh) -> f64 {
        let mut lo = Vector3::repeat(f64::INFINITY);
        let mut hi = Vector3::repeat(f64::NEG_INFINITY);
        for p in &m.positions {
            lo = lo.inf(&p.coords);
            hi = hi.sup(&p.coords);
        }
        (hi - lo).norm()
    }

    /// Signed volume (divergence theorem); positive for outward-oriented closed meshes.
    fn volume(m: &Mesh) -> f64 {
        m.triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| m.positions[i as usize].coords);
                a.dot(&b.cross(&c)) / 6.0
            })
            .sum()
    }

    /// Bijection `ours -> reference` by nearest neighbours within `tol`, or a message.
    fn match_points(ours: &[Point3<f64>], reference: &[Point3<f64>], tol: f64) -> Vec<u32> {
        assert_eq!(ours.len(), reference.len(), "vertex counts");
        let mut used = vec![false; reference.len()];
        let mut map = Vec::with_capacity(ours.len());
        for (i, p) in ours.iter().enumerate() {
            let (j, d) = reference
                .iter()
                .enumerate()
                .map(|(j, q)| (j, (p - q).norm()))
                .min_by(|a, b| a.1.total_cmp(&b.1))
                .unwrap();
            assert!(
                d <= tol,
                "vertex {i} {p:?}: nearest reference point {j} at {d:e} > {tol:e}"
            );
            assert!(!used[j], "reference point {j} matched twice");
            used[j] = true;
            map.push(j as u32);
        }
        map
    }

    /// Triangles as a sorted list, each rotated to start at its smallest index (keeps
    /// orientation).
    fn canonical(triangles: impl IntoIterator<Item = [u32; 3]>) -> Vec<[u32; 3]> {
        let mut v: Vec<[u32; 3]> = triangles
            .into_iter()
            .map(|t| {
                let s = (0..3).min_by_key(|&s| t[s]).unwrap();
                [t[s], t[(s + 1) % 3], t[(s + 2) % 3]]
            })
            .collect();
        v.sort_unstable();
        v
    }

    #[test]
    fn agrees_with_trimesh_subdivide_loop_on_closed_meshes() {
        for name in ["octahedron", "irregular", "torus"] {
            let input = reference_obj(&format!("{name}_input.obj"));
            let reference = reference_obj(&format!("{name}_loop2.obj"));
            let (ours, creases) = loop_subdivide(&input, &Creases::none(), 2).unwrap();
            assert!(creases.is_empty());
            assert_eq!(
                ours.triangles.len(),
                reference.triangles.len(),
                "{name}: triangles"
            );
            let tol = 1e-9 * diagonal(&reference);
            let map = match_points(&ours.positions, &reference.positions, tol);
            // Same connectivity up to the vertex relabelling, same orientation.
            let mapped = ours.triangles.iter().map(|t| t.map(|i| map[i as usize]));
            assert_eq!(
                canonical(mapped),
                canonical(reference.triangles.iter().copied()),
                "{name}"
            );
        }
    }

    /// Ordered vertices of the single boundary loop, starting at its smallest vertex.
    fn boundary_loop(m: &Mesh) -> Vec<u32> {
        let table = EdgeTable::build(&m.triangles, m.positions.len());
        let mut next = vec![u32::MAX; m.positions.len()];
        for (k, &[h, _]) in table.halfedges.iter().enumerate() {
            if table.face_count[k] == 1 {
                let t = m.triangles[h as usize / 3];
                let s = h as usize % 3;
                next[t[s] as usize] = t[(s + 1) % 3];
            }
        }
        let start = next.iter().position(|&n| n != u32::MAX).unwrap() as u32;
        let mut out = vec![start];
        let mut v = next[start as usize];
        while v != start {
            out.push(v);
            v = next[v as usize];
            assert!(out.len() <= m.positions.len(), "not a single loop");
        }
        out
    }

    /// Cubic B-spline subdivision of a closed polygon (the boundary rules in 1D).
    fn curve_step(p: &[Point3<f64>]) -> Vec<Point3<f64>> {
        let n = p.len();
        let mut out = Vec::with_capacity(2 * n);
        for i in 0..n {
            let (l, c, r) = (p[(i + n - 1) % n], p[i], p[(i + 1) % n]);
            out.push(Point3::from((l.coords + c.coords * 6.0 + r.coords) / 8.0));
            out.push(Point3::from((c.coords + r.coords) * 0.5));
        }
        out
    }

    #[test]
    fn planar_open_meshes_stay_planar_and_boundary_follows_the_curve_rule() {
        for mut mesh in [test_meshes::grid(4, 3, false), test_meshes::fan(7)] {
            // Lift interior vertices: the boundary must not notice.
            let mut lifted = mesh.clone();
            let interior: Vec<bool> = {
                let b = boundary_loop(&mesh);
                (0..mesh.positions.len() as u32)
                    .map(|v| !b.contains(&v))
                    .collect()
            };
            for (p, _) in lifted
                .positions
                .iter_mut()
                .zip(&interior)
                .filter(|(_, i)| **i)
            {
                p.z = 0.3;
            }
            let mut curve: Vec<Point3<f64>> = boundary_loop(&mesh)
                .iter()
                .map(|&v| mesh.positions[v as usize])
                .collect();
            let mut creases = Creases::none();
            for _ in 0..3 {
                let (fine, fc) = loop_step(&mesh, &creases).unwrap();
                let (fine_lifted, _) = loop_step(&lifted, &creases).unwrap();
                assert!(fine.positions.iter().all(|p| p.z == 0.0));
                curve = curve_step(&curve);
                let b = boundary_loop(&fine);
                assert_eq!(b, boundary_loop(&fine_lifted));
                assert_eq!(b.len(), curve.len());
                for (v, q) in b.iter().zip(&curve) {
                    let (p, pl) = (
                        fine.positions[*v as usize],
                        fine_lifted.positions[*v as usize],
                    );
                    assert!(
                        (p - q).norm() < 1e-12 && (pl - q).norm() < 1e-12,
                        "{p:?} vs {q:?}"
                    );
                }
                (mesh, creases) = (fine, fc);
                lifted = fine_lifted;
            }
        }
    }

    #[test]
    fn straight_boundary_of_square_grid_stays_on_its_line() {
        let (m, _) = loop_subdivide(&test_meshes::grid(4, 3, false), &Creases::none(), 4).unwrap();
        let b = boundary_loop(&m);
        let mut on_side = 0;
        for p in b.iter().map(|&v| m.positions[v as usize]) {
            // Away from the 4 corners (limit = cubic B-spline: straight where 4 control
            // points are collinear), the boundary is exactly on the square's sides.
            let mid_x = (1.0..=3.0).contains(&p.x);
            let mid_y = (1.0..=2.0).contains(&p.y);
            if mid_x && p.y < 0.5 {
                assert_eq!(p.y, 0.0, "{p:?}");
            } else if mid_x && p.y > 2.5 {
                assert_eq!(p.y, 3.0, "{p:?}");
            } else if mid_y && p.x < 0.5 {
                assert_eq!(p.x, 0.0, "{p:?}");
            } else if mid_y && p.x > 3.5 {
                assert_eq!(p.x, 4.0, "{p:?}");
            } else {
                continue;
            }
            on_side += 1;
        }
        // The straight stretches are 6 of the 14 units of perimeter.
        assert!(10 * on_side > 4 * b.len(), "{on_side} of {}", b.len());
    }

    /// trimesh's boundary vertex rule also sums boundary neighbours across interior edges;
    /// on a quad split along 0-2 it moves vertex 0 to (1/4, 1/4). Ours uses the two
    /// boundary-edge neighbours only: (1/8, 1/8).
    #[test]
    fn boundary_rule_differs_from_trimesh_on_quad_diagonal() {
        let quad = Mesh {
            positions: vec![
                Point3::new(0.0, 0.0, 0.0),
                Point3::new(1.0, 0.0, 0.0),
                Point3::new(1.0, 1.0, 0.0),
                Point3::new(0.0, 1.0, 0.0),
            ],
            triangles: vec![[0, 1, 2], [0, 2, 3]],
        };
        let (f, _) = loop_step(&quad, &Creases::none()).unwrap();
        assert_eq!(f.positions[0], Point3::new(0.125, 0.125, 0.0));
        assert_eq!(f.positions[1], Point3::new(0.875, 0.125, 0.0));
    }

    #[test]
    fn cube_with_creased_edges_stays_a_cube() {
        let cube = test_meshes::cube();
        let creases = detect_creases(&cube, 30.0);
        assert_eq!(creases, test_meshes::cube_edges());
        let levels = 3;
        let (m, fc) = loop_subdivide(&cube, &creases, levels).unwrap();
        assert_eq!(&m.positions[..8], &cube.positions[..], "corners move");
        assert_eq!(fc.len(), 12 << levels);
        // Faces stay planar: every vertex on the cube's surface.
        for p in &m.positions {
            let amax = p.coords.amax();
            assert!((amax - 1.0).abs() < 1e-12, "{p:?}");
        }
        // Edges stay straight: crease vertices have two coordinates exactly ±1.
        for &[a, b] in &fc.edges {
            for v in [a, b] {
                let p = m.positions[v as usize];
                let on = p.coords.iter().filter(|c| c.abs() == 1.0).count();
                assert!(on >= 2, "crease vertex {v} {p:?} left its cube edge");
            }
        }
        assert!((volume(&m) - 8.0).abs() < 1e-12);
        check_creases_are_edges(&m, &fc);
    }

    fn check_creases_are_edges(m: &Mesh, c: &Creases) {
        let table = EdgeTable::build(&m.triangles, m.positions.len());
        assert!(c.is_normalized());
        for e in &c.edges {
            assert!(
                table.edges.binary_search(e).is_ok(),
                "crease {e:?} not an edge"
            );
        }
    }

    #[test]
    fn regular_grid_reproduces_the_planar_lattice() {
        // An affine image of the regular (valence-6) grid in 3D.
        let n = 6;
        let grid = test_meshes::grid(n, n, true);
        let (o, u, w) = (
            Vector3::new(1.0, -2.0, 0.5),
            Vector3::new(0.8, 0.3, -0.2),
            Vector3::new(-0.1, 0.7, 0.4),
        );
        let at = |x: f64, y: f64| Point3::from(o + u * x + w * y);
        let mut lattice: Vec<(f64, f64)> = grid.positions.iter().map(|p| (p.x, p.y)).collect();
        let mut mesh = Mesh {
            positions: lattice.iter().map(|&(x, y)| at(x, y)).collect(),
            triangles: grid.triangles.clone(),
        };
        let normal = u.cross(&w).normalize();
        let nf = f64::from(n);
        let mut creases = Creases::none();
        for _ in 0..3 {
            let (fine, fc) = loop_step(&mesh, &creases).unwrap();
            let edges = EdgeTable::build(&mesh.triangles, mesh.positions.len()).edges;
            for &[a, b] in &edges {
                let (pa, pb) = (lattice[a as usize], lattice[b as usize]);
                lattice.push(((pa.0 + pb.0) / 2.0, (pa.1 + pb.1) / 2.0));
            }
            let mut exact = 0;
            for (p, &(x, y)) in fine.positions.iter().zip(&lattice) {
                assert!(
                    (p - Point3::from(o)).dot(&normal).abs() < 1e-12,
                    "off the plane"
                );
                // Only the 4 corners of the square (boundary crease vertices that turn)
                // move; their influence stays within 2 coarse cells.
                let near_corner = [(0.0, 0.0), (nf, 0.0), (0.0, nf), (nf, nf)]
                    .iter()
                    .any(|&(cx, cy)| (x - cx).abs() < 2.0 && (y - cy).abs() < 2.0);
                if !near_corner {
                    assert!(
                        (p - at(x, y)).norm() < 1e-12,
                        "{p:?} is not lattice point {x},{y}"
                    );
                    exact += 1;
                }
            }
            assert!(exact > fine.positions.len() / 2);
            (mesh, creases) = (fine, fc);
        }
    }

    #[test]
    fn octahedron_volume_shrinks_monotonically_and_converges() {
        let mut mesh = test_meshes::octahedron();
        let mut volumes = vec![volume(&mesh)];
        for _ in 0..6 {
            (mesh, _) = loop_step(&mesh, &Creases::none()).unwrap();
            volumes.push(volume(&mesh));
        }
        let d: Vec<f64> = volumes.windows(2).map(|w| w[0] - w[1]).collect();
        assert!(d.iter().all(|&d| d > 0.0), "not shrinking: {volumes:?}");
        assert!(
            d.windows(2).all(|w| w[1] < 0.4 * w[0]),
            "not converging: {volumes:?}"
        );
        // Vertex 0 converges to its limit position (1 − nχ)v + χΣvᵢ, χ = 1/(3/(8β) + n)
        // (Loop's limit mask, valence 4): x = 1 − 4χ.
        let chi = 1.0 / (3.0 / (8.0 * beta(4)) + 4.0);
        let limit = 1.0 - 4.0 * chi;
        let mut mesh = test_meshes::octahedron();
        let mut errors = Vec::new();
        for _ in 0..8 {
            (mesh, _) = loop_step(&mesh, &Creases::none()).unwrap();
            let p = mesh.positions[0];
            errors.push((p - Point3::new(limit, 0.0, 0.0)).norm());
        }
        assert!(errors.windows(2).all(|w| w[1] < 0.5 * w[0]), "{errors:?}");
        assert!(errors[7] < 1e-4, "{errors:?}");
    }

    #[test]
    fn equator_crease_on_octahedron_stays_in_its_plane() {
        let oct = test_meshes::octahedron();
        // Equator: the square 0-2-1-3 in z = 0.
        let creases = Creases::from_edges([[0, 2], [2, 1], [1, 3], [3, 0]]);
        let (m, fc) = loop_subdivide(&oct, &creases, 4).unwrap();
        assert_eq!(fc.len(), 4 << 4);
        check_creases_are_edges(&m, &fc);
        for &[a, b] in &fc.edges {
            assert_eq!(m.positions[a as usize].z, 0.0);
            assert_eq!(m.positions[b as usize].z, 0.0);
        }
        // Still symmetric about z = 0 (mirror pairs exist).
        let v = volume(&m);
        assert!(v > 0.0 && v < volume(&oct));
    }

    #[test]
    fn invariant_under_triangle_order_and_rotation() {
        let m = test_meshes::irregular_closed();
        let creases = Creases::from_edges([m.triangles[0].map(|i| i)[..2].try_into().unwrap()]);
        let (a, ca) = loop_subdivide(&m, &creases, 2).unwrap();
        let mut shuffled = m.clone();
        shuffled.triangles.reverse();
        for (i, t) in shuffled.triangles.iter_mut().enumerate() {
            t.rotate_left(i % 3);
        }
        let (b, cb) = loop_subdivide(&shuffled, &creases, 2).unwrap();
        // Odd numbering depends on sorted edges only: positions are bitwise equal.
        assert_eq!(a.positions, b.positions);
        assert_eq!(ca, cb);
        assert_eq!(canonical(a.triangles), canonical(b.triangles));
    }

    #[test]
    fn commutes_with_rigid_motions() {
        let m = test_meshes::irregular_closed();
        let iso = Translation3::new(3.0, -1.0, 2.0) * Rotation3::from_euler_angles(0.3, -1.1, 0.7);
        let moved = Mesh {
            positions: m.positions.iter().map(|p| iso * p).collect(),
            triangles: m.triangles.clone(),
        };
        let (a, _) = loop_subdivide(&m, &Creases::none(), 3).unwrap();
        let (b, _) = loop_subdivide(&moved, &Creases::none(), 3).unwrap();
        for (p, q) in a.positions.iter().zip(&b.positions) {
            assert!((iso * p - q).norm() < 1e-12);
        }
    }

    #[test]
    fn deterministic_and_levels_zero_is_identity() {
        let m = test_meshes::grid(3, 2, false);
        let c = Creases::from_edges([[5, 6]]);
        assert_eq!(loop_subdivide(&m, &c, 3), loop_subdivide(&m, &c, 3));
        let (same, c0) = loop_subdivide(&m, &c, 0).unwrap();
        assert_eq!((same, c0), (m.clone(), c.clone()));
        // Unsorted creases are normalized.
        let messy = Creases {
            edges: vec![[6, 5], [6, 5]],
        };
        assert_eq!(loop_subdivide(&m, &messy, 2), loop_subdivide(&m, &c, 2));
        assert_eq!(
            loop_subdivide(&Mesh::default(), &Creases::none(), 3),
            Ok((Mesh::default(), Creases::none()))
        );
    }

    #[test]
    fn isolated_and_corner_vertices_stay() {
        let mut m = test_meshes::fan(5);
        m.positions.push(Point3::new(9.0, 9.0, 9.0));
        let c = Creases::from_edges([[0, 1]]); // centre: 1 sharp edge -> corner
        let (f, _) = loop_subdivide(&m, &c, 2).unwrap();
        assert_eq!(f.positions[6], m.positions[6]);
        assert_eq!(f.positions[0], m.positions[0]);
    }

    #[test]
    fn bowtie_vertex_does_not_panic() {
        // Two triangles sharing only vertex 0: four boundary edges at 0 -> corner.
        let m = Mesh {
            positions: vec![
                Point3::origin(),
                Point3::new(1.0, 0.0, 0.0),
                Point3::new(1.0, 1.0, 0.0),
                Point3::new(-1.0, 0.0, 0.0),
                Point3::new(-1.0, -1.0, 0.0),
            ],
            triangles: vec![[0, 1, 2], [0, 3, 4]],
        };
        let (f, _) = loop_subdivide(&m, &Creases::none(), 2).unwrap();
        assert_eq!(f.positions[0], Point3::origin());
    }

    #[test]
    fn invalid_input_gives_errors_not_panics() {
        let oct = test_meshes::octahedron();
        let none = Creases::none();
        let mut m = oct.clone();
        m.triangles.push([0, 2, 3]); // edge [0,2] now has 3 faces
        let err = loop_subdivide(&m, &none, 1).unwrap_err();
        assert_eq!(
            err,
            SubdivisionError::NonManifoldEdge {
                edge: [0, 2],
                faces: 3
            }
        );
        assert!(err.to_string().contains("[0, 2]"), "{err}");
        let mut m = oct.clone();
        m.triangles[3] = [0, 1, 6];
        assert_eq!(
            loop_subdivide(&m, &none, 1),
            Err(SubdivisionError::IndexOutOfRange {
                triangle: 3,
                index: 6,
                vertex_count: 6
            })
        );
        let mut m = oct.clone();
        m.triangles[1] = [2, 2, 4];
        assert!(matches!(
            loop_subdivide(&m, &none, 1),
            Err(SubdivisionError::DegenerateTriangle { triangle: 1, .. })
        ));
        let mut m = oct.clone();
        m.positions[4].y = f64::NAN;
        assert_eq!(
            loop_step(&m, &none),
            Err(SubdivisionError::NonFinitePosition { vertex: 4 })
        );
        assert_eq!(
            loop_subdivide(&oct, &Creases::from_edges([[0, 1]]), 1),
            Err(SubdivisionError::UnknownCrease { edge: [0, 1] })
        );
        // u32::MAX index: no huge allocation, no panic.
        let m = Mesh {
            positions: vec![],
            triangles: vec![[0, 1, u32::MAX]],
        };
        assert!(loop_subdivide(&m, &none, 2).is_err());
        assert!(detect_creases(&m, 10.0).is_empty());
    }

    #[test]
    fn crease_detection() {
        let smooth = loop_subdivide(&test_meshes::octahedron(), &Creases::none(), 3)
            .unwrap()
            .0;
        assert!(detect_creases(&smooth, 30.0).is_empty());
        assert!(!detect_creases(&smooth, 1.0).is_empty());
        assert!(detect_creases(&test_meshes::cube(), f64::NAN).is_empty());
        // The octahedron's dihedral angle is 180° − 109.47° = 70.53° between normals.
        let oct = test_meshes::octahedron();
        assert_eq!(detect_creases(&oct, 70.0).len(), 12);
        assert!(detect_creases(&oct, 71.0).is_empty());
        // A flat grid with one flipped triangle: orientation is compensated.
        let mut g = test_meshes::grid(3, 3, false);
        g.triangles[4].swap(1, 2);
        assert!(detect_creases(&g, 1.0).is_empty());
        // A folded grid (z = |x − 1.5| roof): the ridge edges x = 1.5 ... none on a 3-wide
        // grid with vertices at integer x; fold at x = 1 instead.
        let mut g = test_meshes::grid(2, 2, true);
        for p in g.positions.iter_mut() {
            p.z = (p.x - 1.0).abs();
        }
        let c = detect_creases(&g, 10.0);
        assert_eq!(c.edges, vec![[1, 4], [4, 7]]);
    }
}
