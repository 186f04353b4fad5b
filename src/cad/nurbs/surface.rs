//! A NURBS surface (IGES entity 128): evaluation with partial derivatives, normals, knot
//! insertion in either direction and the split into Bézier patches (seed 002 §3).

use nalgebra::{Point3, Unit, Vector3, Vector4};

use super::curve::bezier_point;
use super::{
    NurbsError, basis_derivatives, basis_functions, bezier_spans, binomial, check_knots,
    check_points, find_span, homogeneous, insert_knot, refine_to_bezier,
};

/// `S(u, v) = Σᵢ Σⱼ Nᵢ,ₚ(u) Nⱼ,q(v) wᵢⱼ Pᵢⱼ / Σᵢ Σⱼ Nᵢ,ₚ(u) Nⱼ,q(v) wᵢⱼ`; `i` runs along u (the
/// net's rows), `j` along v (its columns).
#[derive(Clone, Debug, PartialEq)]
pub struct NurbsSurface {
    degree: [usize; 2],
    knots_u: Vec<f64>,
    knots_v: Vec<f64>,
    rows: usize,
    columns: usize,
    /// Homogeneous control points, row-major: `points[i · columns + j]`.
    points: Vec<Vector4<f64>>,
}

/// One Bézier patch of a surface: its parameter rectangle and its homogeneous control net.
#[derive(Clone, Debug, PartialEq)]
pub struct BezierPatch {
    /// Parameter interval in u.
    pub u: (f64, f64),
    /// Parameter interval in v.
    pub v: (f64, f64),
    /// Degrees in u and v.
    pub degree: [usize; 2],
    /// `(degree[0] + 1) × (degree[1] + 1)` homogeneous points, row-major.
    pub points: Vec<Vector4<f64>>,
}

impl BezierPatch {
    /// The point at local parameters `s, t ∈ [0, 1]` (de Casteljau along v, then u).
    pub fn point(&self, s: f64, t: f64) -> Point3<f64> {
        let columns = self.degree[1] + 1;
        let along_u: Vec<Vector4<f64>> = self
            .points
            .chunks(columns)
            .map(|row| bezier_point_homogeneous(row, t))
            .collect();
        bezier_point(&along_u, s)
    }

    /// The control points (Euclidean): the patch lies in their convex hull.
    pub fn control_points(&self) -> impl Iterator<Item = Point3<f64>> + '_ {
        self.points.iter().map(|p| Point3::from(p.xyz() / p.w))
    }
}

/// de Casteljau on homogeneous points, staying homogeneous.
fn bezier_point_homogeneous(points: &[Vector4<f64>], t: f64) -> Vector4<f64> {
    let mut q = points.to_vec();
    for level in 1..q.len() {
        for i in 0..q.len() - level {
            q[i] = q[i] * (1.0 - t) + q[i + 1] * t;
        }
    }
    q[0]
}

impl NurbsSurface {
    /// A surface of degrees `degree = [p, q]` on `knots_u`, `knots_v` through the net `net`
    /// (`net[i][j]`, rows along u) with `weights` of the same shape.
    pub fn new(
        degree: [usize; 2],
        knots_u: Vec<f64>,
        knots_v: Vec<f64>,
        net: &[Vec<Point3<f64>>],
        weights: &[Vec<f64>],
    ) -> Result<NurbsSurface, NurbsError> {
        let columns = net.first().map_or(0, Vec::len);
        let mut points = Vec::with_capacity(net.len() * columns);
        for (i, row) in net.iter().enumerate() {
            let w = weights.get(i).map_or(&[][..], |w| &w[..]);
            if row.len() != columns || w.len() != columns {
                return Err(NurbsError::RaggedNet {
                    row: i,
                    found: row.len().min(w.len()),
                    expected: columns,
                });
            }
            points.extend(row.iter().zip(w).map(|(p, &w)| homogeneous(p, w)));
        }
        Self::from_homogeneous(degree, knots_u, knots_v, net.len(), columns, points)
    }

