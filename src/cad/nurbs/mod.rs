//! Non-uniform rational B-splines: exact evaluation of curves and surfaces and their
//! derivatives (rational de Boor in the form of Piegl & Tiller's algorithms A3.1–A4.4), knot
//! insertion (A5.1) and the split into Bézier pieces by knot insertion that seed 002 §3 builds
//! its convex-hull boxes on (its eq. 1–2: a bicubic B-spline surface becomes piecewise bicubic
//! Bézier patches when every interior knot is repeated three times). IGES entities 126 and 128
//! (seed 003 ch. 3) are exactly these objects.
//!
//! Control points are kept homogeneous, `(w·x, w·y, w·z, w)`: evaluation and knot insertion
//! are then the polynomial algorithms on four coordinates, and a rational shape is exact
//! (a NURBS circle stays a circle to the last digit).

mod basis;
mod curve;
mod patches;
mod surface;

pub use basis::{basis_derivatives, basis_functions, binomial, find_span};
pub use curve::NurbsCurve;
pub use curve::bezier_point;
pub use patches::{PatchEvaluator, SurfaceJet};
pub use surface::{BezierPatch, NurbsSurface};

use nalgebra::Vector4;

/// Why a NURBS description is refused.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum NurbsError {
    /// The degree must be at least 1.
    #[error("degree {0}: must be at least 1")]
    Degree(usize),
    /// Fewer control points than the degree needs.
    #[error("{count} control points in a direction of degree {degree}: at least degree + 1 needed")]
    TooFewPoints {
        /// Control points given in that direction.
        count: usize,
        /// Degree in that direction.
        degree: usize,
    },
    /// The knot vector must hold control points + degree + 1 values.
    #[error("{found} knots for {points} control points of degree {degree}: expected {expected}")]
    KnotCount {
        /// Knots given.
        found: usize,
        /// Knots needed.
        expected: usize,
        /// Control points.
        points: usize,
        /// Degree.
        degree: usize,
    },
    /// Knots must not decrease.
    #[error("knot {index} ({value}) is smaller than the one before it")]
    DecreasingKnots {
        /// Index of the offending knot.
        index: usize,
        /// Its value.
        value: f64,
    },
    /// The parameter domain `[knots[p], knots[n + 1]]` is empty.
    #[error("empty parameter domain [{0}, {1}]")]
    EmptyDomain(f64, f64),
    /// Knots, points and weights must be finite, weights positive.
    #[error(
        "control point {index}: weight {weight} (must be finite and positive) or a coordinate is not finite"
    )]
    BadPoint {
        /// Index of the control point (row-major for a surface: `i · columns + j`).
        index: usize,
        /// Its weight.
        weight: f64,
    },
    /// A knot is not finite.
    #[error("knot {0} is not finite")]
    NonFiniteKnot(usize),
    /// The net's rows are not all of one length.
    #[error("control net row {row} has {found} points, the first has {expected}")]
    RaggedNet {
        /// The row.
        row: usize,
        /// Its length.
        found: usize,
        /// The first row's length.
        expected: usize,
    },
}

/// Checks a knot vector for `points` control points of degree `degree`.
pub(crate) fn check_knots(degree: usize, points: usize, knots: &[f64]) -> Result<(), NurbsError> {
    if degree < 1 {
        return Err(NurbsError::Degree(degree));
    }
    if points < degree + 1 {
        return Err(NurbsError::TooFewPoints {
            count: points,
            degree,
        });
    }
    if knots.len() != points + degree + 1 {
        return Err(NurbsError::KnotCount {
            found: knots.len(),
            expected: points + degree + 1,
            points,
            degree,
        });
    }
    if let Some(i) = knots.iter().position(|k| !k.is_finite()) {
        return Err(NurbsError::NonFiniteKnot(i));
    }
    if let Some(i) = (1..knots.len()).find(|&i| knots[i] < knots[i - 1]) {
        return Err(NurbsError::DecreasingKnots {
            index: i,
            value: knots[i],
        });
    }
    let (a, b) = (knots[degree], knots[points]);
    if b <= a {
        return Err(NurbsError::EmptyDomain(a, b));
    }
    Ok(())
}

/// Checks homogeneous control points: finite, positive weights.
pub(crate) fn check_points(points: &[Vector4<f64>]) -> Result<(), NurbsError> {
    match points
        .iter()
        .position(|p| !(p.iter().all(|v| v.is_finite()) && p.w > 0.0))
    {
        Some(index) => Err(NurbsError::BadPoint {
            index,
            weight: points[index].w,
        }),
        None => Ok(()),
    }
}

