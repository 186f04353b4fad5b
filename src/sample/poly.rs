//! Small 2D polygon helpers used for validation and Steiner-point thinning.

/// A point in the (x, y) plane.
pub(super) type P2 = [f64; 2];

fn sub(a: P2, b: P2) -> P2 {
    [a[0] - b[0], a[1] - b[1]]
}

fn cross(a: P2, b: P2) -> f64 {
    a[0] * b[1] - a[1] * b[0]
}

fn dot(a: P2, b: P2) -> f64 {
    a[0] * b[0] + a[1] * b[1]
}

/// Orientation of `c` relative to the directed line `a → b` (> 0: left).
fn orient(a: P2, b: P2, c: P2) -> f64 {
    cross(sub(b, a), sub(c, a))
}

/// Distance from `p` to the closed segment `a b`.
pub(super) fn segment_distance(p: P2, a: P2, b: P2) -> f64 {
    let ab = sub(b, a);
    let ap = sub(p, a);
    let len2 = dot(ab, ab);
    let t = if len2 > 0.0 {
        (dot(ap, ab) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let d = [ap[0] - t * ab[0], ap[1] - t * ab[1]];
    dot(d, d).sqrt()
}

/// Whether the closed segments `a b` and `c d` share a point.
pub(super) fn segments_intersect(a: P2, b: P2, c: P2, d: P2) -> bool {
    let (o1, o2) = (orient(a, b, c), orient(a, b, d));
    let (o3, o4) = (orient(c, d, a), orient(c, d, b));
    if ((o1 > 0.0 && o2 < 0.0) || (o1 < 0.0 && o2 > 0.0))
        && ((o3 > 0.0 && o4 < 0.0) || (o3 < 0.0 && o4 > 0.0))
    {
        return true;
    }
    let on = |p: P2, q: P2, r: P2| {
        r[0] >= p[0].min(q[0])
            && r[0] <= p[0].max(q[0])
            && r[1] >= p[1].min(q[1])
            && r[1] <= p[1].max(q[1])
    };
    (o1 == 0.0 && on(a, b, c))
        || (o2 == 0.0 && on(a, b, d))
        || (o3 == 0.0 && on(c, d, a))
        || (o4 == 0.0 && on(c, d, b))
}

/// Even-odd point-in-polygon test.
pub(super) fn point_in_polygon(p: P2, poly: &[P2]) -> bool {
    let mut inside = false;
    let n = poly.len();
    for i in 0..n {
        let (a, b) = (poly[i], poly[(i + n - 1) % n]);
        if (a[1] > p[1]) != (b[1] > p[1]) {
            let x = a[0] + (p[1] - a[1]) * (b[0] - a[0]) / (b[1] - a[1]);
            if p[0] < x {
                inside = !inside;
            }
        }
    }
    inside
}

/// Twice the signed area (> 0 for counter-clockwise).
pub(super) fn signed_area2(poly: &[P2]) -> f64 {
    let n = poly.len();
    (0..n).map(|i| cross(poly[i], poly[(i + 1) % n])).sum()
}

/// Whether the closed polygon is simple: non-adjacent edges do not meet and no vertex folds
/// straight back onto the previous edge.
pub(super) fn polygon_is_simple(poly: &[P2]) -> bool {
    let n = poly.len();
    if n < 3 {
        return false;
    }
    for i in 0..n {
        let (a, b, c) = (poly[i], poly[(i + 1) % n], poly[(i + 2) % n]);
        if a == b || (orient(a, b, c) == 0.0 && dot(sub(b, a), sub(c, b)) <= 0.0) {
            return false;
        }
        for j in i + 2..n {
            if (j + 1) % n == i {
                continue;
            }
            if segments_intersect(a, b, poly[j], poly[(j + 1) % n]) {
                return false;
            }
        }
    }
    true
}

/// Distance between two closed polygons' boundaries, or 0 if they intersect or one contains
/// the other.
pub(super) fn polygon_distance(p: &[P2], q: &[P2]) -> f64 {
    if p.is_empty() || q.is_empty() {
        return f64::INFINITY;
    }
    if point_in_polygon(p[0], q) || point_in_polygon(q[0], p) {
        return 0.0;
    }
    let mut d = f64::INFINITY;
    for i in 0..p.len() {
        let (a, b) = (p[i], p[(i + 1) % p.len()]);
        for j in 0..q.len() {
            let (c, e) = (q[j], q[(j + 1) % q.len()]);
            if segments_intersect(a, b, c, e) {
                return 0.0;
            }
            d = d
                .min(segment_distance(a, c, e))
                .min(segment_distance(c, a, b));
        }
    }
    d
}

/// A parametric curve sampled densely, for placing points at equal arc-length steps.
#[derive(Debug)]
pub(super) struct ArcTable {
    params: Vec<f64>,
    lengths: Vec<f64>,
}

impl ArcTable {
    /// Samples `f` at `samples + 1` evenly spaced parameters from `t0` to `t1`.
    pub(super) fn new(t0: f64, t1: f64, samples: usize, f: impl Fn(f64) -> P2) -> Self {
        let samples = samples.max(1);
        let mut params = Vec::with_capacity(samples + 1);
        let mut lengths = Vec::with_capacity(samples + 1);
        let mut prev = f(t0);
        let mut acc = 0.0;
        for i in 0..=samples {
            let t = t0 + (t1 - t0) * i as f64 / samples as f64;
            let p = f(t);
            acc += dot(sub(p, prev), sub(p, prev)).sqrt();
            params.push(t);
            lengths.push(acc);
            prev = p;
        }
        Self { params, lengths }
    }

    /// Total arc length.
    pub(super) fn length(&self) -> f64 {
        self.lengths.last().copied().unwrap_or(0.0)
    }

    /// The parameter at arc length `s` (clamped to the curve), interpolated linearly.
    pub(super) fn param_at(&self, s: f64) -> f64 {
        let i = self.lengths.partition_point(|&l| l < s);
        if i == 0 {
            return self.params[0];
        }
        if i >= self.lengths.len() {
            return self.params[self.params.len() - 1];
        }
        let (l0, l1) = (self.lengths[i - 1], self.lengths[i]);
        let f = if l1 > l0 { (s - l0) / (l1 - l0) } else { 0.0 };
        self.params[i - 1] + f * (self.params[i] - self.params[i - 1])
    }
}

/// Polygons that Steiner points must keep out of and away from.
#[derive(Debug, Default)]
pub(super) struct Obstacles {
    /// Each polygon with its bounding box `[min, max]`.
    polys: Vec<(Vec<P2>, [P2; 2])>,
}

impl Obstacles {
    /// Adds a closed polygon.
    pub(super) fn add(&mut self, poly: Vec<P2>) {
        let mut lo = [f64::INFINITY; 2];
        let mut hi = [f64::NEG_INFINITY; 2];
        for p in &poly {
            for k in 0..2 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        self.polys.push((poly, [lo, hi]));
    }

    /// Whether `p` lies outside every polygon and at least `clearance` from each boundary.
    pub(super) fn is_clear(&self, p: P2, clearance: f64) -> bool {
        self.polys.iter().all(|(poly, [lo, hi])| {
            if p[0] < lo[0] - clearance
                || p[0] > hi[0] + clearance
                || p[1] < lo[1] - clearance
                || p[1] > hi[1] + clearance
            {
                return true;
            }
            if point_in_polygon(p, poly) {
                return false;
            }
            let n = poly.len();
            (0..n).all(|i| segment_distance(p, poly[i], poly[(i + 1) % n]) >= clearance)
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn square_helpers() {
        let sq = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
        assert!(polygon_is_simple(&sq));
        assert!(point_in_polygon([0.5, 0.5], &sq));
        assert!(!point_in_polygon([1.5, 0.5], &sq));
        assert_eq!(signed_area2(&sq), 2.0);
        let bow = [[0.0, 0.0], [1.0, 1.0], [1.0, 0.0], [0.0, 1.0]];
        assert!(!polygon_is_simple(&bow));
        let far: Vec<P2> = sq.iter().map(|p| [p[0] + 3.0, p[1]]).collect();
        assert_eq!(polygon_distance(&sq, &far), 2.0);
        let inner: Vec<P2> = sq
            .iter()
            .map(|p| [0.25 + p[0] * 0.5, 0.25 + p[1] * 0.5])
            .collect();
        assert_eq!(polygon_distance(&sq, &inner), 0.0);
        let mut obs = Obstacles::default();
        obs.add(sq.to_vec());
        assert!(!obs.is_clear([0.5, 0.5], 0.1));
        assert!(!obs.is_clear([1.05, 0.5], 0.1));
        assert!(obs.is_clear([1.2, 0.5], 0.1));
    }
}
