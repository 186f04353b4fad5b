//! Endpoint-interpolating cubic B-spline wavelets on [0, 1] (seed 004 §2.2, figs. 2.5–2.6;
//! Stollnitz, DeRose & Salesin 1995).
//!
//! Level j has `2^j + 3` cubic B-splines on the knots `0,0,0,0, 1/2^j, …, 1,1,1,1`.
//! * `P^j` ((2^j+3) × (2^{j−1}+3)) refines level j−1 into level j: Φ^{j−1} = Φ^j P^j (eq. 2.9).
//!   Computed as (Gram^{j,j})⁻¹ Gram^{j,j−1}, exact up to round-off.
//! * `Q^j` ((2^j+3) × 2^{j−1}) spans the orthogonal complement: ⟨Φ^{j−1} | Φ^j⟩ Q^j = 0
//!   (eq. 2.15). Each column is the solution of smallest support: rows
//!   `max(k, 2k−3) ..= 2k+7` from the left end, mirrored from the right end, which is where the
//!   seed's minimal-support wavelets live; normalised so that the entry of largest magnitude
//!   is +1 (the seed's convention).
//!
//! Inner products are exact: B-spline products are degree-6 polynomials on each knot
//! interval, integrated by 4-point Gauss–Legendre.
//!
//! On top of the filters, the multiresolution operations of seed 004 on planar curves whose
//! control points are the rows of an n × 2 matrix:
//! * [`decompose`] — c^{j−1}, d^{j−1} from c^j by solving [P^j | Q^j] [c; d] = c^j (eq. 2.16);
//! * [`reconstruct`] — c^j = P^j c^{j−1} + Q^j d^{j−1} (eq. 2.17);
//! * [`fractional`] — the in-between curve c^{m+t} = P^{m+1} c^m + t Q^{m+1} d^m (eq. 3.2);
//! * [`bezier_matrix`] — M^j, the B-spline → Bézier conversion, and [`deviation_bound`], the
//!   largest entry of E^j = M^j Q^j D^{j−1} (eq. 3.1): by the convex-hull property of the
//!   Bézier pieces of C^j − C^{j−1}, no point of the level-j curve is farther than that from
//!   the level-(j−1) curve at the same parameter;
//! * [`fit`] — least-squares fit of 2^j + 3 control points to samples (the ends interpolated).

use crate::contour::error::{ContourError, Result};
use crate::contour::geometry::Point2;
use nalgebra::{DMatrix, DVector};

/// Knots of level j: four zeros, the interior knots i/2^j, four ones.
fn knots(j: u32) -> Vec<f64> {
    let n = 1u64 << j;
    let mut k = vec![0.0; 4];
    k.extend((1..n).map(|i| i as f64 / n as f64));
    k.extend([1.0; 4]);
    k
}

/// Values of all `2^j + 3` cubic B-splines of level j at `x` (Cox–de Boor).
pub fn basis(j: u32, x: f64) -> Vec<f64> {
    let t = knots(j);
    let count = t.len() - 4;
    // Degree 0: the half-open interval containing x (the last one closed at 1).
    let mut b: Vec<f64> = (0..t.len() - 1)
        .map(|i| {
            let inside = t[i] <= x && x < t[i + 1];
            let last = x >= 1.0 && t[i] < t[i + 1] && t[i + 1] >= 1.0;
            if inside || last { 1.0 } else { 0.0 }
        })
        .collect();
    for p in 1..=3 {
        b = (0..t.len() - 1 - p)
            .map(|i| {
                let left = if t[i + p] > t[i] {
                    (x - t[i]) / (t[i + p] - t[i]) * b[i]
                } else {
                    0.0
                };
                let right = if t[i + p + 1] > t[i + 1] {
                    (t[i + p + 1] - x) / (t[i + p + 1] - t[i + 1]) * b[i + 1]
                } else {
                    0.0
                };
                left + right
            })
            .collect();
    }
    b.truncate(count);
    b
}

