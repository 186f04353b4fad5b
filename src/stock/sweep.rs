//! Swept solids a dexel line can be cut by, with their exact line intervals.
//!
//! Removal asks one question of a swept solid: which interval of an axis-parallel line lies
//! inside it. Every solid here is convex, so the answer is one interval, and it is computed in
//! closed form, not by sampling poses:
//!
//! * [`SphereSweptHull`]: the points within `radius` of the convex hull of up to four points.
//!   A ball-end cutter's body is a capsule (its axis segment thickened by the ball radius); a
//!   move sweeps the segment over the quadrilateral its two end positions span, so the move's
//!   swept body is the sphere-swept hull of those four points. For a pure translation the four
//!   points are coplanar and the hull is exactly the swept parallelogram; when the axis turns,
//!   the segment sweeps a bilinear (twisted) patch, which its hull encloses with an excess of at
//!   most a quarter of the twist `|a₀ − b₀ − a₁ + b₁|` ([`SphereSweptHull::twist`]): the caller
//!   splits the move until that is below its tolerance.
//!
//! The hull thickened by `r` is covered exactly by: the hull itself, each face's prism (points
//! whose projection falls inside the face, within `r` of its plane), and each edge's capsule
//! (which holds the vertex balls). The line interval is the union of the pieces' intervals,
//! which for a convex solid is their smallest start to their largest end.

use crate::geom::{Aabb, Point3, Vector3};

/// A solid a dexel line can be intersected with.
pub trait LineInterval: Sync {
    /// A box containing the solid.
    fn bounds(&self) -> Aabb;
    /// The interval `[t₀, t₁]` of the line `{p + t·e_axis}` (p's own `axis` coordinate is
    /// ignored) inside the solid, or `None` when the line misses it.
    fn line_interval(&self, axis: usize, p: &Point3) -> Option<(f64, f64)>;

    /// Where along the `across` axis lines of direction `axis` can meet the solid, on the row
    /// of lines through `p` (its `axis` and `across` coordinates ignored). The default is the
    /// box; a solid that knows its outline narrows it, so removal tests fewer lines.
    fn row_range(&self, axis: usize, across: usize, p: &Point3) -> Option<(f64, f64)> {
        let _ = (axis, p);
        let b = self.bounds();
        Some((b.min[across], b.max[across]))
    }

    /// A cheap interval along `axis` holding the solid's points on every line whose across
    /// coordinates lie in the box from `lo` to `hi` (their `axis` coordinates ignored; one
    /// line when they are equal), or `None` when no such line meets the solid. Removal skips
    /// lines whose material lies outside it before the exact [`Self::line_interval`]. The
    /// default is the solid's box.
    fn range_over(&self, axis: usize, lo: &Point3, hi: &Point3) -> Option<(f64, f64)> {
        let b = self.bounds();
        for i in 0..3 {
            if i != axis && (hi[i] < b.min[i] || lo[i] > b.max[i]) {
                return None;
            }
        }
        Some((b.min[axis], b.max[axis]))
    }
}

/// Grows `acc` to hold `(t0, t1)`.
fn merge(acc: &mut Option<(f64, f64)>, hit: Option<(f64, f64)>) {
    if let Some((t0, t1)) = hit {
        *acc = Some(match *acc {
            None => (t0, t1),
            Some((a, b)) => (a.min(t0), b.max(t1)),
        });
    }
}

/// The line `p + t·e_axis` inside the ball of `center`, `radius`.
pub fn line_ball(axis: usize, p: &Point3, center: &Point3, radius: f64) -> Option<(f64, f64)> {
    let mut d2 = 0.0;
    for i in 0..3 {
        if i != axis {
            d2 += (p[i] - center[i]).powi(2);
        }
    }
    let h = radius * radius - d2;
    if h < 0.0 {
        return None;
    }
    let h = h.sqrt();
    Some((center[axis] - h, center[axis] + h))
}

