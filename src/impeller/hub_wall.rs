//! Loops round an impeller's hub walls: the bore, facing the rotation axis, and the rim,
//! facing away from it. The parallel planes cannot finish a bore (their axes lean at most so
//! far from the surface's normal, and in a bore any such lean runs the tool into the far
//! wall), and they cross a rim at a slant, their passes on it a stepover apart only where
//! the wall faces across them (elsewhere millimetres); a tool standing along the axis, its
//! ball's side against the wall, finishes either. The wall is a surface of revolution about
//! the axis: its curves of constant height are circles round it (broken where a keyway cuts
//! the wall), a stepover apart along the wall where it stands square to the hub (height
//! steps of the stepover times the wall's steepness there, its low percentile, as round a
//! blade).
//!
//! A bore read from a mesh is a prism of facets, and the ball cannot follow it into the
//! creases between them: touching two facets that turn by θ, it stands r·(1/cos(θ/2) − 1) off
//! the crease (0.002 mm for a 2 mm ball in the blower's bore, its facets turning by 5.3°).
//! The stepover is the one that leaves the rest of the target between the loops there.

use crate::geom::{Point3, Vector3, stepover_for_scallop, weighted_quantile};
use crate::mesh::topology::edges;
use crate::mesh::{Mesh, SectionCurve, level_section};

use super::frame::AxisFrame;
use super::recognise::{Impeller, Region};

/// Which of the hub's walls round the axis.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HubWall {
    /// The inner wall, facing the axis.
    Bore,
    /// The outer wall, facing away from it.
    Rim,
}

/// A wall triangle faces the axis (or away from it): its normal's component that way at
/// least this.
const FACING_AXIS: f64 = 0.8;

/// ... and stands within this of the hub's smallest (largest) radius, mm.
const NEAR_WALL_RADIUS: f64 = 2.0;

/// Facets of the wall that turn by less than this are the tessellation of one round wall;
/// more, and the crease is a feature (a keyway's corner), where the ball does not fit anyway.
const FACETTING_TURN_DEG: f64 = 20.0;

/// The crease standoff takes at most this share of the scallop target: a coarser
/// tessellation would need loops closer than any finish is worth.
const MAX_STANDOFF_SHARE: f64 = 0.75;

/// The loops round a hub wall, from the top down, and which triangles of the part are the
/// wall.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct WallLoops {
    pub curves: Vec<SectionCurve>,
    /// Per triangle of the part: on the wall.
    pub wall: Vec<bool>,
    /// Area of the wall, mm², and its height along the axis, mm.
    pub area_mm2: f64,
    pub height_mm: f64,
    pub level_step: f64,
    /// How far the ball stands off the deepest crease between the wall's facets, mm.
    pub crease_standoff_mm: f64,
}

