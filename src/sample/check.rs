//! Test-only invariant checks for closed triangle meshes: manifoldness, orientation, Euler
//! characteristic, welding, triangle quality, signed volume and self-intersections.

use nalgebra::{Point3, Vector3};

use crate::mesh::Mesh;

/// What [`closed_manifold`] measured.
#[derive(Clone, Debug)]
pub(crate) struct Report {
    pub(crate) vertices: usize,
    pub(crate) edges: usize,
    pub(crate) triangles: usize,
    /// V − E + F.
    pub(crate) euler: i64,
    /// Signed volume by the divergence theorem (> 0 when outward).
    pub(crate) volume: f64,
    /// Smallest interior angle over all triangles, degrees.
    pub(crate) min_angle_deg: f64,
    /// Shortest edge, mm.
    pub(crate) min_edge: f64,
    /// Centroid of the triangle with the smallest angle.
    pub(crate) worst_at: Point3<f64>,
}

impl Report {
    /// One line with every measurement.
    pub(crate) fn summary(&self) -> String {
        format!(
            "V {} E {} F {} (χ = {}), volume {:.1} mm³, min angle {:.2}° at {:.2?}, min edge {:.3} mm",
            self.vertices,
            self.edges,
            self.triangles,
            self.euler,
            self.volume,
            self.min_angle_deg,
            self.worst_at.coords.as_slice(),
            self.min_edge
        )
    }
}

/// Checks that `mesh` is a closed, consistently oriented, welded 2-manifold without unused
/// vertices: every undirected edge is used exactly twice, once in each direction; every
/// vertex's triangles form a single fan; no two vertices share a position.
pub(crate) fn closed_manifold(mesh: &Mesh) -> Result<Report, String> {
    let nv = mesh.positions.len();
    let mut directed = Vec::with_capacity(3 * mesh.triangles.len());
    for (t, tri) in mesh.triangles.iter().enumerate() {
        let [a, b, c] = *tri;
        if tri.iter().any(|&i| i as usize >= nv) {
            return Err(format!("triangle {t} {tri:?} has an index out of range"));
        }
        if a == b || b == c || c == a {
            return Err(format!("triangle {t} {tri:?} repeats a vertex"));
        }
        directed.extend([(a, b), (b, c), (c, a)]);
    }
    directed.sort_unstable();
    if let Some(w) = directed.windows(2).find(|w| w[0] == w[1]) {
        return Err(format!(
            "directed edge {:?} used twice (non-manifold or flipped)",
            w[0]
        ));
    }
    for &(a, b) in &directed {
        if directed.binary_search(&(b, a)).is_err() {
            return Err(format!(
                "edge {a}–{b} has no opposite half-edge (boundary or flipped)"
            ));
        }
    }
    // Fans: around vertex a, triangle (a, b, c) links b → c; one cycle per vertex.
    let mut links: Vec<Vec<(u32, u32)>> = vec![Vec::new(); nv];
    for &[a, b, c] in &mesh.triangles {
        links[a as usize].push((b, c));
        links[b as usize].push((c, a));
        links[c as usize].push((a, b));
    }
    for (v, l) in links.iter_mut().enumerate() {
        if l.is_empty() {
            return Err(format!("vertex {v} is unused"));
        }
        l.sort_unstable();
        let start = l[0].0;
        let mut cur = start;
        let mut steps = 0;
        loop {
            let i = l
                .binary_search_by_key(&cur, |&(from, _)| from)
                .map_err(|_| format!("vertex {v}: fan is open at {cur}"))?;
            cur = l[i].1;
            steps += 1;
            if cur == start || steps > l.len() {
                break;
            }
        }
        if steps != l.len() {
            return Err(format!(
                "vertex {v} is non-manifold: its {} triangles form more than one fan",
                l.len()
            ));
        }
    }
    // Welding: no two vertices at the same position.
    let mut order: Vec<usize> = (0..nv).collect();
    let key = |i: usize| {
        let p = mesh.positions[i];
        [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()]
    };
    order.sort_unstable_by_key(|&i| key(i));
    if let Some(w) = order.windows(2).find(|w| key(w[0]) == key(w[1])) {
        return Err(format!("vertices {} and {} coincide", w[0], w[1]));
    }

    let mut min_angle = f64::INFINITY;
    let mut min_edge = f64::INFINITY;
    let mut volume = 0.0;
    let mut worst_at = Point3::origin();
    for tri in &mesh.triangles {
        let [a, b, c] = tri.map(|i| mesh.positions[i as usize]);
        volume += a.coords.dot(&b.coords.cross(&c.coords)) / 6.0;
        for (p, q, r) in [(a, b, c), (b, c, a), (c, a, b)] {
            let (u, w) = (q - p, r - p);
            let angle = u.cross(&w).norm().atan2(u.dot(&w)).to_degrees();
            if angle < min_angle {
                min_angle = angle;
                worst_at = Point3::from((a.coords + b.coords + c.coords) / 3.0);
            }
            min_edge = min_edge.min(u.norm());
        }
    }
    let edges = directed.len() / 2;
    Ok(Report {
        vertices: nv,
        edges,
        triangles: mesh.triangles.len(),
        euler: nv as i64 - edges as i64 + mesh.triangles.len() as i64,
        volume,
        min_angle_deg: min_angle,
        min_edge,
        worst_at,
    })
}

