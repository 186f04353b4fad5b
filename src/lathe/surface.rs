//! Lens surfaces: analytic sags written once on second-order jets, and freeform NURBS faces
//! read from IGES (seed 003 ch. 3), behind one parametric interface — a point with its first
//! and second partial derivatives at `(u, v)`.
//!
//! Conventions (every length in mm, the optical axis is `z`, the face to be cut looks toward
//! `+z`, where the tool is):
//! * sag `z(x, y)` is measured from the vertex; a positive radius puts the centre of curvature
//!   on `+z` (the face is concave as the tool sees it);
//! * conic: `z = c r² / (1 + √(1 − (1 + k) c² r²))`, `c = 1/R`, `k` the conic constant (0 sphere,
//!   −1 paraboloid);
//! * even asphere: the conic plus `Σᵢ aᵢ r^(2i + 2)`, the first coefficient on `r⁴`;
//! * toric: a conic profile `z_y(y)` in the YZ plane (radius `R_y`, conic `k_y`) swept on a
//!   circle of radius `R_x` about an axis parallel to `y` (Zemax's toroidal surface without its
//!   polynomial): `z = z_y + c_x x² / ((1 − c_x z_y) + √((1 − c_x z_y)² − c_x² x²))`;
//! * XY polynomial: the conic plus `Σ c_ij (x/h)ⁱ (y/h)ʲ` with normalisation length `h`;
//! * Zernike: the conic plus `Σⱼ cⱼ Zⱼ(ρ, φ)`, `ρ = r/h`, in Noll's order and normalisation
//!   (`Z₁ = 1`, `Z₂ = 2ρ cos φ`, `Z₃ = 2ρ sin φ`, `Z₄ = √3 (2ρ² − 1)`, …; even `j` cosine, odd
//!   `j` sine), written as polynomials in `x, y` so the origin is regular.
//!
//! Sag surfaces are parametrised by `(u, v) = (x, y)` and defined on the disc of their clear
//! aperture; a NURBS face by its own parameters on its parameter rectangle.

use nalgebra::{Point3, Vector3};

use super::jet::Jet2;
use crate::cad::nurbs::{NurbsSurface, PatchEvaluator, SurfaceJet};

/// The shape of an analytic lens surface (see the module docs for the formulas).
#[derive(Clone, Debug, PartialEq)]
pub enum SagShape {
    /// A conic of curvature `curvature` (1/mm) and conic constant `conic`, plus even powers
    /// of `r` from `r⁴` up (`even[0]` on `r⁴`): a sphere when both are empty/zero.
    Conic {
        /// Vertex curvature `c = 1/R` (0: flat).
        curvature: f64,
        /// Conic constant `k`.
        conic: f64,
        /// Coefficients of `r⁴, r⁶, …`.
        even: Vec<f64>,
    },
    /// A toric surface: a conic profile in YZ swept about an axis parallel to `y`.
    Toric {
        /// Curvature `1/R_x` of the sweep in XZ.
        curvature_x: f64,
        /// Curvature `1/R_y` of the profile in YZ.
        curvature_y: f64,
        /// Conic constant of the YZ profile.
        conic_y: f64,
    },
    /// A conic plus a polynomial in `x/h, y/h`.
    XyPolynomial {
        /// Vertex curvature of the base conic.
        curvature: f64,
        /// Conic constant of the base conic.
        conic: f64,
        /// Normalisation length `h`.
        normalization: f64,
        /// Terms `(i, j, c_ij)` of `c_ij (x/h)ⁱ (y/h)ʲ`.
        terms: Vec<(u32, u32, f64)>,
    },
    /// A conic plus Zernike polynomials (Noll's order and normalisation) on the disc of radius
    /// `normalization`.
    Zernike {
        /// Vertex curvature of the base conic.
        curvature: f64,
        /// Conic constant of the base conic.
        conic: f64,
        /// Normalisation radius `h`.
        normalization: f64,
        /// `coefficients[j − 1]` multiplies `Z_j`.
        coefficients: Vec<f64>,
    },
}

/// `c r² / (1 + √(1 − (1 + k) c² r²))` on jets; NaN where the conic does not reach.
fn conic_sag(curvature: f64, conic: f64, r2: Jet2) -> Jet2 {
    let root = (-(r2 * ((1.0 + conic) * curvature * curvature)) + 1.0).sqrt();
    r2 * curvature / (root + 1.0)
}

