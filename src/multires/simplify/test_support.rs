//! Test-only helpers: a tiny binary-STL reader with exact-bit welding, shape generators, and
//! invariant checks on meshes.

use std::collections::HashMap;

use nalgebra::{Point3, Vector3};

use super::topology::{self, Topology};
use crate::mesh::Mesh;

/// Welds triangle soup by exact bit equality of coordinates; drops triangles that collapse.
pub(crate) fn weld(soup: &[[Point3<f64>; 3]]) -> Mesh {
    let mut index: HashMap<[u64; 3], u32> = HashMap::new();
    let mut mesh = Mesh::default();
    for tri in soup {
        let ids = tri.map(|p| {
            let key = [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()];
            *index.entry(key).or_insert_with(|| {
                mesh.positions.push(p);
                (mesh.positions.len() - 1) as u32
            })
        });
        if ids[0] != ids[1] && ids[1] != ids[2] && ids[2] != ids[0] {
            mesh.triangles.push(ids);
        }
    }
    mesh
}

/// Reads a binary STL (80-byte header, u32 count, 50 bytes per facet) and welds it.
pub(crate) fn read_binary_stl(bytes: &[u8]) -> Option<Mesh> {
    let count = u32::from_le_bytes(bytes.get(80..84)?.try_into().ok()?) as usize;
    let mut soup = Vec::with_capacity(count);
    for k in 0..count {
        let rec = bytes.get(84 + 50 * k..84 + 50 * (k + 1))?;
        let f = |i: usize| {
            let o = 12 + 4 * i;
            f32::from_le_bytes([rec[o], rec[o + 1], rec[o + 2], rec[o + 3]]) as f64
        };
        soup.push([0, 1, 2].map(|v| Point3::new(f(3 * v), f(3 * v + 1), f(3 * v + 2))));
    }
    Some(close_seams(weld(&soup), 1e-9))
}

/// Merges boundary vertices closer than `tolerance` times the bounding-box diagonal (CAD
/// exports whose revolved seams differ in the last bits, e.g. y = 7e-16 against y = −1e-16),
/// then drops triangles that became degenerate. Unreferenced vertices stay.
pub(crate) fn close_seams(mut mesh: Mesh, tolerance: f64) -> Mesh {
    let mut directed: HashMap<(u32, u32), u32> = HashMap::new();
    for t in &mesh.triangles {
        for k in 0..3 {
            *directed.entry((t[k], t[(k + 1) % 3])).or_default() += 1;
        }
    }
    let mut boundary: Vec<u32> = directed
        .keys()
        .filter(|(a, b)| !directed.contains_key(&(*b, *a)))
        .flat_map(|&(a, b)| [a, b])
        .collect();
    boundary.sort_unstable();
    boundary.dedup();
    let (mut lo, mut hi) = (
        Vector3::repeat(f64::INFINITY),
        Vector3::repeat(f64::NEG_INFINITY),
    );
    for p in &mesh.positions {
        lo = lo.inf(&p.coords);
        hi = hi.sup(&p.coords);
    }
    let eps = tolerance * (hi - lo).norm();
    let mut target: Vec<u32> = (0..mesh.positions.len() as u32).collect();
    for (i, &a) in boundary.iter().enumerate() {
        for &b in &boundary[i + 1..] {
            if target[b as usize] == b
                && (mesh.positions[a as usize] - mesh.positions[b as usize]).norm() <= eps
            {
                target[b as usize] = target[a as usize];
            }
        }
    }
    mesh.triangles = mesh
        .triangles
        .iter()
        .map(|t| t.map(|v| target[v as usize]))
        .filter(|t| t[0] != t[1] && t[1] != t[2] && t[2] != t[0])
        .collect();
    mesh
}

/// Axis-aligned cube `[0, side]³`, each face an `n`×`n` grid, outward CCW.
pub(crate) fn cube_grid(n: usize, side: f64) -> Mesh {
    let mut soup = Vec::new();
    // (origin, u, v) with u × v outward.
    let faces: [([f64; 3], [f64; 3], [f64; 3]); 6] = [
        ([0.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0]), // z = 0, normal −z
        ([0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]), // z = 1, +z
        ([0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]), // y = 0, −y
        ([0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]), // y = 1, +y
        ([0.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, 1.0, 0.0]), // x = 0, −x
        ([1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]), // x = 1, +x
    ];
    for (o, u, v) in faces {
        let (o, u, v) = (Vector3::from(o), Vector3::from(u), Vector3::from(v));
        let p = |i: usize, j: usize| {
            // Integer grid steps, scaled once: exact welds on shared cube edges.
            let q = o * n as f64 + u * i as f64 + v * j as f64;
            Point3::from(q * (side / n as f64))
        };
        for i in 0..n {
            for j in 0..n {
                soup.push([p(i, j), p(i + 1, j), p(i + 1, j + 1)]);
                soup.push([p(i, j), p(i + 1, j + 1), p(i, j + 1)]);
            }
        }
    }
    weld(&soup)
}

