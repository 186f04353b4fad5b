//! Exact f64 point-to-surface queries: closest point, and signed distance by angle-weighted
//! pseudo-normals (Bærentzen & Aanæs 2005), on a bounding-volume hierarchy over the triangles.
//!
//! parry3d works in f32 and treats a TriMesh as a hollow surface (CRATES.md §8.2); the
//! guarantees wavemill gives (no gouge to 1e-6 mm) need f64 and a real inside test, so the
//! queries that decide them are done here.

use crate::geom::{
    Aabb, ClosestFeature, Point3, Vector3, closest_point_on_triangle,
    closest_points_of_segment_and_triangle,
};
use crate::mesh::Mesh;
use crate::mesh::topology::edges;

const LEAF_SIZE: usize = 4;

#[derive(Clone, Debug)]
struct Node {
    aabb: Aabb,
    /// Leaf: `start..start+count` in `order`; inner: children `start` and `start + 1`... stored
    /// as explicit indices because the tree is built depth-first.
    left: u32,
    right: u32,
    start: u32,
    count: u32,
}

/// The traversal stack of a query: nodes with their box distance², on the call stack while
/// the tree is shallow enough (it always is for a median-split tree of a real mesh), so a
/// query allocates nothing.
struct NodeStack {
    inline: [(f64, u32); 64],
    len: usize,
    overflow: Vec<(f64, u32)>,
}

impl NodeStack {
    fn new(first: (f64, u32)) -> Self {
        let mut inline = [(0.0, 0); 64];
        inline[0] = first;
        Self {
            inline,
            len: 1,
            overflow: Vec::new(),
        }
    }

    #[inline(always)]
    fn push(&mut self, item: (f64, u32)) {
        if self.len < self.inline.len() {
            self.inline[self.len] = item;
            self.len += 1;
        } else {
            self.overflow.push(item);
        }
    }

    #[inline(always)]
    fn pop(&mut self) -> Option<(f64, u32)> {
        if let Some(item) = self.overflow.pop() {
            return Some(item);
        }
        if self.len == 0 {
            return None;
        }
        self.len -= 1;
        Some(self.inline[self.len])
    }
}

/// The closest point of the surface to a query point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Closest {
    pub point: Point3,
    pub distance: f64,
    pub triangle: u32,
    pub feature: ClosestFeature,
}

/// A static triangle mesh prepared for exact nearest-point and signed-distance queries.
#[derive(Clone, Debug)]
pub struct SurfaceDistance {
    positions: Vec<Point3>,
    triangles: Vec<[u32; 3]>,
    nodes: Vec<Node>,
    order: Vec<u32>,
    face_normals: Vec<Vector3>,
    /// Per triangle, the pseudo-normal of each of its edges (edge k: corner k to k+1).
    edge_normals: Vec<[Vector3; 3]>,
    vertex_normals: Vec<Vector3>,
    /// Per triangle, the half-planes it lies in, for a bound before the exact distance.
    fences: Vec<Fence>,
}

/// A triangle's plane (unit normal and offset) and, in it, the outward unit normal and
/// offset of each edge's line: the triangle is the plane's part behind all three lines. A
/// point `h` off the plane and `g` beyond one line is at least `√(h² + g²)` from the triangle,
/// and over a segment both are affine, least at an end: a bound of a few dot products that
/// keeps most triangles near a query from the exact test. All zero for a degenerate triangle
/// (no bound).
#[derive(Clone, Copy, Debug)]
struct Fence {
    normal: Vector3,
    offset: f64,
    edges: [(Vector3, f64); 3],
}

/// f64 rounding of the fence's dot products is far below this, so a triangle the bound
/// drops is farther than the limit by more than any rounding.
const FENCE_SLACK: f64 = 1e-9;

impl Fence {
    fn new(corners: &[Point3; 3], normal: Vector3) -> Self {
        let edges = std::array::from_fn(|k| {
            let (a, b) = (corners[k], corners[(k + 1) % 3]);
            // Counter-clockwise about the normal, edge × normal points out of the triangle.
            let out: Vector3 = (b - a).cross(&normal);
            let length = out.norm();
            if length > 0.0 {
                let unit = out / length;
                (unit, unit.dot(&a.coords))
            } else {
                (Vector3::zeros(), 0.0)
            }
        });
        Fence {
            normal,
            offset: normal.dot(&corners[0].coords),
            edges,
        }
    }