/// Whether two meshes are identical bit for bit.
pub(crate) fn bitwise_equal(a: &Mesh, b: &Mesh) -> bool {
    let bits = |m: &Mesh| -> Vec<u64> {
        m.positions
            .iter()
            .flat_map(|p| [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()])
            .collect()
    };
    a.triangles == b.triangles && bits(a) == bits(b)
}

type Tri = [Point3<f64>; 3];

/// Pairs of triangles that intersect improperly, at most `limit` of them. Pairs without a
/// shared vertex must be disjoint (Möller's interval test, with a coplanar 2D test);
/// pairs sharing one vertex may meet only there; pairs sharing an edge must not fold onto
/// each other. Candidates come from a sweep over x of the bounding boxes; every candidate pair
/// gets the exact test.
pub(crate) fn self_intersections(mesh: &Mesh, limit: usize) -> Vec<(usize, usize)> {
    let tris: Vec<Tri> = mesh
        .triangles
        .iter()
        .map(|t| t.map(|i| mesh.positions[i as usize]))
        .collect();
    let scale = tris
        .iter()
        .flatten()
        .map(|p| p.coords.amax())
        .fold(1.0, f64::max);
    let eps = 1e-10 * scale;
    let boxes: Vec<[Point3<f64>; 2]> = tris
        .iter()
        .map(|t| {
            let lo = t[0].inf(&t[1]).inf(&t[2]);
            let hi = t[0].sup(&t[1]).sup(&t[2]);
            [lo, hi]
        })
        .collect();
    let mut order: Vec<usize> = (0..tris.len()).collect();
    order.sort_by(|&a, &b| boxes[a][0].x.total_cmp(&boxes[b][0].x));
    let mut out = Vec::new();
    for (k, &i) in order.iter().enumerate() {
        for &j in &order[k + 1..] {
            if boxes[j][0].x > boxes[i][1].x + eps {
                break;
            }
            let (bi, bj) = (&boxes[i], &boxes[j]);
            if (0..3).any(|d| bj[0][d] > bi[1][d] + eps || bi[0][d] > bj[1][d] + eps) {
                continue;
            }
            let (ti, tj) = (mesh.triangles[i], mesh.triangles[j]);
            let shared: Vec<(usize, usize)> = (0..3)
                .flat_map(|a| (0..3).map(move |b| (a, b)))
                .filter(|&(a, b)| ti[a] == tj[b])
                .collect();
            let bad = match shared.len() {
                0 => tri_tri_intersect(&tris[i], &tris[j], eps),
                1 => corners_overlap(&tris[i], &tris[j], shared[0], eps),
                2 => folded(&tris[i], &tris[j], &shared, eps),
                _ => true,
            };
            if bad {
                out.push((i.min(j), i.max(j)));
                if out.len() >= limit {
                    return out;
                }
            }
        }
    }
    out
}

fn normal(t: &Tri) -> Vector3<f64> {
    (t[1] - t[0]).cross(&(t[2] - t[0]))
}

/// Möller's test: do two triangles without shared vertices intersect (touching counts)?
fn tri_tri_intersect(t: &Tri, u: &Tri, eps: f64) -> bool {
    let n1 = normal(t).normalize();
    let n2 = normal(u).normalize();
    let snap = |d: f64| if d.abs() <= eps { 0.0 } else { d };
    let du = u.map(|p| snap(n1.dot(&(p - t[0]))));
    let dt = t.map(|p| snap(n2.dot(&(p - u[0]))));
    let same_side = |d: &[f64; 3]| d.iter().all(|&x| x > 0.0) || d.iter().all(|&x| x < 0.0);
    if same_side(&du) || same_side(&dt) {
        return false;
    }
    if du.iter().all(|&x| x == 0.0) {
        return coplanar_overlap(t, u, &n1);
    }
    let dir = n1.cross(&n2);
    let interval = |tri: &Tri, d: &[f64; 3]| -> (f64, f64) {
        let proj = tri.map(|p| dir.dot(&p.coords));
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        for a in 0..3 {
            let b = (a + 1) % 3;
            if d[a] == 0.0 {
                lo = lo.min(proj[a]);
                hi = hi.max(proj[a]);
            }
            if d[a] * d[b] < 0.0 {
                let x = proj[a] + (proj[b] - proj[a]) * d[a] / (d[a] - d[b]);
                lo = lo.min(x);
                hi = hi.max(x);
            }
        }
        (lo, hi)
    };
    let (a0, a1) = interval(t, &dt);
    let (b0, b1) = interval(u, &du);
    a0.max(b0) <= a1.min(b1)
}