/// Knot insertion (Piegl & Tiller A5.1) on a sequence of homogeneous points of degree `p`:
/// `u` inserted `r` more times (its multiplicity `s` plus `r` at most `p`). Returns the new
/// knots and points; the shape is unchanged.
pub(crate) fn insert_knot(
    p: usize,
    knots: &[f64],
    points: &[Vector4<f64>],
    u: f64,
    r: usize,
) -> (Vec<f64>, Vec<Vector4<f64>>) {
    let n = points.len() - 1;
    let s = knots.iter().filter(|&&k| k == u).count();
    let r = r.min(p.saturating_sub(s));
    if r == 0 {
        return (knots.to_vec(), points.to_vec());
    }
    // The span with knots[k] ≤ u < knots[k + 1] (u a knot: its last copy).
    let k = knots
        .iter()
        .rposition(|&t| t <= u)
        .unwrap_or(p)
        .clamp(p, knots.len() - 2);
    let mut new_knots = Vec::with_capacity(knots.len() + r);
    new_knots.extend_from_slice(&knots[..=k]);
    new_knots.extend(std::iter::repeat_n(u, r));
    new_knots.extend_from_slice(&knots[k + 1..]);
    let mut q = vec![Vector4::zeros(); n + 1 + r];
    q[..=(k - p)].copy_from_slice(&points[..=(k - p)]);
    q[(k - s + r)..=(n + r)].copy_from_slice(&points[(k - s)..=n]);
    let mut rw: Vec<Vector4<f64>> = (0..=(p - s)).map(|i| points[k - p + i]).collect();
    let mut l = k - p;
    for j in 1..=r {
        l = k - p + j;
        for i in 0..=(p - j - s) {
            let alpha = (u - knots[l + i]) / (knots[i + k + 1] - knots[l + i]);
            rw[i] = rw[i + 1] * alpha + rw[i] * (1.0 - alpha);
        }
        q[l] = rw[0];
        q[k + r - j - s] = rw[p - j - s];
    }
    if l + 1 < k - s {
        q[(l + 1)..(k - s)].copy_from_slice(&rw[1..(k - s - l)]);
    }
    (new_knots, q)
}

/// The distinct knot values in the closed domain `[a, b]`, ascending.
pub(crate) fn breakpoints(knots: &[f64], a: f64, b: f64) -> Vec<f64> {
    let mut out: Vec<f64> = Vec::new();
    for &k in knots {
        if k >= a && k <= b && out.last() != Some(&k) {
            out.push(k);
        }
    }
    out
}

/// Knots and points of degree `p` with every knot value in the domain `[a, b]` raised to
/// multiplicity `p`: then the `p + 1` points of each span are its Bézier points.
pub(crate) fn refine_to_bezier(
    p: usize,
    knots: &[f64],
    points: &[Vector4<f64>],
    a: f64,
    b: f64,
) -> (Vec<f64>, Vec<Vector4<f64>>) {
    let (mut k, mut q) = (knots.to_vec(), points.to_vec());
    for t in breakpoints(knots, a, b) {
        let s = k.iter().filter(|&&v| v == t).count();
        if s < p {
            (k, q) = insert_knot(p, &k, &q, t, p - s);
        }
    }
    (k, q)
}

/// The first point index of each Bézier span of refined knots (see [`refine_to_bezier`]), with
/// the span's parameter interval.
pub(crate) fn bezier_spans(p: usize, knots: &[f64], a: f64, b: f64) -> Vec<(usize, f64, f64)> {
    let cuts = breakpoints(knots, a, b);
    cuts.windows(2)
        .map(|w| {
            let i = knots.iter().rposition(|&t| t <= w[0]).unwrap_or(p);
            (i - p, w[0], w[1])
        })
        .collect()
}

/// Homogeneous point of `p` with weight `w`.
pub fn homogeneous(p: &nalgebra::Point3<f64>, w: f64) -> Vector4<f64> {
    Vector4::new(p.x * w, p.y * w, p.z * w, w)
}

#[cfg(test)]
pub(crate) mod tests {
    use nalgebra::Point3;

    use super::NurbsCurve;

    /// The unit circle as nine control points of degree 2 (weights 1 and √2/2).
    pub(crate) fn unit_circle() -> NurbsCurve {
        let h = std::f64::consts::FRAC_1_SQRT_2;
        let points = [
            [1.0, 0.0],
            [1.0, 1.0],
            [0.0, 1.0],
            [-1.0, 1.0],
            [-1.0, 0.0],
            [-1.0, -1.0],
            [0.0, -1.0],
            [1.0, -1.0],
            [1.0, 0.0],
        ]
        .map(|[x, y]| Point3::new(x, y, 0.0));
        let weights = [1.0, h, 1.0, h, 1.0, h, 1.0, h, 1.0];
        let knots = vec![
            0.0, 0.0, 0.0, 0.25, 0.25, 0.5, 0.5, 0.75, 0.75, 1.0, 1.0, 1.0,
        ];
        NurbsCurve::new(2, knots, &points, &weights).expect("the unit circle")
    }
}
