//! The seed's route, for comparison: an approximate offset surface built first (Piegl & Tiller
//! 1999, seed 003 §3.3.1), the grid projected onto it afterwards (the seed's `projPt`).
//!
//! The surface is split into its Bézier patches; on each, the bounds `M₁, M₂, M₃` of the
//! second derivatives in u, across and in v (from the second differences of the control net,
//! in the patch's own parameter) give the number of samples per side by eq. 3.20,
//! `n = (1/ε)^0.34 · √((M₁ + 2M₂ + M₃)/8)` (at least `p + 1`); every knot span takes the largest
//! `n` of the patches over it, so the samples form one tensor grid. The offset points
//! `S + d N` there are interpolated by a non-rational bicubic B-spline (Piegl & Tiller A9.4:
//! averaged knots, the sample parameters as the interpolation parameters). The seed's last
//! step, knot removal down to the tolerance, only shrinks the control net and is not done here:
//! the report gives the net as interpolated.
//!
//! Rational patches are bounded through their Euclidean control points (exact for the
//! polynomial patches CAD exports of lens surfaces carry; an estimate otherwise, as the
//! seed's own empirical rule is).

use nalgebra::{DMatrix, Point3};

use super::compensate::frame;
use super::surface::{LensSurface, NurbsLens};
use crate::cad::nurbs::{NurbsSurface, basis_functions, find_span};

/// An offset surface built by sampling and interpolation.
#[derive(Clone, Debug)]
pub struct OffsetSurface {
    /// The interpolating bicubic.
    pub surface: NurbsSurface,
    /// Its parameter rectangle (the base surface's).
    pub domain: ((f64, f64), (f64, f64)),
    /// Samples along u and v.
    pub samples: (usize, usize),
    /// Largest `M₁, M₂, M₃` over the patches.
    pub bounds: [f64; 3],
}

impl OffsetSurface {
    /// Control points of the interpolant.
    pub fn control_points(&self) -> usize {
        self.surface.homogeneous_points().len()
    }

    /// The offset as a lens surface (for projecting a grid onto it).
    pub fn as_lens(&self) -> Option<LensSurface> {
        NurbsLens::new(self.surface.clone(), self.domain).map(|l| LensSurface::Nurbs(Box::new(l)))
    }
}

/// Samples per side of a patch by eq. 3.20 (pow 0.34, the non-linear case).
fn samples_for(bounds: [f64; 3], tolerance: f64, degree: usize) -> usize {
    let [m1, m2, m3] = bounds;
    let n = (1.0 / tolerance).powf(0.34) * ((m1 + 2.0 * m2 + m3) / 8.0).sqrt();
    (n.ceil() as usize).max(degree + 1)
}

/// Knots for interpolating at `parameters` with degree `p` (Piegl & Tiller eq. 9.8).
fn averaged_knots(parameters: &[f64], p: usize) -> Vec<f64> {
    let m = parameters.len() - 1;
    let mut knots = vec![parameters[0]; p + 1];
    for j in 1..=m.saturating_sub(p) {
        knots.push(parameters[j..j + p].iter().sum::<f64>() / p as f64);
    }
    knots.extend(std::iter::repeat_n(parameters[m], p + 1));
    knots
}

/// The collocation matrix `N_{i,p}(t_k)` of the interpolation.
fn collocation(parameters: &[f64], knots: &[f64], p: usize) -> DMatrix<f64> {
    let n = parameters.len();
    let mut a = DMatrix::zeros(n, n);
    for (k, &t) in parameters.iter().enumerate() {
        let span = find_span(n - 1, p, t, knots);
        let basis = basis_functions(span, t, p, knots);
        for (r, b) in basis.iter().enumerate() {
            a[(k, span - p + r)] = *b;
        }
    }
    a
}