    /// A lower bound of the squared distance from the segment `a b` (a point when equal) to
    /// the triangle.
    #[inline(always)]
    fn distance_squared_below(&self, a: &Point3, b: &Point3) -> f64 {
        let (ha, hb) = (
            self.normal.dot(&a.coords) - self.offset,
            self.normal.dot(&b.coords) - self.offset,
        );
        let height = if (ha > 0.0) == (hb > 0.0) {
            ha.abs().min(hb.abs())
        } else {
            0.0
        };
        let mut beyond: f64 = 0.0;
        for (out, offset) in &self.edges {
            let least = (out.dot(&a.coords) - offset).min(out.dot(&b.coords) - offset);
            beyond = beyond.max(least);
        }
        let (h, g) = (
            (height - FENCE_SLACK).max(0.0),
            (beyond - FENCE_SLACK).max(0.0),
        );
        h * h + g * g
    }
}

/// The answer of [`SurfaceDistance::segment_search`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SegmentSearch {
    /// No triangle comes within the radius.
    Clear,
    /// Some do, none of their nearest points was accepted.
    Near,
    /// A triangle within the radius had its nearest point accepted.
    Accepted,
}

impl SurfaceDistance {
    pub fn new(mesh: &Mesh) -> Self {
        let n = mesh.triangles.len();
        let face_normals: Vec<Vector3> = (0..n).map(|t| mesh.face_normal(t)).collect();
        let mut vertex_normals = vec![Vector3::zeros(); mesh.positions.len()];
        for (t, tri) in mesh.triangles.iter().enumerate() {
            let p = tri.map(|i| mesh.positions[i as usize]);
            for k in 0..3 {
                let (a, b) = (p[(k + 1) % 3] - p[k], p[(k + 2) % 3] - p[k]);
                let angle = crate::geom::angle_between(&a, &b);
                vertex_normals[tri[k] as usize] += face_normals[t] * angle;
            }
        }
        let mut edge_normals = vec![[Vector3::zeros(); 3]; n];
        for e in edges(&mesh.triangles) {
            let sum: Vector3 = e.faces.iter().map(|&(f, _)| face_normals[f as usize]).sum();
            for &(f, _) in &e.faces {
                let tri = mesh.triangles[f as usize];
                for k in 0..3 {
                    let (a, b) = (tri[k], tri[(k + 1) % 3]);
                    if [a.min(b), a.max(b)] == e.vertices {
                        edge_normals[f as usize][k] = sum;
                    }
                }
            }
        }
        let fences = (0..n)
            .map(|t| Fence::new(&mesh.corners(t), face_normals[t]))
            .collect();
        let mut s = SurfaceDistance {
            positions: mesh.positions.clone(),
            triangles: mesh.triangles.clone(),
            nodes: Vec::new(),
            order: (0..n as u32).collect(),
            face_normals,
            edge_normals,
            vertex_normals,
            fences,
        };
        let centroids: Vec<Point3> = (0..n)
            .map(|t| {
                let [a, b, c] = mesh.corners(t);
                Point3::from((a.coords + b.coords + c.coords) / 3.0)
            })
            .collect();
        if n > 0 {
            s.build(0, n, &centroids);
        }
        s
    }

    fn triangle_aabb(&self, t: u32) -> Aabb {
        Aabb::from_points(&self.corners(t))
    }

    /// Builds the subtree over `order[start..end]` and returns its node index.
    fn build(&mut self, start: usize, end: usize, centroids: &[Point3]) -> u32 {
        let aabb = self.order[start..end]
            .iter()
            .fold(Aabb::empty(), |b, &t| b.merge(&self.triangle_aabb(t)));
        let index = self.nodes.len() as u32;
        self.nodes.push(Node {
            aabb,
            left: 0,
            right: 0,
            start: start as u32,
            count: (end - start) as u32,
        });
        if end - start <= LEAF_SIZE {
            return index;
        }
        let spread = Aabb::from_points(
            self.order[start..end]
                .iter()
                .map(|&t| &centroids[t as usize]),
        )
        .extent();
        let axis = spread.imax();
        let mid = (start + end) / 2;
        // Median split; ties broken by triangle index so the tree is deterministic.
        self.order[start..end].select_nth_unstable_by(mid - start, |&a, &b| {
            centroids[a as usize][axis]
                .total_cmp(&centroids[b as usize][axis])
                .then(a.cmp(&b))
        });
        let left = self.build(start, mid, centroids);
        let right = self.build(mid, end, centroids);
        let node = &mut self.nodes[index as usize];
        node.left = left;
        node.right = right;
        node.count = 0;
        index
    }

