//! Exact f64 distance from a straight segment to a triangle mesh, written for the verifier
//! alone.
//!
//! The back-simulation of a posted program ([`super::posted`]) asks how close a ball centre
//! comes to the part along a piece of its path. A piece is short and nearly straight, so the
//! question is the distance from a segment to the surface, which this module answers exactly
//! (up to f64 rounding) with its own box tree and its own segment–triangle distance. None of it
//! is shared with the planner's queries (`collide::distance`, `geom::triangle`), so a mistake
//! there cannot hide itself here.
//!
//! Segment–triangle distance: two disjoint convex sets are closest at a pair of points of
//! which at least one lies on the boundary of its set, so the distance is 0 when the segment
//! pierces the triangle and otherwise the least of the segment's endpoints to the triangle and
//! the segment to each of the three edges.

use crate::geom::Point3;
use crate::mesh::Mesh;

/// Triangles per leaf of the tree.
const LEAF: usize = 4;

#[derive(Clone, Copy, Debug)]
struct BoxNode {
    lo: [f64; 3],
    hi: [f64; 3],
    /// Inner node: index of the first child (the second follows it). Leaf: first triangle in
    /// `order`.
    first: u32,
    /// Triangles in the leaf; 0 for an inner node.
    count: u32,
}

/// A mesh prepared for segment distance queries.
#[derive(Clone, Debug)]
pub struct SegmentDistance {
    corners: Vec<[Point3; 3]>,
    order: Vec<u32>,
    nodes: Vec<BoxNode>,
}

impl SegmentDistance {
    /// Builds the box tree over `mesh`'s triangles (median split on the longest axis).
    pub fn new(mesh: &Mesh) -> Self {
        let corners: Vec<[Point3; 3]> =
            (0..mesh.triangles.len()).map(|t| mesh.corners(t)).collect();
        let mut tree = SegmentDistance {
            order: (0..corners.len() as u32).collect(),
            corners,
            nodes: Vec::new(),
        };
        if !tree.corners.is_empty() {
            tree.nodes.push(BoxNode {
                lo: [0.0; 3],
                hi: [0.0; 3],
                first: 0,
                count: 0,
            });
            tree.build(0, 0, tree.order.len());
        }
        tree
    }

    fn bounds(&self, range: &[u32]) -> ([f64; 3], [f64; 3]) {
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for &t in range {
            for p in &self.corners[t as usize] {
                for k in 0..3 {
                    lo[k] = lo[k].min(p[k]);
                    hi[k] = hi[k].max(p[k]);
                }
            }
        }
        (lo, hi)
    }

    fn build(&mut self, node: usize, start: usize, end: usize) {
        let (lo, hi) = self.bounds(&self.order[start..end]);
        self.nodes[node].lo = lo;
        self.nodes[node].hi = hi;
        if end - start <= LEAF {
            self.nodes[node].first = start as u32;
            self.nodes[node].count = (end - start) as u32;
            return;
        }
        let axis = (0..3)
            .max_by(|&a, &b| (hi[a] - lo[a]).total_cmp(&(hi[b] - lo[b])))
            .unwrap_or(0);
        let mid = (start + end) / 2;
        let corners = &self.corners;
        // Three times the centroid: the order is all that matters. Ties by index keep the
        // tree the same on every run.
        let key = |t: &u32| {
            let [a, b, c] = &corners[*t as usize];
            a[axis] + b[axis] + c[axis]
        };
        self.order[start..end]
            .select_nth_unstable_by(mid - start, |x, y| key(x).total_cmp(&key(y)).then(x.cmp(y)));
        let first = self.nodes.len();
        let empty = BoxNode {
            lo: [0.0; 3],
            hi: [0.0; 3],
            first: 0,
            count: 0,
        };
        self.nodes.push(empty);
        self.nodes.push(empty);
        self.nodes[node].first = first as u32;
        self.nodes[node].count = 0;
        self.build(first, start, mid);
        self.build(first + 1, mid, end);
    }

