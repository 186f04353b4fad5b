//! The seed's route, for comparison: an approximate offset surface built first (Piegl & Tiller
//! 1999, seed 003 §3.3.1), the grid projected onto it afterwards (the seed's `projPt`).
//!
//! The surface is split into its Bézier patches; on each, the bounds `M₁, M₂, M₃` of the
//! second derivatives in u, across and in v (from the second differences of the control net,
//! in the patch's own parameter) give the number of samples per side by eq. 3.20,
//! `n = (1/ε)^0.34 · √((M₁ + 2M₂ + M₃)/8)` (at least `p + 1`); every knot span takes the largest
//! `n` of the patches over it, so the samples form one tensor grid. The offset points
//! `S + d N` there are interpolated by a non-rational bicubic B-spline (Piegl & Tiller A9.4:
//! averaged knots, the sample parameters as the interpolation parameters). Then the seed's last
//! step: interior knots are removed one at a time (Piegl & Tiller A5.8 applied to every line
//! of the net at once), each removal kept only while the surface stays within ε of every
//! offset sample (checked by evaluating it, so the removals' errors cannot pile up unseen).
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
    /// Control points of the interpolant before knot removal.
    pub interpolated_control_points: usize,
    /// Knots removed.
    pub knots_removed: usize,
    /// Largest distance from the final surface to an offset sample (mm).
    pub sample_error: f64,
}

impl OffsetSurface {
    /// Control points of the offset surface (after knot removal).
    pub fn control_points(&self) -> usize {
        self.surface.homogeneous_points().len()
    }

    /// The offset as a lens surface (for projecting a grid onto it).
    pub fn as_lens(&self) -> Option<LensSurface> {
        NurbsLens::new(self.surface.clone(), self.domain).map(|l| LensSurface::Nurbs(Box::new(l)))
    }
}

/// Most offset samples the interpolation takes.
const MAX_SAMPLES: usize = 4_000_000;

/// Samples per side of a patch by eq. 3.20 (pow 0.34, the non-linear case).
fn samples_for(bounds: [f64; 3], tolerance: f64, degree: usize) -> usize {
    let [m1, m2, m3] = bounds;
    let n = (1.0 / tolerance).powf(0.34) * ((m1 + 2.0 * m2 + m3) / 8.0).sqrt();
    // Capped where the grid's own limit refuses anyway (a net of huge second differences
    // must not ask for billions of samples before that).
    (n.ceil().min(MAX_SAMPLES as f64) as usize).max(degree + 1)
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
    // At most this many along each side (spans outside the range are skipped below): one
    // side alone asking for more than the whole grid may hold is refused before it is laid
    // out.
    let (most_u, most_v) = (
        per_u.iter().fold(1usize, |a, &n| a.saturating_add(n)),
        per_v.iter().fold(1usize, |a, &n| a.saturating_add(n)),
    );
    if most_u.max(most_v) > MAX_SAMPLES {
        return Err(format!(
            "up to {most_u} × {most_v} offset samples: more than 4 million (loosen the offset \
             tolerance)"
        ));
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
    if us.len().saturating_mul(vs.len()) > MAX_SAMPLES {
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
    let interpolated_control_points = nu * nv;
    let samples = Samples {
        us: &us,
        vs: &vs,
        points: &points,
    };
    let reduced = remove_knots(
        Net {
            degree,
            knots: [knots_u, knots_v],
            points: control,
        },
        &samples,
        tolerance,
    )?;
    let surface = reduced.net.surface()?;
    Ok(OffsetSurface {
        surface,
        domain,
        samples: (nu, nv),
        bounds: largest,
        interpolated_control_points,
        knots_removed: reduced.removed,
        sample_error: reduced.error,
    })
}

/// A non-rational tensor-product net: degree, knots in u and v, points `[i][j]` (i along u).
#[derive(Clone)]
struct Net {
    degree: usize,
    knots: [Vec<f64>; 2],
    points: Vec<Vec<Point3<f64>>>,
}

impl Net {
    fn surface(&self) -> Result<NurbsSurface, String> {
        let weights: Vec<Vec<f64>> = self.points.iter().map(|row| vec![1.0; row.len()]).collect();
        NurbsSurface::new(
            [self.degree, self.degree],
            self.knots[0].clone(),
            self.knots[1].clone(),
            &self.points,
            &weights,
        )
        .map_err(|e| format!("the offset surface: {e}"))
    }

    /// The control points along `direction` (0: u) as lines, one per index of the other.
    fn lines(&self, direction: usize) -> Vec<Vec<Point3<f64>>> {
        let (rows, columns) = (self.points.len(), self.points[0].len());
        if direction == 0 {
            (0..columns)
                .map(|j| (0..rows).map(|i| self.points[i][j]).collect())
                .collect()
        } else {
            self.points.clone()
        }
    }

    fn with_lines(&self, direction: usize, knots: Vec<f64>, lines: Vec<Vec<Point3<f64>>>) -> Net {
        let mut out = self.clone();
        out.knots[direction] = knots;
        out.points = if direction == 0 {
            let rows = lines[0].len();
            (0..rows)
                .map(|i| lines.iter().map(|line| line[i]).collect())
                .collect()
        } else {
            lines
        };
        out
    }
}

/// The offset samples the interpolant must stay near.
struct Samples<'a> {
    us: &'a [f64],
    vs: &'a [f64],
    points: &'a [Point3<f64>],
}

impl Samples<'_> {
    /// Largest distance from `surface` to a sample.
    fn error(&self, surface: &NurbsSurface) -> f64 {
        let mut worst = 0.0f64;
        for (k, &u) in self.us.iter().enumerate() {
            for (l, &v) in self.vs.iter().enumerate() {
                worst =
                    worst.max((surface.point(u, v) - self.points[k * self.vs.len() + l]).norm());
            }
        }
        worst
    }
}