/// The line `p + t·e_axis` inside the capsule of segment `a`→`b` and `radius`.
pub fn line_capsule(
    axis: usize,
    p: &Point3,
    a: &Point3,
    b: &Point3,
    radius: f64,
) -> Option<(f64, f64)> {
    let ba = b - a;
    let baba = ba.norm_squared();
    if baba == 0.0 {
        return line_ball(axis, p, a, radius);
    }
    // Work on the line with its axis coordinate at 0: o = p with o[axis] = 0, u = e_axis.
    let mut o = *p;
    o[axis] = 0.0;
    let oa = o - a;
    let (bard, baoa, rdoa, oaoa) = (ba[axis], ba.dot(&oa), oa[axis], oa.norm_squared());
    // The infinite cylinder around the segment's line: α t² + 2β t + γ ≤ 0. Both end balls lie
    // inside it, so a line that misses it misses the capsule.
    let alpha = baba - bard * bard;
    let beta = baba * rdoa - baoa * bard;
    let gamma = baba * oaoa - baoa * baoa - radius * radius * baba;
    if alpha <= 1e-12 * baba {
        // The line runs along the segment: within r of its line everywhere or nowhere; then
        // the capsule's chord runs from one end ball to the other.
        if gamma > 0.0 {
            return None;
        }
        let mut hit = None;
        merge(&mut hit, line_ball(axis, p, a, radius));
        merge(&mut hit, line_ball(axis, p, b, radius));
        return hit;
    }
    let disc = beta * beta - alpha * gamma;
    if disc < 0.0 {
        return None;
    }
    let s = disc.sqrt();
    let (t0, t1) = ((-beta - s) / alpha, (-beta + s) / alpha);
    // Where the cylinder's chord leaves the slab between the end planes, the end ball there
    // decides; where it does not, the balls add nothing beyond the chord (they lie inside the
    // cylinder, and their points beyond the slab would be on this chord outside it).
    // Projection onto the segment, as a fraction of it: (baoa + t·bard) / baba.
    let fraction = |t: f64| (baoa + t * bard) / baba;
    let (f0, f1) = (fraction(t0), fraction(t1));
    let mut hit = None;
    let (mut lo, mut hi) = (t0, t1);
    if bard != 0.0 {
        let (u0, u1) = ((0.0 - baoa) / bard, (baba - baoa) / bard);
        let (u0, u1) = if u0 <= u1 { (u0, u1) } else { (u1, u0) };
        lo = lo.max(u0);
        hi = hi.min(u1);
    } else if !(0.0..=baba).contains(&baoa) {
        lo = f64::INFINITY;
    }
    if lo <= hi {
        hit = Some((lo, hi));
    }
    if f0 < 0.0 || f1 < 0.0 {
        merge(&mut hit, line_ball(axis, p, a, radius));
    }
    if f0 > 1.0 || f1 > 1.0 {
        merge(&mut hit, line_ball(axis, p, b, radius));
    }
    hit
}

/// A capsule: the points within `radius` of the segment `a`→`b` (a ball's centre swept along
/// a straight line).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Capsule {
    pub a: Point3,
    pub b: Point3,
    pub radius: f64,
}

impl LineInterval for Capsule {
    fn bounds(&self) -> Aabb {
        Aabb::from_points(&[self.a, self.b]).inflated(self.radius)
    }

    fn row_range(&self, axis: usize, across: usize, p: &Point3) -> Option<(f64, f64)> {
        let flat = |q: &Point3| {
            let mut q = *q;
            q[axis] = 0.0;
            q
        };
        let mut row = flat(p);
        row[across] = 0.0;
        line_capsule(across, &row, &flat(&self.a), &flat(&self.b), self.radius)
    }

    fn line_interval(&self, axis: usize, p: &Point3) -> Option<(f64, f64)> {
        line_capsule(axis, p, &self.a, &self.b, self.radius)
    }

    fn range_over(&self, axis: usize, lo: &Point3, hi: &Point3) -> Option<(f64, f64)> {
        // Every segment point is within half its length of the middle, so across the lines it
        // is at least d = (distance from the middle to the box) − half away from each of them,
        // and the capsule reaches at most √(r² − d²) along a line from a segment point.
        let middle = nalgebra::center(&self.a, &self.b);
        let half = 0.5 * (self.b - self.a).norm();
        let mut gap2 = 0.0;
        for i in 0..3 {
            if i != axis {
                let outside = (lo[i] - middle[i]).max(middle[i] - hi[i]).max(0.0);
                gap2 += outside * outside;
            }
        }
        let gap = (gap2.sqrt() - half).max(0.0);
        if gap > self.radius {
            return None;
        }
        let reach = (self.radius * self.radius - gap * gap).sqrt();
        Some((
            self.a[axis].min(self.b[axis]) - reach,
            self.a[axis].max(self.b[axis]) + reach,
        ))
    }
}