/// The loops round `impeller`'s hub `wall` in `mesh` for a ball of `radius`, levels apart
/// along the wall by the stepover that leaves `scallop` between them, in the wall's creases
/// too; empty when the hub has no such wall.
pub fn wall_loops(
    mesh: &Mesh,
    impeller: &Impeller,
    frame: &AxisFrame,
    hub_wall: HubWall,
    radius: f64,
    scallop: f64,
) -> WallLoops {
    let [inner, outer] = impeller.hub_radius_mm;
    let wall: Vec<bool> = (0..mesh.triangles.len())
        .map(|t| {
            if impeller.regions[t] != Region::Hub {
                return false;
            }
            let [a, b, c] = mesh.corners(t);
            let centroid = Point3::from((a.coords + b.coords + c.coords) / 3.0);
            let (r, angle, _) = frame.cylindrical(&centroid);
            let outward = mesh.face_normal(t).dot(&frame.radial(angle));
            match hub_wall {
                HubWall::Bore => r <= inner + NEAR_WALL_RADIUS && -outward >= FACING_AXIS,
                HubWall::Rim => r >= outer - NEAR_WALL_RADIUS && outward >= FACING_AXIS,
            }
        })
        .collect();
    let wall_mesh = Mesh::compacted(
        &mesh.positions,
        mesh.triangles
            .iter()
            .zip(&wall)
            .filter(|(_, w)| **w)
            .map(|(t, _)| *t),
    );
    if wall_mesh.triangles.is_empty() {
        return WallLoops::default();
    }
    let normals: Vec<Vector3> = (0..wall_mesh.triangles.len())
        .map(|t| wall_mesh.face_normal(t))
        .collect();
    let height: Vec<f64> = wall_mesh
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
                let [a, b, c] = wall_mesh.corners(t);
                0.5 * (b - a).cross(&(c - a)).norm()
            })
        })
        .collect();
    let least = weighted_quantile(steepness, 0.1).unwrap_or(1.0);
    let standoff = crease_standoff(&wall_mesh, &normals, radius).min(MAX_STANDOFF_SHARE * scallop);
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
        curves.extend(level_section(&wall_mesh, &normals, &shifted));
    }
    WallLoops {
        curves,
        area_mm2: wall_mesh.surface_area(),
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

    /// The sample's `hub_wall`: every loop runs round the wall at its level, on a circle
    /// about the axis whose radius is within `radii` (whole from the last on), the levels no
    /// more than a stepover apart and covering the wall from top to bottom within half a step.
    fn sample_wall_gets_circles_a_stepover_apart(
        hub_wall: HubWall,
        radii: fn(&Impeller) -> (f64, f64, f64),
    ) {
        let mesh = crate::sample::impeller(&Default::default()).expect("sample impeller");
        let impeller = recognise(&mesh, &RecogniseOptions::default()).expect("an impeller");
        let frame = AxisFrame::new(impeller.centre.into(), &Vector3::from(impeller.axis));
        let (least, full_circles_from, most) = radii(&impeller);
        let (radius, scallop) = (2.0, 0.01);
        let loops = wall_loops(&mesh, &impeller, &frame, hub_wall, radius, scallop);
        assert!(!loops.curves.is_empty());
        let stepover = stepover_for_scallop(radius, scallop - loops.crease_standoff_mm);
        assert!(loops.level_step <= stepover + 1e-12 && loops.level_step > 0.75 * stepover);
        let (mut low, mut high) = (f64::INFINITY, f64::NEG_INFINITY);
        for (t, on) in loops.wall.iter().enumerate() {
            if !on {
                continue;
            }
            for p in mesh.corners(t) {
                let (_, _, height) = frame.cylindrical(&p);
                (low, high) = (low.min(height), high.max(height));
            }
        }
        let mut levels: Vec<f64> = Vec::new();
        for curve in &loops.curves {
            let (circle, _, level) = frame.cylindrical(&curve.points[0].point);
            assert!((least..=most).contains(&circle), "{circle}");
            for p in &curve.points {
                let (r, _, height) = frame.cylindrical(&p.point);
                assert!((r - circle).abs() < 0.05, "{r} on a circle of {circle}");
                assert!((height - level).abs() < 1e-6);
                assert!(p.normal.dot(&frame.axis).abs() < 0.6);
            }
            levels.push(level);
            // A full circle on the wall itself (the sample's walls have no keyway); where the
            // hub's top falls to the rim steeply, the blades' roots break it.
            if circle < full_circles_from {
                continue;
            }
            let length: f64 = curve
                .points
                .windows(2)
                .map(|w| (w[1].point - w[0].point).norm())
                .sum();
            let round = 2.0 * std::f64::consts::PI * circle;
            assert!(
                curve.closed && (length - round).abs() < 0.05 * round,
                "{length}"
            );
        }
        levels.sort_by(f64::total_cmp);
        levels.dedup_by(|a, b| (*a - *b).abs() < 1e-6);
        assert!(levels.windows(2).all(|w| w[1] - w[0] <= stepover + 1e-9));
        assert!(levels[0] - low <= 0.5 * loops.level_step + 1e-9);
        assert!(high - levels[levels.len() - 1] <= 0.5 * loops.level_step + 1e-9);
    }

    /// The sample's bore: radius 8, the hub 12 mm tall there.
    #[test]
    fn the_sample_bore_gets_circles_a_stepover_apart_from_top_to_bottom() {
        sample_wall_gets_circles_a_stepover_apart(HubWall::Bore, |_| (7.95, 7.95, 8.05));
    }

    /// The sample's rim: the hub's outer wall, at the radius recognised, and where the hub's
    /// top falls to it steeply.
    #[test]
    fn the_sample_rim_gets_circles_a_stepover_apart_from_top_to_bottom() {
        sample_wall_gets_circles_a_stepover_apart(HubWall::Rim, |impeller| {
            let outer = impeller.hub_radius_mm[1];
            (outer - NEAR_WALL_RADIUS, outer - 0.05, outer + 0.05)
        });
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
