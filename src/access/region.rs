//! One tool axis for a region from its points' visibility maps (seed 004 ch. 5 step 4: the
//! region's map is the intersection of its points' maps; an axis inside it reaches them all).
//!
//! Of the directions every point sees, the one with the most room is taken: farthest, in steps
//! over the direction set's sphere mesh, from any direction some point does not see — the
//! tool has a shank and a holder around its axis, and the smoothing and the chooser turn it a
//! little; ties go to the direction nearest the one the caller prefers. Where no direction is
//! seen from every point, the directions seen from the most points stand in for the region.
//!
//! With a ball end the cusp height does not depend on the axis (seed 004 step 5 chooses among
//! visible axes for the least cusp, which matters for flat and toroidal ends), so room is
//! what decides here.

use std::collections::VecDeque;

use super::directions::{DirectionSet, VisibilityMap};
use crate::geom::Vector3;

/// The axis chosen for a region, and how well it is seen.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RegionAxis {
    /// Unit direction.
    pub direction: Vector3,
    /// Points whose map holds the direction, out of all points.
    pub seen_by: usize,
    pub points: usize,
    /// Directions of the set seen from every point (0 when the fallback chose).
    pub region_directions: usize,
    /// Steps over the direction set's sphere mesh from the direction to the nearest one not
    /// in the region (or not seen by as many points), 0 on its border.
    pub room_steps: usize,
}

/// The axis with the most room among the directions of `level` seen from the most of `maps`
/// (all of them where possible), ties to the nearest to `prefer`; `None` when no point sees
/// any direction (or there are no maps).
pub fn region_axis(
    set: &DirectionSet,
    level: usize,
    maps: &[VisibilityMap],
    prefer: &Vector3,
) -> Option<RegionAxis> {
    let count = set.count(level);
    let mut seen = vec![0usize; count];
    for map in maps {
        for (i, s) in seen.iter_mut().enumerate() {
            *s += usize::from(map.contains(i));
        }
    }
    let most = seen.iter().copied().max().filter(|&m| m > 0)?;
    let inside: Vec<bool> = seen.iter().map(|&s| s == most).collect();

    // Steps from outside: a breadth-first walk from every direction not inside.
    let mut steps = vec![usize::MAX; count];
    let mut queue: VecDeque<usize> = (0..count).filter(|&i| !inside[i]).collect();
    for &i in &queue {
        steps[i] = 0;
    }
    while let Some(i) = queue.pop_front() {
        for &j in set.neighbours(level, i) {
            let j = j as usize;
            if steps[j] == usize::MAX {
                steps[j] = steps[i] + 1;
                queue.push_back(j);
            }
        }
    }
    let directions = set.directions();
    // The whole sphere seen: no border, every direction has all the room there is.
    let room = |i: usize| {
        if steps[i] == usize::MAX {
            count
        } else {
            steps[i]
        }
    };
    let best = (0..count).filter(|&i| inside[i]).max_by(|&a, &b| {
        room(a)
            .cmp(&room(b))
            .then(
                directions[a]
                    .dot(prefer)
                    .total_cmp(&directions[b].dot(prefer)),
            )
            // Equal room and equally near: the lower index, so the answer is deterministic.
            .then(b.cmp(&a))
    })?;
    Some(RegionAxis {
        direction: directions[best],
        seen_by: most,
        points: maps.len(),
        region_directions: if most == maps.len() {
            inside.iter().filter(|&&x| x).count()
        } else {
            0
        },
        room_steps: room(best).saturating_sub(1),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Maps holding the directions within `half_angle` of `centre` (a cone of visibility, as
    /// from the bottom of a round well).
    fn cone(set: &DirectionSet, level: usize, centre: &Vector3, half_angle: f64) -> VisibilityMap {
        let mut map = VisibilityMap::empty(set.count(level));
        for (i, d) in set.directions()[..set.count(level)].iter().enumerate() {
            map.set(i, d.dot(centre) >= half_angle.cos());
        }
        map
    }

    /// Two overlapping cones: the axis is in both and in the middle of their overlap, whatever
    /// the preferred direction; it matches a brute-force search for the overlap's centre
    /// within the set's spacing.
    #[test]
    fn two_cones_give_the_middle_of_their_overlap() {
        let set = DirectionSet::new(4);
        let level = 4;
        let a = Vector3::new(0.3, 0.0, 1.0).normalize();
        let b = Vector3::new(-0.3, 0.1, 1.0).normalize();
        let maps = [cone(&set, level, &a, 0.6), cone(&set, level, &b, 0.6)];
        for prefer in [Vector3::x(), Vector3::z(), -Vector3::y()] {
            let axis = region_axis(&set, level, &maps, &prefer).expect("an overlap");
            assert_eq!((axis.seen_by, axis.points), (2, 2));
            assert!(axis.region_directions > 0);
            let d = axis.direction;
            // The overlap of two equal cones is symmetric about their bisector.
            let middle = (a + b).normalize();
            assert!(d.dot(&middle).acos() < 0.12, "{d} vs {middle}");
            for c in [a, b] {
                assert!(d.dot(&c) >= 0.6f64.cos());
            }
        }
    }

    /// Disjoint cones: nothing is seen from every point, so the most-seen directions stand in
    /// (here one cone, seen from two of three points), and the preferred direction breaks the
    /// tie between cones seen equally often.
    #[test]
    fn without_a_common_direction_the_most_seen_stand_in() {
        let set = DirectionSet::new(3);
        let level = 3;
        let (up, side) = (Vector3::z(), Vector3::x());
        let maps = [
            cone(&set, level, &up, 0.3),
            cone(&set, level, &up, 0.3),
            cone(&set, level, &side, 0.3),
        ];
        let axis = region_axis(&set, level, &maps, &side).expect("most seen");
        assert_eq!((axis.seen_by, axis.region_directions), (2, 0));
        assert!(axis.direction.dot(&up) > 0.99);
        // Opposite cones: the icosphere is symmetric through its centre, so both have the
        // same room.
        let tie = [cone(&set, level, &up, 0.3), cone(&set, level, &-up, 0.3)];
        for prefer in [up, -up] {
            let axis = region_axis(&set, level, &tie, &prefer).expect("most seen");
            assert!(axis.direction.dot(&prefer) > 0.99);
        }
        assert!(region_axis(&set, level, &[VisibilityMap::empty(set.count(level))], &up).is_none());
        assert!(region_axis(&set, level, &[], &up).is_none());
    }
}
