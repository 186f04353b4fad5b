//! Fast repeated evaluation of a NURBS surface: its Bézier patches in power form.
//!
//! Tessellation evaluates one surface hundreds of thousands of times. De Boor's evaluation
//! pays `p(p + 1)/2` divisions per direction and point; a Bézier patch rewritten in the
//! monomial basis of its local parameters, `Σₖ Σₗ Cₖₗ sᵏ tˡ` on homogeneous coordinates, costs
//! only nested Horner steps. On `[0, 1]` and at the degrees of CAD surfaces (up to 7) the
//! change of basis loses a few bits at most; the test holds it to 1e-12 of the part size.

use nalgebra::{Point3, Vector3, Vector4};

use super::{NurbsSurface, binomial};

/// Most patches a table is built for (a bicubic table of this many is 51 MB).
const MAX_PATCHES: usize = 100_000;

/// A NURBS surface ready for many evaluations.
#[derive(Clone, Debug)]
pub struct PatchEvaluator {
    degree: [usize; 2],
    /// Patch boundaries along u and v (ascending; `len = patches + 1` in each direction).
    breaks_u: Vec<f64>,
    breaks_v: Vec<f64>,
    /// Per patch (u-major), `(p + 1)(q + 1)` homogeneous monomial coefficients `C[k][l]`,
    /// row-major in k.
    coefficients: Vec<Vector4<f64>>,
}

/// Bernstein to monomial: `B_i,n(s) = Σ_{k ≥ i} (−1)^{k−i} C(n, k) C(k, i) sᵏ`; entry `[k][i]`.
fn bernstein_to_monomial(n: usize) -> Vec<Vec<f64>> {
    (0..=n)
        .map(|k| {
            (0..=n)
                .map(|i| {
                    if i > k {
                        0.0
                    } else {
                        let sign = if (k - i) % 2 == 0 { 1.0 } else { -1.0 };
                        sign * binomial(n, k) * binomial(k, i)
                    }
                })
                .collect()
        })
        .collect()
}

impl PatchEvaluator {
    /// Splits the surface into its Bézier patches and rewrites each in power form; `None`
    /// for a surface of more than `MAX_PATCHES` patches (the table would outweigh the
    /// evaluations it saves) or none.
    pub fn new(surface: &NurbsSurface) -> Option<PatchEvaluator> {
        let [p, q] = surface.degree();
        let (knots_u, knots_v) = surface.knots();
        let spans = |k: &[f64]| k.windows(2).filter(|w| w[1] > w[0]).count();
        if spans(knots_u) * spans(knots_v) > MAX_PATCHES {
            return None;
        }
        let patches = surface.bezier_patches();
        let mut breaks_u: Vec<f64> = patches.iter().flat_map(|b| [b.u.0, b.u.1]).collect();
        let mut breaks_v: Vec<f64> = patches.iter().flat_map(|b| [b.v.0, b.v.1]).collect();
        for breaks in [&mut breaks_u, &mut breaks_v] {
            breaks.sort_by(f64::total_cmp);
            breaks.dedup();
        }
        let mu = bernstein_to_monomial(p);
        let mv = bernstein_to_monomial(q);
        let mut coefficients = Vec::with_capacity(patches.len() * (p + 1) * (q + 1));
        for b in &patches {
            let net = |i: usize, j: usize| b.points[i * (q + 1) + j];
            for row_u in &mu {
                for row_v in &mv {
                    // Entries above the diagonal are zero, so the sums run over all i, j.
                    let mut c = Vector4::zeros();
                    for (i, &a) in row_u.iter().enumerate() {
                        for (j, &b) in row_v.iter().enumerate() {
                            c += net(i, j) * (a * b);
                        }
                    }
                    coefficients.push(c);
                }
            }
        }
        if breaks_u.len() < 2 || breaks_v.len() < 2 {
            return None;
        }
        Some(PatchEvaluator {
            degree: [p, q],
            breaks_u,
            breaks_v,
            coefficients,
        })
    }

    /// The point at `(u, v)`, clamped into the domain.
    pub fn point(&self, u: f64, v: f64) -> Point3<f64> {
        let [p, q] = self.degree;
        let (iu, s) = locate(&self.breaks_u, u);
        let (iv, t) = locate(&self.breaks_v, v);
        let patch = iu * (self.breaks_v.len() - 1) + iv;
        let c = &self.coefficients[patch * (p + 1) * (q + 1)..(patch + 1) * (p + 1) * (q + 1)];
        let mut sum = Vector4::zeros();
        for k in (0..=p).rev() {
            let row = &c[k * (q + 1)..(k + 1) * (q + 1)];
            let mut r = row[q];
            for l in (0..q).rev() {
                r = r * t + row[l];
            }
            sum = sum * s + r;
        }
        Point3::from(sum.xyz() / sum.w)
    }