/// ⟨Φ^a | Φ^b⟩: the matrix of inner products of the level-a and level-b B-splines.
pub fn gram(a: u32, b: u32) -> DMatrix<f64> {
    const NODES: [f64; 4] = [
        -0.861_136_311_594_052_6,
        -0.339_981_043_584_856_3,
        0.339_981_043_584_856_3,
        0.861_136_311_594_052_6,
    ];
    const WEIGHTS: [f64; 4] = [
        0.347_854_845_137_453_9,
        0.652_145_154_862_546_1,
        0.652_145_154_862_546_1,
        0.347_854_845_137_453_9,
    ];
    let finest = a.max(b);
    let intervals = 1u64 << finest;
    let mut g = DMatrix::zeros((1 << a) + 3, (1 << b) + 3);
    for i in 0..intervals {
        let (lo, hi) = (
            i as f64 / intervals as f64,
            (i + 1) as f64 / intervals as f64,
        );
        for (node, weight) in NODES.iter().zip(WEIGHTS) {
            let x = 0.5 * (lo + hi) + 0.5 * (hi - lo) * node;
            let w = 0.5 * (hi - lo) * weight;
            let (fa, fb) = (basis(a, x), basis(b, x));
            for (r, va) in fa.iter().enumerate().filter(|(_, v)| **v != 0.0) {
                for (c, vb) in fb.iter().enumerate().filter(|(_, v)| **v != 0.0) {
                    g[(r, c)] += w * va * vb;
                }
            }
        }
    }
    g
}

/// The refinement matrix P^j (j ≥ 1).
pub fn synthesis_p(j: u32) -> DMatrix<f64> {
    let fine = gram(j, j);
    let mixed = gram(j, j - 1);
    // invariant: the Gram matrix of a B-spline basis is symmetric positive definite.
    fine.cholesky()
        .expect("B-spline Gram matrices are positive definite")
        .solve(&mixed)
}

/// The wavelet matrix Q^j (j ≥ 1), minimal-support columns, largest entry +1.
pub fn synthesis_q(j: u32) -> DMatrix<f64> {
    let rows = (1usize << j) + 3;
    let columns = 1usize << (j - 1);
    let constraints = gram(j - 1, j);
    let mut q = DMatrix::zeros(rows, columns);
    for k in 0..columns {
        let mirror = columns - 1 - k;
        let last = rows - 1;
        let lo = k
            .max((2 * k).saturating_sub(3))
            .max(last.saturating_sub(2 * mirror + 7));
        let hi = (2 * k + 7).min(last - mirror.max((2 * mirror).saturating_sub(3)));
        let width = hi - lo + 1;
        // The null vector of the window's constraints: the right singular vector of the
        // smallest singular value. Zero rows pad a wide system to square, because a thin SVD
        // of a wide matrix does not return its null space.
        let window = DMatrix::from_fn(constraints.nrows().max(width), width, |r, c| {
            if r < constraints.nrows() {
                constraints[(r, lo + c)]
            } else {
                0.0
            }
        });
        let svd = window.svd(false, true);
        let Some(v_t) = svd.v_t else { continue };
        let smallest = svd
            .singular_values
            .iter()
            .enumerate()
            .fold(
                (0, f64::INFINITY),
                |best, (i, s)| if *s < best.1 { (i, *s) } else { best },
            )
            .0;
        let mut v: DVector<f64> = v_t.row(smallest).transpose();
        let peak = v
            .iter()
            .copied()
            .fold(0.0f64, |m, x| if x.abs() > m.abs() { x } else { m });
        if peak != 0.0 {
            v /= peak;
        }
        for (i, value) in v.iter().enumerate() {
            q[(lo + i, k)] = *value;
        }
    }
    q
}

/// Control points of a planar curve: one row per point, columns x and y.
pub type Controls = DMatrix<f64>;

/// Number of control points of level j.
pub fn count(j: u32) -> usize {
    (1usize << j) + 3
}

fn level_of(c: &Controls, what: &str) -> Result<u32> {
    let n = c.nrows();
    (0..=20)
        .find(|&j| count(j) == n)
        .ok_or_else(|| ContourError::BadPath(format!("{what}: {n} control points is not 2^j + 3")))
}

