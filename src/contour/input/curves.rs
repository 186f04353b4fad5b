//! Curves of the input formats and their conversion to lines and circular arcs.
//!
//! Circles and circular arcs (also after similarity transforms) become exact bulge arcs.
//! Everything else — cubic/quadratic Béziers, elliptical arcs (including circles under
//! non-uniform scale or skew) and NURBS — is replaced by G1-continuous biarcs:
//!
//! * the curve is first cut at inflections (sign changes of the curvature) and wherever its
//!   tangent has turned by more than 90°, so every piece is a gentle C shape;
//! * each piece is covered greedily from its start by the longest parameter span whose
//!   equal-distance biarc (Bolton's d₁ = d₂ construction: both arcs tangent to the curve at the
//!   span's ends, the junction midway between the two tangent control points) stays within
//!   75 % of the tolerance of densely sampled points of the true curve; the span is found by
//!   bisection, which keeps the number of arcs (NC blocks) close to the minimum.

use std::f64::consts::{FRAC_PI_2, PI};

use nalgebra::Matrix2;

use super::Chain;
use super::segmath::{cross, dist_point_segment};
use crate::contour::geometry::{Point2, Segment, Vector2, Vertex};

/// An affine map of the plane, `p ↦ m p + t`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Affine {
    pub m: Matrix2<f64>,
    pub t: Vector2,
}

impl Affine {
    pub fn identity() -> Self {
        Self {
            m: Matrix2::identity(),
            t: Vector2::zeros(),
        }
    }

    /// The SVG matrix `(a b c d e f)`: x' = a x + c y + e, y' = b x + d y + f.
    pub fn svg(a: f64, b: f64, c: f64, d: f64, e: f64, f: f64) -> Self {
        Self {
            m: Matrix2::new(a, c, b, d),
            t: Vector2::new(e, f),
        }
    }

    pub fn apply(&self, p: Point2) -> Point2 {
        Point2::from(self.m * p.coords + self.t)
    }

    /// `self ∘ inner`: apply `inner` first.
    pub fn compose(&self, inner: &Affine) -> Affine {
        Affine {
            m: self.m * inner.m,
            t: self.m * inner.t + self.t,
        }
    }

    pub fn is_finite(&self) -> bool {
        self.m.iter().all(|v| v.is_finite()) && self.t.iter().all(|v| v.is_finite())
    }
}

/// Position and first two derivatives of a parametric curve.
#[derive(Clone, Copy, Debug)]
pub struct Eval {
    pub p: Point2,
    pub d1: Vector2,
    pub d2: Vector2,
}

/// A smooth (C²) parametric curve.
pub trait Curve {
    fn eval(&self, t: f64) -> Eval;
}

/// A cubic Bézier curve, t ∈ [0, 1].
#[derive(Clone, Copy, Debug)]
pub struct Cubic {
    pub p: [Point2; 4],
}

impl Cubic {
    /// The cubic equal to the quadratic Bézier `p0, p1, p2` (degree elevation).
    pub fn from_quadratic(p0: Point2, p1: Point2, p2: Point2) -> Self {
        let c1 = p0 + (p1 - p0) * (2.0 / 3.0);
        let c2 = p2 + (p1 - p2) * (2.0 / 3.0);
        Self {
            p: [p0, c1, c2, p2],
        }
    }

    pub fn transformed(&self, a: &Affine) -> Self {
        Self {
            p: self.p.map(|q| a.apply(q)),
        }
    }
}

impl Curve for Cubic {
    fn eval(&self, t: f64) -> Eval {
        let [p0, p1, p2, p3] = self.p.map(|q| q.coords);
        let mt = 1.0 - t;
        let p = p0 * (mt * mt * mt)
            + p1 * (3.0 * mt * mt * t)
            + p2 * (3.0 * mt * t * t)
            + p3 * (t * t * t);
        let d1 = ((p1 - p0) * (mt * mt) + (p2 - p1) * (2.0 * mt * t) + (p3 - p2) * (t * t)) * 3.0;
        let d2 = ((p2 - p1 * 2.0 + p0) * mt + (p3 - p2 * 2.0 + p1) * t) * 6.0;
        Eval {
            p: Point2::from(p),
            d1,
            d2,
        }
    }
}