/// One removal of the interior knot `knots[r]` (multiplicity `s`) from a curve of degree `p`
/// (Piegl & Tiller A5.8 with t = 1): the new control points, or `None` when the two
/// estimates of the new points differ by more than `tolerance`.
fn remove_once(
    knots: &[f64],
    points: &[Point3<f64>],
    p: usize,
    r: usize,
    s: usize,
    tolerance: f64,
) -> Option<Vec<Point3<f64>>> {
    let u = knots[r];
    let order = p + 1;
    let (first, last) = (r - p, r - s);
    let off = first - 1;
    let mut temp = vec![Point3::origin(); last - off + 2];
    temp[0] = points[off];
    temp[last + 1 - off] = points[last + 1];
    let (mut i, mut j) = (first, last);
    let (mut ii, mut jj) = (1, last - off);
    while j > i {
        let alpha_i = (u - knots[i]) / (knots[i + order] - knots[i]);
        let alpha_j = (u - knots[j]) / (knots[j + order] - knots[j]);
        temp[ii] =
            Point3::from((points[i].coords - temp[ii - 1].coords * (1.0 - alpha_i)) / alpha_i);
        temp[jj] =
            Point3::from((points[j].coords - temp[jj + 1].coords * alpha_j) / (1.0 - alpha_j));
        i += 1;
        ii += 1;
        j -= 1;
        jj -= 1;
    }
    let distance = if j < i {
        (temp[ii - 1] - temp[jj + 1]).norm()
    } else {
        let alpha_i = (u - knots[i]) / (knots[i + order] - knots[i]);
        (points[i].coords - (temp[ii + 1].coords * alpha_i + temp[ii - 1].coords * (1.0 - alpha_i)))
            .norm()
    };
    if distance > tolerance {
        return None;
    }
    let mut out = points.to_vec();
    let (mut i, mut j) = (first, last);
    while j > i {
        out[i] = temp[i - off];
        out[j] = temp[j - off];
        i += 1;
        j -= 1;
    }
    // With one removal the point at (2r − s − p)/2 goes.
    out.remove((2 * r - s - p) / 2);
    Some(out)
}

