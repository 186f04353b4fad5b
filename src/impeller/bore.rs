//! Loops round an impeller's bore: the hub's inner wall, facing the rotation axis. The
//! parallel planes cannot finish it (their axes lean at most so far from the surface's normal,
//! and in a bore any such lean runs the tool into the far wall); a tool standing along the
//! axis, its ball's side against the wall, can. The wall is a surface of revolution about the
//! axis: its curves of constant height are circles round it (broken where a keyway cuts the
//! wall), a stepover apart along the wall where it stands square to the hub (height steps of
//! the stepover times the wall's steepness there, its low percentile, as round a blade).
//!
//! A bore read from a mesh is a prism of facets, and the ball cannot follow it into the
//! creases between them: touching two facets that turn by θ, it stands r·(1/cos(θ/2) − 1) off
//! the crease (0.0056 mm for a 2 mm ball in the blower's 42-gon). The stepover is the one that
//! leaves the rest of the target between the loops there.

use crate::geom::{Point3, Vector3, stepover_for_scallop, weighted_quantile};
use crate::mesh::topology::edges;
use crate::mesh::{Mesh, SectionCurve, level_section};

use super::frame::AxisFrame;
use super::recognise::{Impeller, Region};

/// A bore triangle faces the axis: its normal's component toward the axis at least this.
const FACING_AXIS: f64 = 0.8;

/// ... and stands within this of the hub's smallest radius, mm.
const NEAR_INNER_RADIUS: f64 = 2.0;

/// Facets of the wall that turn by less than this are the tessellation of one round wall;
/// more, and the crease is a feature (a keyway's corner), where the ball does not fit anyway.
const FACETTING_TURN_DEG: f64 = 20.0;

/// The crease standoff takes at most this share of the scallop target: a coarser
/// tessellation would need loops closer than any finish is worth.
const MAX_STANDOFF_SHARE: f64 = 0.75;

/// The loops round the bore, from the top down, and which triangles of the part are its wall.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct BoreLoops {
    pub curves: Vec<SectionCurve>,
    /// Per triangle of the part: on the bore's wall.
    pub wall: Vec<bool>,
    /// Area of the wall, mm², and its height along the axis, mm.
    pub area_mm2: f64,
    pub height_mm: f64,
    pub level_step: f64,
    /// How far the ball stands off the deepest crease between the wall's facets, mm.
    pub crease_standoff_mm: f64,
}

/// The loops round `impeller`'s bore in `mesh` for a ball of `radius`, levels apart along the
/// wall by the stepover that leaves `scallop` between them, in the wall's creases too; empty
/// when the hub has no wall facing the axis.
pub fn bore_loops(
    mesh: &Mesh,
    impeller: &Impeller,
    frame: &AxisFrame,
    radius: f64,
    scallop: f64,
) -> BoreLoops {
    let inner = impeller.hub_radius_mm[0];
    let wall: Vec<bool> = (0..mesh.triangles.len())
        .map(|t| {
            if impeller.regions[t] != Region::Hub {
                return false;
            }
            let [a, b, c] = mesh.corners(t);
            let centroid = Point3::from((a.coords + b.coords + c.coords) / 3.0);
            let (radius, angle, _) = frame.cylindrical(&centroid);
            let inward = -frame.radial(angle);
            radius <= inner + NEAR_INNER_RADIUS && mesh.face_normal(t).dot(&inward) >= FACING_AXIS
        })
        .collect();
    let bore = Mesh::compacted(
        &mesh.positions,
        mesh.triangles
            .iter()
            .zip(&wall)
            .filter(|(_, w)| **w)
            .map(|(t, _)| *t),
    );
    if bore.triangles.is_empty() {
        return BoreLoops::default();
    }
    let normals: Vec<Vector3> = (0..bore.triangles.len())
        .map(|t| bore.face_normal(t))
        .collect();
    let height: Vec<f64> = bore
        .positions
        .iter()
        .map(|p| frame.cylindrical(p).2)
        .collect();
    let (low, high) = height
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), h| {
            (lo.min(*h), hi.max(*h))
        });
    // The height changes along the wall by the sine of its steepness: 1 on a cylinder.
    let steepness: Vec<(f64, f64)> = normals
        .iter()
        .enumerate()
        .map(|(t, n)| {
            let along_axis = n.dot(&frame.axis);
            ((1.0 - along_axis * along_axis).max(0.0).sqrt(), {
                let [a, b, c] = bore.corners(t);
                0.5 * (b - a).cross(&(c - a)).norm()
            })
        })
        .collect();
    let least = weighted_quantile(steepness, 0.1).unwrap_or(1.0);
    let standoff = crease_standoff(&bore, &normals, radius).min(MAX_STANDOFF_SHARE * scallop);
    let stepover = stepover_for_scallop(radius, scallop - standoff);
    let level_step = (stepover * least).max(1e-3);
    // Levels from half a step below the top to half a step above the bottom, evenly.
    let span = high - low;
    let levels = (span / level_step).ceil().max(1.0) as usize;
    let step = span / levels as f64;
    let mut curves = Vec::new();
    for k in 0..levels {
        let level = high - (k as f64 + 0.5) * step;
        let shifted: Vec<f64> = height.iter().map(|h| h - level).collect();
        curves.extend(level_section(&bore, &normals, &shifted));
    }
    BoreLoops {
        curves,
        area_mm2: bore.surface_area(),
        wall,
        height_mm: span,
        level_step: step,
        crease_standoff_mm: standoff,
    }
}