    /// A surface from a row-major net of `rows × columns` homogeneous points.
    pub fn from_homogeneous(
        degree: [usize; 2],
        knots_u: Vec<f64>,
        knots_v: Vec<f64>,
        rows: usize,
        columns: usize,
        points: Vec<Vector4<f64>>,
    ) -> Result<NurbsSurface, NurbsError> {
        if points.len() != rows * columns {
            return Err(NurbsError::RaggedNet {
                row: rows,
                found: points.len(),
                expected: rows * columns,
            });
        }
        check_knots(degree[0], rows, &knots_u)?;
        check_knots(degree[1], columns, &knots_v)?;
        check_points(&points)?;
        Ok(NurbsSurface {
            degree,
            knots_u,
            knots_v,
            rows,
            columns,
            points,
        })
    }

    /// Degrees in u and v.
    pub fn degree(&self) -> [usize; 2] {
        self.degree
    }

    /// Knot vectors in u and v.
    pub fn knots(&self) -> (&[f64], &[f64]) {
        (&self.knots_u, &self.knots_v)
    }

    /// Net size: rows (along u) and columns (along v).
    pub fn net_size(&self) -> (usize, usize) {
        (self.rows, self.columns)
    }

    /// The homogeneous control points, row-major.
    pub fn homogeneous_points(&self) -> &[Vector4<f64>] {
        &self.points
    }

    /// The parameter domain `([u₀, u₁], [v₀, v₁])`.
    pub fn domain(&self) -> ((f64, f64), (f64, f64)) {
        let [p, q] = self.degree;
        (
            (self.knots_u[p], self.knots_u[self.rows]),
            (self.knots_v[q], self.knots_v[self.columns]),
        )
    }

    fn clamp(&self, u: f64, v: f64) -> (f64, f64) {
        let ((u0, u1), (v0, v1)) = self.domain();
        (u.clamp(u0, u1), v.clamp(v0, v1))
    }

    /// The point at `(u, v)` (clamped into the domain).
    pub fn point(&self, u: f64, v: f64) -> Point3<f64> {
        let (u, v) = self.clamp(u, v);
        let [p, q] = self.degree;
        let su = find_span(self.rows - 1, p, u, &self.knots_u);
        let sv = find_span(self.columns - 1, q, v, &self.knots_v);
        let nu = basis_functions(su, u, p, &self.knots_u);
        let nv = basis_functions(sv, v, q, &self.knots_v);
        let mut sw = Vector4::zeros();
        for (l, &bv) in nv.iter().enumerate() {
            let mut temp = Vector4::zeros();
            for (k, &bu) in nu.iter().enumerate() {
                temp += self.points[(su - p + k) * self.columns + sv - q + l] * bu;
            }
            sw += temp * bv;
        }
        Point3::from(sw.xyz() / sw.w)
    }

    /// The point and its partial derivatives up to total order `d` at `(u, v)`:
    /// `s[k][l] = ∂ᵏ⁺ˡS / ∂uᵏ∂vˡ` for `k + l ≤ d` (zero otherwise). Rational derivatives by Piegl
    /// & Tiller A4.4 on the homogeneous ones (A3.6).
    pub fn derivatives(&self, u: f64, v: f64, d: usize) -> Vec<Vec<Vector3<f64>>> {
        let (u, v) = self.clamp(u, v);
        let [p, q] = self.degree;
        let su = find_span(self.rows - 1, p, u, &self.knots_u);
        let sv = find_span(self.columns - 1, q, v, &self.knots_v);
        let du = basis_derivatives(su, u, p, d, &self.knots_u);
        let dv = basis_derivatives(sv, v, q, d, &self.knots_v);
        let mut a = vec![vec![Vector4::zeros(); d + 1]; d + 1];
        for k in 0..=d {
            let mut temp = vec![Vector4::zeros(); q + 1];
            for (s, t) in temp.iter_mut().enumerate() {
                for (r, &b) in du[k].iter().enumerate() {
                    *t += self.points[(su - p + r) * self.columns + sv - q + s] * b;
                }
            }
            for l in 0..=(d - k) {
                a[k][l] = (0..=q).map(|s| temp[s] * dv[l][s]).sum();
            }
        }
        let w = |k: usize, l: usize| a[k][l].w;
        let mut out = vec![vec![Vector3::zeros(); d + 1]; d + 1];
        for k in 0..=d {
            for l in 0..=(d - k) {
                let mut v = a[k][l].xyz();
                for j in 1..=l {
                    v -= out[k][l - j] * (binomial(l, j) * w(0, j));
                }
                for i in 1..=k {
                    v -= out[k - i][l] * (binomial(k, i) * w(i, 0));
                    let mut v2 = Vector3::zeros();
                    for j in 1..=l {
                        v2 += out[k - i][l - j] * (binomial(l, j) * w(i, j));
                    }
                    v -= v2 * binomial(k, i);
                }
                out[k][l] = v / w(0, 0);
            }
        }
        out
    }