/// Noll's index `j ≥ 1` as the radial order `n` and the signed azimuthal order `m` (negative:
/// sine term).
pub fn noll_to_nm(j: usize) -> (u32, i32) {
    let j = j.max(1);
    // n(n + 1)/2 < j ≤ (n + 1)(n + 2)/2
    let mut n = 0usize;
    while (n + 1) * (n + 2) / 2 < j {
        n += 1;
    }
    let k = j - n * (n + 1) / 2 - 1;
    let m = if n.is_multiple_of(2) {
        2 * k.div_ceil(2)
    } else {
        2 * (k / 2) + 1
    };
    let signed = if m == 0 || j.is_multiple_of(2) {
        m as i32
    } else {
        -(m as i32)
    };
    (n as u32, signed)
}

/// Factorial as a float (orders stay small).
fn factorial(n: u32) -> f64 {
    (1..=n).map(f64::from).product()
}

/// Noll's `Z_j` at `(X, Y) = (x/h, y/h)` on jets.
fn zernike(j: usize, x: Jet2, y: Jet2) -> Jet2 {
    let (n, m) = noll_to_nm(j);
    let am = m.unsigned_abs();
    // R_n^m(ρ) = ρ^m Σ_s a_s (ρ²)^((n − m)/2 − s); ρ^m cos mφ = Re (X + iY)^m.
    let rho2 = x.square() + y.square();
    let half = (n - am) / 2;
    let mut radial = Jet2::constant(0.0);
    for s in 0..=half {
        let a = (if s % 2 == 0 { 1.0 } else { -1.0 }) * factorial(n - s)
            / (factorial(s) * factorial((n + am) / 2 - s) * factorial((n - am) / 2 - s));
        radial = radial + rho2.powi(half - s) * a;
    }
    let (mut re, mut im) = (Jet2::constant(1.0), Jet2::constant(0.0));
    for _ in 0..am {
        (re, im) = (re * x - im * y, re * y + im * x);
    }
    let (angular, norm) = match m.cmp(&0) {
        std::cmp::Ordering::Equal => (re, f64::from(n + 1).sqrt()),
        std::cmp::Ordering::Greater => (re, (2.0 * f64::from(n + 1)).sqrt()),
        std::cmp::Ordering::Less => (im, (2.0 * f64::from(n + 1)).sqrt()),
    };
    radial * angular * norm
}

impl SagShape {
    /// The sag and its derivatives at `(x, y)`.
    pub fn sag(&self, x: f64, y: f64) -> Jet2 {
        let (x, y) = Jet2::variables(x, y);
        match self {
            SagShape::Conic {
                curvature,
                conic,
                even,
            } => {
                let r2 = x.square() + y.square();
                let mut z = conic_sag(*curvature, *conic, r2);
                let mut power = r2.square();
                for &a in even {
                    z = z + power * a;
                    power = power * r2;
                }
                z
            }
            SagShape::Toric {
                curvature_x,
                curvature_y,
                conic_y,
            } => {
                let zy = conic_sag(*curvature_y, *conic_y, y.square());
                let w = -(zy * *curvature_x) + 1.0;
                let root = (w.square() - x.square() * (curvature_x * curvature_x)).sqrt();
                zy + x.square() * *curvature_x / (w + root)
            }
            SagShape::XyPolynomial {
                curvature,
                conic,
                normalization,
                terms,
            } => {
                let r2 = x.square() + y.square();
                let (xn, yn) = (x / *normalization, y / *normalization);
                terms
                    .iter()
                    .fold(conic_sag(*curvature, *conic, r2), |z, &(i, j, c)| {
                        z + xn.powi(i) * yn.powi(j) * c
                    })
            }
            SagShape::Zernike {
                curvature,
                conic,
                normalization,
                coefficients,
            } => {
                let r2 = x.square() + y.square();
                let (xn, yn) = (x / *normalization, y / *normalization);
                coefficients
                    .iter()
                    .enumerate()
                    .filter(|(_, c)| **c != 0.0)
                    .fold(conic_sag(*curvature, *conic, r2), |z, (i, &c)| {
                        z + zernike(i + 1, xn, yn) * c
                    })
            }
        }
    }
}