    /// The closest surface point within `max_distance` of `p` (use `f64::INFINITY` for no limit).
    pub fn closest(&self, p: &Point3, max_distance: f64) -> Option<Closest> {
        self.closest_where(p, max_distance, |_| true)
    }

    /// The closest point within `max_distance` on the triangles `accept` lets through (by
    /// index). Used to project onto the side of a thin wall that faces the right way.
    pub fn closest_where(
        &self,
        p: &Point3,
        max_distance: f64,
        accept: impl Fn(u32) -> bool,
    ) -> Option<Closest> {
        if self.nodes.is_empty() {
            return None;
        }
        let mut best: Option<Closest> = None;
        let mut best_d2 = max_distance * max_distance;
        let mut stack = NodeStack::new((self.nodes[0].aabb.distance_squared(p), 0));
        while let Some((d2, ni)) = stack.pop() {
            if d2 > best_d2 {
                continue;
            }
            let node = &self.nodes[ni as usize];
            if node.count > 0 {
                for &t in &self.order[node.start as usize..(node.start + node.count) as usize] {
                    if self.fences[t as usize].distance_squared_below(p, p) > best_d2 || !accept(t)
                    {
                        continue;
                    }
                    let [a, b, c] = self.corners(t);
                    let (q, feature) = closest_point_on_triangle(p, &a, &b, &c);
                    let qd2 = (q - p).norm_squared();
                    let better = match &best {
                        None => qd2 <= best_d2,
                        Some(bc) => qd2 < best_d2 || (qd2 == best_d2 && t < bc.triangle),
                    };
                    if better {
                        best_d2 = qd2;
                        best = Some(Closest {
                            point: q,
                            distance: qd2.sqrt(),
                            triangle: t,
                            feature,
                        });
                    }
                }
            } else {
                self.push_children(node, p, &mut stack);
            }
        }
        best
    }

    /// Whether some triangle comes strictly closer than `radius` to `p`. Stops at the first
    /// one found: far cheaper than [`SurfaceDistance::closest`] when the answer is yes, which
    /// is what a Hausdorff distance asks of almost every sample.
    pub fn any_within(&self, p: &Point3, radius: f64) -> bool {
        self.any_within_from(p, radius, &mut None)
    }

    /// [`SurfaceDistance::any_within`], trying the triangle `hint` first and leaving in it the
    /// triangle that answered yes. Queries in a coherent order (samples along an edge, over a
    /// triangle) mostly answer at the hint without walking the tree.
    pub fn any_within_from(&self, p: &Point3, radius: f64, hint: &mut Option<u32>) -> bool {
        if self.nodes.is_empty() || radius.is_nan() || radius <= 0.0 {
            return false;
        }
        let r2 = radius * radius;
        let near = |t: u32| {
            let [a, b, c] = self.corners(t);
            (closest_point_on_triangle(p, &a, &b, &c).0 - p).norm_squared() < r2
        };
        if let Some(t) = *hint
            && (t as usize) < self.triangles.len()
            && near(t)
        {
            return true;
        }
        let mut stack = NodeStack::new((self.nodes[0].aabb.distance_squared(p), 0));
        while let Some((d2, ni)) = stack.pop() {
            if d2 >= r2 {
                continue;
            }
            let node = &self.nodes[ni as usize];
            if node.count > 0 {
                let leaf = &self.order[node.start as usize..(node.start + node.count) as usize];
                // A corner inside the ball answers without the full triangle test.
                if let Some(&t) = leaf.iter().find(|&&t| {
                    self.triangles[t as usize]
                        .iter()
                        .any(|&i| (self.positions[i as usize] - p).norm_squared() < r2)
                }) {
                    *hint = Some(t);
                    return true;
                }
                if let Some(&t) = leaf.iter().find(|&&t| near(t)) {
                    *hint = Some(t);
                    return true;
                }
            } else {
                self.push_children(node, p, &mut stack);
            }
        }
        false
    }

