//! B-spline basis functions on a knot vector: the knot span of a parameter, the non-zero basis
//! functions there and their derivatives (the Cox–de Boor recurrence in the triangular form of
//! Piegl & Tiller, *The NURBS Book*, algorithms A2.1–A2.3; seed 002 eq. 1, seed 003 §3.1).

/// The span `i` with `knots[i] ≤ u < knots[i + 1]` among the `n + 1` basis functions of degree
/// `p` (`knots.len() = n + p + 2`); `u` at or beyond the end of the domain gets the last
/// non-empty span, before its start the first, so that the domain is closed at both ends.
pub fn find_span(n: usize, p: usize, u: f64, knots: &[f64]) -> usize {
    if u >= knots[n + 1] {
        // The last span of non-zero length.
        let mut i = n;
        while i > p && knots[i] >= knots[n + 1] {
            i -= 1;
        }
        return i;
    }
    if u <= knots[p] {
        let mut i = p;
        while i < n && knots[i + 1] <= knots[p] {
            i += 1;
        }
        return i;
    }
    let (mut low, mut high) = (p, n + 1);
    let mut mid = (low + high) / 2;
    while u < knots[mid] || u >= knots[mid + 1] {
        if u < knots[mid] {
            high = mid;
        } else {
            low = mid;
        }
        mid = (low + high) / 2;
    }
    mid
}

/// Basis function values of one span.
pub type Basis = smallvec::SmallVec<[f64; 12]>;

/// The `p + 1` basis functions of degree `p` that are non-zero on span `i`, at `u`:
/// `N[i − p + j](u)` for `j = 0..=p`.
///
/// Held inline up to degree 11 (the surfaces of real parts are cubic or quintic), so that
/// evaluating a point allocates nothing.
pub fn basis_functions(i: usize, u: f64, p: usize, knots: &[f64]) -> Basis {
    let mut n: Basis = smallvec::smallvec![0.0; p + 1];
    let mut left: Basis = smallvec::smallvec![0.0; p + 1];
    let mut right: Basis = smallvec::smallvec![0.0; p + 1];
    n[0] = 1.0;
    for j in 1..=p {
        left[j] = u - knots[i + 1 - j];
        right[j] = knots[i + j] - u;
        let mut saved = 0.0;
        for r in 0..j {
            let temp = n[r] / (right[r + 1] + left[j - r]);
            n[r] = saved + right[r + 1] * temp;
            saved = left[j - r] * temp;
        }
        n[j] = saved;
    }
    n
}

/// The basis functions non-zero on span `i` and their derivatives up to order `d` at `u`:
/// `ders[k][j]` is the `k`-th derivative of `N[i − p + j]` (zero beyond order `p`).
pub fn basis_derivatives(i: usize, u: f64, p: usize, d: usize, knots: &[f64]) -> Vec<Vec<f64>> {
    // ndu holds the functions (upper triangle) and the knot differences (lower).
    let mut ndu = vec![vec![0.0; p + 1]; p + 1];
    let mut left = vec![0.0; p + 1];
    let mut right = vec![0.0; p + 1];
    ndu[0][0] = 1.0;
    for j in 1..=p {
        left[j] = u - knots[i + 1 - j];
        right[j] = knots[i + j] - u;
        let mut saved = 0.0;
        for r in 0..j {
            ndu[j][r] = right[r + 1] + left[j - r];
            let temp = ndu[r][j - 1] / ndu[j][r];
            ndu[r][j] = saved + right[r + 1] * temp;
            saved = left[j - r] * temp;
        }
        ndu[j][j] = saved;
    }
    let mut ders = vec![vec![0.0; p + 1]; d + 1];
    for j in 0..=p {
        ders[0][j] = ndu[j][p];
    }
    let mut a = [vec![0.0; p + 1], vec![0.0; p + 1]];
    for r in 0..=p {
        let (mut s1, mut s2) = (0usize, 1usize);
        a[0][0] = 1.0;
        for k in 1..=d.min(p) {
            let mut value = 0.0;
            let rk = r as isize - k as isize;
            let pk = p - k;
            if r >= k {
                a[s2][0] = a[s1][0] / ndu[pk + 1][r - k];
                value = a[s2][0] * ndu[r - k][pk];
            }
            let j1 = if rk >= -1 { 1 } else { (-rk) as usize };
            let j2 = if r as isize - 1 <= pk as isize {
                k - 1
            } else {
                p - r
            };
            for j in j1..=j2 {
                let idx = (rk + j as isize) as usize;
                a[s2][j] = (a[s1][j] - a[s1][j - 1]) / ndu[pk + 1][idx];
                value += a[s2][j] * ndu[idx][pk];
            }
            if r <= pk {
                a[s2][k] = -a[s1][k - 1] / ndu[pk + 1][r];
                value += a[s2][k] * ndu[r][pk];
            }
            ders[k][r] = value;
            std::mem::swap(&mut s1, &mut s2);
        }
    }
    let mut factor = p as f64;
    for (k, row) in ders.iter_mut().enumerate().take(d.min(p) + 1).skip(1) {
        for v in row.iter_mut() {
            *v *= factor;
        }
        factor *= (p - k) as f64;
    }
    ders
}