/// Splits the level-j control points `c` into the coarse points c^{j−1} and the wavelet
/// coefficients d^{j−1} (eq. 2.16, solved by LU of the square matrix [P^j | Q^j]).
pub fn decompose(c: &Controls) -> Result<(Controls, Controls)> {
    let j = level_of(c, "decompose")?;
    if j == 0 {
        return Err(ContourError::BadPath(
            "decompose: level 0 has no coarser level".into(),
        ));
    }
    let (p, q) = (synthesis_p(j), synthesis_q(j));
    let pq = DMatrix::from_fn(p.nrows(), p.ncols() + q.ncols(), |r, col| {
        if col < p.ncols() {
            p[(r, col)]
        } else {
            q[(r, col - p.ncols())]
        }
    });
    let x = pq
        .lu()
        .solve(c)
        .ok_or_else(|| ContourError::BadPath(format!("decompose: [P{j}|Q{j}] is singular")))?;
    let coarse = x.rows(0, p.ncols()).into_owned();
    let detail = x.rows(p.ncols(), q.ncols()).into_owned();
    Ok((coarse, detail))
}

/// c^j = P^j c^{j−1} + Q^j d^{j−1} (eq. 2.17).
pub fn reconstruct(coarse: &Controls, detail: &Controls) -> Result<Controls> {
    fractional(coarse, detail, 1.0)
}

/// The fractional level c^{m+t} = P^{m+1} c^m + t Q^{m+1} d^m (eq. 3.2): t = 0 is the coarse
/// curve written on the finer knots, t = 1 the fine curve.
pub fn fractional(coarse: &Controls, detail: &Controls, t: f64) -> Result<Controls> {
    let m = level_of(coarse, "reconstruct")?;
    if detail.nrows() != 1usize << m || detail.ncols() != coarse.ncols() {
        return Err(ContourError::BadPath(format!(
            "reconstruct: level {m} needs {} wavelet coefficients, got {}",
            1usize << m,
            detail.nrows()
        )));
    }
    Ok(synthesis_p(m + 1) * coarse + synthesis_q(m + 1) * detail * t)
}

/// Point of the level-j curve with control points `c` (2^j + 3 rows; any other row count is
/// read as level 0, using its first four rows) at parameter u ∈ [0, 1].
pub fn evaluate(c: &Controls, u: f64) -> Point2 {
    let j = level_of(c, "evaluate").unwrap_or(0);
    let b = basis(j, u.clamp(0.0, 1.0));
    let mut p = Point2::origin();
    for (i, w) in b.iter().enumerate().filter(|(_, w)| **w != 0.0) {
        if i < c.nrows() {
            p.x += w * c[(i, 0)];
            p.y += w * c[(i, 1)];
        }
    }
    p
}

/// M^j: rows 4s..4s+3 are the Bézier control points of knot span s of a level-j curve, as
/// combinations of its 2^j + 3 B-spline control points. Each span's polynomial is sampled at
/// u = 0, 1/3, 2/3, 1 of the span and the cubic Bernstein matrix inverted (exact).
pub fn bezier_matrix(j: u32) -> DMatrix<f64> {
    let spans = 1usize << j;
    let n = count(j);
    // Inverse of the cubic Bernstein matrix at t = 0, 1/3, 2/3, 1.
    let bern = DMatrix::from_fn(4, 4, |k, i| {
        let t = k as f64 / 3.0;
        let binom = [1.0, 3.0, 3.0, 1.0][i];
        binom * t.powi(i as i32) * (1.0 - t).powi(3 - i as i32)
    });
    // invariant: the cubic Bernstein basis at four distinct points is a basis of the cubics.
    let inv = bern
        .try_inverse()
        .expect("the cubic Bernstein matrix at 0, 1/3, 2/3, 1 is invertible");
    let mut m = DMatrix::zeros(4 * spans, n);
    for s in 0..spans {
        let values = DMatrix::from_fn(4, n, |k, i| {
            let u = (s as f64 + k as f64 / 3.0) / spans as f64;
            // The value at the span's right end must come from this span's polynomial: the
            // basis is continuous, so evaluating at the end point is the same.
            basis(j, u)[i]
        });
        let block = &inv * values;
        m.view_mut((4 * s, 0), (4, n)).copy_from(&block);
    }
    m
}

