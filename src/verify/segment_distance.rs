//! Exact f64 distance from a straight segment, or a triangle, to a triangle mesh, written for
//! the verifier alone.
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
//!
//! The flutes sweep a sheet (their axis, from the ball centre up) that the back-simulation
//! covers with small triangles; triangle–triangle distance is the least of each triangle's
//! edges against the other ([`triangle_triangle_distance`]).

use crate::geom::{Point3, Vector3};
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
    /// Each triangle's unit normal (zero for a degenerate one) and its plane's offset along
    /// it: a query held on one side of the plane is at least that far from the triangle, a
    /// bound of a few dot products before the exact distance.
    planes: Vec<(Vector3, f64)>,
    /// Each triangle's three edges as in-plane unit normals pointing out of it, with their
    /// offsets (zero for a degenerate triangle): the triangle lies in the half-plane of its
    /// plane behind each edge, which sharpens the plane's bound (see [`Self::nearest`]).
    edges: Vec<[(Vector3, f64); 3]>,
    order: Vec<u32>,
    nodes: Vec<BoxNode>,
}

impl SegmentDistance {
    /// Builds the box tree over `mesh`'s triangles (median split on the longest axis).
    pub fn new(mesh: &Mesh) -> Self {
        let corners: Vec<[Point3; 3]> =
            (0..mesh.triangles.len()).map(|t| mesh.corners(t)).collect();
        let planes = corners
            .iter()
            .map(|[a, b, c]| {
                let n = (b - a).cross(&(c - a));
                let length = n.norm();
                let unit = if length > 0.0 {
                    n / length
                } else {
                    Vector3::zeros()
                };
                (unit, unit.dot(&a.coords))
            })
            .collect();
        let edges = corners
            .iter()
            .zip(&planes)
            .map(|(triangle, (normal, _)): (&[Point3; 3], &(Vector3, f64))| {
                std::array::from_fn(|k| {
                    let (a, b) = (triangle[k], triangle[(k + 1) % 3]);
                    // Counter-clockwise about the normal, edge × normal points out.
                    let out: Vector3 = (b - a).cross(normal);
                    let length = out.norm();
                    if length > 0.0 {
                        let unit = out / length;
                        (unit, unit.dot(&a.coords))
                    } else {
                        (Vector3::zeros(), 0.0)
                    }
                })
            })
            .collect();
        let mut tree = SegmentDistance {
            order: (0..corners.len() as u32).collect(),
            planes,
            edges,
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
        self.nearest(&[*p, *q], limit, |t, _| {
            let [a, b, c] = &self.corners[t];
            segment_triangle_distance(p, q, a, b, c)
        })
    }

    /// The distance from triangle `a b c` to the mesh, or `limit` when nothing is closer.
    pub fn triangle_distance(&self, a: &Point3, b: &Point3, c: &Point3, limit: f64) -> f64 {
        self.nearest(&[*a, *b, *c], limit, |t, _| {
            let [u, v, w] = &self.corners[t];
            triangle_triangle_distance(a, b, c, u, v, w)
        })
    }

    /// The distance from the two triangles `p00 p10 p11` and `p00 p11 p01` (a quadrilateral
    /// cut along its diagonal) to the mesh triangles `keep` keeps, or `limit` when nothing
    /// is closer.
    pub fn quad_distance(
        &self,
        corners: &[Point3; 4],
        limit: f64,
        keep: impl Fn(&[Point3; 3]) -> bool,
    ) -> f64 {
        let [p00, p10, p11, p01] = corners;
        // Three directions to look for a gap along before measuring exactly: across the
        // quadrilateral (its mean normal) and along its two sides. Any unit direction
        // separating the projections bounds the distance from below.
        let directions = [
            (p11 - p00).cross(&(p01 - p10)),
            p10 - p00 + (p11 - p01),
            p01 - p00 + (p11 - p10),
        ]
        .map(|d| {
            let length = d.norm();
            if length > 0.0 { d / length } else { d }
        });
        let spans = directions.map(|d| {
            corners
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| {
                    let x = d.dot(&p.coords);
                    (lo.min(x), hi.max(x))
                })
        });
        self.nearest(corners, limit, |t, best| {
            let triangle = &self.corners[t];
            let separated = directions.iter().zip(&spans).any(|(d, (lo, hi))| {
                let (mut below, mut above) = (f64::INFINITY, f64::NEG_INFINITY);
                for p in triangle {
                    let x = d.dot(&p.coords);
                    below = below.min(x);
                    above = above.max(x);
                }
                let gap = (below - hi).max(lo - above);
                gap > best + 1e-12 * (1.0 + best + hi.abs() + lo.abs())
            });
            if separated || !keep(triangle) {
                return best;
            }
            let [u, v, w] = triangle;
            let first = triangle_triangle_distance(p00, p10, p11, u, v, w);
            if first == 0.0 {
                return 0.0;
            }
            first.min(triangle_triangle_distance(p00, p11, p01, u, v, w))
        })
    }