    /// The unit normal `S_u × S_v` at `(u, v)`; `None` where the surface is degenerate there
    /// (a collapsed edge).
    pub fn normal(&self, u: f64, v: f64) -> Option<Unit<Vector3<f64>>> {
        let d = self.derivatives(u, v, 1);
        let n = d[1][0].cross(&d[0][1]);
        (n.norm() > 1e-14 * (d[1][0].norm() * d[0][1].norm()).max(1e-300))
            .then(|| Unit::new_normalize(n))
    }

    /// The net's columns (along u) or rows (along v) as point sequences.
    fn lines(&self, along_u: bool) -> Vec<Vec<Vector4<f64>>> {
        if along_u {
            (0..self.columns)
                .map(|j| {
                    (0..self.rows)
                        .map(|i| self.points[i * self.columns + j])
                        .collect()
                })
                .collect()
        } else {
            self.points
                .chunks(self.columns)
                .map(<[_]>::to_vec)
                .collect()
        }
    }

    /// Rebuilds the net from lines made by [`Self::lines`] and transformed.
    fn with_lines(&self, along_u: bool, knots: Vec<f64>, lines: Vec<Vec<Vector4<f64>>>) -> Self {
        let mut out = self.clone();
        if along_u {
            out.rows = lines[0].len();
            out.knots_u = knots;
            out.points = (0..out.rows)
                .flat_map(|i| lines.iter().map(move |line| line[i]))
                .collect();
        } else {
            out.columns = lines[0].len();
            out.knots_v = knots;
            out.points = lines.into_iter().flatten().collect();
        }
        out
    }

    /// The same surface with `value` inserted `times` more in u (`along_u`) or v.
    pub fn insert_knot(&self, along_u: bool, value: f64, times: usize) -> NurbsSurface {
        let (p, knots) = if along_u {
            (self.degree[0], &self.knots_u)
        } else {
            (self.degree[1], &self.knots_v)
        };
        let mut new_knots = knots.clone();
        let lines: Vec<Vec<Vector4<f64>>> = self
            .lines(along_u)
            .iter()
            .map(|line| {
                let (k, q) = insert_knot(p, knots, line, value, times);
                new_knots = k;
                q
            })
            .collect();
        self.with_lines(along_u, new_knots, lines)
    }