/// The eq. 3.1 bound: max over the rows of E^j = M^j Q^j D^{j−1} of their length, where
/// `detail` = D^{j−1} are the wavelet coefficients removed when going from level j to j − 1.
pub fn deviation_bound(detail: &Controls) -> Result<f64> {
    let rows = detail.nrows();
    let j = (1..=20)
        .find(|&j| 1usize << (j - 1) == rows)
        .ok_or_else(|| ContourError::BadPath(format!("bound: {rows} coefficients")))?;
    let e = bezier_matrix(j) * synthesis_q(j) * detail;
    Ok((0..e.nrows())
        .map(|r| {
            (0..e.ncols())
                .map(|c| e[(r, c)].powi(2))
                .sum::<f64>()
                .sqrt()
        })
        .fold(0.0, f64::max))
}

/// Least-squares fit of a level-j curve to `points` at parameters `params` (∈ [0, 1]), with
/// the first and last control points fixed at the first and last sample (end interpolation,
/// so pieces fitted separately meet exactly).
pub fn fit(points: &[Point2], params: &[f64], j: u32) -> Result<Controls> {
    let n = count(j);
    if points.len() != params.len() || points.len() < n {
        return Err(ContourError::BadPath(format!(
            "fit: {} samples for {} control points",
            points.len(),
            n
        )));
    }
    let (first, last) = (points[0], points[points.len() - 1]);
    // Normal equations on the interior control points; B is banded (4 non-zeros a row).
    let inner = n - 2;
    let mut ata = DMatrix::zeros(inner, inner);
    let mut atb = DMatrix::zeros(inner, 2);
    for (p, &u) in points.iter().zip(params) {
        let b = basis(j, u.clamp(0.0, 1.0));
        let fixed = first.coords * b[0] + last.coords * b[n - 1];
        let rhs = p.coords - fixed;
        for a in 1..n - 1 {
            if b[a] == 0.0 {
                continue;
            }
            atb[(a - 1, 0)] += b[a] * rhs.x;
            atb[(a - 1, 1)] += b[a] * rhs.y;
            for c in 1..n - 1 {
                if b[c] != 0.0 {
                    ata[(a - 1, c - 1)] += b[a] * b[c];
                }
            }
        }
    }
    let x = ata
        .cholesky()
        .map(|ch| ch.solve(&atb))
        .ok_or_else(|| ContourError::BadPath(format!("fit: samples too sparse for level {j}")))?;
    let mut c = DMatrix::zeros(n, 2);
    c[(0, 0)] = first.x;
    c[(0, 1)] = first.y;
    c[(n - 1, 0)] = last.x;
    c[(n - 1, 1)] = last.y;
    c.view_mut((1, 0), (inner, 2)).copy_from(&x);
    Ok(c)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn assert_matrix(actual: &DMatrix<f64>, expected: &[&[f64]], what: &str) {
        assert_eq!(actual.nrows(), expected.len(), "{what}: rows");
        for (r, row) in expected.iter().enumerate() {
            assert_eq!(actual.ncols(), row.len(), "{what}: columns");
            for (c, e) in row.iter().enumerate() {
                assert!(
                    (actual[(r, c)] - e).abs() < 1e-10,
                    "{what}[{r},{c}] = {} expected {e}",
                    actual[(r, c)]
                );
            }
        }
    }

    #[test]
    fn refinement_matrices_match_figure_2_5() {
        let s = 1.0 / 16.0;
        let p1: Vec<Vec<f64>> = [
            [16, 0, 0, 0],
            [8, 8, 0, 0],
            [0, 8, 8, 0],
            [0, 0, 8, 8],
            [0, 0, 0, 16],
        ]
        .iter()
        .map(|r| r.iter().map(|&x| x as f64 * s).collect())
        .collect();
        assert_matrix(
            &synthesis_p(1),
            &p1.iter().map(Vec::as_slice).collect::<Vec<_>>(),
            "P1",
        );
        let p2: Vec<Vec<f64>> = [
            [16, 0, 0, 0, 0],
            [8, 8, 0, 0, 0],
            [0, 12, 4, 0, 0],
            [0, 3, 10, 3, 0],
            [0, 0, 4, 12, 0],
            [0, 0, 0, 8, 8],
            [0, 0, 0, 0, 16],
        ]
        .iter()
        .map(|r| r.iter().map(|&x| x as f64 * s).collect())
        .collect();
        assert_matrix(
            &synthesis_p(2),
            &p2.iter().map(Vec::as_slice).collect::<Vec<_>>(),
            "P2",
        );
        // j >= 3: the first columns of the figure, then translates of the fourth column.
        for j in 3..=5 {
            let p = synthesis_p(j);
            let first = [
                [16.0, 0.0, 0.0],
                [8.0, 8.0, 0.0],
                [0.0, 12.0, 4.0],
                [0.0, 3.0, 11.0],
                [0.0, 0.0, 8.0],
                [0.0, 0.0, 2.0],
            ];
            for (r, row) in first.iter().enumerate() {
                for (c, e) in row.iter().enumerate() {
                    assert!((p[(r, c)] - e * s).abs() < 1e-10, "P{j}[{r},{c}]");
                }
            }
            // Column 3 is 2, 8, 12, 8, 2 (/16) from row 3; column c ≥ 3 shifted by 2(c − 3).
            for c in 3..p.ncols() - 3 {
                for (i, e) in [2.0, 8.0, 12.0, 8.0, 2.0].iter().enumerate() {
                    assert!(
                        (p[(3 + 2 * (c - 3) + i, c)] - e * s).abs() < 1e-10,
                        "P{j} column {c}"
                    );
                }
            }
        }
    }

    #[test]
    fn wavelet_matrices_match_figure_2_6() {
        assert_matrix(
            &synthesis_q(1),
            &[
                &[1.0 / 3.0],
                &[-2.0 / 3.0],
                &[1.0],
                &[-2.0 / 3.0],
                &[1.0 / 3.0],
            ],
            "Q1",
        );
        let d = 2064.0;
        assert_matrix(
            &synthesis_q(2),
            &[
                &[-1368.0 / d, 0.0],
                &[1.0, 240.0 / d],
                &[-1793.0 / d, -691.0 / d],
                &[1053.0 / d, 1053.0 / d],
                &[-691.0 / d, -1793.0 / d],
                &[240.0 / d, 1.0],
                &[0.0, -1368.0 / d],
            ],
            "Q2",
        );
        let q3 = synthesis_q(3);
        let col0 = [
            -394762.0 / 574765.0,
            1.0,
            -33030599.0 / 41383080.0,
            633094403.0 / 1655323200.0,
            -19083341.0 / 137943600.0,
            4681957.0 / 165532320.0,
            -864187.0 / 413830800.0,
            27877.0 / 1655323200.0,
            0.0,
            0.0,
            0.0,
        ];
        let col1 = [
            0.0,
            -7166160.0 / 28124263.0,
            333497715.0 / 478112471.0,
            -881412943.0 / 956224942.0,
            1.0,
            -689203555.0 / 956224942.0,
            8833647.0 / 28124263.0,
            -74736797.0 / 956224942.0,
            6908335.0 / 478112471.0,
            0.0,
            0.0,
        ];
        for r in 0..11 {
            assert!(
                (q3[(r, 0)] - col0[r]).abs() < 1e-10,
                "Q3[{r},0] = {} expected {}",
                q3[(r, 0)],
                col0[r]
            );
            assert!(
                (q3[(r, 1)] - col1[r]).abs() < 1e-10,
                "Q3[{r},1] = {} expected {}",
                q3[(r, 1)],
                col1[r]
            );
            // Columns 2 and 3 mirror columns 1 and 0.
            assert!((q3[(r, 3)] - col0[10 - r]).abs() < 1e-10, "Q3[{r},3]");
            assert!((q3[(r, 2)] - col1[10 - r]).abs() < 1e-10, "Q3[{r},2]");
        }
        // j >= 4: the fourth column is the interior wavelet of the figure.
        let interior = [
            -1.0 / 24264.0,
            31.0 / 6066.0,
            -559.0 / 8088.0,
            988.0 / 3033.0,
            -9241.0 / 12132.0,
            1.0,
            -9241.0 / 12132.0,
            988.0 / 3033.0,
            -559.0 / 8088.0,
            31.0 / 6066.0,
            -1.0 / 24264.0,
        ];
        for j in 4..=5 {
            let q = synthesis_q(j);
            for (i, e) in interior.iter().enumerate() {
                assert!(
                    (q[(3 + i, 3)] - e).abs() < 1e-10,
                    "Q{j}[{},3] = {} expected {e}",
                    3 + i,
                    q[(3 + i, 3)]
                );
            }
            let second = [
                0.0,
                -1050072320.0 / 4096633377.0,
                2096854390.0 / 2989435167.0,
                -11070246427.0 / 11957740668.0,
                1.0,
            ];
            for (r, e) in second.iter().enumerate() {
                assert!(
                    (q[(r, 1)] - e).abs() < 1e-10,
                    "Q{j}[{r},1] = {} expected {e}",
                    q[(r, 1)]
                );
            }
        }
    }

    /// Independent of how P and Q were computed: the refinement holds pointwise
    /// (Φ^{j−1}(x) = Φ^j(x) P^j, eq. 2.9) and the wavelets are orthogonal to the coarse space.
    #[test]
    fn refinement_holds_pointwise_and_wavelets_are_orthogonal() {
        for j in 1..=6 {
            let p = synthesis_p(j);
            for s in 0..=97 {
                let x = s as f64 / 97.0;
                let coarse = DVector::from_vec(basis(j - 1, x));
                let fine = DVector::from_vec(basis(j, x));
                let refined = p.transpose() * fine;
                assert!((refined - coarse).amax() < 1e-12, "P{j} at x = {x}");
            }
            let q = synthesis_q(j);
            assert!((gram(j - 1, j) * &q).amax() < 1e-12, "Q{j} not orthogonal");
            // [P | Q] is invertible: decomposition (eq. 2.16) is well posed.
            let pq = DMatrix::from_fn(p.nrows(), p.ncols() + q.ncols(), |r, c| {
                if c < p.ncols() {
                    p[(r, c)]
                } else {
                    q[(r, c - p.ncols())]
                }
            });
            assert!(pq.determinant().abs() > 1e-12, "[P{j}|Q{j}] singular");
        }
    }

    #[test]
    fn basis_is_a_partition_of_unity_interpolating_the_ends() {
        for j in 0..=4 {
            for s in 0..=50 {
                let b = basis(j, s as f64 / 50.0);
                assert!((b.iter().sum::<f64>() - 1.0).abs() < 1e-12);
            }
            assert_eq!(basis(j, 0.0)[0], 1.0);
            assert_eq!(*basis(j, 1.0).last().unwrap(), 1.0);
        }
    }

    fn wiggly(j: u32) -> Controls {
        DMatrix::from_fn(count(j), 2, |r, c| {
            let x = r as f64;
            if c == 0 {
                x + (1.3 * x).sin()
            } else {
                (0.7 * x).cos() * 3.0 + 0.1 * x * x
            }
        })
    }

    #[test]
    fn decomposition_then_reconstruction_is_exact() {
        for j in 1..=6 {
            let c = wiggly(j);
            let (coarse, detail) = decompose(&c).expect("decompose");
            assert_eq!(coarse.nrows(), count(j - 1));
            assert_eq!(detail.nrows(), 1 << (j - 1));
            let back = reconstruct(&coarse, &detail).expect("reconstruct");
            assert!((back - &c).amax() < 1e-12 * c.amax().max(1.0), "level {j}");
            // t = 0 is the coarse curve, pointwise the same as on its own knots.
            let half = fractional(&coarse, &detail, 0.0).expect("fractional");
            for s in 0..=40 {
                let u = s as f64 / 40.0;
                assert!((evaluate(&half, u) - evaluate(&coarse, u)).norm() < 1e-12);
            }
        }
        assert!(decompose(&DMatrix::zeros(6, 2)).is_err());
    }

    #[test]
    fn coarse_curve_is_the_least_squares_projection() {
        // Orthogonality (eq. 2.15) makes c^{j−1} the L2-best level-(j−1) curve: perturbing
        // any coarse control point can only increase the L2 distance to the fine curve.
        let c = wiggly(4);
        let (coarse, _) = decompose(&c).expect("decompose");
        let l2 = |a: &Controls| {
            (0..2000)
                .map(|s| {
                    let u = (s as f64 + 0.5) / 2000.0;
                    (evaluate(a, u) - evaluate(&c, u)).norm_squared()
                })
                .sum::<f64>()
        };
        let base = l2(&coarse);
        for k in 0..coarse.nrows() {
            let mut other = coarse.clone();
            other[(k, 0)] += 0.05;
            assert!(l2(&other) > base, "control point {k}");
        }
    }

    #[test]
    fn eq_3_1_bounds_the_sampled_deviation_between_levels() {
        for j in 2..=6 {
            let c = wiggly(j);
            let (coarse, detail) = decompose(&c).expect("decompose");
            let bound = deviation_bound(&detail).expect("bound");
            let worst = (0..=4000)
                .map(|s| {
                    let u = s as f64 / 4000.0;
                    (evaluate(&c, u) - evaluate(&coarse, u)).norm()
                })
                .fold(0.0, f64::max);
            assert!(worst <= bound + 1e-12, "level {j}: {worst} > {bound}");
            // Conservative, not absurd.
            assert!(bound < 4.0 * worst, "level {j}: bound {bound} vs {worst}");
        }
    }

    #[test]
    fn bezier_matrix_reproduces_the_curve() {
        let c = wiggly(3);
        let bez = bezier_matrix(3) * &c;
        for s in 0..8 {
            for k in 0..=10 {
                let t = k as f64 / 10.0;
                let w = [
                    (1.0 - t).powi(3),
                    3.0 * t * (1.0 - t).powi(2),
                    3.0 * t * t * (1.0 - t),
                    t.powi(3),
                ];
                let mut p = Point2::origin();
                for (i, wi) in w.iter().enumerate() {
                    p.x += wi * bez[(4 * s + i, 0)];
                    p.y += wi * bez[(4 * s + i, 1)];
                }
                let u = (s as f64 + t) / 8.0;
                assert!((p - evaluate(&c, u)).norm() < 1e-10, "span {s} t {t}");
            }
        }
    }

    #[test]
    fn fit_recovers_a_curve_of_its_own_level_and_interpolates_the_ends() {
        let c = wiggly(3);
        let params: Vec<f64> = (0..=200).map(|s| s as f64 / 200.0).collect();
        let pts: Vec<Point2> = params.iter().map(|&u| evaluate(&c, u)).collect();
        let f = fit(&pts, &params, 3).expect("fit");
        assert!((f - &c).amax() < 1e-9);
        // A circle quarter at a coarse level: within a small distance, ends exact.
        let pts: Vec<Point2> = params
            .iter()
            .map(|u| Point2::new((u * 1.5).cos() * 10.0, (u * 1.5).sin() * 10.0))
            .collect();
        let f = fit(&pts, &params, 1).expect("fit");
        assert_eq!(evaluate(&f, 0.0), pts[0]);
        assert_eq!(evaluate(&f, 1.0), pts[200]);
        for (p, u) in pts.iter().zip(&params) {
            assert!((evaluate(&f, *u) - p).norm() < 0.01);
        }
        assert!(fit(&pts[..3], &params[..3], 3).is_err());
    }
}
