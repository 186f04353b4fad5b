//! The optional k-disk lifting update (seed 004 eqs. 2.22–2.24).
//!
//! With the plain factorisation, fine = `P c + Q d`. A further update step stores
//! `c' = c + S d` instead of `c` (analysis `A_kd = A + S B`, eq. 2.23) and synthesises with
//! `c = c' − S d`, i.e. wavelets `Q_kd = Q − P S` (eq. 2.22): exactly invertible for *any* S.
//! Column k of S is supported on the "1-disk" of edge k (its endpoints and, for an interior
//! edge, its two opposite vertices) and chosen by least squares, eq. 2.24, so that the coarse
//! scaling functions absorb as much of wavelet k as they can:
//! `min_s ‖P s − Q e_k‖²`, i.e. `(P_Nᵀ P_N) s = P_Nᵀ Q e_k`. As a substitute for the `L²`
//! inner products of eq. 2.24 (which need the Loop basis functions), the inner product is the
//! discrete one over fine control-point values, so S depends on connectivity only and the
//! transform stays linear. With d = 0 nothing changes: pure Loop surfaces keep zero details.

use nalgebra::{Cholesky, DMatrix, DVector, Vector3};

use super::level::{EdgeRule, LevelTopology};

/// The sparse matrix S, stored by columns (one per coarse edge).
#[derive(Clone, Debug)]
pub(super) struct KDiskUpdate {
    offsets: Vec<usize>,
    entries: Vec<(u32, f64)>,
}

/// Sparse dot product of two columns sorted by row.
fn dot(x: &[(u32, f64)], y: &[(u32, f64)]) -> f64 {
    let (mut i, mut j, mut s) = (0, 0, 0.0);
    while i < x.len() && j < y.len() {
        match x[i].0.cmp(&y[j].0) {
            std::cmp::Ordering::Less => i += 1,
            std::cmp::Ordering::Greater => j += 1,
            std::cmp::Ordering::Equal => {
                s += x[i].1 * y[j].1;
                i += 1;
                j += 1;
            }
        }
    }
    s
}

/// Appends the coefficients of Loop's edge rule for edge k as `(coarse, weight)`.
fn predict_weights(
    level: &LevelTopology,
    k: usize,
    scale: f64,
    out: &mut Vec<(u32, u32, f64)>,
    row: u32,
) {
    let [a, b] = level.edges()[k];
    match level.edge_rule(k) {
        EdgeRule::Sharp => {
            out.push((a, row, 0.5 * scale));
            out.push((b, row, 0.5 * scale));
        }
        EdgeRule::Interior { opposite: [p, q] } => {
            out.push((a, row, 0.375 * scale));
            out.push((b, row, 0.375 * scale));
            out.push((p, row, 0.125 * scale));
            out.push((q, row, 0.125 * scale));
        }
    }
}

impl KDiskUpdate {
    /// Builds S for `level` (whose update weights and edge rules are already set).
    pub(super) fn new(level: &LevelTopology) -> Self {
        let v = level.coarse_vertices();
        let e = level.edge_count();
        // Triplets (coarse column, fine row, weight) of the Loop subdivision matrix P.
        let mut trip: Vec<(u32, u32, f64)> = Vec::new();
        for k in 0..e {
            predict_weights(level, k, 1.0, &mut trip, (v + k) as u32);
        }
        for i in 0..v {
            trip.push((i as u32, i as u32, level.alpha(i)));
        }
        for (k, &[a, b]) in level.edges().iter().enumerate() {
            for i in [a, b] {
                if level.contributes(i, k) {
                    predict_weights(level, k, level.gamma(i as usize), &mut trip, i);
                }
            }
        }
        trip.sort_by_key(|x| (x.0, x.1));
        let mut col_start = vec![0usize; v + 1];
        let mut cols: Vec<(u32, f64)> = Vec::with_capacity(trip.len());
        let mut col_of: Vec<u32> = Vec::with_capacity(trip.len());
        for &(c, r, w) in &trip {
            if let (Some(&lc), Some(last)) = (col_of.last(), cols.last_mut())
                && lc == c
                && last.0 == r
            {
                last.1 += w;
                continue;
            }
            cols.push((r, w));
            col_of.push(c);
        }
        for &c in &col_of {
            col_start[c as usize + 1] += 1;
        }
        for j in 0..v {
            col_start[j + 1] += col_start[j];
        }
        let column = |j: u32| &cols[col_start[j as usize]..col_start[j as usize + 1]];

        let mut offsets = Vec::with_capacity(e + 1);
        offsets.push(0);
        let mut entries = Vec::with_capacity(4 * e);
        for (k, &[a, b]) in level.edges().iter().enumerate() {
            let mut disk = vec![a, b];
            if let EdgeRule::Interior { opposite: [p, q] } = level.edge_rule(k) {
                disk.push(p);
                disk.push(q);
            }
            disk.sort_unstable();
            disk.dedup();
            // The wavelet Q e_k: 1 at odd vertex v + k, γ at contributing endpoints.
            let mut psi: Vec<(u32, f64)> = vec![((v + k) as u32, 1.0)];
            for i in [a, b] {
                if level.contributes(i, k) {
                    psi.push((i, level.gamma(i as usize)));
                }
            }
            psi.sort_by_key(|x| x.0);
            let n = disk.len();
            let g = DMatrix::from_fn(n, n, |r, c| dot(column(disk[r]), column(disk[c])));
            let rhs = DVector::from_fn(n, |r, _| dot(column(disk[r]), &psi));
            if let Some(ch) = Cholesky::new(g) {
                let s = ch.solve(&rhs);
                for (r, &j) in disk.iter().enumerate() {
                    if s[r].is_finite() {
                        entries.push((j, s[r]));
                    }
                }
            }
            offsets.push(entries.len());
        }
        KDiskUpdate { offsets, entries }
    }

    /// `c += sign · S d` (lengths pre-validated by the caller).
    pub(super) fn apply(&self, c: &mut [Vector3<f64>], d: &[Vector3<f64>], sign: f64) {
        for (k, dk) in d.iter().enumerate() {
            for &(j, w) in &self.entries[self.offsets[k]..self.offsets[k + 1]] {
                c[j as usize] += dk * (sign * w);
            }
        }
    }
}