    /// Whether some triangle comes strictly closer than `radius` to the segment `a b`: the
    /// straight move of a ball centre, checked along its whole length (a chord can cut deepest
    /// anywhere, not only at its midpoint).
    pub fn segment_within(&self, a: &Point3, b: &Point3, radius: f64) -> bool {
        self.segment_search(a, b, radius, |_| true) != SegmentSearch::Clear
    }

    /// Which triangles come closer than `radius` to the segment `ab`, and whether one of
    /// them has its point nearest the segment accepted by `accept` (the search stops there).
    pub fn segment_search(
        &self,
        a: &Point3,
        b: &Point3,
        radius: f64,
        accept: impl FnMut(&Point3) -> bool,
    ) -> SegmentSearch {
        self.search_near(a, b, radius, accept, |_| true, |_, pair| Some(pair))
    }

    /// Like [`SurfaceDistance::segment_search`], for the solid cylinder of `radius` around
    /// `ab` with flat ends: only the part of each triangle between the planes through `a` and
    /// `b` square to `ab` counts, and the point handed to `accept` lies there. Those pieces
    /// of a tool body are what the body occupies; the capsule's round ends reach past them,
    /// where a ball-end tool's flutes start at the ball, which touches the part.
    pub fn cylinder_search(
        &self,
        a: &Point3,
        b: &Point3,
        radius: f64,
        accept: impl FnMut(&Point3) -> bool,
    ) -> SegmentSearch {
        let axis = b - a;
        let length = axis.norm();
        if length.is_nan() || length <= 0.0 {
            return self.segment_search(a, b, radius, accept);
        }
        let k = axis / length;
        // The slab a hair wider than the segment: widening only keeps more triangles near.
        let slack = 1e-9 * (1.0 + length);
        let (low, high) = (-slack, length + slack);
        // A triangle wholly below or above the slab has no part in it: a ball's contacts,
        // just below the flutes' lower end, are passed by without measuring them.
        let in_slab = |corners: &[Point3; 3]| {
            let heights = corners.map(|p| (p - a).dot(&k));
            !(heights.iter().all(|&h| h < low) || heights.iter().all(|&h| h > high))
        };
        self.search_near(a, b, radius, accept, in_slab, |corners, whole| {
            slab_nearest(a, b, &k, high, low, corners, whole)
        })
    }