/// The part of a convex solid on one side of a plane: the points of `solid` with
/// `normal·x ≥ offset`. Convex, so still one interval per line, and one a line can often be
/// dismissed by without touching the solid (see [`crate::stock::cutter`]).
#[derive(Clone, Debug, PartialEq)]
pub struct Clipped<S> {
    pub solid: S,
    pub normal: Vector3,
    pub offset: f64,
}

impl<S> Clipped<S> {
    /// Narrows `[t_lo, t_hi]` to where lines through the box `lo`..`hi` (across `axis`) can be
    /// on the plane's side: `normal·x ≥ offset` with `normal·x` at its largest over the box.
    fn clip_over(
        &self,
        axis: usize,
        lo: &Point3,
        hi: &Point3,
        t_lo: &mut f64,
        t_hi: &mut f64,
    ) -> bool {
        let n = &self.normal;
        let mut most = 0.0;
        for i in 0..3 {
            if i != axis {
                most += (n[i] * lo[i]).max(n[i] * hi[i]);
            }
        }
        // n[axis]·t ≥ offset − most.
        let need = self.offset - most;
        let slope = n[axis];
        if slope.abs() < 1e-300 {
            return need <= 0.0;
        }
        let t = need / slope;
        if slope > 0.0 {
            *t_lo = t_lo.max(t);
        } else {
            *t_hi = t_hi.min(t);
        }
        *t_lo <= *t_hi
    }
}

impl<S: LineInterval> LineInterval for Clipped<S> {
    fn bounds(&self) -> Aabb {
        self.solid.bounds()
    }

    fn row_range(&self, axis: usize, across: usize, p: &Point3) -> Option<(f64, f64)> {
        self.solid.row_range(axis, across, p)
    }

    fn range_over(&self, axis: usize, lo: &Point3, hi: &Point3) -> Option<(f64, f64)> {
        let (mut t_lo, mut t_hi) = self.solid.range_over(axis, lo, hi)?;
        self.clip_over(axis, lo, hi, &mut t_lo, &mut t_hi)
            .then_some((t_lo, t_hi))
    }

    fn line_interval(&self, axis: usize, p: &Point3) -> Option<(f64, f64)> {
        let (mut lo, mut hi) = (f64::NEG_INFINITY, f64::INFINITY);
        if !self.clip_over(axis, p, p, &mut lo, &mut hi) {
            return None;
        }
        let (t0, t1) = self.solid.line_interval(axis, p)?;
        let (lo, hi) = (lo.max(t0), hi.min(t1));
        (lo <= hi).then_some((lo, hi))
    }
}

/// Clips the line `o + t·e_axis` (o with its axis coordinate 0) by the half-space
/// `g·x + h ≥ 0`, narrowing `[lo, hi]`; `false` when nothing is left.
fn clip(axis: usize, o: &Point3, g: &Vector3, h: f64, lo: &mut f64, hi: &mut f64) -> bool {
    let value = g.dot(&o.coords) + h;
    let slope = g[axis];
    if slope.abs() < 1e-300 {
        return value >= 0.0;
    }
    let t = -value / slope;
    if slope > 0.0 {
        *lo = lo.max(t);
    } else {
        *hi = hi.min(t);
    }
    *lo <= *hi
}