/// Projects onto the coordinate plane most orthogonal to `n`.
fn project(n: &Vector3<f64>) -> impl Fn(&Point3<f64>) -> [f64; 2] {
    let a = n.abs();
    let (i, j) = if a.x >= a.y && a.x >= a.z {
        (1, 2)
    } else if a.y >= a.z {
        (2, 0)
    } else {
        (0, 1)
    };
    move |p| [p[i], p[j]]
}

fn orient2(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> f64 {
    (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
}

/// Coplanar triangles: does any edge pair cross or any vertex lie inside the other?
fn coplanar_overlap(t: &Tri, u: &Tri, n: &Vector3<f64>) -> bool {
    let pr = project(n);
    let (a, b) = (t.map(|p| pr(&p)), u.map(|p| pr(&p)));
    for i in 0..3 {
        for j in 0..3 {
            let (p, q, r, s) = (a[i], a[(i + 1) % 3], b[j], b[(j + 1) % 3]);
            let (o1, o2) = (orient2(p, q, r), orient2(p, q, s));
            let (o3, o4) = (orient2(r, s, p), orient2(r, s, q));
            if o1 * o2 < 0.0 && o3 * o4 < 0.0 {
                return true;
            }
        }
    }
    let inside = |tri: &[[f64; 2]; 3], p: [f64; 2]| {
        let s = orient2(tri[0], tri[1], tri[2]).signum();
        (0..3).all(|k| orient2(tri[k], tri[(k + 1) % 3], p) * s >= 0.0)
    };
    a.iter().any(|&p| inside(&b, p)) || b.iter().any(|&p| inside(&a, p))
}

/// Two triangles sharing exactly one vertex (`t[i] == u[j]`): do they overlap beyond it?
fn corners_overlap(t: &Tri, u: &Tri, (i, j): (usize, usize), eps: f64) -> bool {
    let s = t[i];
    let (ta, tb) = (t[(i + 1) % 3] - s, t[(i + 2) % 3] - s);
    let (ua, ub) = (u[(j + 1) % 3] - s, u[(j + 2) % 3] - s);
    let (n1, n2) = (ta.cross(&tb).normalize(), ua.cross(&ub).normalize());
    // Strictly inside the corner (a, b) with normal n, with a relative tolerance.
    let within = |a: &Vector3<f64>, b: &Vector3<f64>, n: &Vector3<f64>, d: &Vector3<f64>| {
        let tol = 1e-9 * d.norm() * a.norm().max(b.norm());
        a.cross(d).dot(n) > tol && d.cross(b).dot(n) > tol
    };
    let dir = n1.cross(&n2);
    if dir.norm() > 1e-9 {
        // The triangles meet on the line through s along dir; they overlap beyond s iff
        // that line enters both corners on the same side of s.
        return [dir, -dir]
            .iter()
            .any(|d| within(&ta, &tb, &n1, d) && within(&ua, &ub, &n2, d));
    }
    // (Nearly) parallel planes: they touch beyond s only if coplanar.
    let off = [ua, ub].iter().map(|v| n1.dot(v).abs()).fold(0.0, f64::max);
    if off > eps {
        return false;
    }
    let n = if n1.dot(&n2) >= 0.0 { n2 } else { -n2 };
    let m = if n1.dot(&n2) >= 0.0 {
        (ua, ub)
    } else {
        (ub, ua)
    };
    within(&ta, &tb, &n1, &m.0)
        || within(&ta, &tb, &n1, &m.1)
        || within(&m.0, &m.1, &n, &ta)
        || within(&m.0, &m.1, &n, &tb)
        || (ta.normalize() - m.0.normalize()).norm() < 1e-12
            && (tb.normalize() - m.1.normalize()).norm() < 1e-12
}

/// Two triangles sharing an edge: folded flat onto each other (coplanar, same side)?
fn folded(t: &Tri, u: &Tri, shared: &[(usize, usize)], eps: f64) -> bool {
    let ti = 3 - shared[0].0 - shared[1].0;
    let uj = 3 - shared[0].1 - shared[1].1;
    let (a, b) = (t[shared[0].0], t[shared[1].0]);
    let n = normal(t).normalize();
    let d = u[uj] - a;
    if n.dot(&d).abs() > eps {
        return false;
    }
    let e = b - a;
    e.cross(&(t[ti] - a)).dot(&n) * e.cross(&d).dot(&n) > 0.0
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tetra() -> Mesh {
        Mesh {
            positions: vec![
                Point3::new(0.0, 0.0, 0.0),
                Point3::new(1.0, 0.0, 0.0),
                Point3::new(0.0, 1.0, 0.0),
                Point3::new(0.0, 0.0, 1.0),
            ],
            triangles: vec![[0, 2, 1], [0, 1, 3], [1, 2, 3], [2, 0, 3]],
        }
    }

    #[test]
    fn tetrahedron_passes() {
        let r = closed_manifold(&tetra()).unwrap();
        assert_eq!(r.euler, 2);
        assert!((r.volume - 1.0 / 6.0).abs() < 1e-15);
        assert!(self_intersections(&tetra(), 10).is_empty());
    }

    #[test]
    fn defects_are_caught() {
        let mut m = tetra();
        m.triangles[0] = [0, 1, 2];
        assert!(closed_manifold(&m).is_err(), "flipped face");
        let mut m = tetra();
        m.triangles.pop();
        assert!(closed_manifold(&m).is_err(), "hole");
        let mut m = tetra();
        m.positions.push(Point3::new(5.0, 5.0, 5.0));
        assert!(closed_manifold(&m).is_err(), "unused vertex");
        // Two tetrahedra glued at one vertex: closed, but vertex 0 is non-manifold.
        let mut m = tetra();
        let off = Vector3::new(-1.0, -1.0, -1.0);
        for k in 1..4 {
            m.positions.push(m.positions[k] + off * 2.0);
        }
        m.triangles
            .extend([[0, 4, 5], [0, 6, 4], [4, 6, 5], [5, 6, 0]].map(|t| t.map(|i| i as u32)));
        let e = closed_manifold(&m).unwrap_err();
        assert!(e.contains("non-manifold"), "{e}");
        // Duplicate position.
        let mut m = tetra();
        m.positions[3] = m.positions[0];
        assert!(closed_manifold(&m).is_err());
    }

    #[test]
    fn intersections_are_caught() {
        // A second tetrahedron poking through the first one's slanted face.
        let mut m = tetra();
        let q = [
            Point3::new(0.2, 0.2, 0.2),
            Point3::new(1.2, 0.2, 0.2),
            Point3::new(0.2, 1.2, 0.2),
            Point3::new(0.2, 0.2, 1.2),
        ];
        m.positions.extend(q);
        m.triangles
            .extend([[4, 6, 5], [4, 5, 7], [5, 6, 7], [6, 4, 7]].map(|t| t.map(|i| i as u32)));
        assert!(!self_intersections(&m, 10).is_empty());
        // Shared vertex, one triangle piercing the other.
        let t: Tri = [
            Point3::new(0.0, 0.0, 0.0),
            Point3::new(2.0, 0.0, 0.0),
            Point3::new(0.0, 2.0, 0.0),
        ];
        let u: Tri = [
            Point3::new(0.0, 0.0, 0.0),
            Point3::new(1.0, 1.0, -1.0),
            Point3::new(0.5, 0.2, 1.0),
        ];
        assert!(corners_overlap(&t, &u, (0, 0), 1e-12));
        let w: Tri = [
            Point3::new(0.0, 0.0, 0.0),
            Point3::new(-1.0, -1.0, -1.0),
            Point3::new(-0.5, -0.2, 1.0),
        ];
        assert!(!corners_overlap(&t, &w, (0, 0), 1e-12));
        // Coplanar overlap with a shared vertex.
        let c: Tri = [
            Point3::new(0.0, 0.0, 0.0),
            Point3::new(1.0, 0.5, 0.0),
            Point3::new(0.5, 1.0, 0.0),
        ];
        assert!(corners_overlap(&t, &c, (0, 0), 1e-12));
        // Folded edge pair.
        let f: Tri = [
            Point3::new(2.0, 0.0, 0.0),
            Point3::new(0.0, 0.0, 0.0),
            Point3::new(0.5, 0.5, 0.0),
        ];
        assert!(folded(&t, &f, &[(0, 1), (1, 0)], 1e-12));
    }
}
