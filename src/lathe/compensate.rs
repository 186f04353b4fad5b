//! Nose-radius compensation, exactly per point (seed 003 §3.3).
//!
//! The control drives the centre of the tool's nose arc, so the programmed point over the grid
//! line `(x, y)` is `C = S + ρ N`: the surface point `S(u, v)` whose offset along its unit
//! normal `N` (toward the tool) lands on that line. The seed builds an approximate offset
//! surface first (Piegl–Tiller, to a tolerance) and then projects the grid onto it; here the
//! two unknowns `(u, v)` are solved directly from
//!
//! ```text
//! F(u, v) = (S + ρ N)ₓᵧ − (x, y) = 0,    ∂F/∂u = (S_u + ρ N_u)ₓᵧ,    ∂F/∂v = (S_v + ρ N_v)ₓᵧ
//! ```
//!
//! with `N_u, N_v` from the Weingarten equations (first and second fundamental forms), by
//! Newton's method with a backtracking step, to 1e-11 mm. The same second fundamental form
//! gives the principal curvatures at the contact: where one of them, concave toward the tool,
//! reaches `1/ρ`, the nose cannot follow the surface (the offset folds) and the point is
//! refused with its location.

use nalgebra::{Matrix2, Point3, Vector2, Vector3};

use super::surface::LensSurface;
use crate::cad::nurbs::SurfaceJet;

/// Where the nose touches the surface for one programmed point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Contact {
    /// The surface parameters of the contact point.
    pub parameters: (f64, f64),
    /// The contact point on the design surface.
    pub point: Point3<f64>,
    /// The unit normal there, toward the tool.
    pub normal: Vector3<f64>,
    /// The nose centre `point + ρ normal`: the programmed point.
    pub centre: Point3<f64>,
    /// Principal curvatures at the contact, largest first; positive where the surface is
    /// concave toward the tool.
    pub curvatures: [f64; 2],
    /// Newton iterations taken.
    pub iterations: u32,
}

/// Why no nose centre was found over a grid line.
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
pub enum ContactError {
    /// The nose would have to touch the surface outside its domain.
    #[error(
        "the nose centre over ({x:.4}, {y:.4}) needs the surface beyond its edge (the grid is \
         wider than the surface there)"
    )]
    OffSurface {
        /// Grid line.
        x: f64,
        /// Grid line.
        y: f64,
    },
    /// The surface turns vertical or its normal is undefined.
    #[error(
        "the surface is vertical or degenerate near ({x:.4}, {y:.4}): the tool cannot reach it from +z"
    )]
    Degenerate {
        /// Grid line.
        x: f64,
        /// Grid line.
        y: f64,
    },
    /// The nose radius exceeds a concave radius of curvature.
    #[error(
        "the nose radius {nose_radius} mm exceeds the surface's concave radius of curvature \
         {radius:.4} mm at ({x:.4}, {y:.4}): the tool cannot follow it there"
    )]
    TooConcave {
        /// Contact point.
        x: f64,
        /// Contact point.
        y: f64,
        /// The smallest concave radius there.
        radius: f64,
        /// The nose radius.
        nose_radius: f64,
    },
    /// Newton did not converge.
    #[error("no nose centre found over ({x:.4}, {y:.4}) (residual {residual:.3e} mm)")]
    NoConvergence {
        /// Grid line.
        x: f64,
        /// Grid line.
        y: f64,
        /// The residual left.
        residual: f64,
    },
}

/// How close the nose centre must land on its grid line.
pub const LANDING_TOLERANCE: f64 = 1e-11;

/// Normal and its parameter derivatives from a jet (Weingarten), with the principal
/// curvatures; `None` where the surface is degenerate.
pub(crate) struct Frame {
    pub normal: Vector3<f64>,
    pub normal_u: Vector3<f64>,
    pub normal_v: Vector3<f64>,
    pub curvatures: [f64; 2],
}

pub(crate) fn frame(surface: &LensSurface, jet: &SurfaceJet) -> Option<Frame> {
    let n = surface.normal(jet)?;
    let (e, f, g) = (
        jet.du.dot(&jet.du),
        jet.du.dot(&jet.dv),
        jet.dv.dot(&jet.dv),
    );
    let (l, m, nn) = (jet.duu.dot(&n), jet.duv.dot(&n), jet.dvv.dot(&n));
    let den = e * g - f * f;
    if den.abs() < 1e-300 || !den.is_finite() {
        return None;
    }
    let normal_u = (jet.du * (m * f - l * g) + jet.dv * (l * f - m * e)) / den;
    let normal_v = (jet.du * (nn * f - m * g) + jet.dv * (m * f - nn * e)) / den;
    // Principal curvatures: eigenvalues of I⁻¹ II (mean H, Gaussian K).
    let mean = (e * nn - 2.0 * f * m + g * l) / (2.0 * den);
    let gauss = (l * nn - m * m) / den;
    let spread = (mean * mean - gauss).max(0.0).sqrt();
    Some(Frame {
        normal: n,
        normal_u,
        normal_v,
        curvatures: [mean + spread, mean - spread],
    })
}