/// Torus with radii `big` and `small`, `nu`×`nv` quads, outward CCW.
pub(crate) fn torus(big: f64, small: f64, nu: usize, nv: usize) -> Mesh {
    let idx = |i: usize, j: usize| ((i % nu) * nv + (j % nv)) as u32;
    let mut mesh = Mesh::default();
    for i in 0..nu {
        for j in 0..nv {
            let (u, v) = (
                std::f64::consts::TAU * i as f64 / nu as f64,
                std::f64::consts::TAU * j as f64 / nv as f64,
            );
            let r = big + small * v.cos();
            mesh.positions
                .push(Point3::new(r * u.cos(), r * u.sin(), small * v.sin()));
        }
    }
    for i in 0..nu {
        for j in 0..nv {
            let (a, b, c, d) = (idx(i, j), idx(i + 1, j), idx(i + 1, j + 1), idx(i, j + 1));
            mesh.triangles.push([a, b, c]);
            mesh.triangles.push([a, c, d]);
        }
    }
    mesh
}

/// Spherical cap (open disc) of sphere radius `r`, `rings` rings of `sectors` vertices,
/// boundary at polar angle `max_polar`. Vertex 0 is the pole; the last `sectors` vertices are
/// the boundary loop in CCW order (seen from +z).
pub(crate) fn spherical_cap(r: f64, max_polar: f64, rings: usize, sectors: usize) -> Mesh {
    let mut mesh = Mesh::default();
    mesh.positions.push(Point3::new(0.0, 0.0, r));
    for k in 1..=rings {
        let polar = max_polar * k as f64 / rings as f64;
        for s in 0..sectors {
            let az = std::f64::consts::TAU * s as f64 / sectors as f64;
            mesh.positions.push(Point3::new(
                r * polar.sin() * az.cos(),
                r * polar.sin() * az.sin(),
                r * polar.cos(),
            ));
        }
    }
    let ring = |k: usize, s: usize| (1 + (k - 1) * sectors + s % sectors) as u32;
    for s in 0..sectors {
        mesh.triangles.push([0, ring(1, s), ring(1, s + 1)]);
    }
    for k in 1..rings {
        for s in 0..sectors {
            let (a, b, c, d) = (
                ring(k, s),
                ring(k + 1, s),
                ring(k + 1, s + 1),
                ring(k, s + 1),
            );
            mesh.triangles.push([a, b, c]);
            mesh.triangles.push([a, c, d]);
        }
    }
    mesh
}

/// An `n`×`n` grid over the unit square mapped into 3-D by `map`, CCW seen from the side the
/// map's `∂x × ∂y` points to.
pub(crate) fn grid(n: usize, map: impl Fn(f64, f64) -> Point3<f64>) -> Mesh {
    let mut mesh = Mesh::default();
    for i in 0..=n {
        for j in 0..=n {
            mesh.positions
                .push(map(i as f64 / n as f64, j as f64 / n as f64));
        }
    }
    let id = |i: usize, j: usize| (i * (n + 1) + j) as u32;
    for i in 0..n {
        for j in 0..n {
            mesh.triangles
                .push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
            mesh.triangles
                .push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    mesh
}

/// Validates the mesh as the simplifier's input would be; panics on failure.
pub(crate) fn manifold(mesh: &Mesh) -> Topology {
    match topology::analyse(&mesh.triangles, mesh.positions.len()) {
        Ok(t) => t,
        Err(e) => panic!("not an oriented manifold: {e}"),
    }
}

/// Genus of a closed connected mesh from its Euler characteristic.
pub(crate) fn genus(mesh: &Mesh) -> i64 {
    let t = manifold(mesh);
    assert_eq!(t.component_count(), 1);
    assert_eq!(t.boundary_edge_count(), 0);
    (2 - t.euler_characteristic(&mesh.triangles)) / 2
}

/// Signed volume (positive for an outward-oriented closed mesh).
pub(crate) fn signed_volume(mesh: &Mesh) -> f64 {
    mesh.triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|v| mesh.positions[v as usize].coords);
            a.dot(&b.cross(&c)) / 6.0
        })
        .sum()
}