/// An arc of the ellipse `center + m (cos θ, sin θ)`, θ from `theta0` by `dtheta` (signed);
/// curve parameter t ∈ [0, 1]. Any affine image of a circular or elliptical arc has this form.
#[derive(Clone, Copy, Debug)]
pub struct EllipseArc {
    pub center: Point2,
    pub m: Matrix2<f64>,
    pub theta0: f64,
    pub dtheta: f64,
}

impl EllipseArc {
    pub fn point_at_angle(&self, theta: f64) -> Point2 {
        self.center + self.m * Vector2::new(theta.cos(), theta.sin())
    }

    pub fn start(&self) -> Point2 {
        self.point_at_angle(self.theta0)
    }

    pub fn end(&self) -> Point2 {
        self.point_at_angle(self.theta0 + self.dtheta)
    }

    pub fn transformed(&self, a: &Affine) -> Self {
        Self {
            center: a.apply(self.center),
            m: a.m * self.m,
            ..*self
        }
    }

    /// Whether the image is a circle: the two singular values of `m` agree to 1e-9 relative
    /// or to 1 % of the tolerance (then the exact arc through the true endpoints is used).
    fn is_circular(&self, tol: f64) -> bool {
        let sum = self.m.column(0).norm_squared() + self.m.column(1).norm_squared();
        let det = self.m.determinant().abs();
        // (σ₁ − σ₂)² = σ₁² + σ₂² − 2 σ₁σ₂.
        let diff = (sum - 2.0 * det).max(0.0).sqrt();
        let smax = sum.sqrt();
        diff <= 1e-9 * smax || diff <= 0.01 * tol
    }

    /// Appends the arc to `chain` (which must end at the arc's start), ending exactly at `end`.
    pub fn emit(&self, tol: f64, end: Point2, chain: &mut Chain) {
        if self.dtheta == 0.0 {
            return;
        }
        if self.is_circular(tol) {
            // Pieces of at most a half turn keep |bulge| ≤ 1.
            let n = ((self.dtheta.abs() / PI) - 1e-9).ceil().max(1.0) as usize;
            let step = self.dtheta / n as f64;
            let sweep = step * self.m.determinant().signum();
            let bulge = (sweep / 4.0).tan();
            for k in 1..=n {
                let to = if k == n {
                    end
                } else {
                    self.point_at_angle(self.theta0 + step * k as f64)
                };
                chain.push(to, bulge);
            }
        } else {
            let vs = fit_curve(self, 0.0, 1.0, tol);
            chain.extend(&vs, end);
        }
    }
}

impl Curve for EllipseArc {
    fn eval(&self, t: f64) -> Eval {
        let th = self.theta0 + self.dtheta * t;
        let (s, c) = th.sin_cos();
        let k = self.dtheta;
        Eval {
            p: self.center + self.m * Vector2::new(c, s),
            d1: self.m * Vector2::new(-s, c) * k,
            d2: self.m * Vector2::new(-c, -s) * (k * k),
        }
    }
}

/// A planar NURBS curve in homogeneous form.
#[derive(Clone, Debug)]
pub struct Nurbs {
    degree: usize,
    knots: Vec<f64>,
    /// (w x, w y, w) per control point.
    cw: Vec<[f64; 3]>,
}

impl Nurbs {
    /// Validates and builds a NURBS curve; `weights` may be empty (all 1).
    pub fn new(
        degree: usize,
        knots: Vec<f64>,
        points: &[Point2],
        weights: &[f64],
    ) -> Result<Self, String> {
        let n = points.len();
        if !(1..=30).contains(&degree) {
            return Err(format!("degree {degree} is not in 1..=30"));
        }
        if n < degree + 1 {
            return Err(format!(
                "{n} control points are too few for degree {degree}"
            ));
        }
        if knots.len() != n + degree + 1 {
            return Err(format!(
                "{} knots do not match {n} control points of degree {degree} (expected {})",
                knots.len(),
                n + degree + 1
            ));
        }
        if knots.iter().any(|k| !k.is_finite()) || knots.windows(2).any(|w| w[1] < w[0]) {
            return Err("knots are not finite and non-decreasing".into());
        }
        if !weights.is_empty() && weights.len() != n {
            return Err(format!("{} weights for {n} control points", weights.len()));
        }
        if weights.iter().any(|w| !(w.is_finite() && *w > 0.0)) {
            return Err("weights must be positive".into());
        }
        if points.iter().any(|p| !(p.x.is_finite() && p.y.is_finite())) {
            return Err("control points are not finite".into());
        }
        let cw = points
            .iter()
            .enumerate()
            .map(|(i, p)| {
                let w = weights.get(i).copied().unwrap_or(1.0);
                [p.x * w, p.y * w, w]
            })
            .collect();
        let out = Self { degree, knots, cw };
        if out.spans().is_empty() {
            return Err("the knot vector has an empty domain".into());
        }
        Ok(out)
    }