/// The Piegl–Tiller offset of a NURBS lens at `distance` toward the tool, to `tolerance`.
pub fn piegl_tiller_offset(
    surface: &LensSurface,
    distance: f64,
    tolerance: f64,
) -> Result<OffsetSurface, String> {
    let LensSurface::Nurbs(lens) = surface else {
        return Err("the Piegl–Tiller offset applies to NURBS surfaces (an IGES face)".into());
    };
    if !(tolerance.is_finite() && tolerance > 0.0) {
        return Err(format!("offset tolerance {tolerance}: must be positive"));
    }
    let base = &lens.surface;
    let [p, q] = base.degree();
    let domain = surface.domain();
    let patches = base.bezier_patches();
    // Spans along u and v, in order.
    let mut spans_u: Vec<(f64, f64)> = patches.iter().map(|b| b.u).collect();
    let mut spans_v: Vec<(f64, f64)> = patches.iter().map(|b| b.v).collect();
    for spans in [&mut spans_u, &mut spans_v] {
        spans.sort_by(|a, b| a.0.total_cmp(&b.0));
        spans.dedup();
    }
    let mut per_u = vec![p + 1; spans_u.len()];
    let mut per_v = vec![q + 1; spans_v.len()];
    let mut largest = [0.0f64; 3];
    for b in &patches {
        let columns = q + 1;
        let at = |i: usize, j: usize| {
            let h = b.points[i * columns + j];
            h.xyz() / h.w
        };
        let mut bounds = [0.0f64; 3];
        for i in 0..=p {
            for j in 0..=q {
                if i + 2 <= p {
                    let d = at(i + 2, j) - at(i + 1, j) * 2.0 + at(i, j);
                    bounds[0] = bounds[0].max((p * (p - 1)) as f64 * d.norm());
                }
                if i < p && j < q {
                    let d = at(i + 1, j + 1) - at(i + 1, j) - at(i, j + 1) + at(i, j);
                    bounds[1] = bounds[1].max((p * q) as f64 * d.norm());
                }
                if j + 2 <= q {
                    let d = at(i, j + 2) - at(i, j + 1) * 2.0 + at(i, j);
                    bounds[2] = bounds[2].max((q * (q - 1)) as f64 * d.norm());
                }
            }
        }
        for k in 0..3 {
            largest[k] = largest[k].max(bounds[k]);
        }
        let n = samples_for(bounds, tolerance, p.max(q));
        if let Some(k) = spans_u.iter().position(|s| *s == b.u) {
            per_u[k] = per_u[k].max(n);
        }
        if let Some(k) = spans_v.iter().position(|s| *s == b.v) {
            per_v[k] = per_v[k].max(n);
        }
    }
    let sample_parameters = |spans: &[(f64, f64)], per: &[usize], range: (f64, f64)| {
        let mut t = Vec::new();
        for (s, &n) in spans.iter().zip(per) {
            let (a, b) = (s.0.max(range.0), s.1.min(range.1));
            if b <= a {
                continue;
            }
            for k in 0..n {
                t.push(a + (b - a) * k as f64 / n as f64);
            }
        }
        t.push(range.1);
        t
    };
    let us = sample_parameters(&spans_u, &per_u, domain.0);
    let vs = sample_parameters(&spans_v, &per_v, domain.1);
    if us.len() * vs.len() > 4_000_000 {
        return Err(format!(
            "{} × {} offset samples: more than 4 million (loosen the offset tolerance)",
            us.len(),
            vs.len()
        ));
    }
    let degree = 3usize.min(us.len() - 1).min(vs.len() - 1);
    // The offset points.
    let mut points = vec![Point3::origin(); us.len() * vs.len()];
    for (k, &u) in us.iter().enumerate() {
        for (l, &v) in vs.iter().enumerate() {
            let jet = surface.jet(u, v);
            let f = frame(surface, &jet)
                .ok_or_else(|| format!("degenerate surface at parameters ({u:.4}, {v:.4})"))?;
            points[k * vs.len() + l] = jet.point + f.normal * distance;
        }
    }
    // Interpolate along u for every column of samples, then along v for every row of that.
    let knots_u = averaged_knots(&us, degree);
    let knots_v = averaged_knots(&vs, degree);
    let lu_u = collocation(&us, &knots_u, degree).lu();
    let lu_v = collocation(&vs, &knots_v, degree).lu();
    let (nu, nv) = (us.len(), vs.len());
    let mut right = DMatrix::zeros(nu, 3 * nv);
    for k in 0..nu {
        for l in 0..nv {
            let p = points[k * nv + l];
            for c in 0..3 {
                right[(k, 3 * l + c)] = p[c];
            }
        }
    }
    let along_u = lu_u
        .solve(&right)
        .ok_or("the interpolation along u is singular")?;
    let mut right = DMatrix::zeros(nv, 3 * nu);
    for i in 0..nu {
        for l in 0..nv {
            for c in 0..3 {
                right[(l, 3 * i + c)] = along_u[(i, 3 * l + c)];
            }
        }
    }
    let net = lu_v
        .solve(&right)
        .ok_or("the interpolation along v is singular")?;
    let control: Vec<Vec<Point3<f64>>> = (0..nu)
        .map(|i| {
            (0..nv)
                .map(|j| Point3::new(net[(j, 3 * i)], net[(j, 3 * i + 1)], net[(j, 3 * i + 2)]))
                .collect()
        })
        .collect();
    let weights = vec![vec![1.0; nv]; nu];
    let surface = NurbsSurface::new([degree, degree], knots_u, knots_v, &control, &weights)
        .map_err(|e| format!("the offset interpolant: {e}"))?;
    Ok(OffsetSurface {
        surface,
        domain,
        samples: (nu, nv),
        bounds: largest,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lathe::compensate::nose_centre;

    /// On the sample freeform lens, the interpolated offset passes through its samples and
    /// stays near the exact nose-centre surface; a tighter tolerance samples more densely and
    /// comes closer.
    #[test]
    fn the_offset_interpolant_approaches_the_exact_offset() {
        let patch = crate::sample::lens::freeform_lens_patch().unwrap();
        let surface = LensSurface::Nurbs(Box::new(
            NurbsLens::new(patch, ((0.0, 1.0), (0.0, 1.0))).unwrap(),
        ));
        let rho = 0.5;
        let mut errors = Vec::new();
        for tolerance in [1e-2, 1e-4] {
            let offset = piegl_tiller_offset(&surface, rho, tolerance).unwrap();
            let projected = offset.as_lens().unwrap();
            let mut worst = 0.0f64;
            for &(x, y) in &[
                (0.0, 0.0),
                (5.0, -3.0),
                (-12.0, 9.0),
                (14.0, 13.0),
                (-17.0, -8.0),
            ] {
                let guess = surface.parameters_over(x, y).unwrap();
                let exact = nose_centre(&surface, rho, (x, y), guess).unwrap().centre.z;
                let (u, v) = projected.parameters_over(x, y).unwrap();
                let z = projected.jet(u, v).point.z;
                worst = worst.max((z - exact).abs());
            }
            errors.push((offset.control_points(), worst));
        }
        assert!(errors[1].0 > errors[0].0, "{errors:?}");
        assert!(errors[1].1 < errors[0].1, "{errors:?}");
        assert!(errors[1].1 < 1e-4, "{errors:?}");
    }
}