    /// The point with its first and second partial derivatives at `(u, v)` (clamped into the
    /// domain): Horner with derivatives on the homogeneous power form, then the quotient rule
    /// (Piegl & Tiller eq. 4.20 up to second order).
    pub fn jet(&self, u: f64, v: f64) -> SurfaceJet {
        let [p, q] = self.degree;
        let (iu, s, su) = locate_scaled(&self.breaks_u, u);
        let (iv, t, sv) = locate_scaled(&self.breaks_v, v);
        let patch = iu * (self.breaks_v.len() - 1) + iv;
        let c = &self.coefficients[patch * (p + 1) * (q + 1)..(patch + 1) * (p + 1) * (q + 1)];
        // a[k][l] = ∂ᵏ⁺ˡA/∂sᵏ∂tˡ of the homogeneous A(s, t), k + l ≤ 2.
        let zero = Vector4::zeros();
        let (mut a, mut a_s, mut a_ss) = (zero, zero, zero);
        let (mut a_t, mut a_st, mut a_tt) = (zero, zero, zero);
        for k in (0..=p).rev() {
            let row = &c[k * (q + 1)..(k + 1) * (q + 1)];
            // The row's polynomial in t and its first two derivatives.
            let (mut r, mut r1, mut r2) = (row[q], zero, zero);
            for l in (0..q).rev() {
                r2 = r2 * t + r1 * 2.0;
                r1 = r1 * t + r;
                r = r * t + row[l];
            }
            a_ss = a_ss * s + a_s * 2.0;
            a_s = a_s * s + a;
            a = a * s + r;
            a_st = a_st * s + a_t;
            a_t = a_t * s + r1;
            a_tt = a_tt * s + r2;
        }
        let (a_s, a_t) = (a_s * su, a_t * sv);
        let (a_ss, a_st, a_tt) = (a_ss * (su * su), a_st * (su * sv), a_tt * (sv * sv));
        let w = a.w;
        let point = a.xyz() / w;
        let du = (a_s.xyz() - point * a_s.w) / w;
        let dv = (a_t.xyz() - point * a_t.w) / w;
        let duu = (a_ss.xyz() - du * (2.0 * a_s.w) - point * a_ss.w) / w;
        let dvv = (a_tt.xyz() - dv * (2.0 * a_t.w) - point * a_tt.w) / w;
        let duv = (a_st.xyz() - du * a_t.w - dv * a_s.w - point * a_st.w) / w;
        SurfaceJet {
            point: Point3::from(point),
            du,
            dv,
            duu,
            duv,
            dvv,
        }
    }

    /// The parameter domain `([u₀, u₁], [v₀, v₁])`.
    pub fn domain(&self) -> ((f64, f64), (f64, f64)) {
        (
            (self.breaks_u[0], self.breaks_u[self.breaks_u.len() - 1]),
            (self.breaks_v[0], self.breaks_v[self.breaks_v.len() - 1]),
        )
    }
}

/// A surface point with its first and second partial derivatives.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfaceJet {
    /// `S(u, v)`.
    pub point: Point3<f64>,
    /// `∂S/∂u`.
    pub du: Vector3<f64>,
    /// `∂S/∂v`.
    pub dv: Vector3<f64>,
    /// `∂²S/∂u²`.
    pub duu: Vector3<f64>,
    /// `∂²S/∂u∂v`.
    pub duv: Vector3<f64>,
    /// `∂²S/∂v²`.
    pub dvv: Vector3<f64>,
}

/// [`locate`] with the factor `ds/du` of the local parameter.
fn locate_scaled(breaks: &[f64], x: f64) -> (usize, f64, f64) {
    let (i, s) = locate(breaks, x);
    let width = breaks[i + 1] - breaks[i];
    (i, s, if width > 0.0 { 1.0 / width } else { 0.0 })
}

/// The interval of `breaks` that holds `x` (clamped) and the local parameter in it.
fn locate(breaks: &[f64], x: f64) -> (usize, f64) {
    let last = breaks.len() - 2;
    let x = x.clamp(breaks[0], breaks[last + 1]);
    let i = breaks[1..=last].partition_point(|&b| b <= x).min(last);
    let (a, b) = (breaks[i], breaks[i + 1]);
    (i, if b > a { (x - a) / (b - a) } else { 0.0 })
}