/// Binomial coefficient `n over k` as a float (small arguments: derivative orders).
pub fn binomial(n: usize, k: usize) -> f64 {
    (0..k).fold(1.0, |acc, i| acc * (n - i) as f64 / (i + 1) as f64)
}

#[cfg(test)]
mod tests {
    use super::*;

    const KNOTS: [f64; 12] = [0.0, 0.0, 0.0, 0.0, 0.2, 0.5, 0.5, 0.8, 1.0, 1.0, 1.0, 1.0];

    /// The functions of a span are non-negative and sum to one (partition of unity), and the
    /// span found brackets the parameter, closed at the domain's end.
    #[test]
    fn basis_functions_partition_unity() {
        let (n, p) = (KNOTS.len() - 5, 3);
        for k in 0..=200 {
            let u = k as f64 / 200.0;
            let i = find_span(n, p, u, &KNOTS);
            assert!(KNOTS[i] <= u && (u < KNOTS[i + 1] || (u == 1.0 && KNOTS[i + 1] == 1.0)));
            let b = basis_functions(i, u, p, &KNOTS);
            assert!(b.iter().all(|&v| v >= -1e-15), "{b:?}");
            assert!((b.iter().sum::<f64>() - 1.0).abs() < 1e-14);
        }
    }

    /// Derivatives of order 0 are the functions; order 1 and 2 agree with central differences
    /// away from the knots, and the derivatives of the sum (one) vanish.
    #[test]
    fn derivatives_agree_with_differences() {
        let (n, p) = (KNOTS.len() - 5, 3);
        for &u in &[0.1, 0.31, 0.42, 0.66, 0.9] {
            let i = find_span(n, p, u, &KNOTS);
            let d = basis_derivatives(i, u, p, 3, &KNOTS);
            assert_eq!(d[0][..], basis_functions(i, u, p, &KNOTS)[..]);
            let h = 1e-5;
            let (lo, hi) = (
                basis_functions(i, u - h, p, &KNOTS),
                basis_functions(i, u + h, p, &KNOTS),
            );
            let mid = basis_functions(i, u, p, &KNOTS);
            for j in 0..=p {
                let first = (hi[j] - lo[j]) / (2.0 * h);
                let second = (hi[j] - 2.0 * mid[j] + lo[j]) / (h * h);
                assert!((d[1][j] - first).abs() < 1e-6, "{} vs {first}", d[1][j]);
                assert!((d[2][j] - second).abs() < 1e-3, "{} vs {second}", d[2][j]);
            }
            for row in &d[1..] {
                assert!(row.iter().sum::<f64>().abs() < 1e-9);
            }
        }
        assert_eq!(binomial(5, 2), 10.0);
        assert_eq!(binomial(4, 0), 1.0);
    }
}
