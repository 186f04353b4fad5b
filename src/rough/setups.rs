//! Indexed setups proposed from the visibility maps (DESIGN.md §3.5; seed 004 ch. 5 step 4,
//! Chen & Woo's maps): which fixed tilted tool axes see the rest the vertical layers left, and
//! the fewest of them that see most of it, for [`super::indexed`] to rough along.
//!
//! Each point of rest (a place on the part with material standing on it, weighted by how much)
//! gets a visibility map over a near-uniform direction set, its rays starting off the surface
//! by the tool's radius (what a tool centre there sees, not the surface point). A point the
//! vertical already sees is left out: the vertical layers were there, and what they left is
//! for a smaller tool, not another axis. A direction counts for a point only when the point
//! also sees the direction's neighbours on the set's sphere mesh, so the axis has a cone of
//! room about it rather than a grazing line of sight. Then greedily: the allowed direction
//! that sees the most weight not yet seen becomes a setup, what it sees is taken as seen, and
//! so on while a setup would see at least `min_share` of the whole. Ties go to the lower
//! direction index, so the proposal is the same on every run and thread count.

use crate::access::RayScene;
use crate::access::directions::DirectionSet;
use crate::access::visibility::{
    SurfacePoint, VisibilityError, VisibilityOptions, visibility_hierarchical,
};
use crate::geom::{Point3, Vector3};

/// A place with rest on it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RestPoint {
    pub point: Point3,
    /// Outward normal of the part there (any non-zero length).
    pub normal: Vector3,
    /// How much rest it stands for (mm of rest × mm² of surface).
    pub weight: f64,
}

/// What the proposal may choose from.
#[derive(Clone, Debug, PartialEq)]
pub struct SetupOptions {
    pub max_setups: usize,
    /// Axes at least this far from the vertical, degrees (nearer ones see what it sees).
    pub min_tilt_deg: f64,
    /// Axes at most this far from the vertical, degrees.
    pub max_tilt_deg: f64,
    /// A setup must see at least this share of the rest's whole weight.
    pub min_share: f64,
    /// Level of the direction set (3: 642 directions, about 8° apart).
    pub level: usize,
    /// How far off the surface the rays start, mm.
    pub lift: f64,
}

/// One proposed setup.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct ProposedSetup {
    /// The tool axis, part frame, unit.
    pub axis: [f64; 3],
    pub tilt_deg: f64,
    /// Share of the rest's weight this setup sees that no setup before it did.
    pub share: f64,
    /// Rest points it sees first.
    pub points: usize,
    /// Their indices in the proposal's input.
    #[serde(skip)]
    pub seen: Vec<usize>,
}

/// What the proposal saw.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Proposal {
    pub setups: Vec<ProposedSetup>,
    /// Rest points in all, and those the vertical already sees (left out).
    pub rest_points: usize,
    pub seen_from_vertical: usize,
    /// Share of the whole weight no direction within the tilt limits sees with room about it.
    pub unseen_share: f64,
    /// Share seen with room only along directions the machine cannot take.
    pub beyond_machine_share: f64,
}