    /// Knot spans `k` (p ≤ k < n) with `knots[k] < knots[k + 1]`: the polynomial pieces.
    pub fn spans(&self) -> Vec<usize> {
        let n = self.cw.len();
        (self.degree..n)
            .filter(|&k| self.knots[k] < self.knots[k + 1])
            .collect()
    }

    /// The piece of the curve on span `k`, parameter in `[knots[k], knots[k + 1]]`; at the
    /// span's ends it gives the one-sided limits of that polynomial piece.
    pub fn span(&self, k: usize) -> (NurbsSpan<'_>, f64, f64) {
        (
            NurbsSpan {
                nurbs: self,
                span: k,
            },
            self.knots[k],
            self.knots[k + 1],
        )
    }

    /// Basis function values and derivatives (The NURBS Book, algorithm A2.3) for span `i`.
    fn ders_basis(&self, i: usize, u: f64, nd: usize) -> Vec<Vec<f64>> {
        crate::cad::nurbs::basis_derivatives(i, u, self.degree, nd, &self.knots)
    }
}

/// One polynomial piece of a [`Nurbs`].
pub struct NurbsSpan<'a> {
    nurbs: &'a Nurbs,
    span: usize,
}

impl Curve for NurbsSpan<'_> {
    fn eval(&self, u: f64) -> Eval {
        let nb = self.nurbs;
        let p = nb.degree;
        let nd = p.min(2);
        let ders = nb.ders_basis(self.span, u, nd);
        // Homogeneous value and derivatives A⁽ᵏ⁾ = Σ N⁽ᵏ⁾ (w P, w).
        let mut h = [[0.0f64; 3]; 3];
        for (k, row) in ders.iter().enumerate() {
            for (j, nv) in row.iter().enumerate() {
                let c = nb.cw[self.span - p + j];
                for q in 0..3 {
                    h[k][q] += nv * c[q];
                }
            }
        }
        let w = h[0][2];
        let a0 = Vector2::new(h[0][0], h[0][1]);
        let a1 = Vector2::new(h[1][0], h[1][1]);
        let a2 = Vector2::new(h[2][0], h[2][1]);
        let (w1, w2) = (h[1][2], h[2][2]);
        let c0 = a0 / w;
        let c1 = (a1 - c0 * w1) / w;
        let c2 = (a2 - c1 * (2.0 * w1) - c0 * w2) / w;
        Eval {
            p: Point2::from(c0),
            d1: c1,
            d2: c2,
        }
    }
}

/// Samples per candidate biarc when measuring its distance to the true curve.
const CHECK_SAMPLES: usize = 32;
/// Samples when scanning a curve for inflections and turning.
const SCAN_SAMPLES: usize = 64;
/// Share of the tolerance the fitter aims at: sampling between the check points can only make
/// the true error slightly larger than the measured one.
const FIT_SHARE: f64 = 0.75;

/// Replaces `curve` on `[t0, t1]` by lines and arcs within `tol`; returns the vertices that
/// start each segment (the first at `curve(t0)`); the last segment ends at `curve(t1)`.
pub fn fit_curve(curve: &dyn Curve, t0: f64, t1: f64, tol: f64) -> Vec<Vertex> {
    let mut out = Vec::new();
    if t0.is_nan() || t1.is_nan() || t1 <= t0 {
        return out;
    }
    let samples: Vec<Point2> = (0..=SCAN_SAMPLES)
        .map(|i| {
            curve
                .eval(t0 + (t1 - t0) * i as f64 / SCAN_SAMPLES as f64)
                .p
        })
        .collect();
    if samples
        .iter()
        .any(|p| !(p.x.is_finite() && p.y.is_finite()))
    {
        return out;
    }
    let extent = super::points_size(&samples);
    if !extent.is_finite() || extent <= 0.5 * tol * 1e-6 {
        return out;
    }
    // Below ~1e-10 of the coordinates' magnitude, f64 cannot tell the curve from its biarcs
    // any more; asking for less would only produce a flood of vanishing arcs.
    let magnitude = samples
        .iter()
        .map(|p| p.x.abs().max(p.y.abs()))
        .fold(0.0, f64::max);
    let tol = tol.max(1e-10 * (magnitude + extent));
    let ctx = Fit {
        curve,
        tol,
        speed_ref: extent / (t1 - t0),
    };
    let breaks = ctx.breakpoints(t0, t1, extent);
    for w in breaks.windows(2) {
        ctx.fit_piece(w[0], w[1], &mut out);
    }
    out
}