/// The points of a plane polygon (all of `points`, which lie in the plane of `normal`) on their
/// convex hull, in order around it.
fn convex_polygon(points: &[Point3], normal: &Vector3) -> Vec<Point3> {
    let (u, v) = crate::geom::orthonormal_frame(normal);
    let flat: Vec<(f64, f64)> = points
        .iter()
        .map(|p| (p.coords.dot(&u), p.coords.dot(&v)))
        .collect();
    // Gift wrapping from the lowest point: at most four points.
    let start = (0..points.len())
        .min_by(|&i, &j| {
            flat[i]
                .partial_cmp(&flat[j])
                .unwrap_or(std::cmp::Ordering::Equal)
        })
        .unwrap_or(0);
    let mut hull = vec![start];
    loop {
        let current = *hull.last().unwrap_or(&start);
        let mut next = (current + 1) % points.len();
        for k in 0..points.len() {
            let (c, n, q) = (flat[current], flat[next], flat[k]);
            let turn = (n.0 - c.0) * (q.1 - c.1) - (n.1 - c.1) * (q.0 - c.0);
            let farther = (q.0 - c.0).hypot(q.1 - c.1) > (n.0 - c.0).hypot(n.1 - c.1);
            if turn < 0.0 || (turn == 0.0 && farther) {
                next = k;
            }
        }
        if next == start || hull.len() == points.len() {
            break;
        }
        hull.push(next);
    }
    hull.into_iter().map(|i| points[i]).collect()
}

/// The points within `radius` of the convex hull of two to four points (see the module docs).
#[derive(Clone, Debug, PartialEq)]
pub struct SphereSweptHull {
    points: Vec<Point3>,
    radius: f64,
    bounds: Aabb,
    /// Edges of the hull (each thickened into a capsule).
    edges: Vec<(Point3, Point3)>,
    /// The hull's faces as triangles with unit normals.
    triangles: Vec<([Point3; 3], Vector3)>,
    /// The tetrahedron's outward face planes `(g, h)` with inside `g·x + h ≥ 0`; empty when
    /// the points are (nearly) coplanar and the hull has no interior.
    solid: Vec<(Vector3, f64)>,
}

impl SphereSweptHull {
    /// The solid of `points` (1 to 4) thickened by `radius`.
    pub fn new(points: &[Point3], radius: f64) -> Self {
        assert!(
            (1..=4).contains(&points.len()),
            "a sphere-swept hull takes 1 to 4 points"
        );
        let mut bounds = Aabb::empty();
        for p in points {
            bounds.grow(p);
        }
        let bounds = bounds.inflated(radius);
        let scale = points
            .iter()
            .flat_map(|p| points.iter().map(move |q| (p - q).norm()))
            .fold(0.0, f64::max);
        let n = points.len();
        let pairs = || (0..n).flat_map(move |i| (i + 1..n).map(move |j| (i, j)));
        // A tetrahedron: all its edges and faces, and its interior.
        if n == 4 {
            let [a, b, c, d] = [points[0], points[1], points[2], points[3]];
            let volume6 = (b - a).cross(&(c - a)).dot(&(d - a));
            if volume6.abs() > 1e-9 * scale * scale * scale {
                let mut solid = Vec::new();
                let mut triangles = Vec::new();
                for (p, q, r, opposite) in [(a, b, c, d), (a, b, d, c), (a, c, d, b), (b, c, d, a)]
                {
                    let mut g = (q - p).cross(&(r - p));
                    if g.dot(&(opposite - p)) < 0.0 {
                        g = -g;
                    }
                    solid.push((g, -g.dot(&p.coords)));
                    triangles.push(([p, q, r], g.normalize()));
                }
                return SphereSweptHull {
                    points: points.to_vec(),
                    radius,
                    bounds,
                    edges: pairs().map(|(i, j)| (points[i], points[j])).collect(),
                    triangles,
                    solid,
                };
            }
        }
        // Flat: the polygon the points span in their plane (a translation's parallelogram),
        // its boundary edges and a fan of triangles; no diagonals, no interior.
        let widest = (0..n)
            .flat_map(|i| (i + 1..n).flat_map(move |j| (j + 1..n).map(move |k| (i, j, k))))
            .map(|(i, j, k)| {
                let normal = (points[j] - points[i]).cross(&(points[k] - points[i]));
                (normal.norm(), normal)
            })
            .max_by(|x, y| x.0.total_cmp(&y.0));
        if let Some((area, normal)) = widest
            && area > 1e-12 * scale * scale
        {
            let normal = normal / area;
            let polygon = convex_polygon(points, &normal);
            let m = polygon.len();
            let edges = (0..m).map(|i| (polygon[i], polygon[(i + 1) % m])).collect();
            // A fan triangle with two corners at one point (a pivot about the ball's centre
            // leaves the centre where it was) has no inside, and its edge planes would bound
            // nothing: left out, its corners' and edges' capsules hold what it would.
            let triangles = (1..m - 1)
                .map(|i| [polygon[0], polygon[i], polygon[i + 1]])
                .filter(|[a, b, c]| (b - a).cross(&(c - a)).norm() > 1e-12 * scale * scale)
                .map(|corners| (corners, normal))
                .collect();
            return SphereSweptHull {
                points: points.to_vec(),
                radius,
                bounds,
                edges,
                triangles,
                solid: Vec::new(),
            };
        }
        // On a line (or one point): the capsule of the farthest pair.
        let (i, j) = pairs()
            .max_by(|x, y| {
                (points[x.0] - points[x.1])
                    .norm_squared()
                    .total_cmp(&(points[y.0] - points[y.1]).norm_squared())
            })
            .unwrap_or((0, 0));
        SphereSweptHull {
            points: points.to_vec(),
            radius,
            bounds,
            edges: vec![(points[i], points[j])],
            triangles: Vec::new(),
            solid: Vec::new(),
        }
    }