/// Proposes setups for `points` on the part `scene` holds; `allowed` says which axes the
/// machine can take (module docs).
pub fn propose_setups(
    scene: &RayScene,
    points: &[RestPoint],
    allowed: impl Fn(&Vector3) -> bool,
    options: &SetupOptions,
) -> Result<Proposal, VisibilityError> {
    let set = DirectionSet::new(options.level);
    let level = options.level.min(set.levels() - 1);
    let count = set.count(level);
    let surface: Vec<SurfacePoint> = points
        .iter()
        .map(|p| SurfacePoint {
            point: p.point,
            normal: p.normal,
        })
        .collect();
    let maps = visibility_hierarchical(
        scene,
        &set,
        &surface,
        &VisibilityOptions::default()
            .with_level(level)
            .with_lift(options.lift),
    )?;
    let directions = &set.directions()[..count];
    let up = set.nearest(level, &Vector3::z());
    let (min_cos, max_cos) = (
        options.max_tilt_deg.to_radians().cos(),
        options.min_tilt_deg.to_radians().cos(),
    );
    let in_tilt: Vec<usize> = (0..count)
        .filter(|&i| {
            let d = directions[i].normalize();
            d.z >= min_cos && d.z <= max_cos
        })
        .collect();
    let candidates: Vec<usize> = in_tilt
        .iter()
        .copied()
        .filter(|&i| allowed(&directions[i].normalize()))
        .collect();
    // Per point, the candidates it sees with room about them.
    let roomy = |map: &crate::access::directions::VisibilityMap, i: usize| {
        map.contains(i)
            && set
                .neighbours(level, i)
                .iter()
                .all(|&n| map.contains(n as usize))
    };
    let total: f64 = points.iter().map(|p| p.weight).sum();
    let mut seen_from_vertical = 0;
    let mut open: Vec<(usize, f64, Vec<usize>)> = Vec::new();
    let (mut unseen, mut beyond_machine) = (0.0, 0.0);
    for (index, (p, map)) in points.iter().zip(&maps.maps).enumerate() {
        if map.contains(up) {
            seen_from_vertical += 1;
            continue;
        }
        let sees: Vec<usize> = (0..candidates.len())
            .filter(|&k| roomy(map, candidates[k]))
            .collect();
        if sees.is_empty() {
            if in_tilt.iter().any(|&i| roomy(map, i)) {
                beyond_machine += p.weight;
            } else {
                unseen += p.weight;
            }
        } else {
            open.push((index, p.weight, sees));
        }
    }
    let mut setups = Vec::new();
    while setups.len() < options.max_setups && !open.is_empty() {
        let mut score = vec![0.0; candidates.len()];
        for (_, weight, sees) in &open {
            for &k in sees {
                score[k] += weight;
            }
        }
        let Some(best) =
            (0..candidates.len()).reduce(|a, b| if score[b] > score[a] { b } else { a })
        else {
            break;
        };
        if total <= 0.0 || score[best] < options.min_share * total {
            break;
        }
        let (seen, rest): (Vec<_>, Vec<_>) = open
            .into_iter()
            .partition(|(_, _, sees)| sees.contains(&best));
        open = rest;
        let d = directions[candidates[best]].normalize();
        setups.push(ProposedSetup {
            axis: [d.x, d.y, d.z],
            tilt_deg: d.z.clamp(-1.0, 1.0).acos().to_degrees(),
            share: score[best] / total,
            points: seen.len(),
            seen: seen.into_iter().map(|(index, _, _)| index).collect(),
        });
    }
    let share = |w: f64| if total > 0.0 { w / total } else { 0.0 };
    Ok(Proposal {
        setups,
        rest_points: points.len(),
        seen_from_vertical,
        unseen_share: share(unseen),
        beyond_machine_share: share(beyond_machine),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::fixtures::{box_between, joined};

    /// A shelf over a floor, walled but towards +x: the floor under the shelf is hidden from above
    /// and seen only along axes leaning towards +x. The proposal's one setup leans that way,
    /// within the tilt allowed, and sees every point; points out in the open are seen from
    /// the vertical and left out.
    #[test]
    fn a_shelf_gets_a_setup_leaning_out_from_under_it() {
        let scene = RayScene::new(&joined([
            box_between(
                Point3::new(-20.0, -20.0, -2.0),
                Point3::new(20.0, 20.0, 0.0),
            ),
            box_between(
                Point3::new(-20.0, -20.0, 0.0),
                Point3::new(-16.0, 20.0, 14.0),
            ),
            box_between(
                Point3::new(-16.0, -20.0, 10.0),
                Point3::new(0.0, 20.0, 14.0),
            ),
            box_between(
                Point3::new(-16.0, -20.0, 0.0),
                Point3::new(0.0, -16.0, 10.0),
            ),
            box_between(Point3::new(-16.0, 16.0, 0.0), Point3::new(0.0, 20.0, 10.0)),
        ]));
        let under: Vec<RestPoint> = (0..5)
            .flat_map(|i| (0..5).map(move |j| (i, j)))
            .map(|(i, j)| RestPoint {
                point: Point3::new(-12.0 + 2.0 * i as f64, -4.0 + 2.0 * j as f64, 0.0),
                normal: Vector3::z(),
                weight: 1.0,
            })
            .collect();
        let open = RestPoint {
            point: Point3::new(10.0, 0.0, 0.0),
            normal: Vector3::z(),
            weight: 1.0,
        };
        let mut points = under.clone();
        points.push(open);
        let options = SetupOptions {
            max_setups: 3,
            min_tilt_deg: 10.0,
            max_tilt_deg: 80.0,
            min_share: 0.05,
            level: 3,
            lift: 1.0,
        };
        let proposal = propose_setups(&scene, &points, |_| true, &options).unwrap();
        assert_eq!(proposal.seen_from_vertical, 1);
        assert_eq!(proposal.setups.len(), 1, "{proposal:?}");
        let setup = &proposal.setups[0];
        assert!(setup.axis[0] > 0.5, "{setup:?}");
        assert!(setup.tilt_deg <= 80.0 && setup.tilt_deg >= 10.0);
        assert_eq!(setup.points, under.len());
        // Held to 45°, the shelf's points furthest in see no axis: no setup sees them all.
        let steep = SetupOptions {
            max_tilt_deg: 45.0,
            ..options.clone()
        };
        let held = propose_setups(&scene, &points, |_| true, &steep).unwrap();
        assert!(held.setups.iter().all(|s| s.tilt_deg <= 45.0 + 1e-9));
        assert!(held.unseen_share > 0.0, "{held:?}");
        // A machine that cannot lean towards +x gets no setup.
        let none = propose_setups(&scene, &points, |d| d.x < 0.0, &options).unwrap();
        assert!(none.setups.is_empty(), "{none:?}");
        assert!(
            (none.beyond_machine_share - 25.0 / 26.0).abs() < 1e-12,
            "{none:?}"
        );
        assert_eq!(none.unseen_share, 0.0);
    }
}