    /// The surface as Bézier patches over its domain, u-major: every interior knot raised to
    /// the degree in its direction (seed 002 §3), each span's net a patch.
    pub fn bezier_patches(&self) -> Vec<BezierPatch> {
        let ((u0, u1), (v0, v1)) = self.domain();
        let [p, q] = self.degree;
        let refine = |surface: &NurbsSurface, along_u: bool, (a, b): (f64, f64)| {
            let (degree, knots) = if along_u {
                (p, &surface.knots_u)
            } else {
                (q, &surface.knots_v)
            };
            let mut new_knots = knots.clone();
            let lines: Vec<Vec<Vector4<f64>>> = surface
                .lines(along_u)
                .iter()
                .map(|line| {
                    let (k, points) = refine_to_bezier(degree, knots, line, a, b);
                    new_knots = k;
                    points
                })
                .collect();
            surface.with_lines(along_u, new_knots, lines)
        };
        let refined = refine(&refine(self, true, (u0, u1)), false, (v0, v1));
        let spans_u = bezier_spans(p, &refined.knots_u, u0, u1);
        let spans_v = bezier_spans(q, &refined.knots_v, v0, v1);
        let mut patches = Vec::with_capacity(spans_u.len() * spans_v.len());
        for &(first_u, ua, ub) in &spans_u {
            for &(first_v, va, vb) in &spans_v {
                let points = (0..=p)
                    .flat_map(|i| {
                        let row = (first_u + i) * refined.columns + first_v;
                        refined.points[row..=row + q].iter().copied()
                    })
                    .collect();
                patches.push(BezierPatch {
                    u: (ua, ub),
                    v: (va, vb),
                    degree: [p, q],
                    points,
                });
            }
        }
        patches
    }
}

#[cfg(test)]
mod tests {
    use super::super::tests::unit_circle;
    use super::*;

    /// The unit circle swept 2 mm up: a cylinder of revolution as a degree 2 × 1 NURBS.
    fn cylinder() -> NurbsSurface {
        let circle = unit_circle();
        let net: Vec<Vec<Point3<f64>>> = circle
            .homogeneous_points()
            .iter()
            .map(|p| {
                let c = Point3::from(p.xyz() / p.w);
                vec![c, c + Vector3::new(0.0, 0.0, 2.0)]
            })
            .collect();
        let weights: Vec<Vec<f64>> = circle
            .homogeneous_points()
            .iter()
            .map(|p| vec![p.w, p.w])
            .collect();
        NurbsSurface::new(
            [2, 1],
            circle.knots().to_vec(),
            vec![0.0, 0.0, 1.0, 1.0],
            &net,
            &weights,
        )
        .unwrap()
    }

    /// Every point of the cylinder is at radius 1 and height 2v; the normal is radial; the
    /// curvature across (from the second derivative in u) is 1 and along v 0.
    #[test]
    fn the_nurbs_cylinder_is_a_cylinder() {
        let s = cylinder();
        for a in 0..=60 {
            for b in 0..=4 {
                let (u, v) = (a as f64 / 60.0, b as f64 / 4.0);
                let p = s.point(u, v);
                assert!((p.xy().coords.norm() - 1.0).abs() < 1e-14);
                assert!((p.z - 2.0 * v).abs() < 1e-14);
                let n = s.normal(u, v).unwrap();
                let radial = Vector3::new(p.x, p.y, 0.0);
                assert!(n.cross(&radial).norm() < 1e-12, "{n:?} at {p}");
                let d = s.derivatives(u, v, 2);
                assert!((d[0][0] - p.coords).norm() < 1e-14);
                let kappa = d[1][0].cross(&d[2][0]).norm() / d[1][0].norm().powi(3);
                assert!((kappa - 1.0).abs() < 1e-11, "{kappa}");
                assert!(
                    d[0][2].norm() < 1e-12
                        && (d[0][1] - Vector3::new(0.0, 0.0, 2.0)).norm() < 1e-12
                );
            }
        }
    }