/// A freeform NURBS face ready for many evaluations.
#[derive(Clone, Debug)]
pub struct NurbsLens {
    /// The surface as read.
    pub surface: NurbsSurface,
    evaluator: PatchEvaluator,
    /// The face's parameter rectangle (the 128's `U(0), U(1), V(0), V(1)`).
    domain: ((f64, f64), (f64, f64)),
    /// +1 when `S_u × S_v` points toward `+z`, −1 when the parametrisation turns it away.
    orientation: f64,
    /// A coarse table of `(u, v, x, y)` for first guesses of the parameters over a point.
    table: Vec<[f64; 4]>,
    /// The table's entries bucketed by `(x, y)` on a square grid.
    buckets: Buckets,
}

/// Table entries bucketed by position in plan, for the nearest-entry lookup.
#[derive(Clone, Debug)]
struct Buckets {
    origin: (f64, f64),
    cell: f64,
    side: usize,
    /// Entry indices per cell, row-major.
    cells: Vec<Vec<u32>>,
}

impl Buckets {
    fn new(table: &[[f64; 4]], side: usize) -> Buckets {
        let (mut x0, mut y0, mut x1, mut y1) = (
            f64::INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NEG_INFINITY,
        );
        for e in table {
            (x0, y0, x1, y1) = (x0.min(e[2]), y0.min(e[3]), x1.max(e[2]), y1.max(e[3]));
        }
        let cell = ((x1 - x0).max(y1 - y0) / side as f64).max(1e-12);
        let mut buckets = Buckets {
            origin: (x0, y0),
            cell,
            side,
            cells: vec![Vec::new(); side * side],
        };
        for (k, e) in table.iter().enumerate() {
            let (i, j) = buckets.cell_of(e[2], e[3]);
            buckets.cells[j * side + i].push(k as u32);
        }
        buckets
    }

    fn cell_of(&self, x: f64, y: f64) -> (usize, usize) {
        let clamp = |t: f64| (t.floor().max(0.0) as usize).min(self.side - 1);
        (
            clamp((x - self.origin.0) / self.cell),
            clamp((y - self.origin.1) / self.cell),
        )
    }

    /// The entry nearest `(x, y)` among the cells around its own, widening the ring until one
    /// holds an entry, then one ring more (an entry in a farther cell can be nearer).
    fn nearest(&self, table: &[[f64; 4]], x: f64, y: f64) -> Option<usize> {
        let (ci, cj) = self.cell_of(x, y);
        let mut best: Option<(f64, usize)> = None;
        let mut found_at = None;
        for ring in 0..self.side {
            let (i0, i1) = (ci.saturating_sub(ring), (ci + ring).min(self.side - 1));
            let (j0, j1) = (cj.saturating_sub(ring), (cj + ring).min(self.side - 1));
            for j in j0..=j1 {
                for i in i0..=i1 {
                    if i != i0 && i != i1 && j != j0 && j != j1 {
                        continue; // inside the ring: seen already
                    }
                    for &k in &self.cells[j * self.side + i] {
                        let e = table[k as usize];
                        let d = (e[2] - x).powi(2) + (e[3] - y).powi(2);
                        if best.is_none_or(|(b, bk)| d < b || (d == b && (k as usize) < bk)) {
                            best = Some((d, k as usize));
                        }
                    }
                }
            }
            match found_at {
                Some(r) if ring > r => break,
                None if best.is_some() => found_at = Some(ring),
                _ => {}
            }
        }
        best.map(|(_, k)| k)
    }
}

/// Samples per side of the first-guess table.
const TABLE_SIDE: usize = 49;