    /// The search behind [`SurfaceDistance::segment_search`] and
    /// [`SurfaceDistance::cylinder_search`]: every triangle within `radius` of the segment
    /// (the closest pair of points of the two) goes to `nearest`, which may narrow the pair to
    /// the part of the triangle that counts, or say none does; `may_count` passes by, before
    /// anything is measured, triangles with no part that counts.
    fn search_near(
        &self,
        a: &Point3,
        b: &Point3,
        radius: f64,
        mut accept: impl FnMut(&Point3) -> bool,
        may_count: impl Fn(&[Point3; 3]) -> bool,
        nearest: impl Fn([Point3; 3], (Point3, Point3)) -> Option<(Point3, Point3)>,
    ) -> SegmentSearch {
        if self.nodes.is_empty() || radius.is_nan() || radius <= 0.0 {
            return SegmentSearch::Clear;
        }
        let r2 = radius * radius;
        let segment_box = Aabb::from_points([a, b]);
        let mut found = SegmentSearch::Clear;
        let along = b - a;
        let length2 = along.norm_squared();
        // A long tilted segment's box holds much that is far from it: a box whose centre is
        // farther from the segment than the radius and half its diagonal is passed by too.
        let enter = |node: &Aabb| {
            if node.distance_squared_to_box(&segment_box) >= r2 {
                return false;
            }
            let centre = node.center();
            let s = if length2 > 0.0 {
                ((centre - a).dot(&along) / length2).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let reach = radius + 0.5 * node.extent().norm() + FENCE_SLACK;
            (a + along * s - centre).norm_squared() < reach * reach
        };
        self.visit_leaves(enter, |t, [p, q, r]| {
            if self.fences[t as usize].distance_squared_below(a, b) >= r2 || !may_count(&[p, q, r])
            {
                return false;
            }
            // The plain distance first: most triangles under the box are farther.
            let pair = closest_points_of_segment_and_triangle(a, b, &p, &q, &r);
            if (pair.0 - pair.1).norm_squared() >= r2 {
                return false;
            }
            let Some((on_segment, on_triangle)) = nearest([p, q, r], pair) else {
                return false;
            };
            if (on_segment - on_triangle).norm_squared() >= r2 {
                return false;
            }
            if accept(&on_triangle) {
                found = SegmentSearch::Accepted;
                return true;
            }
            found = SegmentSearch::Near;
            false
        });
        found
    }

    /// The corners of triangle `t`. Indexed out one by one: the hot loops are built at
    /// opt-level 1 in tests, where an array `map` stays a call.
    #[inline(always)]
    fn corners(&self, t: u32) -> [Point3; 3] {
        let [i, j, k] = self.triangles[t as usize];
        [
            self.positions[i as usize],
            self.positions[j as usize],
            self.positions[k as usize],
        ]
    }

    /// Depth-first over the tree: the corners of every triangle in a leaf whose box passes
    /// `enter` go to `visit`, until `visit` answers `true` (stop).
    fn visit_leaves(
        &self,
        enter: impl Fn(&Aabb) -> bool,
        mut visit: impl FnMut(u32, [Point3; 3]) -> bool,
    ) {
        if self.nodes.is_empty() {
            return;
        }
        let mut stack = vec![0u32];
        while let Some(ni) = stack.pop() {
            let node = &self.nodes[ni as usize];
            if !enter(&node.aabb) {
                continue;
            }
            if node.count == 0 {
                stack.push(node.right);
                stack.push(node.left);
                continue;
            }
            for &t in &self.order[node.start as usize..(node.start + node.count) as usize] {
                if visit(t, self.corners(t)) {
                    return;
                }
            }
        }
    }

    /// Queues an inner node's children with their box distances, the nearer last so that it
    /// is popped first.
    #[inline(always)]
    fn push_children(&self, node: &Node, p: &Point3, stack: &mut NodeStack) {
        let (l, r) = (node.left, node.right);
        let (dl, dr) = (
            self.nodes[l as usize].aabb.distance_squared(p),
            self.nodes[r as usize].aabb.distance_squared(p),
        );
        if dl <= dr {
            stack.push((dr, r));
            stack.push((dl, l));
        } else {
            stack.push((dl, l));
            stack.push((dr, r));
        }
    }

    /// The pseudo-normal at a closest point: its sign against `p - point` tells outside (>0)
    /// from inside (<0) exactly for a closed, consistently oriented surface.
    pub fn pseudo_normal(&self, c: &Closest) -> Vector3 {
        let t = c.triangle as usize;
        match c.feature {
            ClosestFeature::Face => self.face_normals[t],
            ClosestFeature::Edge(k) => self.edge_normals[t][k as usize],
            ClosestFeature::Vertex(k) => {
                self.vertex_normals[self.triangles[t][k as usize] as usize]
            }
        }
    }

    /// Signed distance: negative inside the solid. Meaningful for watertight meshes.
    pub fn signed_distance(&self, p: &Point3) -> Option<(f64, Closest)> {
        let c = self.closest(p, f64::INFINITY)?;
        let sign = if (p - c.point).dot(&self.pseudo_normal(&c)) < 0.0 {
            -1.0
        } else {
            1.0
        };
        Some((sign * c.distance, c))
    }

    /// How many triangles the ray `origin + s·direction`, s > 0, crosses (Möller–Trumbore in
    /// f64). Its parity tells inside from outside for any closed surface, manifold or not.
    pub fn ray_crossings(&self, origin: &Point3, direction: &Vector3) -> usize {
        let inverse = direction.map(|d| 1.0 / d);
        let hits_box = |b: &Aabb| {
            let (mut near, mut far) = (0.0f64, f64::INFINITY);
            for i in 0..3 {
                let t1 = (b.min[i] - origin[i]) * inverse[i];
                let t2 = (b.max[i] - origin[i]) * inverse[i];
                near = near.max(t1.min(t2));
                far = far.min(t1.max(t2));
            }
            near <= far
        };
        let mut count = 0;
        self.visit_leaves(hits_box, |_, [a, b, c]| {
            let (e1, e2) = (b - a, c - a);
            let p = direction.cross(&e2);
            let det = e1.dot(&p);
            if det != 0.0 {
                let s = origin - a;
                let u = s.dot(&p) / det;
                let q = s.cross(&e1);
                let v = direction.dot(&q) / det;
                if u >= 0.0 && v >= 0.0 && u + v <= 1.0 && e2.dot(&q) / det > 0.0 {
                    count += 1;
                }
            }
            false
        });
        count
    }

    /// Inside the closed surface by ray parity: the majority of three fixed, generic
    /// directions, so that a ray grazing an edge or vertex is outvoted.
    pub fn contains_by_parity(&self, p: &Point3) -> bool {
        // Unnormalised (parity does not care), no zero component, no symmetry of the grids
        // the shapes come from.
        const DIRECTIONS: [[f64; 3]; 3] = [[1.0, 1.1, 1.3], [-1.3, 0.7, 1.1], [0.3, -1.2, 0.9]];
        DIRECTIONS
            .iter()
            .filter(|d| self.ray_crossings(p, &Vector3::new(d[0], d[1], d[2])) % 2 == 1)
            .count()
            >= 2
    }

    /// Unit normal of triangle `t`.
    pub fn face_normal(&self, t: u32) -> Vector3 {
        self.face_normals[t as usize]
    }

    pub fn triangle_count(&self) -> usize {
        self.triangles.len()
    }
}

/// The closest points `(on ab, on the triangle)` of segment `ab` (unit direction `k`) and
/// the part of triangle `corners` between the planes `h = low` and `h = high` (`h` measured
/// from `a` along `k`), or `None` when no part of the triangle lies there. The clipped
/// triangle is a convex polygon of up to five corners, measured as a fan of triangles; a
/// triangle wholly between the planes keeps `whole`, the pair measured on all of it.
fn slab_nearest(
    a: &Point3,
    b: &Point3,
    k: &Vector3,
    high: f64,
    low: f64,
    corners: [Point3; 3],
    whole: (Point3, Point3),
) -> Option<(Point3, Point3)> {
    let height = |p: &Point3| (p - a).dot(k);
    if corners.iter().all(|p| (low..=high).contains(&height(p))) {
        return Some(whole);
    }
    // Sutherland–Hodgman against each plane in turn.
    let mut polygon: smallvec::SmallVec<[Point3; 5]> = corners.into_iter().collect();
    for (limit, keep_below) in [(high, true), (low, false)] {
        let side = |p: &Point3| {
            let h = height(p);
            if keep_below { limit - h } else { h - limit }
        };
        let mut clipped = smallvec::SmallVec::<[Point3; 5]>::new();
        for (i, p) in polygon.iter().enumerate() {
            let q = &polygon[(i + 1) % polygon.len()];
            let (sp, sq) = (side(p), side(q));
            if sp >= 0.0 {
                clipped.push(*p);
            }
            if (sp >= 0.0) != (sq >= 0.0) {
                let t = sp / (sp - sq);
                clipped.push(p + (q - p) * t);
            }
        }
        if clipped.is_empty() {
            return None;
        }
        polygon = clipped;
    }
    // A plane through a corner or along an edge may leave a point or an edge.
    while polygon.len() < 3 {
        polygon.push(polygon[polygon.len() - 1]);
    }
    let p = polygon[0];
    (1..polygon.len() - 1)
        .map(|i| closest_points_of_segment_and_triangle(a, b, &p, &polygon[i], &polygon[i + 1]))
        .min_by(|x, y| {
            (x.0 - x.1)
                .norm_squared()
                .total_cmp(&(y.0 - y.1).norm_squared())
        })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::fixtures::{torus, uv_sphere};

    fn brute_force(mesh: &Mesh, p: &Point3) -> f64 {
        (0..mesh.triangles.len())
            .map(|t| {
                let [a, b, c] = mesh.corners(t);
                (closest_point_on_triangle(p, &a, &b, &c).0 - p).norm()
            })
            .fold(f64::INFINITY, f64::min)
    }

    /// Deterministic pseudo-random points (no rand dependency needed for a test grid).
    fn probe_points(n: usize, half: f64) -> Vec<Point3> {
        let mut s = 0x9E3779B97F4A7C15u64;
        let mut next = || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            (s >> 11) as f64 / (1u64 << 53) as f64 * 2.0 * half - half
        };
        (0..n)
            .map(|_| Point3::new(next(), next(), next()))
            .collect()
    }

