//! A NURBS curve (IGES entity 126): evaluation with derivatives, knot insertion, Bézier pieces.

use nalgebra::{Point3, Vector3, Vector4};

use super::{
    NurbsError, basis_derivatives, basis_functions, bezier_spans, binomial, check_knots,
    check_points, find_span, homogeneous, insert_knot, refine_to_bezier,
};

/// `C(u) = Σ Nᵢ,ₚ(u) wᵢ Pᵢ / Σ Nᵢ,ₚ(u) wᵢ` over `u ∈ [knots[p], knots[n + 1]]`.
#[derive(Clone, Debug, PartialEq)]
pub struct NurbsCurve {
    degree: usize,
    knots: Vec<f64>,
    /// Homogeneous control points `(w·P, w)`.
    points: Vec<Vector4<f64>>,
}

impl NurbsCurve {
    /// A curve of `degree` through control points `points` with `weights` (all 1 for a
    /// non-rational B-spline) on `knots` (`points + degree + 1` values, not decreasing).
    pub fn new(
        degree: usize,
        knots: Vec<f64>,
        points: &[Point3<f64>],
        weights: &[f64],
    ) -> Result<NurbsCurve, NurbsError> {
        if weights.len() != points.len() {
            return Err(NurbsError::BadPoint {
                index: weights.len().min(points.len()),
                weight: f64::NAN,
            });
        }
        let homogeneous: Vec<Vector4<f64>> = points
            .iter()
            .zip(weights)
            .map(|(p, &w)| homogeneous(p, w))
            .collect();
        Self::from_homogeneous(degree, knots, homogeneous)
    }

    /// A curve from homogeneous control points `(w·x, w·y, w·z, w)`.
    pub fn from_homogeneous(
        degree: usize,
        knots: Vec<f64>,
        points: Vec<Vector4<f64>>,
    ) -> Result<NurbsCurve, NurbsError> {
        check_knots(degree, points.len(), &knots)?;
        check_points(&points)?;
        Ok(NurbsCurve {
            degree,
            knots,
            points,
        })
    }

    /// The degree.
    pub fn degree(&self) -> usize {
        self.degree
    }

    /// The knot vector.
    pub fn knots(&self) -> &[f64] {
        &self.knots
    }

    /// The homogeneous control points.
    pub fn homogeneous_points(&self) -> &[Vector4<f64>] {
        &self.points
    }

    /// The parameter domain `[knots[p], knots[n + 1]]`.
    pub fn domain(&self) -> (f64, f64) {
        (self.knots[self.degree], self.knots[self.points.len()])
    }

    /// The point at `u` (clamped into the domain).
    pub fn point(&self, u: f64) -> Point3<f64> {
        let (a, b) = self.domain();
        let u = u.clamp(a, b);
        let p = self.degree;
        let span = find_span(self.points.len() - 1, p, u, &self.knots);
        let n = basis_functions(span, u, p, &self.knots);
        let cw: Vector4<f64> = (0..=p).map(|j| self.points[span - p + j] * n[j]).sum();
        Point3::from(cw.xyz() / cw.w)
    }

    /// The point and its derivatives up to order `d` at `u`: `[C, C′, C″, …]` (the point as a
    /// vector from the origin). Rational derivatives by Piegl & Tiller A4.2.
    pub fn derivatives(&self, u: f64, d: usize) -> Vec<Vector3<f64>> {
        let (a, b) = self.domain();
        let u = u.clamp(a, b);
        let p = self.degree;
        let span = find_span(self.points.len() - 1, p, u, &self.knots);
        let ders = basis_derivatives(span, u, p, d, &self.knots);
        let homogeneous: Vec<Vector4<f64>> = (0..=d)
            .map(|k| {
                (0..=p)
                    .map(|j| self.points[span - p + j] * ders[k][j])
                    .sum()
            })
            .collect();
        let w0 = homogeneous[0].w;
        let mut out: Vec<Vector3<f64>> = Vec::with_capacity(d + 1);
        for k in 0..=d {
            let mut v = homogeneous[k].xyz();
            for i in 1..=k {
                v -= out[k - i] * (binomial(k, i) * homogeneous[i].w);
            }
            out.push(v / w0);
        }
        out
    }

    /// The same curve with `u` inserted `times` more (up to multiplicity = degree).
    pub fn insert_knot(&self, u: f64, times: usize) -> NurbsCurve {
        let (knots, points) = insert_knot(self.degree, &self.knots, &self.points, u, times);
        NurbsCurve {
            degree: self.degree,
            knots,
            points,
        }
    }

    /// The curve as Bézier pieces over its domain, in order, each with its parameter interval.
    pub fn bezier_pieces(&self) -> Vec<(f64, f64, Vec<Vector4<f64>>)> {
        let (a, b) = self.domain();
        let p = self.degree;
        let (knots, points) = refine_to_bezier(p, &self.knots, &self.points, a, b);
        bezier_spans(p, &knots, a, b)
            .into_iter()
            .map(|(first, lo, hi)| (lo, hi, points[first..=first + p].to_vec()))
            .collect()
    }
}

/// The point of a Bézier piece (homogeneous points, local parameter `t ∈ [0, 1]`) by de
/// Casteljau's algorithm.
pub fn bezier_point(points: &[Vector4<f64>], t: f64) -> Point3<f64> {
    let mut q = points.to_vec();
    for level in 1..q.len() {
        for i in 0..q.len() - level {
            q[i] = q[i] * (1.0 - t) + q[i + 1] * t;
        }
    }
    Point3::from(q[0].xyz() / q[0].w)
}

