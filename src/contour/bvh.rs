//! A static bounding-volume hierarchy over line/arc segments: exact nearest-segment queries by
//! branch and bound (box distance is a lower bound of the exact distance), so the overcut check
//! of a path against a part costs about O((n + m) log m) instead of O(n·m).

use crate::contour::geometry::{Point2, Segment};
use crate::contour::segops::{bbox, point_distance, segment_distance};
use crate::geom::Aabb2;

const LEAF_SIZE: usize = 4;

#[derive(Clone, Debug)]
enum Kind {
    Leaf { first: usize, count: usize },
    Inner { left: usize, right: usize },
}

#[derive(Clone, Debug)]
struct Node {
    bbox: Aabb2,
    kind: Kind,
}

/// The closest segment of the hierarchy to a query.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Nearest {
    /// Exact minimum distance.
    pub distance: f64,
    /// Index of the closest segment (in the order given to [`SegmentBvh::new`]).
    pub index: usize,
    /// Closest point on the query.
    pub on_query: Point2,
    /// Closest point on the indexed segment.
    pub on_segment: Point2,
}

/// Static BVH over a set of segments.
#[derive(Clone, Debug)]
pub struct SegmentBvh {
    segs: Vec<Segment>,
    boxes: Vec<Aabb2>,
    order: Vec<usize>,
    nodes: Vec<Node>,
}

impl SegmentBvh {
    /// Builds the hierarchy (median split on the longer axis; deterministic).
    pub fn new(segs: Vec<Segment>) -> Self {
        let boxes: Vec<Aabb2> = segs.iter().map(bbox).collect();
        let mut order: Vec<usize> = (0..segs.len()).collect();
        let mut nodes = Vec::new();
        if !segs.is_empty() {
            build(&boxes, &mut order, 0, segs.len(), &mut nodes);
        }
        Self {
            segs,
            boxes,
            order,
            nodes,
        }
    }

    /// The indexed segments.
    pub fn segments(&self) -> &[Segment] {
        &self.segs
    }

    /// Bounding box of everything, `None` when empty.
    pub fn bounds(&self) -> Option<Aabb2> {
        self.nodes.first().map(|n| n.bbox)
    }

    /// The indexed segment closest to `q` (exact), `None` when the hierarchy is empty.
    pub fn nearest(&self, q: &Segment) -> Option<Nearest> {
        let qb = bbox(q);
        self.search(|b| b.distance(&qb), |s| segment_distance(q, s))
    }

    /// The indexed segment closest to the point `p` (exact).
    pub fn nearest_point(&self, p: Point2) -> Option<Nearest> {
        self.search(
            |b| b.point_distance(p),
            |s| {
                let (d, q) = point_distance(p, s);
                (d, p, q)
            },
        )
    }

    fn search(
        &self,
        lower: impl Fn(&Aabb2) -> f64,
        exact: impl Fn(&Segment) -> (f64, Point2, Point2),
    ) -> Option<Nearest> {
        if self.nodes.is_empty() {
            return None;
        }
        let mut best: Option<Nearest> = None;
        let mut stack = vec![(0usize, lower(&self.nodes[0].bbox))];
        while let Some((ni, lb)) = stack.pop() {
            if best.is_some_and(|b| lb >= b.distance) {
                continue;
            }
            match self.nodes[ni].kind {
                Kind::Leaf { first, count } => {
                    for &si in &self.order[first..first + count] {
                        if best.is_some_and(|b| lower(&self.boxes[si]) >= b.distance) {
                            continue;
                        }
                        let (d, on_query, on_segment) = exact(&self.segs[si]);
                        // Ties go to the lower index so the answer does not depend on the tree.
                        if best.is_none_or(|b| d < b.distance || (d == b.distance && si < b.index))
                        {
                            best = Some(Nearest {
                                distance: d,
                                index: si,
                                on_query,
                                on_segment,
                            });
                        }
                    }
                }
                Kind::Inner { left, right } => {
                    let (dl, dr) = (
                        lower(&self.nodes[left].bbox),
                        lower(&self.nodes[right].bbox),
                    );
                    // Push the farther child first so the nearer one is explored first.
                    if dl <= dr {
                        stack.push((right, dr));
                        stack.push((left, dl));
                    } else {
                        stack.push((left, dl));
                        stack.push((right, dr));
                    }
                }
            }
        }
        best
    }