    /// The twist of a segment moving from `a0`→`b0` to `a1`→`b1`: its hull exceeds the swept
    /// bilinear patch by at most a quarter of this.
    pub fn twist(a0: &Point3, b0: &Point3, a1: &Point3, b1: &Point3) -> f64 {
        ((a0 - b0) - (a1 - b1)).norm()
    }

    /// The points whose hull is thickened.
    pub fn points(&self) -> &[Point3] {
        &self.points
    }

    /// The thickening radius.
    pub fn radius(&self) -> f64 {
        self.radius
    }
}

impl LineInterval for SphereSweptHull {
    fn bounds(&self) -> Aabb {
        self.bounds
    }

    fn row_range(&self, axis: usize, across: usize, p: &Point3) -> Option<(f64, f64)> {
        // Seen along `axis`, the solid is the hull's shadow thickened by r; a row's slice of
        // that convex outline ends on it, within r of a shadow edge: the union of the edges'
        // 2D capsule slices has the same ends. (The hull's edges include the shadow's.)
        let flat = |q: &Point3| {
            let mut q = *q;
            q[axis] = 0.0;
            q
        };
        let mut row = flat(p);
        row[across] = 0.0;
        let mut hit = None;
        for (a, b) in &self.edges {
            merge(
                &mut hit,
                line_capsule(across, &row, &flat(a), &flat(b), self.radius),
            );
        }
        hit
    }

    fn line_interval(&self, axis: usize, p: &Point3) -> Option<(f64, f64)> {
        // Quick reject on the box, across the line.
        for i in 0..3 {
            if i != axis && (p[i] < self.bounds.min[i] || p[i] > self.bounds.max[i]) {
                return None;
            }
        }
        let r = self.radius;
        let mut hit = None;
        for (a, b) in &self.edges {
            merge(&mut hit, line_capsule(axis, p, a, b, r));
        }
        let mut o = *p;
        o[axis] = 0.0;
        for ([a, b, c], n) in &self.triangles {
            let (mut lo, mut hi) = (f64::NEG_INFINITY, f64::INFINITY);
            // Within r of the plane: n·(x − a) + r ≥ 0 and −n·(x − a) + r ≥ 0.
            let d = n.dot(&a.coords);
            let mut inside = clip(axis, &o, n, r - d, &mut lo, &mut hi)
                && clip(axis, &o, &-n, r + d, &mut lo, &mut hi);
            // Projection inside the triangle: on the inner side of each edge's plane.
            // (Each edge's inner side is the one its opposite corner is on, whichever way round
            // the corners run.)
            for (s, e, opposite) in [(a, b, c), (b, c, a), (c, a, b)] {
                if !inside {
                    break;
                }
                let mut g = n.cross(&(e - s));
                if g.dot(&(opposite - s)) < 0.0 {
                    g = -g;
                }
                inside = clip(axis, &o, &g, -g.dot(&s.coords), &mut lo, &mut hi);
            }
            if inside {
                merge(&mut hit, Some((lo, hi)));
            }
        }
        if !self.solid.is_empty() {
            let (mut lo, mut hi) = (f64::NEG_INFINITY, f64::INFINITY);
            if self
                .solid
                .iter()
                .all(|(g, h)| clip(axis, &o, g, *h, &mut lo, &mut hi))
            {
                merge(&mut hit, Some((lo, hi)));
            }
        }
        hit
    }
}