impl NurbsLens {
    /// Prepares a NURBS face on the parameter rectangle `domain`; `None` when the surface has
    /// too many patches to tabulate.
    pub fn new(surface: NurbsSurface, domain: ((f64, f64), (f64, f64))) -> Option<NurbsLens> {
        let evaluator = PatchEvaluator::new(&surface)?;
        let ((u0, u1), (v0, v1)) = domain;
        let mut table = Vec::with_capacity(TABLE_SIDE * TABLE_SIDE);
        let mut normal_z = 0.0;
        for i in 0..TABLE_SIDE {
            for j in 0..TABLE_SIDE {
                let u = u0 + (u1 - u0) * i as f64 / (TABLE_SIDE - 1) as f64;
                let v = v0 + (v1 - v0) * j as f64 / (TABLE_SIDE - 1) as f64;
                let jet = evaluator.jet(u, v);
                normal_z += jet.du.cross(&jet.dv).normalize().z;
                table.push([u, v, jet.point.x, jet.point.y]);
            }
        }
        let buckets = Buckets::new(&table, TABLE_SIDE - 1);
        Some(NurbsLens {
            surface,
            evaluator,
            domain,
            orientation: if normal_z >= 0.0 { 1.0 } else { -1.0 },
            table,
            buckets,
        })
    }
}

/// A lens surface: analytic over a disc, or a NURBS face.
#[derive(Clone, Debug)]
pub enum LensSurface {
    /// An analytic sag on the disc of diameter `aperture` about the axis.
    Sag {
        /// The formula.
        shape: SagShape,
        /// Clear aperture (diameter, mm).
        aperture: f64,
    },
    /// A freeform NURBS face.
    Nurbs(Box<NurbsLens>),
}

impl LensSurface {
    /// The point and its partial derivatives at parameters `(u, v)`; for a NURBS face the
    /// parameters are clamped into its rectangle.
    pub fn jet(&self, u: f64, v: f64) -> SurfaceJet {
        match self {
            LensSurface::Sag { shape, .. } => {
                let z = shape.sag(u, v);
                let [zx, zy] = z.gradient;
                let [zxx, zxy, zyy] = z.hessian;
                SurfaceJet {
                    point: Point3::new(u, v, z.value),
                    du: Vector3::new(1.0, 0.0, zx),
                    dv: Vector3::new(0.0, 1.0, zy),
                    duu: Vector3::new(0.0, 0.0, zxx),
                    duv: Vector3::new(0.0, 0.0, zxy),
                    dvv: Vector3::new(0.0, 0.0, zyy),
                }
            }
            LensSurface::Nurbs(lens) => {
                let ((u0, u1), (v0, v1)) = lens.domain;
                lens.evaluator.jet(u.clamp(u0, u1), v.clamp(v0, v1))
            }
        }
    }

    /// The unit normal toward the tool (`+z` side) from a jet of this surface; `None` where
    /// the surface is degenerate.
    pub fn normal(&self, jet: &SurfaceJet) -> Option<Vector3<f64>> {
        let sign = match self {
            LensSurface::Sag { .. } => 1.0,
            LensSurface::Nurbs(lens) => lens.orientation,
        };
        let n = jet.du.cross(&jet.dv) * sign;
        let length = n.norm();
        (length > 1e-300 && length.is_finite()).then(|| n / length)
    }

    /// Whether `(u, v)` lies on the surface (within `slack` of its parameter domain, in the
    /// parameters' own units).
    pub fn contains(&self, u: f64, v: f64, slack: f64) -> bool {
        match self {
            LensSurface::Sag { aperture, .. } => u.hypot(v) <= aperture / 2.0 + slack,
            LensSurface::Nurbs(lens) => {
                let ((u0, u1), (v0, v1)) = lens.domain;
                u >= u0 - slack && u <= u1 + slack && v >= v0 - slack && v <= v1 + slack
            }
        }
    }

    /// The parameter rectangle `((u₀, u₁), (v₀, v₁))` (a sag's: the aperture's square).
    pub fn domain(&self) -> ((f64, f64), (f64, f64)) {
        match self {
            LensSurface::Sag { aperture, .. } => {
                let r = aperture / 2.0;
                ((-r, r), (-r, r))
            }
            LensSurface::Nurbs(lens) => lens.domain,
        }
    }