    #[test]
    fn closest_agrees_with_brute_force() {
        let m = torus(20.0, 6.0, 40, 20);
        let s = SurfaceDistance::new(&m);
        for p in probe_points(300, 35.0) {
            let c = s.closest(&p, f64::INFINITY).unwrap();
            assert!((c.distance - brute_force(&m, &p)).abs() < 1e-12);
            assert!((c.point - p).norm() - c.distance < 1e-12);
        }
    }

    /// `any_within` answers exactly what the brute-force distance says, just above and just
    /// below it, and refuses empty or non-positive radii.
    #[test]
    fn any_within_agrees_with_brute_force() {
        let m = torus(20.0, 6.0, 40, 20);
        let s = SurfaceDistance::new(&m);
        // With a hint carried from query to query (often a wrong one), the same answers.
        let mut hint = Some(u32::MAX);
        for p in probe_points(300, 35.0) {
            let d = brute_force(&m, &p);
            assert!(s.any_within(&p, d * (1.0 + 1e-9) + 1e-12), "{p} at {d}");
            assert!(!s.any_within(&p, d * (1.0 - 1e-9)), "{p} at {d}");
            assert!(s.any_within_from(&p, d * (1.0 + 1e-9) + 1e-12, &mut hint));
            assert!(hint.is_some_and(|t| (t as usize) < m.triangles.len()));
            assert!(!s.any_within_from(&p, d * (1.0 - 1e-9), &mut hint));
        }
        let on = m.positions[7];
        assert!(!s.any_within(&on, 0.0));
        assert!(!s.any_within(&on, f64::NAN));
        assert!(s.any_within(&on, 1e-9));
    }