/// The box of the hull of two discs about the line through `base` along the unit `axis`, each
/// `(height along the axis, radius)`: a disc reaches √(1 − k_i²)·r each way along axis i.
pub(crate) fn discs_bounds(base: &Point3, axis: &Vector3, discs: [(f64, f64); 2]) -> Aabb {
    let mut b = Aabb::empty();
    for (h, r) in discs {
        let c = base + h * axis;
        for i in 0..3 {
            let reach = r * (1.0 - axis[i] * axis[i]).max(0.0).sqrt();
            let (mut lo, mut hi) = (c, c);
            lo[i] -= reach;
            hi[i] += reach;
            b.grow(&lo);
            b.grow(&hi);
        }
    }
    b
}

/// A solid frustum of a cone (or a cylinder) about the axis through `base` along the unit
/// `axis`: the points at height `h ∈ [from, to]` above `base` within `radius(h)` of the axis,
/// the radius linear from `radius_from` to `radius_to`. Convex, so a line meets it in one
/// interval, found in closed form.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frustum {
    pub base: Point3,
    pub axis: Vector3,
    pub from: f64,
    pub to: f64,
    pub radius_from: f64,
    pub radius_to: f64,
}

impl Frustum {
    /// How deep `p` is inside the frustum: its distance to the side (radially, at its height)
    /// or to the nearer end, whichever is less; negative outside.
    pub fn depth(&self, p: &Point3) -> f64 {
        let d = p - self.base;
        let h = d.dot(&self.axis);
        let along = (h - self.from) / (self.to - self.from);
        let radius = self.radius_from + along * (self.radius_to - self.radius_from);
        let radial = radius - (d - h * self.axis).norm();
        radial.min(h - self.from).min(self.to - h)
    }
}

impl LineInterval for Frustum {
    fn bounds(&self) -> Aabb {
        discs_bounds(
            &self.base,
            &self.axis,
            [(self.from, self.radius_from), (self.to, self.radius_to)],
        )
    }