    /// The parameters of the surface point over `(x, y)` (its vertical projection, the seed's
    /// `fnPt`): Newton on `S_xy(u, v) = (x, y)` from the nearest tabulated sample; `None` when
    /// no point of the surface lies over `(x, y)`.
    pub fn parameters_over(&self, x: f64, y: f64) -> Option<(f64, f64)> {
        let lens = match self {
            LensSurface::Sag { .. } => return self.contains(x, y, 0.0).then_some((x, y)),
            LensSurface::Nurbs(lens) => lens,
        };
        let start = lens.table[lens.buckets.nearest(&lens.table, x, y)?];
        let ((u0, u1), (v0, v1)) = lens.domain;
        let (mut u, mut v) = (start[0], start[1]);
        for _ in 0..60 {
            let jet = lens.evaluator.jet(u, v);
            let (fx, fy) = (jet.point.x - x, jet.point.y - y);
            if fx.hypot(fy) < 1e-12 * (1.0 + x.hypot(y)) {
                return Some((u, v));
            }
            let det = jet.du.x * jet.dv.y - jet.du.y * jet.dv.x;
            if det.abs() < 1e-300 {
                return None;
            }
            let du = (fx * jet.dv.y - fy * jet.dv.x) / det;
            let dv = (jet.du.x * fy - jet.du.y * fx) / det;
            u = (u - du).clamp(u0, u1);
            v = (v - dv).clamp(v0, v1);
        }
        let jet = lens.evaluator.jet(u, v);
        ((jet.point.x - x).hypot(jet.point.y - y) < 1e-9).then_some((u, v))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn noll_indices_follow_the_standard_table() {
        let expected = [
            (1, 0, 0),
            (2, 1, 1),
            (3, 1, -1),
            (4, 2, 0),
            (5, 2, -2),
            (6, 2, 2),
            (7, 3, -1),
            (8, 3, 1),
            (9, 3, -3),
            (10, 3, 3),
            (11, 4, 0),
            (12, 4, 2),
            (13, 4, -2),
            (14, 4, 4),
            (15, 4, -4),
        ];
        for (j, n, m) in expected {
            assert_eq!(noll_to_nm(j), (n, m), "Z{j}");
        }
    }

    /// The Zernike polynomials in x, y against their polar closed forms.
    #[test]
    fn zernike_terms_match_their_polar_forms() {
        type Closed = fn(f64, f64) -> f64;
        let cases: [(usize, Closed); 6] = [
            (2, |r, p| 2.0 * r * p.cos()),
            (5, |r, p| 6f64.sqrt() * r * r * (2.0 * p).sin()),
            (4, |r, _| 3f64.sqrt() * (2.0 * r * r - 1.0)),
            (8, |r, p| {
                8f64.sqrt() * (3.0 * r.powi(3) - 2.0 * r) * p.cos()
            }),
            (11, |r, _| {
                5f64.sqrt() * (6.0 * r.powi(4) - 6.0 * r * r + 1.0)
            }),
            (13, |r, p| {
                10f64.sqrt() * (4.0 * r.powi(4) - 3.0 * r * r) * (2.0 * p).sin()
            }),
        ];
        for (j, closed) in cases {
            for &(r, p) in &[(0.0, 0.0), (0.3, 1.1), (0.8, -2.5), (1.0, 0.4)] {
                let (x, y) = Jet2::variables(r * f64::cos(p), r * f64::sin(p));
                let z = zernike(j, x, y).value;
                assert!((z - closed(r, p)).abs() < 1e-12, "Z{j}({r}, {p}) = {z}");
            }
        }
    }

    #[test]
    fn a_sphere_sag_is_the_sphere() {
        let shape = SagShape::Conic {
            curvature: 1.0 / 30.0,
            conic: 0.0,
            even: vec![],
        };
        for &(x, y) in &[(0.0, 0.0), (5.0, 3.0), (-12.0, 9.0)] {
            let z = shape.sag(x, y).value;
            // On the sphere of radius 30 about (0, 0, 30).
            assert!(((x * x + y * y + (z - 30.0).powi(2)).sqrt() - 30.0).abs() < 1e-12);
        }
        // A toric with equal radii and no conic is the same sphere.
        let toric = SagShape::Toric {
            curvature_x: 1.0 / 30.0,
            curvature_y: 1.0 / 30.0,
            conic_y: 0.0,
        };
        for &(x, y) in &[(0.0, 0.0), (5.0, 3.0), (-12.0, 9.0)] {
            let (a, b) = (shape.sag(x, y), toric.sag(x, y));
            assert!((a.value - b.value).abs() < 1e-12);
            assert!((a.hessian[1] - b.hessian[1]).abs() < 1e-12);
        }
    }
}