/// How far a ball of `radius` stands off the deepest concave crease between facets of
/// `wall` that tessellate one round surface, mm: r·(1/cos(θ/2) − 1) for the largest turn θ.
/// Where two balls a stepover s apart meet over such a crease, the material stands
/// r + standoff − √(r² − s²/4) high: the flat cusp plus the standoff.
fn crease_standoff(wall: &Mesh, normals: &[Vector3], radius: f64) -> f64 {
    let centroid = |t: usize| {
        let [a, b, c] = wall.corners(t);
        Point3::from((a.coords + b.coords + c.coords) / 3.0)
    };
    let limit = FACETTING_TURN_DEG.to_radians();
    let mut turn: f64 = 0.0;
    for edge in edges(&wall.triangles) {
        let [(f, _), (g, _)] = edge.faces[..] else {
            continue;
        };
        let (f, g) = (f as usize, g as usize);
        let concave = (centroid(g) - centroid(f)).dot(&normals[f]) > 0.0;
        let angle = normals[f].dot(&normals[g]).clamp(-1.0, 1.0).acos();
        if concave && angle < limit {
            turn = turn.max(angle);
        }
    }
    radius * (1.0 / (0.5 * turn).cos() - 1.0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::impeller::{RecogniseOptions, recognise};

    /// The sample's bore (radius 8, the hub 12 mm tall there): every loop runs round the wall
    /// at its level, on the circle of the bore's radius, the levels no more than a stepover
    /// apart and covering the wall from top to bottom within half a step; the wall's triangles
    /// face the axis.
    #[test]
    fn the_sample_bore_gets_circles_a_stepover_apart_from_top_to_bottom() {
        let mesh = crate::sample::impeller(&Default::default()).expect("sample impeller");
        let impeller = recognise(&mesh, &RecogniseOptions::default()).expect("an impeller");
        let frame = AxisFrame::new(impeller.centre.into(), &Vector3::from(impeller.axis));
        let (radius, scallop) = (2.0, 0.01);
        let bore = bore_loops(&mesh, &impeller, &frame, radius, scallop);
        assert!(!bore.curves.is_empty());
        let stepover = stepover_for_scallop(radius, scallop - bore.crease_standoff_mm);
        assert!(bore.level_step <= stepover + 1e-12 && bore.level_step > 0.75 * stepover);
        let (mut low, mut high) = (f64::INFINITY, f64::NEG_INFINITY);
        for (t, on) in bore.wall.iter().enumerate() {
            if !on {
                continue;
            }
            let [a, b, c] = mesh.corners(t);
            for p in [a, b, c] {
                let (radius, _, height) = frame.cylindrical(&p);
                assert!((radius - 8.0).abs() < 0.05, "{radius}");
                (low, high) = (low.min(height), high.max(height));
            }
        }
        let mut levels: Vec<f64> = Vec::new();
        for curve in &bore.curves {
            let (_, _, level) = frame.cylindrical(&curve.points[0].point);
            for p in &curve.points {
                let (radius, _, height) = frame.cylindrical(&p.point);
                assert!((radius - 8.0).abs() < 0.05 && (height - level).abs() < 1e-6);
                assert!(p.normal.dot(&frame.axis).abs() < 0.2);
            }
            levels.push(level);
        }
        levels.sort_by(f64::total_cmp);
        levels.dedup_by(|a, b| (*a - *b).abs() < 1e-6);
        assert!(levels.windows(2).all(|w| w[1] - w[0] <= stepover + 1e-9));
        assert!(levels[0] - low <= 0.5 * bore.level_step + 1e-9);
        assert!(high - levels[levels.len() - 1] <= 0.5 * bore.level_step + 1e-9);
        // A full circle each: the sample's bore has no keyway.
        let round = 2.0 * std::f64::consts::PI * 8.0;
        for curve in &bore.curves {
            let length: f64 = curve
                .points
                .windows(2)
                .map(|w| (w[1].point - w[0].point).norm())
                .sum();
            assert!(
                curve.closed && (length - round).abs() < 0.05 * round,
                "{length}"
            );
        }
    }

    /// The inside of an n-sided prism: the ball stands r·(1/cos(π/n) − 1) off its creases,
    /// and two balls in a crease a stepover apart for the rest of the target leave exactly
    /// the target over it.
    #[test]
    fn the_ball_stands_off_a_prism_bores_creases_by_the_closed_form() {
        let (sides, bore_radius, height) = (42u32, 2.5, 3.0);
        let mut positions = Vec::new();
        for k in 0..sides {
            let angle = 2.0 * std::f64::consts::PI * f64::from(k) / f64::from(sides);
            let (s, c) = angle.sin_cos();
            positions.push(Point3::new(bore_radius * c, bore_radius * s, 0.0));
            positions.push(Point3::new(bore_radius * c, bore_radius * s, height));
        }
        let mut triangles = Vec::new();
        for k in 0..sides {
            let (a, b) = (2 * k, 2 * ((k + 1) % sides));
            // Wound to face the axis.
            triangles.push([a, a + 1, b]);
            triangles.push([b, a + 1, b + 1]);
        }
        let wall = Mesh {
            positions,
            triangles,
        };
        let normals: Vec<Vector3> = (0..wall.triangles.len())
            .map(|t| wall.face_normal(t))
            .collect();
        let centroid = wall.corners(0).iter().map(|p| p.coords).sum::<Vector3>() / 3.0;
        assert!(normals[0].dot(&centroid) < 0.0, "the wall faces the axis");
        let radius = 2.0;
        let half_turn = std::f64::consts::PI / f64::from(sides);
        let standoff = crease_standoff(&wall, &normals, radius);
        assert!((standoff - radius * (1.0 / half_turn.cos() - 1.0)).abs() < 1e-12);
        // The crease at angle 0 on the x axis; the balls touching both facets beside it stand
        // on the x axis, r + standoff from the crease toward the axis, a stepover apart.
        let scallop = 0.01;
        let step = stepover_for_scallop(radius, scallop - standoff);
        let centre = |z: f64| Point3::new(bore_radius - (radius + standoff), 0.0, z);
        for centre in [centre(1.0), centre(1.0 + step)] {
            let clear = (0..wall.triangles.len()).all(|t| {
                let [a, ..] = wall.corners(t);
                (centre - a).dot(&normals[t]) >= radius - 1e-9
            });
            assert!(
                clear,
                "the ball in the crease stays off every facet's plane"
            );
        }
        // Halfway between them, a ray from the crease toward the axis enters the balls the
        // target in.
        let crease = Point3::new(bore_radius, 0.0, 1.0 + 0.5 * step);
        let inward = -Vector3::x();
        let to_centre = centre(1.0) - crease;
        let along = to_centre.dot(&inward);
        let off_squared = to_centre.norm_squared() - along * along;
        let entry = along - (radius * radius - off_squared).sqrt();
        assert!((entry - scallop).abs() < 1e-9, "{entry}");
    }
}