    fn line_interval(&self, axis: usize, p: &Point3) -> Option<(f64, f64)> {
        let k = self.axis;
        let mut o = *p;
        o[axis] = 0.0;
        let w = o - self.base;
        // Height along the line: h(t) = w·k + t k[axis]; radius R(h) = a + b h.
        let (wk, uk) = (w.dot(&k), k[axis]);
        let slope = (self.radius_to - self.radius_from) / (self.to - self.from);
        let (a, b) = (self.radius_from - slope * self.from, slope);
        // ρ² − R² = A t² + 2B t + C, with ρ² = |w + t u|² − h², u = e_axis.
        let (r0, r1) = (a + b * wk, b * uk);
        let big_a = 1.0 - uk * uk - r1 * r1;
        let big_b = w[axis] - wk * uk - r0 * r1;
        let big_c = w.norm_squared() - wk * wk - r0 * r0;
        // The slab of heights.
        let (mut lo, mut hi) = (f64::NEG_INFINITY, f64::INFINITY);
        if uk.abs() > 1e-15 {
            let (t0, t1) = ((self.from - wk) / uk, (self.to - wk) / uk);
            lo = t0.min(t1);
            hi = t0.max(t1);
        } else if !(self.from..=self.to).contains(&wk) {
            return None;
        }
        let inside = |t: f64| big_a * t * t + 2.0 * big_b * t + big_c <= 0.0;
        if big_a.abs() < 1e-15 {
            // Linear in t: 2B t + C ≤ 0.
            if big_b.abs() < 1e-300 {
                return (big_c <= 0.0 && lo < hi).then_some((lo, hi));
            }
            let t = -big_c / (2.0 * big_b);
            if big_b > 0.0 {
                hi = hi.min(t)
            } else {
                lo = lo.max(t)
            }
            return (lo < hi).then_some((lo, hi));
        }
        let disc = big_b * big_b - big_a * big_c;
        if disc < 0.0 {
            // No root: inside everywhere or nowhere (within the slab, where R > 0).
            let mid = if lo.is_finite() && hi.is_finite() {
                0.5 * (lo + hi)
            } else {
                0.0
            };
            return (big_a < 0.0 && inside(mid) && lo < hi).then_some((lo, hi));
        }
        let s = disc.sqrt();
        let (q0, q1) = ((-big_b - s) / big_a, (-big_b + s) / big_a);
        let (q0, q1) = (q0.min(q1), q0.max(q1));
        if big_a > 0.0 {
            lo = lo.max(q0);
            hi = hi.min(q1);
            return (lo < hi).then_some((lo, hi));
        }
        // Outside the roots; the slab keeps the one piece on this nappe (the solid is convex).
        let left = (lo, hi.min(q0));
        let right = (lo.max(q1), hi);
        match (left.0 < left.1, right.0 < right.1) {
            (true, false) => Some(left),
            (false, true) => Some(right),
            (true, true) => Some((left.0, right.1)),
            (false, false) => None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::closest_point_on_triangle;
    use proptest::prelude::*;

    /// Distance from `x` to the hull of the points, by brute force: 0 inside the tetrahedron
    /// (barycentric test), else the nearest point on any triangle or segment of the points.
    fn hull_distance(points: &[Point3], x: &Point3) -> f64 {
        let mut best = f64::INFINITY;
        let n = points.len();
        for i in 0..n {
            best = best.min((x - points[i]).norm());
            for j in i + 1..n {
                let (a, b) = (points[i], points[j]);
                let ab = b - a;
                let t = if ab.norm_squared() > 0.0 {
                    ((x - a).dot(&ab) / ab.norm_squared()).clamp(0.0, 1.0)
                } else {
                    0.0
                };
                best = best.min((x - (a + t * ab)).norm());
                for c in &points[j + 1..n] {
                    let q = closest_point_on_triangle(x, &a, &b, c);
                    best = best.min((x - q.0).norm());
                }
            }
        }
        if n == 4 {
            let m = nalgebra::Matrix3::from_columns(&[
                points[1] - points[0],
                points[2] - points[0],
                points[3] - points[0],
            ]);
            if let Some(inv) = m.try_inverse() {
                let l = inv * (x - points[0]);
                if l.iter().all(|&v| v >= 0.0) && l.sum() <= 1.0 {
                    return 0.0;
                }
            }
        }
        best
    }

    fn point() -> impl Strategy<Value = Point3> {
        (-5.0..5.0f64, -5.0..5.0f64, -5.0..5.0f64).prop_map(|(x, y, z)| Point3::new(x, y, z))
    }

    proptest! {
        /// The interval's ends are on the surface (distance = r, to 1e-7) and a point between
        /// them is inside, a point just beyond each end is outside.
        #[test]
        fn line_intervals_agree_with_the_distance_to_the_hull(
            pts in proptest::collection::vec(point(), 1..=4),
            radius in 0.05..2.0f64,
            axis in 0usize..3,
            across in (-6.0..6.0f64, -6.0..6.0f64),
            flat in any::<bool>(),
        ) {
            let mut pts = pts;
            if flat && pts.len() == 4 {
                // A translation: a parallelogram.
                pts[3] = pts[1] + (pts[2] - pts[0]);
            }
            let solid = SphereSweptHull::new(&pts, radius);
            let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
            let mut p = Point3::origin();
            p[u] = across.0;
            p[v] = across.1;
            let at = |t: f64| { let mut q = p; q[axis] = t; q };
            match solid.line_interval(axis, &p) {
                Some((t0, t1)) => {
                    prop_assert!(t0 <= t1);
                    for t in [t0, t1] {
                        let d = hull_distance(&pts, &at(t));
                        prop_assert!((d - radius).abs() < 1e-7 || (t0 == t1), "end at distance {} vs r {}", d, radius);
                    }
                    prop_assert!(hull_distance(&pts, &at(0.5 * (t0 + t1))) <= radius + 1e-9);
                    prop_assert!(hull_distance(&pts, &at(t0 - 1e-6)) > radius - 1e-9);
                    prop_assert!(hull_distance(&pts, &at(t1 + 1e-6)) > radius - 1e-9);
                }
                None => {
                    // The line stays out: its closest approach is beyond r (checked on a fine
                    // sweep of t over the solid's box).
                    let b = solid.bounds();
                    for k in 0..=400 {
                        let t = b.min[axis] + (b.max[axis] - b.min[axis]) * k as f64 / 400.0;
                        prop_assert!(hull_distance(&pts, &at(t)) > radius - 1e-6);
                    }
                }
            }
        }

        /// No line outside a row's range meets the solid, and the range's ends are met (to
        /// the sampling): the narrowing loses nothing and is tight.
        #[test]
        fn row_ranges_hold_every_line_that_meets_the_solid(
            pts in proptest::collection::vec(point(), 1..=4),
            radius in 0.05..2.0f64,
            axis in 0usize..3,
            row in -6.0..6.0f64,
        ) {
            let solid = SphereSweptHull::new(&pts, radius);
            let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
            let mut p = Point3::origin();
            p[v] = row;
            let range = solid.row_range(axis, u, &p);
            let mut met: Option<(f64, f64)> = None;
            for k in 0..=1200 {
                let x = -8.0 + 16.0 * k as f64 / 1200.0;
                p[u] = x;
                if solid.line_interval(axis, &p).is_some() {
                    met = Some(met.map_or((x, x), |(a, b)| (a.min(x), b.max(x))));
                }
            }
            match (met, range) {
                (None, _) => {}
                (Some(_), None) => prop_assert!(false, "lines meet the solid on an empty row"),
                (Some((a, b)), Some((lo, hi))) => {
                    prop_assert!(lo <= a + 1e-9 && b <= hi + 1e-9, "met {a}..{b}, range {lo}..{hi}");
                    prop_assert!(a - lo < 0.02 && hi - b < 0.02, "loose: met {a}..{b}, range {lo}..{hi}");
                }
            }
        }

        /// A frustum's line interval agrees with a direct membership test of points along the
        /// line (height in range, within the radius there).
        #[test]
        fn frustum_intervals_agree_with_membership(
            base in point(),
            axis in (-1.0..1.0f64, -1.0..1.0f64, 0.1..1.0f64),
            from in 0.0..3.0f64,
            length in 0.5..6.0f64,
            radii in (0.2..4.0f64, 0.2..4.0f64),
            line_axis in 0usize..3,
            across in (-8.0..8.0f64, -8.0..8.0f64),
        ) {
            let k = Vector3::new(axis.0, axis.1, axis.2).normalize();
            let f = Frustum { base, axis: k, from, to: from + length, radius_from: radii.0, radius_to: radii.1 };
            let (u, v) = ((line_axis + 1) % 3, (line_axis + 2) % 3);
            let mut p = Point3::origin();
            p[u] = across.0;
            p[v] = across.1;
            let member = |t: f64| {
                let mut q = p;
                q[line_axis] = t;
                let d = q - base;
                let h = d.dot(&k);
                let r = f.radius_from + (f.radius_to - f.radius_from) * (h - f.from) / (f.to - f.from);
                (f.from..=f.to).contains(&h) && (d - h * k).norm() <= r
            };
            let hit = f.line_interval(line_axis, &p);
            for step in 0..=2000 {
                let t = -20.0 + 40.0 * step as f64 / 2000.0;
                let inside = hit.is_some_and(|(a, b)| a + 1e-9 < t && t < b - 1e-9);
                let outside = hit.is_none_or(|(a, b)| t < a - 1e-9 || t > b + 1e-9);
                if inside { prop_assert!(member(t), "t {} inside {:?} but not a member", t, hit); }
                if outside { prop_assert!(!member(t), "t {} outside {:?} but a member", t, hit); }
            }
            let b = f.bounds();
            if let Some((t0, t1)) = hit {
                prop_assert!(t0 >= b.min[line_axis] - 1e-9 && t1 <= b.max[line_axis] + 1e-9);
            }
        }
    }
}
