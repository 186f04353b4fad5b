//! Geometry of the input that drives the collapse: sharp edges (boundary edges and creases by
//! dihedral angle) and the initial per-vertex quadrics (area-weighted face planes plus heavily
//! weighted constraint planes along sharp edges).

use nalgebra::{Point3, Vector3};

use super::quadric::Quadric;
use super::topology::Topology;

/// Weight of a sharp edge's constraint plane, relative to the squared edge length. The face
/// planes are weighted by area (≈ length²), so this makes moving off a feature line about
/// `sqrt(CONSTRAINT_WEIGHT)` ≈ 30 times as costly as moving off the surface by the same amount.
const CONSTRAINT_WEIGHT: f64 = 1000.0;

/// A triangle whose doubled area is below this fraction of its squared longest edge has no
/// reliable normal: it is not used to classify creases or to build constraint planes.
pub(crate) const DEGENERATE_RATIO: f64 = 1e-12;

/// Unit normal of triangle `(a, b, c)`, or `None` when it is (numerically) degenerate.
pub(crate) fn unit_normal(
    a: &Point3<f64>,
    b: &Point3<f64>,
    c: &Point3<f64>,
) -> Option<Vector3<f64>> {
    let n = (b - a).cross(&(c - a));
    let longest = (b - a)
        .norm_squared()
        .max((c - b).norm_squared())
        .max((a - c).norm_squared());
    let len = n.norm();
    (len > DEGENERATE_RATIO * longest && len.is_finite()).then(|| n / len)
}

/// Sharp edges of the input as `[min, max]` pairs in the order of `topology.edges`: every
/// boundary edge, and every interior edge whose dihedral angle (angle between the two face
/// normals) exceeds `crease_angle_deg`.
pub(crate) fn sharp_edges(
    positions: &[Point3<f64>],
    triangles: &[[u32; 3]],
    topology: &Topology,
    crease_angle_deg: f64,
) -> Vec<[u32; 2]> {
    let cos_limit = crease_angle_deg.to_radians().cos();
    let normal = |t: u32| {
        let [a, b, c] = triangles[t as usize];
        unit_normal(
            &positions[a as usize],
            &positions[b as usize],
            &positions[c as usize],
        )
    };
    topology
        .edges
        .iter()
        .filter(|e| {
            e.is_boundary()
                || match (normal(e.faces[0]), normal(e.faces[1])) {
                    (Some(n0), Some(n1)) => n0.dot(&n1) < cos_limit,
                    _ => false,
                }
        })
        .map(|e| e.vertices)
        .collect()
}

/// Initial quadric of every vertex, with positions taken relative to `origin`.
///
/// Face planes are weighted by triangle area and added to the triangle's three vertices
/// (Garland & Heckbert 1997, §5). For each sharp edge, the plane through the edge and
/// perpendicular to each adjacent valid face is added to both endpoints with weight
/// [`CONSTRAINT_WEIGHT`]·length² (Garland & Heckbert 1997, §6.1).
/// The per-vertex quadrics the collapse starts from.
pub(crate) struct InitialQuadrics {
    /// Face planes plus the constraint planes that hold sharp edges in place: the cost of
    /// placing a vertex.
    pub(crate) quadrics: Vec<Quadric>,
    /// Face planes only, and only at smooth vertices (zero on feature lines): how far a point
    /// of a triangle spanning several vertices' regions lies from the surface those regions
    /// were. The constraint planes, or the two sides' planes a crease vertex sums, would
    /// penalise any point off a crease line, which every triangle next to a crease has.
    pub(crate) surface: Vec<Quadric>,
}

pub(crate) fn initial_quadrics(
    positions: &[Point3<f64>],
    origin: &Vector3<f64>,
    triangles: &[[u32; 3]],
    topology: &Topology,
    sharp: &[[u32; 2]],
) -> InitialQuadrics {
    let rel = |v: u32| positions[v as usize].coords - origin;
    let mut quadrics = vec![Quadric::default(); positions.len()];
    let mut face_normal = Vec::with_capacity(triangles.len());
    for &[a, b, c] in triangles {
        let (pa, pb, pc) = (rel(a), rel(b), rel(c));
        let cross = (pb - pa).cross(&(pc - pa));
        let area = 0.5 * cross.norm();
        let n = unit_normal(
            &positions[a as usize],
            &positions[b as usize],
            &positions[c as usize],
        );
        face_normal.push(n);
        if let Some(n) = n {
            let q = Quadric::plane(n, -n.dot(&pa), area, area);
            for v in [a, b, c] {
                quadrics[v as usize].add(&q);
            }
        }
    }
    // A vertex on a crease or boundary sums the planes of both sides, and every point of a
    // triangle next to the crease lies off the other side's plane: its surface quadric would
    // forbid any triangle there. Feature vertices are held on the feature lines anyway; the
    // span measure uses the smooth corners only.
    let mut surface = quadrics.clone();
    for &v in sharp.iter().flatten() {
        surface[v as usize] = Quadric::default();
    }
    // Sharp edges are a subsequence of the sorted edge list: walk both.
    let mut k = 0;
    for e in &topology.edges {
        if k >= sharp.len() {
            break;
        }
        if e.vertices != sharp[k] {
            continue;
        }
        k += 1;
        let [a, b] = e.vertices;
        let (pa, pb) = (rel(a), rel(b));
        let d = pb - pa;
        let faces = &e.faces[..e.count as usize];
        for &f in faces {
            if let Some(n) = face_normal[f as usize] {
                let m = d.cross(&n);
                let len = m.norm();
                if len > 0.0 && len.is_finite() {
                    let m = m / len;
                    let q =
                        Quadric::plane(m, -m.dot(&pa), CONSTRAINT_WEIGHT * d.norm_squared(), 0.0);
                    quadrics[a as usize].add(&q);
                    quadrics[b as usize].add(&q);
                }
            }
        }
    }
    InitialQuadrics { quadrics, surface }
}