    /// The distance from segment `p q` to the mesh, or `limit` when nothing is closer.
    pub fn distance(&self, p: &Point3, q: &Point3, limit: f64) -> f64 {
        if self.nodes.is_empty() {
            return limit;
        }
        let seg_lo = [p.x.min(q.x), p.y.min(q.y), p.z.min(q.z)];
        let seg_hi = [p.x.max(q.x), p.y.max(q.y), p.z.max(q.z)];
        // A lower bound of the distance from the segment to anything in a node: the gap
        // between the segment's box and the node's box.
        let gap = |n: &BoxNode| -> f64 {
            let mut s = 0.0;
            for k in 0..3 {
                let g = (n.lo[k] - seg_hi[k]).max(seg_lo[k] - n.hi[k]).max(0.0);
                s += g * g;
            }
            s.sqrt()
        };
        let mut best = limit;
        let mut stack: Vec<(f64, u32)> = Vec::with_capacity(64);
        stack.push((gap(&self.nodes[0]), 0));
        while let Some((bound, index)) = stack.pop() {
            if bound >= best {
                continue;
            }
            let node = &self.nodes[index as usize];
            if node.count > 0 {
                let start = node.first as usize;
                for &t in &self.order[start..start + node.count as usize] {
                    let [a, b, c] = &self.corners[t as usize];
                    best = best.min(segment_triangle_distance(p, q, a, b, c));
                }
            } else {
                let (l, r) = (node.first, node.first + 1);
                let (gl, gr) = (gap(&self.nodes[l as usize]), gap(&self.nodes[r as usize]));
                // The nearer child is popped first.
                if gl <= gr {
                    stack.push((gr, r));
                    stack.push((gl, l));
                } else {
                    stack.push((gl, l));
                    stack.push((gr, r));
                }
            }
        }
        best
    }
}

/// Distance from point `p` to triangle `abc`: to its plane when the foot falls inside, else to
/// the nearest edge. A degenerate triangle is measured by its edges.
pub fn point_triangle_distance(p: &Point3, a: &Point3, b: &Point3, c: &Point3) -> f64 {
    let n = (b - a).cross(&(c - a));
    let n2 = n.norm_squared();
    if n2 > 0.0 {
        let height = (p - a).dot(&n) / n2;
        let foot = p - n * height;
        // The foot is inside when it lies on the inner side of all three edges.
        let inside = [(a, b), (b, c), (c, a)]
            .iter()
            .all(|(u, v)| (*v - *u).cross(&(foot - *u)).dot(&n) >= 0.0);
        if inside {
            return height.abs() * n2.sqrt();
        }
    }
    point_segment_distance(p, a, b)
        .min(point_segment_distance(p, b, c))
        .min(point_segment_distance(p, c, a))
}