    /// A wavy rational bicubic with uneven knots: the partial derivatives agree with central
    /// differences, knot insertion keeps the surface, and its Bézier patches reproduce it.
    #[test]
    fn derivatives_insertion_and_patches_of_a_rational_surface() {
        let (rows, columns) = (6, 5);
        let net: Vec<Vec<Point3<f64>>> = (0..rows)
            .map(|i| {
                (0..columns)
                    .map(|j| {
                        let (x, y) = (i as f64, j as f64);
                        Point3::new(x, y, (x * 0.9).sin() + (y * 1.3).cos() * 0.5)
                    })
                    .collect()
            })
            .collect();
        let weights: Vec<Vec<f64>> = (0..rows)
            .map(|i| {
                (0..columns)
                    .map(|j| 0.6 + 0.1 * ((i * 3 + j * 7) % 9) as f64)
                    .collect()
            })
            .collect();
        let s = NurbsSurface::new(
            [3, 2],
            vec![0.0, 0.0, 0.0, 0.0, 0.4, 0.55, 1.0, 1.0, 1.0, 1.0],
            vec![0.0, 0.0, 0.0, 0.3, 0.7, 1.0, 1.0, 1.0],
            &net,
            &weights,
        )
        .unwrap();
        // The power-form patches agree with de Boor everywhere, seams and ends included.
        let fast = super::super::PatchEvaluator::new(&s).expect("a table");
        for i in 0..=40 {
            for j in 0..=40 {
                let (u, v) = (i as f64 / 40.0, j as f64 / 40.0);
                let error = (fast.point(u, v) - s.point(u, v)).norm();
                assert!(error < 1e-12, "({u}, {v}): {error}");
            }
        }
        assert!((fast.point(-1.0, 2.0) - s.point(0.0, 1.0)).norm() < 1e-12);
        // Its second-order jets agree with the rational de Boor derivatives (A4.4).
        for i in 0..=20 {
            for j in 0..=20 {
                let (u, v) = (i as f64 / 20.0, j as f64 / 20.0);
                let d = s.derivatives(u, v, 2);
                let jet = fast.jet(u, v);
                let pairs = [
                    (jet.point.coords, d[0][0]),
                    (jet.du, d[1][0]),
                    (jet.dv, d[0][1]),
                    (jet.duu, d[2][0]),
                    (jet.duv, d[1][1]),
                    (jet.dvv, d[0][2]),
                ];
                for (k, (a, b)) in pairs.into_iter().enumerate() {
                    assert!(
                        (a - b).norm() < 1e-9 * b.norm().max(1.0),
                        "({u}, {v}) #{k}: {a} {b}"
                    );
                }
            }
        }
        let h = 1e-5;
        for &(u, v) in &[(0.1, 0.2), (0.45, 0.5), (0.8, 0.9), (0.6, 0.31)] {
            let d = s.derivatives(u, v, 2);
            let su = (s.point(u + h, v) - s.point(u - h, v)) / (2.0 * h);
            let sv = (s.point(u, v + h) - s.point(u, v - h)) / (2.0 * h);
            let at = |du: f64, dv: f64| s.point(u + du, v + dv).coords;
            let suv = (at(h, h) - at(h, -h) - at(-h, h) + at(-h, -h)) / (4.0 * h * h);
            assert!((d[1][0] - su).norm() < 1e-5 * su.norm().max(1.0));
            assert!((d[0][1] - sv).norm() < 1e-5 * sv.norm().max(1.0));
            assert!(
                (d[1][1] - suv).norm() < 1e-3 * suv.norm().max(1.0),
                "{} {}",
                d[1][1],
                suv
            );
        }
        let refined = s
            .insert_knot(true, 0.2, 2)
            .insert_knot(false, 0.5, 1)
            .insert_knot(false, 0.3, 3);
        let patches = s.bezier_patches();
        assert_eq!(patches.len(), 3 * 3);
        for a in 0..=40 {
            for b in 0..=40 {
                let (u, v) = (a as f64 / 40.0, b as f64 / 40.0);
                let exact = s.point(u, v);
                assert!((refined.point(u, v) - exact).norm() < 1e-13);
                let patch = patches
                    .iter()
                    .find(|p| u >= p.u.0 && u <= p.u.1 && v >= p.v.0 && v <= p.v.1)
                    .unwrap();
                let local = (
                    (u - patch.u.0) / (patch.u.1 - patch.u.0),
                    (v - patch.v.0) / (patch.v.1 - patch.v.0),
                );
                assert!((patch.point(local.0, local.1) - exact).norm() < 1e-13);
            }
        }
    }
}