/// Boundary loops as vertex cycles (each follows the triangles' orientation).
pub(crate) fn boundary_loops(mesh: &Mesh) -> Vec<Vec<u32>> {
    let mut directed: HashMap<(u32, u32), usize> = HashMap::new();
    for t in &mesh.triangles {
        for k in 0..3 {
            *directed.entry((t[k], t[(k + 1) % 3])).or_default() += 1;
        }
    }
    let mut next: HashMap<u32, u32> = HashMap::new();
    for &(a, b) in directed.keys() {
        if !directed.contains_key(&(b, a)) {
            assert!(
                next.insert(a, b).is_none(),
                "boundary vertex {a} visited twice"
            );
        }
    }
    let mut starts: Vec<u32> = next.keys().copied().collect();
    starts.sort_unstable();
    let mut seen = std::collections::HashSet::new();
    let mut loops = Vec::new();
    for s in starts {
        if seen.contains(&s) {
            continue;
        }
        let mut cycle = vec![s];
        seen.insert(s);
        let mut v = next[&s];
        while v != s {
            cycle.push(v);
            seen.insert(v);
            v = next[&v];
        }
        loops.push(cycle);
    }
    loops
}

/// Distance from `p` to triangle `(a, b, c)` (Ericson, Real-Time Collision Detection §5.1.5).
pub(crate) fn point_triangle_distance(
    p: &Point3<f64>,
    a: &Point3<f64>,
    b: &Point3<f64>,
    c: &Point3<f64>,
) -> f64 {
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(&ap), ac.dot(&ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return (p - a).norm();
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(&bp), ac.dot(&bp));
    if d3 >= 0.0 && d4 <= d3 {
        return (p - b).norm();
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 / (d1 - d3);
        return (p - (a + ab * v)).norm();
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(&cp), ac.dot(&cp));
    if d6 >= 0.0 && d5 <= d6 {
        return (p - c).norm();
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return (p - (a + ac * w)).norm();
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return (p - (b + (c - b) * w)).norm();
    }
    let denom = 1.0 / (va + vb + vc);
    let (v, w) = (vb * denom, vc * denom);
    (p - (a + ab * v + ac * w)).norm()
}

/// Index of the triangle of `mesh` nearest to `p`, and the distance (brute force).
pub(crate) fn nearest_triangle(mesh: &Mesh, p: &Point3<f64>) -> (usize, f64) {
    let mut best = (usize::MAX, f64::INFINITY);
    for (t, tri) in mesh.triangles.iter().enumerate() {
        let [a, b, c] = tri.map(|v| mesh.positions[v as usize]);
        let d = point_triangle_distance(p, &a, &b, &c);
        if d < best.1 {
            best = (t, d);
        }
    }
    best
}

/// Unit normal of triangle `t` of `mesh` (zero vector if degenerate).
pub(crate) fn triangle_normal(mesh: &Mesh, t: usize) -> Vector3<f64> {
    let [a, b, c] = mesh.triangles[t].map(|v| mesh.positions[v as usize]);
    (b - a)
        .cross(&(c - a))
        .try_normalize(0.0)
        .unwrap_or_else(Vector3::zeros)
}

/// Generalised winding number of closed `mesh` at `p` (1 inside, 0 outside), from the
/// triangles' solid angles (Van Oosterom & Strackee 1983).
pub(crate) fn winding_number(mesh: &Mesh, p: &Point3<f64>) -> f64 {
    let mut total = 0.0;
    for tri in &mesh.triangles {
        let [a, b, c] = tri.map(|v| mesh.positions[v as usize] - p);
        let (la, lb, lc) = (a.norm(), b.norm(), c.norm());
        let det = a.dot(&b.cross(&c));
        let den = la * lb * lc + a.dot(&b) * lc + b.dot(&c) * la + c.dot(&a) * lb;
        total += 2.0 * det.atan2(den);
    }
    total / (4.0 * std::f64::consts::PI)
}

/// Output triangles that are inside out with respect to the input solid: just in front of
/// the centroid (along the output normal, at distance `eps`) the input is more "inside" than
/// just behind it. Where both probes are outside, or both inside (a coarse triangle cutting
/// through a thin blade), the test is silent: it only flags real inversions.
pub(crate) fn inverted_triangles(input: &Mesh, output: &Mesh, eps: f64) -> Vec<usize> {
    (0..output.triangles.len())
        .filter(|&t| {
            let [a, b, c] = output.triangles[t].map(|v| output.positions[v as usize]);
            let centroid = Point3::from((a.coords + b.coords + c.coords) / 3.0);
            let n = triangle_normal(output, t);
            let front = winding_number(input, &(centroid + n * eps));
            let back = winding_number(input, &(centroid - n * eps));
            front - back > 0.5
        })
        .collect()
}