    /// Calls `f` with the index of every segment whose bounding box is within `max_dist` of
    /// `query` (a superset of the segments within `max_dist`), in increasing index order.
    pub fn candidates_near(&self, query: &Aabb2, max_dist: f64) -> Vec<usize> {
        let mut out = Vec::new();
        if self.nodes.is_empty() {
            return out;
        }
        let mut stack = vec![0usize];
        while let Some(ni) = stack.pop() {
            let node = &self.nodes[ni];
            if node.bbox.distance(query) > max_dist {
                continue;
            }
            match node.kind {
                Kind::Leaf { first, count } => {
                    for &si in &self.order[first..first + count] {
                        if self.boxes[si].distance(query) <= max_dist {
                            out.push(si);
                        }
                    }
                }
                Kind::Inner { left, right } => {
                    stack.push(left);
                    stack.push(right);
                }
            }
        }
        out.sort_unstable();
        out
    }
}

fn build(
    boxes: &[Aabb2],
    order: &mut [usize],
    lo: usize,
    hi: usize,
    nodes: &mut Vec<Node>,
) -> usize {
    let mut bb = boxes[order[lo]];
    for &i in &order[lo + 1..hi] {
        bb = bb.union(&boxes[i]);
    }
    let me = nodes.len();
    nodes.push(Node {
        bbox: bb,
        kind: Kind::Leaf {
            first: lo,
            count: hi - lo,
        },
    });
    if hi - lo <= LEAF_SIZE {
        return me;
    }
    let mut cb = Aabb2::point(boxes[order[lo]].center());
    for &i in &order[lo + 1..hi] {
        cb.add(boxes[i].center());
    }
    let axis_x = cb.max.x - cb.min.x >= cb.max.y - cb.min.y;
    let key = |i: usize| {
        let c = boxes[i].center();
        if axis_x { c.x } else { c.y }
    };
    let mid = (lo + hi) / 2;
    order[lo..hi]
        .select_nth_unstable_by(mid - lo, |&a, &b| key(a).total_cmp(&key(b)).then(a.cmp(&b)));
    let left = build(boxes, order, lo, mid, nodes);
    let right = build(boxes, order, mid, hi, nodes);
    nodes[me].kind = Kind::Inner { left, right };
    me
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nearest_matches_brute_force() {
        let mut random = crate::geom::SeededRandom::new(7);
        let mut rnd = move || random.range(-10.0, 10.0);
        let mut segs = Vec::new();
        for i in 0..300 {
            let a = Point2::new(rnd(), rnd());
            let b = Point2::new(a.x + rnd() * 0.2, a.y + rnd() * 0.2);
            segs.push(Segment::new(
                a,
                b,
                if i % 3 == 0 { 0.0 } else { rnd() * 0.1 },
            ));
        }
        let bvh = SegmentBvh::new(segs.clone());
        for _ in 0..200 {
            let a = Point2::new(rnd(), rnd());
            let q = Segment::new(
                a,
                Point2::new(a.x + rnd() * 0.3, a.y + rnd() * 0.3),
                rnd() * 0.1,
            );
            let got = bvh.nearest(&q).expect("non-empty");
            let brute = segs
                .iter()
                .map(|s| segment_distance(&q, s).0)
                .fold(f64::INFINITY, f64::min);
            assert_eq!(got.distance, brute);
            let p = Point2::new(rnd(), rnd());
            let gp = bvh.nearest_point(p).expect("non-empty");
            let bp = segs
                .iter()
                .map(|s| point_distance(p, s).0)
                .fold(f64::INFINITY, f64::min);
            assert_eq!(gp.distance, bp);
        }
    }
}