    /// The least of `measure` over the mesh's triangles, or `limit` when nothing is closer,
    /// for a convex query set held by the box of `points` (which bounds the search).
    /// `measure(t, best)` is triangle `t`'s distance, or anything not below `best` when it is
    /// not nearer than that. A triangle whose plane has the whole query beyond `best` on one
    /// side (the query is the hull of `points`) is not measured.
    fn nearest(&self, points: &[Point3], limit: f64, measure: impl Fn(usize, f64) -> f64) -> f64 {
        if self.nodes.is_empty() {
            return limit;
        }
        let mut query_lo = [f64::INFINITY; 3];
        let mut query_hi = [f64::NEG_INFINITY; 3];
        for point in points {
            for k in 0..3 {
                query_lo[k] = query_lo[k].min(point[k]);
                query_hi[k] = query_hi[k].max(point[k]);
            }
        }
        // A lower bound of the distance from the query to anything in a node: the gap
        // between the query's box and the node's box.
        let gap = |n: &BoxNode| -> f64 {
            let mut s = 0.0;
            for k in 0..3 {
                let g = (n.lo[k] - query_hi[k]).max(query_lo[k] - n.hi[k]).max(0.0);
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
                    let (normal, offset) = &self.planes[t as usize];
                    let (mut below, mut above) = (f64::INFINITY, f64::NEG_INFINITY);
                    for point in points {
                        let height = normal.dot(&point.coords) - offset;
                        below = below.min(height);
                        above = above.max(height);
                    }
                    // Beyond the best by more than the heights' rounding: a nearer triangle
                    // is never skipped.
                    let slack = 1e-12 * (1.0 + best + offset.abs());
                    let height = below.max(-above).max(0.0);
                    if height > best + slack {
                        continue;
                    }
                    // The triangle lies in the half-plane of its plane behind each edge. A
                    // point `h` off the plane and `g` beyond the edge's line is
                    // `√(h² + g²)` from that half-plane, and over the query's hull both are
                    // affine, least at one of its points: the sum of their least squares
                    // bounds the least distance from below.
                    let (mut beyond, mut scale): (f64, f64) = (0.0, 0.0);
                    for (out, edge_offset) in &self.edges[t as usize] {
                        let least = points
                            .iter()
                            .map(|point| out.dot(&point.coords) - edge_offset)
                            .fold(f64::INFINITY, f64::min);
                        beyond = beyond.max(least);
                        scale = scale.max(edge_offset.abs());
                    }
                    if beyond > 0.0
                        && (height * height + beyond * beyond).sqrt()
                            > best + slack + 1e-12 * (1.0 + scale)
                    {
                        continue;
                    }
                    best = best.min(measure(t as usize, best));
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

/// Distance from point `p` to segment `a b`.
pub(super) fn point_segment_distance(p: &Point3, a: &Point3, b: &Point3) -> f64 {
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

/// Distance between triangles `abc` and `uvw`: of two disjoint convex sets' closest pair one
/// point can always be taken on the boundary of its set (two triangles' interiors can be
/// closest only when parallel, and then an edge is as close), so it is the least of each
/// triangle's three edges measured against the other; 0 when they meet, which an edge of one
/// piercing the other (or two edges touching) shows.
pub fn triangle_triangle_distance(
    a: &Point3,
    b: &Point3,
    c: &Point3,
    u: &Point3,
    v: &Point3,
    w: &Point3,
) -> f64 {
    let mut best = f64::INFINITY;
    for (p, q) in [(a, b), (b, c), (c, a)] {
        best = best.min(segment_triangle_distance(p, q, u, v, w));
        if best == 0.0 {
            return 0.0;
        }
    }
    for (p, q) in [(u, v), (v, w), (w, u)] {
        best = best.min(segment_triangle_distance(p, q, a, b, c));
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;
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

    /// Points over a triangle's area (a barycentric grid).
    fn area_samples(a: &Point3, b: &Point3, c: &Point3, n: usize) -> Vec<Point3> {
        let mut out = Vec::new();
        for j in 0..=n {
            for k in 0..=(n - j) {
                let (u, v) = (j as f64 / n as f64, k as f64 / n as f64);
                out.push(a + (b - a) * u + (c - a) * v);
            }
        }
        out
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]
        /// Never more than the distance between the two sampled areas, and within their
        /// sampling resolution of it; 0 exactly when the sampling finds them crossing.
        #[test]
        fn triangle_triangle_distance_agrees_with_dense_sampling(
            a in point(), b in point(), c in point(), u in point(), v in point(), w in point()
        ) {
            let exact = triangle_triangle_distance(&a, &b, &c, &u, &v, &w);
            prop_assert_eq!(exact, triangle_triangle_distance(&u, &v, &w, &a, &b, &c));
            let n = 40;
            let (first, second) = (area_samples(&a, &b, &c, n), area_samples(&u, &v, &w, n));
            let dense = first
                .iter()
                .flat_map(|x| second.iter().map(move |y| (x - y).norm()))
                .fold(f64::INFINITY, f64::min);
            prop_assert!(exact <= dense + 1e-9, "{exact} > {dense}");
            // A point of either triangle lies within half a grid cell's diagonal of a sample.
            let cell = |p: &Point3, q: &Point3, r: &Point3| {
                ((q - p).norm() + (r - p).norm()) / n as f64
            };
            prop_assert!(dense - exact <= cell(&a, &b, &c) + cell(&u, &v, &w), "{exact} vs {dense}");
        }
    }

    #[test]
    fn crossing_and_stacked_triangles_are_at_their_closed_form_distances() {
        let (a, b, c) = (
            Point3::new(0.0, 0.0, 0.0),
            Point3::new(4.0, 0.0, 0.0),
            Point3::new(0.0, 4.0, 0.0),
        );
        // Standing through the first's interior: they meet, though no corner is near.
        let crossing = triangle_triangle_distance(
            &a,
            &b,
            &c,
            &Point3::new(1.0, -3.0, -1.0),
            &Point3::new(1.0, 5.0, -1.0),
            &Point3::new(1.0, 1.0, 3.0),
        );
        assert_eq!(crossing, 0.0);
        // A smaller copy 0.25 above, wholly over the first: only interiors face each other.
        let stacked = triangle_triangle_distance(
            &a,
            &b,
            &c,
            &Point3::new(0.5, 0.5, 0.25),
            &Point3::new(1.5, 0.5, 0.25),
            &Point3::new(0.5, 1.5, 0.25),
        );
        assert!((stacked - 0.25).abs() < 1e-15, "{stacked}");
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
        // Short pieces and points a ball's radius or so off the surface, as the
        // back-simulation asks.
        for i in 0..400 {
            let s = i as f64 * 0.173;
            let p = Point3::new(s.cos(), s.sin(), (0.7 * s).sin()) * 12.0;
            let length = [0.0, 1e-4, 0.01, 0.2][i % 4];
            let q = p + Vector3::new((1.3 * s).sin(), (0.3 * s).cos(), -0.4) * length;
            assert_eq!(tree.distance(&p, &q, f64::INFINITY), brute(&p, &q));
        }
        // Grazing the surface: every nearby plane and edge bound is within a hair of the
        // answer, and a limit just above it must still find it.
        for i in 0..400 {
            let s = i as f64 * 0.291;
            let p = Point3::new(s.cos(), s.sin(), (0.4 * s).sin())
                .coords
                .normalize()
                * 10.002;
            let q = Point3::from(p) + Vector3::new((0.7 * s).cos(), (1.9 * s).sin(), 0.3) * 0.3;
            let p = Point3::from(p);
            let exact = brute(&p, &q);
            assert_eq!(tree.distance(&p, &q, f64::INFINITY), exact);
            assert_eq!(tree.distance(&p, &q, exact + 1e-9), exact);
        }
    }

    /// The tree's triangle and quadrilateral queries against every triangle, on slivers and
    /// sheets around and through a sphere.
    #[test]
    fn tree_triangle_and_quad_queries_equal_brute_force_on_a_sphere() {
        let sphere = uv_sphere(10.0, 16, 32);
        let tree = SegmentDistance::new(&sphere);
        for i in 0..200 {
            let s = i as f64 * 0.41;
            let a = Point3::new(13.0 * s.cos(), 13.0 * s.sin(), 11.0 * (0.6 * s).sin());
            let b = a + Vector3::new((1.1 * s).sin(), (0.5 * s).cos(), -0.7) * (2.0 + s % 5.0);
            let c = a + Vector3::new(0.2, (0.9 * s).sin(), (0.4 * s).cos()) * (1.0 + s % 3.0);
            let exact = (0..sphere.triangles.len())
                .map(|t| {
                    let [u, v, w] = sphere.corners(t);
                    triangle_triangle_distance(&a, &b, &c, &u, &v, &w)
                })
                .fold(f64::INFINITY, f64::min);
            assert_eq!(tree.triangle_distance(&a, &b, &c, f64::INFINITY), exact);
            assert_eq!(tree.triangle_distance(&a, &b, &c, exact * 0.5), exact * 0.5);
            // A twisted quadrilateral on a, b, c: its two triangles, with the gap tests along
            // its sides and across it in front of the exact ones.
            let d = c + (b - a) * 0.8 + Vector3::new(0.3, -0.2, 0.5) * (s % 2.0);
            let quad = [a, b, d, c];
            let exact = (0..sphere.triangles.len())
                .map(|t| {
                    let [u, v, w] = sphere.corners(t);
                    triangle_triangle_distance(&a, &b, &d, &u, &v, &w)
                        .min(triangle_triangle_distance(&a, &d, &c, &u, &v, &w))
                })
                .fold(f64::INFINITY, f64::min);
            assert_eq!(tree.quad_distance(&quad, f64::INFINITY, |_| true), exact);
            assert_eq!(tree.quad_distance(&quad, 7.0, |_| false), 7.0);
        }
    }
}
