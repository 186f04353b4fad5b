//! A freeform lens to turn (seed 003's kind of part): a 44 × 44 mm rational bicubic B-spline
//! patch — a concave sphere of radius 150 mm with a cubic freeform term `A (x y² + x³/3)`
//! (an Alvarez-plate profile) and a gentle saddle — closed by five planes (four sides and a
//! bottom), written as IGES. The weights and knots are uneven on purpose, so the patch's
//! parametrisation is not its x, y: a lens tool must solve for the parameters, as with a real
//! CAD export. Deterministic: the same text every time.

use nalgebra::Point3;

use crate::cad::iges::write_surfaces;
use crate::cad::nurbs::{NurbsError, NurbsSurface};

/// Half the side of the square patch (mm).
pub const LENS_HALF_SIDE: f64 = 22.0;

/// The design sag the patch's control points sample.
fn design_sag(x: f64, y: f64) -> f64 {
    let sphere = 150.0 - (150.0f64 * 150.0 - x * x - y * y).sqrt();
    let alvarez = 2.0e-5 * (x * y * y + x * x * x / 3.0);
    let saddle = 4.0e-4 * (x * x - y * y) * 0.5;
    sphere + alvarez + saddle
}

/// The freeform patch: 14 × 14 control points, uneven knots, weights within ±4 % of 1.
pub fn freeform_lens_patch() -> Result<NurbsSurface, NurbsError> {
    let n = 14;
    // Clamped cubic knots, interior ones spaced unevenly.
    let interior: Vec<f64> = (1..n - 3)
        .map(|k| {
            let t = k as f64 / (n - 3) as f64;
            t + 0.03 * (std::f64::consts::TAU * t).sin()
        })
        .collect();
    let mut knots = vec![0.0; 4];
    knots.extend(&interior);
    knots.extend([1.0; 4]);
    // Greville abscissae place the control points over the parameters they pull.
    let greville: Vec<f64> = (0..n)
        .map(|i| (knots[i + 1] + knots[i + 2] + knots[i + 3]) / 3.0)
        .collect();
    let coordinate = |g: f64| -LENS_HALF_SIDE + 2.0 * LENS_HALF_SIDE * g;
    let net: Vec<Vec<Point3<f64>>> = (0..n)
        .map(|i| {
            (0..n)
                .map(|j| {
                    let (x, y) = (coordinate(greville[i]), coordinate(greville[j]));
                    Point3::new(x, y, design_sag(x, y))
                })
                .collect()
        })
        .collect();
    let weights: Vec<Vec<f64>> = (0..n)
        .map(|i| {
            (0..n)
                .map(|j| 1.0 + 0.04 * ((i as f64 * 0.9).sin() * (j as f64 * 0.7).cos()))
                .collect()
        })
        .collect();
    NurbsSurface::new([3, 3], knots.clone(), knots, &net, &weights)
}

/// A bilinear plane through four corners (`a b` along u, `a d` along v).
fn plane(
    a: Point3<f64>,
    b: Point3<f64>,
    c: Point3<f64>,
    d: Point3<f64>,
) -> Result<NurbsSurface, NurbsError> {
    NurbsSurface::new(
        [1, 1],
        vec![0.0, 0.0, 1.0, 1.0],
        vec![0.0, 0.0, 1.0, 1.0],
        &[vec![a, d], vec![b, c]],
        &[vec![1.0, 1.0], vec![1.0, 1.0]],
    )
}

/// The lens as an IGES file: the freeform patch first, then the bottom (z = −6) and the four
/// sides as planes.
pub fn freeform_lens_iges() -> Result<String, NurbsError> {
    let h = LENS_HALF_SIDE;
    let bottom = -6.0;
    let corner = |x: f64, y: f64, z: f64| Point3::new(x, y, z);
    let unit = ((0.0, 1.0), (0.0, 1.0));
    let surfaces = vec![
        (freeform_lens_patch()?, unit),
        (
            plane(
                corner(-h, -h, bottom),
                corner(-h, h, bottom),
                corner(h, h, bottom),
                corner(h, -h, bottom),
            )?,
            unit,
        ),
        (
            plane(
                corner(-h, -h, bottom),
                corner(h, -h, bottom),
                corner(h, -h, 0.0),
                corner(-h, -h, 0.0),
            )?,
            unit,
        ),
        (
            plane(
                corner(h, -h, bottom),
                corner(h, h, bottom),
                corner(h, h, 0.0),
                corner(h, -h, 0.0),
            )?,
            unit,
        ),
        (
            plane(
                corner(h, h, bottom),
                corner(-h, h, bottom),
                corner(-h, h, 0.0),
                corner(h, h, 0.0),
            )?,
            unit,
        ),
        (
            plane(
                corner(-h, h, bottom),
                corner(-h, -h, bottom),
                corner(-h, -h, 0.0),
                corner(-h, h, 0.0),
            )?,
            unit,
        ),
    ];
    Ok(write_surfaces(&surfaces, "freeform_lens_44mm.igs"))
}