/// What knot removal left.
struct Reduced {
    net: Net,
    removed: usize,
    error: f64,
}

/// Removes interior knots, u then v, pass after pass until none can go, each removal kept
/// only when every line passes A5.8's test and the surface stays within `tolerance` of every
/// sample.
fn remove_knots(mut net: Net, samples: &Samples<'_>, tolerance: f64) -> Result<Reduced, String> {
    let p = net.degree;
    let mut removed = 0;
    let mut error = samples.error(&net.surface()?);
    loop {
        let mut any = false;
        for direction in 0..2 {
            let mut k = p + 1;
            while k + p + 1 < net.knots[direction].len() {
                let knots = &net.knots[direction];
                // The last index of this knot value and its multiplicity.
                let value = knots[k];
                let r = (k..knots.len())
                    .take_while(|&i| knots[i] == value)
                    .last()
                    .unwrap_or(k);
                let s = r + 1 - k;
                if r + p + 1 >= knots.len() || s > p {
                    k = r + 1;
                    continue;
                }
                let lines = net.lines(direction);
                let new_lines: Option<Vec<_>> = lines
                    .iter()
                    .map(|line| remove_once(knots, line, p, r, s, tolerance))
                    .collect();
                let mut kept = false;
                if let Some(new_lines) = new_lines {
                    let mut new_knots = knots.clone();
                    new_knots.remove(r);
                    let candidate = net.with_lines(direction, new_knots, new_lines);
                    let candidate_error = samples.error(&candidate.surface()?);
                    if candidate_error <= tolerance {
                        net = candidate;
                        error = candidate_error;
                        removed += 1;
                        any = true;
                        kept = true;
                    }
                }
                if !kept {
                    k = r + 1;
                }
            }
        }
        if !any {
            break;
        }
    }
    Ok(Reduced {
        net,
        removed,
        error,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lathe::compensate::nose_centre;

    /// A knot inserted into a cubic and removed again gives back the curve's own control
    /// points; a knot the curve needs is refused.
    #[test]
    fn a_knot_inserted_and_removed_gives_the_curve_back() {
        use crate::cad::nurbs::NurbsCurve;
        let points: Vec<Point3<f64>> = (0..7)
            .map(|i| Point3::new(i as f64, (i as f64 * 1.3).sin(), 0.2 * i as f64))
            .collect();
        let knots = vec![0.0, 0.0, 0.0, 0.0, 0.2, 0.45, 0.7, 1.0, 1.0, 1.0, 1.0];
        let curve = NurbsCurve::new(3, knots.clone(), &points, &[1.0; 7]).unwrap();
        let refined = curve.insert_knot(0.37, 1);
        let refined_points: Vec<Point3<f64>> = refined
            .homogeneous_points()
            .iter()
            .map(|h| Point3::from(h.xyz() / h.w))
            .collect();
        let r = refined.knots().iter().rposition(|&k| k == 0.37).unwrap();
        let back = remove_once(refined.knots(), &refined_points, 3, r, 1, 1e-12).unwrap();
        assert_eq!(back.len(), points.len());
        for (a, b) in back.iter().zip(&points) {
            assert!((a - b).norm() < 1e-12, "{a} vs {b}");
        }
        // The original's own knot 0.45 carries shape: not removable to 1e-6.
        let r = knots.iter().rposition(|&k| k == 0.45).unwrap();
        assert!(remove_once(&knots, &points, 3, r, 1, 1e-6).is_none());
    }

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
        // Knot removal shrank the net and kept it within ε of every sample.
        let offset = piegl_tiller_offset(&surface, rho, 1e-3).unwrap();
        assert!(offset.knots_removed > 0, "{}", offset.knots_removed);
        assert!(offset.control_points() < offset.interpolated_control_points);
        assert!(offset.sample_error <= 1e-3);
        assert!(errors[1].1 < errors[0].1, "{errors:?}");
        assert!(errors[1].1 < 1e-4, "{errors:?}");
    }
}