    /// `cylinder_search` against the triangles sampled densely: where it says clear, no
    /// sample between the end planes comes within the radius of the axis; where it says near,
    /// one comes within the radius plus the sampling's spacing; every point it hands over lies
    /// between the end planes within the radius. Segments round a torus, some crossing it.
    #[test]
    fn cylinder_search_agrees_with_sampled_triangles() {
        let m = torus(20.0, 6.0, 40, 20);
        let s = SurfaceDistance::new(&m);
        let (starts, ends) = (probe_points(240, 30.0), probe_points(480, 1.0));
        let (radius, steps) = (2.5, 40);
        let (mut clear, mut near) = (0, 0);
        for (i, a) in starts.iter().enumerate() {
            let b = a + (ends[2 * i + 1] - Point3::origin()).normalize() * 8.0;
            let k = (b - a).normalize();
            let in_cylinder = |p: &Point3, slack: f64| {
                let h = (p - a).dot(&k);
                let off = (p - a) - k * h;
                (-slack..=8.0 + slack).contains(&h) && off.norm() < radius + slack
            };
            let mut handed = Vec::new();
            let answer = s.cylinder_search(a, &b, radius, |p| {
                handed.push(*p);
                false
            });
            assert!(handed.iter().all(|p| in_cylinder(p, 1e-8)), "{a} {b}");
            let mut spacing: f64 = 0.0;
            let sampled_inside = |slack: f64, spacing: &mut f64| {
                (0..m.triangles.len()).any(|t| {
                    let [p, q, r] = m.corners(t);
                    if crate::geom::segment_triangle_distance_squared(a, &b, &p, &q, &r)
                        >= radius * radius
                    {
                        return false;
                    }
                    let longest = [(p - q).norm(), (q - r).norm(), (r - p).norm()]
                        .into_iter()
                        .fold(0.0, f64::max);
                    *spacing = spacing.max(longest / steps as f64);
                    (0..=steps).any(|u| {
                        (0..=steps - u).any(|v| {
                            let (u, v) = (u as f64 / steps as f64, v as f64 / steps as f64);
                            let x = p + (q - p) * u + (r - p) * v;
                            in_cylinder(&x, slack)
                        })
                    })
                })
            };
            match answer {
                SegmentSearch::Clear => {
                    clear += 1;
                    assert!(!sampled_inside(0.0, &mut spacing), "{a} {b}: clear");
                }
                SegmentSearch::Near => {
                    near += 1;
                    assert!(!handed.is_empty());
                    let _ = sampled_inside(0.0, &mut spacing);
                    assert!(sampled_inside(spacing, &mut spacing), "{a} {b}: near");
                }
                SegmentSearch::Accepted => panic!("nothing was accepted"),
            }
        }
        assert!(clear > 20 && near > 20, "{clear} clear, {near} near");
    }