fn point_segment_distance(p: &Point3, a: &Point3, b: &Point3) -> f64 {
    let d = b - a;
    let len2 = d.norm_squared();
    let s = if len2 > 0.0 {
        ((p - a).dot(&d) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (a + d * s - p).norm()
}

/// Distance between segments `p1 q1` and `p2 q2`: the minimum of the convex quadratic
/// |p1 + s·d1 − p2 − t·d2|² over the unit square, found on its stationary point when that is
/// inside and otherwise on the square's four sides.
pub fn segment_segment_distance(p1: &Point3, q1: &Point3, p2: &Point3, q2: &Point3) -> f64 {
    let d1 = q1 - p1;
    let d2 = q2 - p2;
    let r = p1 - p2;
    let (a, e, b) = (d1.dot(&d1), d2.dot(&d2), d1.dot(&d2));
    let (c, f) = (d1.dot(&r), d2.dot(&r));
    let denom = a * e - b * b;
    if denom > 1e-12 * a * e && a > 0.0 && e > 0.0 {
        let s = (b * f - c * e) / denom;
        let t = (a * f - b * c) / denom;
        if (0.0..=1.0).contains(&s) && (0.0..=1.0).contains(&t) {
            return (r + d1 * s - d2 * t).norm();
        }
    }
    // The minimum lies on a side of the square: each side is a point-to-segment distance.
    point_segment_distance(p1, p2, q2)
        .min(point_segment_distance(q1, p2, q2))
        .min(point_segment_distance(p2, p1, q1))
        .min(point_segment_distance(q2, p1, q1))
}

/// Whether segment `p q` meets triangle `abc` (touching counts).
fn segment_pierces_triangle(p: &Point3, q: &Point3, a: &Point3, b: &Point3, c: &Point3) -> bool {
    let n = (b - a).cross(&(c - a));
    let (dp, dq) = ((p - a).dot(&n), (q - a).dot(&n));
    if (dp > 0.0 && dq > 0.0) || (dp < 0.0 && dq < 0.0) || dp == dq {
        // Both ends strictly on one side, or the segment lies in the plane (its distance is
        // then that of its ends or of the edges, which the caller measures).
        return false;
    }
    let x: Point3 = p + (q - p) * (dp / (dp - dq));
    let side = |u: &Point3, v: &Point3| -> f64 { (v - u).cross(&(x - u)).dot(&n) };
    let (s0, s1, s2) = (side(a, b), side(b, c), side(c, a));
    (s0 >= 0.0 && s1 >= 0.0 && s2 >= 0.0) || (s0 <= 0.0 && s1 <= 0.0 && s2 <= 0.0)
}

/// Distance from segment `p q` to triangle `abc` (see the module docs).
pub fn segment_triangle_distance(
    p: &Point3,
    q: &Point3,
    a: &Point3,
    b: &Point3,
    c: &Point3,
) -> f64 {
    if segment_pierces_triangle(p, q, a, b, c) {
        return 0.0;
    }
    point_triangle_distance(p, a, b, c)
        .min(point_triangle_distance(q, a, b, c))
        .min(segment_segment_distance(p, q, a, b))
        .min(segment_segment_distance(p, q, b, c))
        .min(segment_segment_distance(p, q, c, a))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::Vector3;
    use crate::mesh::fixtures::uv_sphere;
    use proptest::prelude::*;

    /// Dense sampling of both sets: an upper bound that converges to the distance.
    fn sampled(p: &Point3, q: &Point3, a: &Point3, b: &Point3, c: &Point3) -> f64 {
        let n = 60;
        let mut best = f64::INFINITY;
        for i in 0..=n {
            let x = p + (q - p) * (i as f64 / n as f64);
            for j in 0..=n {
                for k in 0..=(n - j) {
                    let (u, v) = (j as f64 / n as f64, k as f64 / n as f64);
                    let y = a + (b - a) * u + (c - a) * v;
                    best = best.min((x - y).norm());
                }
            }
        }
        best
    }

    fn point() -> impl Strategy<Value = Point3> {
        (-3.0..3.0f64, -3.0..3.0f64, -3.0..3.0f64).prop_map(|(x, y, z)| Point3::new(x, y, z))
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]
        /// Never more than the sampled distance (it is exact), and within the sampling's own
        /// resolution of it.
        #[test]
        fn segment_triangle_distance_agrees_with_dense_sampling(
            p in point(), q in point(), a in point(), b in point(), c in point()
        ) {
            let exact = segment_triangle_distance(&p, &q, &a, &b, &c);
            let dense = sampled(&p, &q, &a, &b, &c);
            prop_assert!(exact <= dense + 1e-9, "{exact} > {dense}");
            // Sample spacing: 6/60 along the segment's box and the triangle's edges.
            let spacing = ((q - p).norm() + (b - a).norm() + (c - a).norm()) / 60.0;
            prop_assert!(dense - exact <= spacing, "{exact} vs {dense}");
        }
    }

    #[test]
    fn a_segment_through_a_triangle_is_at_distance_zero_and_beside_it_at_its_gap() {
        let (a, b, c) = (
            Point3::new(0.0, 0.0, 0.0),
            Point3::new(4.0, 0.0, 0.0),
            Point3::new(0.0, 4.0, 0.0),
        );
        let through = segment_triangle_distance(
            &Point3::new(1.0, 1.0, -1.0),
            &Point3::new(1.0, 1.0, 1.0),
            &a,
            &b,
            &c,
        );
        assert_eq!(through, 0.0);
        // Parallel to the plane, 0.5 above, over the face.
        let above = segment_triangle_distance(
            &Point3::new(0.5, 0.5, 0.5),
            &Point3::new(2.0, 1.0, 0.5),
            &a,
            &b,
            &c,
        );
        assert!((above - 0.5).abs() < 1e-15);
        // Crossing over the hypotenuse edge x + y = 4 at height 1, beyond it.
        let beyond = segment_triangle_distance(
            &Point3::new(5.0, 0.0, 1.0),
            &Point3::new(0.0, 5.0, 1.0),
            &a,
            &b,
            &c,
        );
        let expected = (0.5f64 + 1.0).sqrt(); // (1/√2 in-plane)² + 1²
        assert!((beyond - expected).abs() < 1e-12, "{beyond}");
    }

    /// The tree against every triangle, on chords around and through a sphere.
    #[test]
    fn tree_query_equals_brute_force_on_a_sphere() {
        let sphere = uv_sphere(10.0, 16, 32);
        let tree = SegmentDistance::new(&sphere);
        let brute = |p: &Point3, q: &Point3| {
            (0..sphere.triangles.len())
                .map(|t| {
                    let [a, b, c] = sphere.corners(t);
                    segment_triangle_distance(p, q, &a, &b, &c)
                })
                .fold(f64::INFINITY, f64::min)
        };
        for i in 0..200 {
            let s = i as f64 * 0.37;
            let p = Point3::new(14.0 * s.cos(), 14.0 * s.sin(), 12.0 * (0.7 * s).sin());
            let q = p + Vector3::new((1.3 * s).sin(), (0.3 * s).cos(), -0.4) * (3.0 + s % 7.0);
            let exact = brute(&p, &q);
            assert_eq!(tree.distance(&p, &q, f64::INFINITY), exact);
            // A limit below the answer returns the limit.
            assert_eq!(tree.distance(&p, &q, exact * 0.5), exact * 0.5);
        }
    }
}