#[cfg(test)]
mod tests {
    use super::super::tests::unit_circle as circle;
    use super::*;

    /// Every point of the NURBS circle is at radius 1 to rounding, its tangent is perpendicular
    /// to the radius, and its curvature |C′ × C″| / |C′|³ is 1.
    #[test]
    fn the_nurbs_circle_is_a_circle() {
        let c = circle();
        for k in 0..=400 {
            let u = k as f64 / 400.0;
            let d = c.derivatives(u, 2);
            assert!((c.point(u).coords - d[0]).norm() < 1e-15);
            assert!((d[0].norm() - 1.0).abs() < 1e-14, "{u}: {}", d[0].norm());
            assert!(d[0].dot(&d[1]).abs() < 1e-12 * d[1].norm());
            let curvature = d[1].cross(&d[2]).norm() / d[1].norm().powi(3);
            assert!((curvature - 1.0).abs() < 1e-12, "{u}: {curvature}");
        }
    }

    /// Derivatives of a rational cubic with uneven knots agree with central differences.
    #[test]
    fn rational_derivatives_agree_with_differences() {
        let points: Vec<Point3<f64>> = (0..7)
            .map(|i| {
                let t = i as f64;
                Point3::new(t, (t * 1.3).sin() * 3.0, (t * 0.7).cos())
            })
            .collect();
        let weights = [1.0, 0.5, 2.0, 1.5, 0.8, 1.2, 1.0];
        let knots = vec![0.0, 0.0, 0.0, 0.0, 0.3, 0.35, 0.7, 1.0, 1.0, 1.0, 1.0];
        let c = NurbsCurve::new(3, knots, &points, &weights).unwrap();
        let h = 1e-5;
        for &u in &[0.1, 0.32, 0.5, 0.71, 0.95] {
            let d = c.derivatives(u, 2);
            let (lo, mid, hi) = (c.point(u - h), c.point(u), c.point(u + h));
            let first = (hi - lo) / (2.0 * h);
            let second = (hi.coords - 2.0 * mid.coords + lo.coords) / (h * h);
            assert!((d[1] - first).norm() < 1e-5 * d[1].norm().max(1.0));
            assert!((d[2] - second).norm() < 1e-3 * d[2].norm().max(1.0));
        }
    }

    /// Knot insertion leaves the curve where it was; the Bézier pieces reproduce it.
    #[test]
    fn knot_insertion_and_bezier_pieces_keep_the_shape() {
        let c = circle();
        let refined = c
            .insert_knot(0.4, 1)
            .insert_knot(0.6, 2)
            .insert_knot(0.25, 5);
        assert_eq!(refined.knots().len(), c.knots().len() + 3);
        let pieces = c.bezier_pieces();
        assert_eq!(pieces.len(), 4);
        for k in 0..=100 {
            let u = k as f64 / 100.0;
            assert!((refined.point(u) - c.point(u)).norm() < 1e-14);
            let (lo, hi, points) = pieces
                .iter()
                .find(|(lo, hi, _)| u >= *lo && u <= *hi)
                .unwrap();
            let t = (u - lo) / (hi - lo);
            assert!((bezier_point(points, t) - c.point(u)).norm() < 1e-14);
        }
    }

    /// Unclamped (uniform) knots: the pieces still reproduce the curve over its domain.
    #[test]
    fn an_unclamped_curve_splits_into_its_pieces() {
        let points: Vec<Point3<f64>> = (0..6)
            .map(|i| Point3::new(i as f64, ((i * i) % 5) as f64, 0.5 * i as f64))
            .collect();
        let knots: Vec<f64> = (0..10).map(|i| i as f64).collect();
        let c = NurbsCurve::new(3, knots, &points, &[1.0; 6]).unwrap();
        assert_eq!(c.domain(), (3.0, 6.0));
        let pieces = c.bezier_pieces();
        assert_eq!(pieces.len(), 3);
        for k in 0..=60 {
            let u = 3.0 + k as f64 / 20.0;
            let (lo, hi, points) = pieces
                .iter()
                .find(|(lo, hi, _)| u >= *lo && u <= *hi)
                .unwrap();
            let t = (u - lo) / (hi - lo);
            assert!((bezier_point(points, t) - c.point(u)).norm() < 1e-12);
        }
    }

    /// Bad descriptions are refused with the reason.
    #[test]
    fn bad_curves_are_refused() {
        let p = [Point3::origin(); 3];
        let e = |degree, knots: Vec<f64>, w: [f64; 3]| {
            NurbsCurve::new(degree, knots, &p, &w).unwrap_err()
        };
        assert!(matches!(
            e(0, vec![0.0; 4], [1.0; 3]),
            NurbsError::Degree(0)
        ));
        assert!(matches!(
            e(2, vec![0.0; 5], [1.0; 3]),
            NurbsError::KnotCount { expected: 6, .. }
        ));
        assert!(matches!(
            e(2, vec![0.0, 0.0, 0.0, 1.0, 0.5, 1.0], [1.0; 3]),
            NurbsError::DecreasingKnots { index: 4, .. }
        ));
        assert!(matches!(
            e(2, vec![0.0, 0.0, 0.0, 1.0, 1.0, 1.0], [1.0, -1.0, 1.0]),
            NurbsError::BadPoint { index: 1, .. }
        ));
        assert!(matches!(
            e(2, vec![0.0; 6], [1.0; 3]),
            NurbsError::EmptyDomain(..)
        ));
        assert!(matches!(
            e(3, vec![0.0; 7], [1.0; 3]),
            NurbsError::TooFewPoints { .. }
        ));
    }
}