/// The nose centre over the grid line `(x, y)` for a nose of radius `nose_radius`, by Newton
/// from the surface parameters `guess`.
pub fn nose_centre(
    surface: &LensSurface,
    nose_radius: f64,
    (x, y): (f64, f64),
    guess: (f64, f64),
) -> Result<Contact, ContactError> {
    let target = Vector2::new(x, y);
    let ((u0, u1), (v0, v1)) = surface.domain();
    // Sag surfaces are evaluated past their aperture while iterating (their formulas are
    // defined there); the contact itself must lie within it.
    let clamp = |u: f64, v: f64| match surface {
        LensSurface::Sag { .. } => (u, v),
        LensSurface::Nurbs(_) => (u.clamp(u0, u1), v.clamp(v0, v1)),
    };
    let residual_at = |u: f64, v: f64| -> Option<(Vector2<f64>, SurfaceJet, Frame)> {
        let jet = surface.jet(u, v);
        let fr = frame(surface, &jet)?;
        let c = jet.point.coords + fr.normal * nose_radius;
        let r = Vector2::new(c.x, c.y) - target;
        r.iter().all(|v| v.is_finite()).then_some((r, jet, fr))
    };
    let (mut u, mut v) = clamp(guess.0, guess.1);
    let degenerate = ContactError::Degenerate { x, y };
    let (mut r, mut jet, mut fr) = residual_at(u, v).ok_or(degenerate)?;
    let mut iterations = 0;
    while r.norm() > LANDING_TOLERANCE {
        if iterations == 60 {
            return Err(ContactError::NoConvergence {
                x,
                y,
                residual: r.norm(),
            });
        }
        iterations += 1;
        let cu = jet.du + fr.normal_u * nose_radius;
        let cv = jet.dv + fr.normal_v * nose_radius;
        let jacobian = Matrix2::new(cu.x, cv.x, cu.y, cv.y);
        let step = jacobian.lu().solve(&r).ok_or(degenerate)?;
        // Backtrack until the residual drops (the first full step almost always does).
        let mut scale = 1.0;
        loop {
            let (nu, nv) = clamp(u - step.x * scale, v - step.y * scale);
            if let Some((nr, njet, nfr)) = residual_at(nu, nv)
                && nr.norm() < r.norm()
            {
                (u, v, r, jet, fr) = (nu, nv, nr, njet, nfr);
                break;
            }
            scale *= 0.5;
            if scale < 1e-6 {
                // Stuck: on the domain's edge the residual cannot drop further.
                let on_edge = matches!(surface, LensSurface::Nurbs(_))
                    && (u <= u0 || u >= u1 || v <= v0 || v >= v1);
                return Err(if on_edge {
                    ContactError::OffSurface { x, y }
                } else {
                    ContactError::NoConvergence {
                        x,
                        y,
                        residual: r.norm(),
                    }
                });
            }
        }
    }
    if !surface.contains(u, v, 1e-9) {
        return Err(ContactError::OffSurface { x, y });
    }
    if fr.curvatures[0] * nose_radius >= 1.0 {
        return Err(ContactError::TooConcave {
            x: jet.point.x,
            y: jet.point.y,
            radius: 1.0 / fr.curvatures[0],
            nose_radius,
        });
    }
    Ok(Contact {
        parameters: (u, v),
        point: jet.point,
        normal: fr.normal,
        centre: jet.point + fr.normal * nose_radius,
        curvatures: fr.curvatures,
        iterations,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lathe::surface::SagShape;

    fn sphere(radius: f64, aperture: f64) -> LensSurface {
        LensSurface::Sag {
            shape: SagShape::Conic {
                curvature: 1.0 / radius,
                conic: 0.0,
                even: vec![],
            },
            aperture,
        }
    }

    /// A concave sphere of radius R about (0, 0, R): the nose centres lie on the concentric
    /// sphere of radius R − ρ, `z = R − √((R − ρ)² − r²)`.
    #[test]
    fn concave_sphere_centres_are_on_the_smaller_sphere() {
        let (radius, rho) = (40.0, 0.5);
        let s = sphere(radius, 30.0);
        for &(x, y) in &[(0.0, 0.0), (3.0, 4.0), (-9.0, 8.5), (10.0, -10.0)] {
            let c = nose_centre(&s, rho, (x, y), (x, y)).unwrap();
            let expected = radius - ((radius - rho).powi(2) - x * x - y * y).sqrt();
            assert!((c.centre.z - expected).abs() < 1e-12, "{x},{y}: {c:?}");
            assert!((c.centre.x - x).abs() < 1e-11 && (c.centre.y - y).abs() < 1e-11);
            assert!((c.curvatures[0] - 1.0 / radius).abs() < 1e-12);
            assert!((c.curvatures[1] - 1.0 / radius).abs() < 1e-12);
        }
        // Convex: radius −R about (0, 0, −R), centres on the sphere of radius R + ρ.
        let s = sphere(-radius, 30.0);
        let c = nose_centre(&s, rho, (6.0, -7.0), (6.0, -7.0)).unwrap();
        let expected = -radius + ((radius + rho).powi(2) - 85.0).sqrt();
        assert!((c.centre.z - expected).abs() < 1e-12);
        assert!(c.curvatures[0] < 0.0);
    }

    #[test]
    fn a_nose_larger_than_the_concave_radius_is_refused_where_it_happens() {
        let s = sphere(2.0, 3.0);
        match nose_centre(&s, 2.5, (0.1, 0.0), (0.1, 0.0)) {
            Err(ContactError::TooConcave { radius, .. }) => assert!((radius - 2.0).abs() < 1e-9),
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn a_grid_line_beyond_the_aperture_is_refused() {
        let s = sphere(-50.0, 20.0);
        assert!(nose_centre(&s, 0.5, (9.9, 0.0), (9.9, 0.0)).is_ok());
        assert!(matches!(
            nose_centre(&s, 0.5, (10.5, 0.0), (10.5, 0.0)),
            Err(ContactError::OffSurface { .. })
        ));
    }
}
