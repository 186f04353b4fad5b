//! Garland–Heckbert error quadrics: `Q(p) = pᵀAp + 2bᵀp + c`, a weighted sum of squared
//! distances to planes, plus the optimal-placement solve.
//!
//! Positions handed to a [`Quadric`] are relative to a model origin chosen by the caller (the
//! bounding-box centre), which keeps `pᵀAp + 2bᵀp + c` free of large cancellations.

use nalgebra::{Matrix3, SymmetricEigen, Vector3};

/// Eigenvalues of `A` below this fraction of the largest one are treated as zero when solving
/// for the optimal position (the solve then stays at the reference point along those
/// directions, as in Lindstrom's pseudo-inverse placement).
const EIGEN_CUTOFF: f64 = 1e-3;

/// A symmetric 4×4 error quadric stored as its 10 distinct coefficients, plus the total
/// surface area `weight` it was built from (used to turn the sum into a mean squared distance).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct Quadric {
    /// Upper triangle of `A`: xx, xy, xz, yy, yz, zz.
    a: [f64; 6],
    b: [f64; 3],
    c: f64,
    /// Area (mm²) of the faces whose planes were summed (constraint planes add none).
    pub(crate) area: f64,
}

impl Quadric {
    /// The quadric of the plane `n·p + d = 0` (`n` unit) with weight `w`, counting `area`
    /// towards the normalising area.
    pub(crate) fn plane(n: Vector3<f64>, d: f64, w: f64, area: f64) -> Self {
        Self {
            a: [
                w * n.x * n.x,
                w * n.x * n.y,
                w * n.x * n.z,
                w * n.y * n.y,
                w * n.y * n.z,
                w * n.z * n.z,
            ],
            b: [w * d * n.x, w * d * n.y, w * d * n.z],
            c: w * d * d,
            area,
        }
    }

    /// Adds `other` to `self`.
    pub(crate) fn add(&mut self, other: &Self) {
        for (s, o) in self.a.iter_mut().zip(other.a) {
            *s += o;
        }
        for (s, o) in self.b.iter_mut().zip(other.b) {
            *s += o;
        }
        self.c += other.c;
        self.area += other.area;
    }

    /// The sum `self + other`.
    pub(crate) fn sum(&self, other: &Self) -> Self {
        let mut q = *self;
        q.add(other);
        q
    }

    fn matrix(&self) -> Matrix3<f64> {
        let [xx, xy, xz, yy, yz, zz] = self.a;
        Matrix3::new(xx, xy, xz, xy, yy, yz, xz, yz, zz)
    }

    /// `Q(p)`, clamped at zero against rounding.
    pub(crate) fn eval(&self, p: &Vector3<f64>) -> f64 {
        let [xx, xy, xz, yy, yz, zz] = self.a;
        let ap = Vector3::new(
            xx * p.x + xy * p.y + xz * p.z,
            xy * p.x + yy * p.y + yz * p.z,
            xz * p.x + yz * p.y + zz * p.z,
        );
        let b = Vector3::from(self.b);
        (p.dot(&ap) + 2.0 * b.dot(p) + self.c).max(0.0)
    }

    /// The position minimising `Q`, solved in the eigenbasis of `A` with eigenvalues below
    /// [`EIGEN_CUTOFF`]·λ_max dropped; along the dropped (ill-conditioned) directions the
    /// result stays at `reference`. `None` when `A` vanishes or the solve is not finite.
    pub(crate) fn optimum_near(&self, reference: &Vector3<f64>) -> Option<Vector3<f64>> {
        let a = self.matrix();
        let eig = SymmetricEigen::new(a);
        let lambda_max = eig.eigenvalues.iter().fold(0.0_f64, |m, &l| m.max(l));
        if lambda_max <= 0.0 || lambda_max.is_nan() {
            return None;
        }
        // Residual gradient at the reference point: ∇Q/2 = A·r + b.
        let g = a * reference + Vector3::from(self.b);
        let mut p = *reference;
        for i in 0..3 {
            let l = eig.eigenvalues[i];
            if l > EIGEN_CUTOFF * lambda_max {
                let v = eig.eigenvectors.column(i);
                p -= v * (v.dot(&g) / l);
            }
        }
        p.iter().all(|c| c.is_finite()).then_some(p)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn three_planes_meet_at_their_corner() {
        let mut q = Quadric::plane(Vector3::x(), -1.0, 1.0, 1.0);
        q.add(&Quadric::plane(Vector3::y(), -2.0, 1.0, 1.0));
        q.add(&Quadric::plane(Vector3::z(), -3.0, 1.0, 1.0));
        let p = q.optimum_near(&Vector3::zeros()).unwrap();
        assert!((p - Vector3::new(1.0, 2.0, 3.0)).norm() < 1e-12);
        assert!(q.eval(&p) < 1e-20);
        assert!((q.eval(&Vector3::zeros()) - 14.0).abs() < 1e-12);
        assert_eq!(q.area, 3.0);
    }

    #[test]
    fn single_plane_projects_the_reference() {
        let n = Vector3::new(1.0, 2.0, 2.0) / 3.0;
        let q = Quadric::plane(n, -3.0, 2.0, 1.0);
        let r = Vector3::new(5.0, -1.0, 0.5);
        let p = q.optimum_near(&r).unwrap();
        // On the plane, and moved only along the normal.
        assert!((n.dot(&p) - 3.0).abs() < 1e-12);
        assert!((p - r).cross(&n).norm() < 1e-12);
    }

    #[test]
    fn empty_quadric_has_no_optimum() {
        assert!(Quadric::default().optimum_near(&Vector3::zeros()).is_none());
    }
}