struct Fit<'a> {
    curve: &'a dyn Curve,
    tol: f64,
    /// A typical |dC/dt|, to recognise a vanishing derivative.
    speed_ref: f64,
}

impl Fit<'_> {
    fn kappa_sign(&self, t: f64, extent: f64) -> i8 {
        let e = self.curve.eval(t);
        let s = e.d1.norm();
        if s <= 1e-12 * self.speed_ref {
            return 0;
        }
        let k = cross(e.d1, e.d2) / (s * s * s);
        // Curvature radius beyond 1e9 × the curve's size counts as straight.
        if (k * extent).abs() < 1e-9 {
            0
        } else {
            k.signum() as i8
        }
    }

    /// Parameters cutting the curve at inflections and every ~90° of turning.
    fn breakpoints(&self, t0: f64, t1: f64, extent: f64) -> Vec<f64> {
        let mut out = vec![t0];
        let (mut last_sign, mut last_t) = (0i8, t0);
        let mut turn = 0.0;
        let mut prev_dir: Option<f64> = None;
        for i in 0..=SCAN_SAMPLES {
            let t = t0 + (t1 - t0) * i as f64 / SCAN_SAMPLES as f64;
            let sg = self.kappa_sign(t, extent);
            if sg != 0 {
                if last_sign != 0 && sg != last_sign {
                    // Bisection on the curvature sign between the two samples.
                    let (mut lo, mut hi) = (last_t, t);
                    for _ in 0..40 {
                        let mid = 0.5 * (lo + hi);
                        if self.kappa_sign(mid, extent) == last_sign {
                            lo = mid
                        } else {
                            hi = mid
                        }
                    }
                    out.push(0.5 * (lo + hi));
                    turn = 0.0;
                }
                last_sign = sg;
                last_t = t;
            }
            let d1 = self.curve.eval(t).d1;
            if d1.norm() > 1e-12 * self.speed_ref {
                let dir = d1.y.atan2(d1.x);
                if let Some(pd) = prev_dir {
                    let mut dd = dir - pd;
                    dd -= (dd / (2.0 * PI)).round() * 2.0 * PI;
                    turn += dd.abs();
                    if turn > FRAC_PI_2 && i < SCAN_SAMPLES {
                        out.push(t);
                        turn = 0.0;
                    }
                }
                prev_dir = Some(dir);
            }
        }
        out.push(t1);
        out.sort_by(f64::total_cmp);
        let min_gap = (t1 - t0) * 1e-9;
        let mut dedup: Vec<f64> = Vec::with_capacity(out.len());
        for t in out {
            match dedup.last() {
                Some(&l) if t - l <= min_gap => {}
                _ => dedup.push(t),
            }
        }
        if let Some(l) = dedup.last_mut() {
            *l = t1;
        }
        if dedup.len() < 2 {
            dedup = vec![t0, t1];
        }
        dedup
    }

    /// Unit tangent in the direction of travel at `t`; `forward` selects the one-sided limit
    /// (start of a span: true, end: false) where the derivative vanishes.
    fn tangent(&self, t: f64, forward: bool, chord: Vector2) -> Vector2 {
        let e = self.curve.eval(t);
        let tiny = 1e-9 * self.speed_ref;
        if e.d1.norm() > tiny {
            return e.d1.normalize();
        }
        // C'(t ± h) ≈ ± h C''(t) when C'(t) = 0.
        if e.d2.norm() > tiny {
            return if forward {
                e.d2.normalize()
            } else {
                -e.d2.normalize()
            };
        }
        let n = chord.norm();
        if n > 0.0 {
            chord / n
        } else {
            Vector2::new(1.0, 0.0)
        }
    }

    fn fit_piece(&self, a: f64, b: f64, out: &mut Vec<Vertex>) {
        let mut pos = a;
        let mut guard = 0;
        while pos < b && guard < 100_000 {
            guard += 1;
            if let Some(v) = self.try_span(pos, b) {
                out.extend(v);
                return;
            }
            let (mut lo, mut hi) = (pos, b);
            let mut best: Option<(f64, Vec<Vertex>)> = None;
            for _ in 0..60 {
                let mid = 0.5 * (lo + hi);
                if mid <= lo || mid >= hi {
                    break;
                }
                match self.try_span(pos, mid) {
                    Some(v) => {
                        best = Some((mid, v));
                        lo = mid;
                    }
                    None => hi = mid,
                }
                if best.is_some() && hi - lo <= 0.02 * (hi - pos) {
                    break;
                }
            }
            match best {
                Some((m, v)) => {
                    out.extend(v);
                    pos = m;
                }
                None => {
                    // Nothing fits even a vanishing span (numerically degenerate curve): a line
                    // over that span is within tolerance.
                    out.push(Vertex {
                        point: self.curve.eval(pos).p,
                        bulge: 0.0,
                    });
                    pos = hi;
                }
            }
        }
    }

    /// The biarc of `[a, b]` when it is within tolerance of the curve.
    fn try_span(&self, a: f64, b: f64) -> Option<Vec<Vertex>> {
        let p0 = self.curve.eval(a).p;
        let p1 = self.curve.eval(b).p;
        let chord = p1 - p0;
        let limit = FIT_SHARE * self.tol;
        if chord.norm() == 0.0 {
            // A closed loop cannot be one biarc; a vanishing span can be dropped.
            let far = (1..CHECK_SAMPLES)
                .map(|k| {
                    (self
                        .curve
                        .eval(a + (b - a) * k as f64 / CHECK_SAMPLES as f64)
                        .p
                        - p0)
                        .norm()
                })
                .fold(0.0, f64::max);
            return (far <= limit).then(Vec::new);
        }
        let t0 = self.tangent(a, true, chord);
        let t1 = self.tangent(b, false, chord);
        let verts = biarc(p0, t0, p1, t1, self.tol)?;
        let segs: Vec<Segment> = (0..verts.len())
            .map(|i| {
                let to = verts.get(i + 1).map_or(p1, |v| v.point);
                Segment::new(verts[i].point, to, verts[i].bulge)
            })
            .collect();
        for k in 1..CHECK_SAMPLES {
            let q = self
                .curve
                .eval(a + (b - a) * k as f64 / CHECK_SAMPLES as f64)
                .p;
            let d = segs
                .iter()
                .map(|s| dist_point_segment(q, s))
                .fold(f64::INFINITY, f64::min);
            if d.is_nan() || d > limit {
                return None;
            }
        }
        Some(verts)
    }
}