    /// The fences and the boxes' centre test only pass by what is out of reach: just above
    /// and just below each segment's exact distance (every triangle measured), the search
    /// answers near and clear.
    #[test]
    fn segment_search_answers_at_the_exact_distance() {
        let m = torus(20.0, 6.0, 40, 20);
        let s = SurfaceDistance::new(&m);
        let (starts, ends) = (probe_points(300, 30.0), probe_points(600, 1.0));
        for (i, a) in starts.iter().enumerate() {
            // Short chords and long tilted shanks.
            let length = [0.3, 4.0, 30.0][i % 3];
            let b = a + (ends[2 * i + 1] - Point3::origin()).normalize() * length;
            let exact = (0..m.triangles.len())
                .map(|t| {
                    let [p, q, r] = m.corners(t);
                    crate::geom::segment_triangle_distance_squared(a, &b, &p, &q, &r)
                })
                .fold(f64::INFINITY, f64::min)
                .sqrt();
            if exact > 1e-6 {
                assert!(
                    s.segment_within(a, &b, exact * (1.0 + 1e-9) + 1e-12),
                    "{a} {b}"
                );
                assert!(!s.segment_within(a, &b, exact * (1.0 - 1e-9)), "{a} {b}");
            }
            let c = s.closest(a, f64::INFINITY).map(|c| c.distance);
            assert_eq!(c, Some(brute_force(&m, a)));
        }
    }

    /// Filtering by facing: from just inside a thin slab, the nearest face is the far side; the
    /// nearest face whose normal agrees with +z is the top.
    #[test]
    fn filtered_search_finds_the_facing_side() {
        let mut slab = crate::mesh::fixtures::cuboid(10.0, 10.0, 0.2);
        for p in &mut slab.positions {
            p.z -= 0.1;
        }
        let s = SurfaceDistance::new(&slab);
        let p = Point3::new(5.0, 5.0, -0.05);
        assert!((s.closest(&p, f64::INFINITY).unwrap().point.z + 0.1).abs() < 1e-12);
        let up = s
            .closest_where(&p, f64::INFINITY, |t| s.face_normal(t).z > 0.5)
            .unwrap();
        assert!((up.point.z - 0.1).abs() < 1e-12);
        let brute = (0..slab.triangles.len() as u32)
            .filter(|&t| s.face_normal(t).z > 0.5)
            .map(|t| {
                let [a, b, c] = slab.corners(t as usize);
                (closest_point_on_triangle(&p, &a, &b, &c).0 - p).norm()
            })
            .fold(f64::INFINITY, f64::min);
        assert!((up.distance - brute).abs() < 1e-12);
    }

    #[test]
    fn max_distance_limits_the_search() {
        let m = uv_sphere(10.0, 16, 32);
        let s = SurfaceDistance::new(&m);
        assert!(s.closest(&Point3::new(0.0, 0.0, 25.0), 5.0).is_none());
        assert!(s.closest(&Point3::new(0.0, 0.0, 14.0), 5.0).is_some());
    }

    /// Inside/outside from pseudo-normals against the analytic torus, away from the surface
    /// by more than the tessellation error.
    #[test]
    fn sign_matches_the_analytic_solid() {
        let (big, small) = (20.0, 6.0);
        let m = torus(big, small, 96, 48);
        let s = SurfaceDistance::new(&m);
        let mut checked = 0;
        for p in probe_points(2000, 30.0) {
            let ring = ((p.x * p.x + p.y * p.y).sqrt() - big).hypot(p.z) - small;
            if ring.abs() < 0.2 {
                continue;
            }
            let (d, _) = s.signed_distance(&p).unwrap();
            assert_eq!(d < 0.0, ring < 0.0, "wrong side at {p:?}");
            checked += 1;
        }
        assert!(checked > 1500);
        // Exactly on vertices and edges the sign must not flip to "inside" for points lifted
        // along the pseudo-normal.
        for (i, v) in m.positions.iter().enumerate().step_by(37) {
            let out =
                v + (v.coords - Vector3::new(v.x, v.y, 0.0).normalize() * big).normalize() * 1e-9;
            let (d, _) = s.signed_distance(&out).unwrap();
            assert!(d > 0.0, "vertex {i}");
        }
    }
}