/// Bulge of the arc from `a` to `b` leaving `a` in direction `t` (unit), snapped to a line when
/// its sagitta is below 1 % of the tolerance. `None` for more than a half turn.
fn bulge_from_start_tangent(a: Point2, b: Point2, t: Vector2, tol: f64) -> Option<f64> {
    let c = b - a;
    let sweep = 2.0 * cross(t, c).atan2(t.dot(&c));
    snap_bulge(c.norm(), sweep, tol)
}

fn snap_bulge(chord: f64, sweep: f64, tol: f64) -> Option<f64> {
    let bulge = (sweep / 4.0).tan();
    if !bulge.is_finite() || bulge.abs() > 1.0 + 1e-12 {
        return None;
    }
    // Sagitta = chord · |bulge| / 2.
    if 0.5 * chord * bulge.abs() <= 0.01 * tol {
        Some(0.0)
    } else {
        Some(bulge)
    }
}

/// The equal-distance biarc from `p0` (unit tangent `t0`) to `p1` (unit tangent `t1`): vertices
/// starting each of its (one or two) segments.
fn biarc(p0: Point2, t0: Vector2, p1: Point2, t1: Vector2, tol: f64) -> Option<Vec<Vertex>> {
    let v = p1 - p0;
    let vv = v.norm_squared();
    let tt = t0 + t1;
    let b = v.dot(&tt);
    let denom = 2.0 * (1.0 - t0.dot(&t1));
    // |v − d (t0 + t1)| = 2d  ⇔  denom d² + 2 b d − v·v = 0; the positive root, rationalised so
    // that denom → 0 (parallel tangents) needs no special case.
    let s = (b * b + denom * vv).max(0.0).sqrt();
    if (s + b).is_nan() || s + b <= 0.0 {
        return None;
    }
    let d = vv / (s + b);
    if !(d.is_finite() && d > 0.0) {
        return None;
    }
    let q0 = p0 + t0 * d;
    let q1 = p1 - t1 * d;
    let j = nalgebra::center(&q0, &q1);
    let tiny = 1e-12 * vv.sqrt();
    let c1 = j - p0;
    let c2 = p1 - j;
    if c1.norm() <= tiny || c2.norm() <= tiny {
        // Degenerate junction: a single arc tangent at the start.
        let b1 = bulge_from_start_tangent(p0, p1, t0, tol)?;
        return Some(vec![Vertex {
            point: p0,
            bulge: b1,
        }]);
    }
    let b1 = bulge_from_start_tangent(p0, j, t0, tol)?;
    // The second arc ends in direction t1: its sweep is twice the angle from chord to t1.
    let sweep2 = 2.0 * cross(c2, t1).atan2(c2.dot(&t1));
    let b2 = snap_bulge(c2.norm(), sweep2, tol)?;
    if b1 == 0.0 && b2 == 0.0 {
        let off = cross(v, j - p0).abs() / vv.sqrt();
        if off <= 0.01 * tol {
            return Some(vec![Vertex {
                point: p0,
                bulge: 0.0,
            }]);
        }
    }
    Some(vec![
        Vertex {
            point: p0,
            bulge: b1,
        },
        Vertex {
            point: j,
            bulge: b2,
        },
    ])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contour::input::test_util::{approx_to_curve_distance, curve_to_approx_distance};

    fn fitted(curve: &dyn Curve, tol: f64) -> (Vec<Vertex>, Point2) {
        (fit_curve(curve, 0.0, 1.0, tol), curve.eval(1.0).p)
    }

    #[test]
    fn cubic_biarcs_within_tolerance_against_dense_samples() {
        let cases = [
            [(0.0, 0.0), (10.0, 20.0), (30.0, 20.0), (40.0, 0.0)],
            // S curve (inflection).
            [(0.0, 0.0), (30.0, 30.0), (10.0, -30.0), (40.0, 0.0)],
            // Loop.
            [(0.0, 0.0), (60.0, 40.0), (-20.0, 40.0), (40.0, 0.0)],
            // Cusp.
            [(0.0, 0.0), (40.0, 30.0), (0.0, 30.0), (40.0, 0.0)],
            // Coincident control points (vanishing end derivatives).
            [(0.0, 0.0), (0.0, 0.0), (25.0, 5.0), (25.0, 5.0)],
            // Straight.
            [(0.0, 0.0), (1.0, 1.0), (2.0, 2.0), (5.0, 5.0)],
        ];
        for tol in [0.001, 0.01, 0.1] {
            for c in cases {
                let cubic = Cubic {
                    p: c.map(|(x, y)| Point2::new(x, y)),
                };
                let (vs, end) = fitted(&cubic, tol);
                assert!(!vs.is_empty());
                let d = curve_to_approx_distance(&cubic, 0.0, 1.0, &vs, end, 20_000);
                assert!(d <= tol, "curve→approx {d} > {tol} for {c:?}");
                let d2 = approx_to_curve_distance(&cubic, 0.0, 1.0, &vs, end, 20_000);
                assert!(d2 <= tol * 1.01, "approx→curve {d2} > {tol} for {c:?}");
                for v in &vs {
                    assert!(v.bulge.abs() <= 1.0 + 1e-9);
                }
            }
        }
    }

    #[test]
    fn arc_count_is_small() {
        // A gentle quarter-circle-like cubic of radius ~50 mm at 0.001 mm.
        let k = 0.5522847498 * 50.0;
        let cubic = Cubic {
            p: [
                Point2::new(50.0, 0.0),
                Point2::new(50.0, k),
                Point2::new(k, 50.0),
                Point2::new(0.0, 50.0),
            ],
        };
        let (vs, _) = fitted(&cubic, 0.001);
        // The cubic deviates from the circle by ~0.013 mm; a handful of biarcs suffice.
        assert!(vs.len() <= 8, "{} segments", vs.len());
        let straight = Cubic {
            p: [
                Point2::new(0.0, 0.0),
                Point2::new(1.0, 0.0),
                Point2::new(2.0, 0.0),
                Point2::new(3.0, 0.0),
            ],
        };
        let (vs, _) = fitted(&straight, 0.001);
        assert_eq!(vs.len(), 1);
        assert_eq!(vs[0].bulge, 0.0);
    }

    #[test]
    fn ellipse_biarcs_within_tolerance() {
        let e = EllipseArc {
            center: Point2::new(3.0, -2.0),
            m: Matrix2::new(40.0, 5.0, 0.0, 10.0),
            theta0: 0.3,
            dtheta: -5.5,
        };
        for tol in [0.001, 0.05] {
            let (vs, end) = fitted(&e, tol);
            let d = curve_to_approx_distance(&e, 0.0, 1.0, &vs, end, 20_000);
            assert!(d <= tol, "{d}");
            let d2 = approx_to_curve_distance(&e, 0.0, 1.0, &vs, end, 20_000);
            assert!(d2 <= tol * 1.01, "{d2}");
        }
    }

    #[test]
    fn circular_ellipse_arc_is_exact() {
        // A circle of radius 5 rotated and mirrored: stays a circle, emitted as exact arcs.
        let rot = Matrix2::new(0.6, -0.8, 0.8, 0.6);
        let mirror = Matrix2::new(1.0, 0.0, 0.0, -1.0);
        let e = EllipseArc {
            center: Point2::new(1.0, 1.0),
            m: mirror * rot * 5.0,
            theta0: 0.0,
            dtheta: 2.0 * PI,
        };
        let mut ch = Chain::new(e.start());
        e.emit(0.001, e.start(), &mut ch);
        assert_eq!(ch.vertices.len(), 2);
        let c = crate::contour::geometry::Contour {
            vertices: ch.into_closed_vertices(),
        };
        // Mirrored: clockwise.
        assert!(
            (c.signed_area() + PI * 25.0).abs() < 1e-10,
            "{}",
            c.signed_area()
        );
        assert!((c.length() - 10.0 * PI).abs() < 1e-10);
    }

    #[test]
    fn nurbs_quarter_circle_and_derivatives() {
        let w = std::f64::consts::FRAC_1_SQRT_2;
        let pts = [
            Point2::new(1.0, 0.0),
            Point2::new(1.0, 1.0),
            Point2::new(0.0, 1.0),
        ];
        let n = Nurbs::new(2, vec![0.0, 0.0, 0.0, 1.0, 1.0, 1.0], &pts, &[1.0, w, 1.0]).unwrap();
        let spans = n.spans();
        assert_eq!(spans, vec![2]);
        let (c, a, b) = n.span(2);
        for i in 0..=50 {
            let u = a + (b - a) * i as f64 / 50.0;
            let e = c.eval(u);
            assert!((e.p.coords.norm() - 1.0).abs() < 1e-14);
            // Derivatives against central differences.
            let h = 1e-6;
            if i > 0 && i < 50 {
                let fd = (c.eval(u + h).p - c.eval(u - h).p) / (2.0 * h);
                assert!((fd - e.d1).norm() < 1e-7, "{fd} {}", e.d1);
                let fd2 = (c.eval(u + h).d1 - c.eval(u - h).d1) / (2.0 * h);
                assert!((fd2 - e.d2).norm() < 1e-6);
            }
        }
        // Cubic B-spline with an interior knot: compare with its own finite differences.
        let pts: Vec<Point2> = (0..6)
            .map(|i| Point2::new(i as f64, ((i * 7) % 5) as f64))
            .collect();
        let n = Nurbs::new(3, vec![0., 0., 0., 0., 0.4, 0.7, 1., 1., 1., 1.], &pts, &[]).unwrap();
        assert_eq!(n.spans().len(), 3);
        // Continuity across spans (C² for simple knots).
        let sp = n.spans();
        for w in sp.windows(2) {
            let (c0, _, b0) = n.span(w[0]);
            let (c1, a1, _) = n.span(w[1]);
            let (e0, e1) = (c0.eval(b0), c1.eval(a1));
            assert!((e0.p - e1.p).norm() < 1e-12);
            assert!((e0.d1 - e1.d1).norm() < 1e-10);
            assert!((e0.d2 - e1.d2).norm() < 1e-8);
        }
        // Clamped ends interpolate the end control points.
        let (c0, a0, _) = n.span(sp[0]);
        assert!((c0.eval(a0).p - pts[0]).norm() < 1e-14);
        assert!(Nurbs::new(3, vec![0.0; 4], &pts, &[]).is_err());
        assert!(
            Nurbs::new(
                2,
                vec![0., 0., 0., 1., 1., 1.],
                &pts[..3],
                &[1.0, -1.0, 1.0]
            )
            .is_err()
        );
    }
}
