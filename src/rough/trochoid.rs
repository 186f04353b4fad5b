//! Engagement held down in slots and at concave corners: the stretches of a layer's pass that
//! would take a wider band of uncut material than `max_engagement` are cut as trochoidal loops
//! instead of straight through.
//!
//! Contour-parallel passes engage one stepover where the pass before them lies a stepover
//! away. They engage more in two places: at a sharp concave corner of the region, where
//! consecutive offsets' corners lie s / sin(θ/2) apart along the bisector (θ the corner's
//! angle), and along the first pass cut into a region that was not opened before — the
//! farthest level between two blades, a full slot of the tool's diameter. The material map of
//! the layer ([`MaterialMap`]) tells where: the pass is replayed on a copy of it, and each
//! stamp's fresh area averaged over a tool radius of travel (as the layer reports engagement)
//! marks the stretches above the bound.
//!
//! Each such stretch, from its first heavy stamp to half a radius past its last, becomes
//! loops: the tool spirals out from the pass to a loop radius ρ at most `pitch` further per
//! turn, circles counter-clockwise — the material ahead on the cutter's right, climb with an
//! M3 spindle — while the loop's centre advances `pitch` per turn along the pass, and spirals
//! back onto the pass at the stretch's end. Each turn then takes a crescent about a pitch thick. ρ is at most r/2 (a
//! slot one and a half diameters wide, the usual trochoidal rule): larger loops travel
//! farther for the same crescent (measured on the sample impeller: loops of r took 42 % longer
//! than loops of r/2 for a higher peak engagement).
//!
//! Where each loop goes is decided point by point along the stretch (`loops_for`):
//! centred on the pass where it lies more than ρ + r (+ `margin`) from the regions the tool
//! must keep r from (the part; what the shank must not touch); else moved away from the
//! nearest of them by up to ρ; else the largest loop that, moved off the nearest wall by its
//! own radius and the margin, keeps r from every wall — a pass along the wall itself is cut by
//! loops that touch the wall's offset from the open side, leaving at most the margin on it;
//! else (less room than `min_loop_radius`: a sharp concave corner, a channel narrower than the
//! tool and a loop) straight along the pass, counted. With ρ ≤ r and the loop at most ρ off
//! the pass, the loops sweep everything the straight pass would have. Every loop is checked
//! against those regions exactly, segment by segment, to come no nearer than r (or than the
//! pass itself does); where they fail, the pass is cut straight at those samples, growing
//! until the loops clear, else the loops are planned smaller. The pitch starts at the
//! bound and shrinks until the loops' own engagement, replayed on the map, keeps within it
//! (down to 0.3 of the bound; the layer reports what it measures).

use crate::contour::geometry::{Point2, Segment, Vector2};
use crate::contour::material::{MaterialMap, Window};
use crate::contour::region::RegionIndex;
use crate::rough::moves::{point_along, polyline_length, walk};

/// How the heavy stretches are looped.
#[derive(Clone, Debug, PartialEq)]
pub struct LoopOptions {
    /// Radial engagement above which a stretch is looped, mm (averaged over a tool radius of
    /// travel).
    pub max_engagement: f64,
    /// Largest loop radius, mm.
    pub max_loop_radius: f64,
    /// Smallest loop radius worth looping, mm: with less room the stretch stays straight.
    pub min_loop_radius: f64,
    /// Kept between the loops and the regions the tool stays r from, beyond r, mm.
    pub margin: f64,
    /// Farthest a loop's sides stray inside its circle, mm (how many points a turn has).
    pub sagitta: f64,
}

impl LoopOptions {
    /// Loops for a tool of radius `r` holding `max_engagement`: loop radius up to r/2 (a
    /// slot of 3r, the trochoidal milling rule of 1.5 diameters; larger loops travel farther
    /// for the same crescent), down to r/4, sides within 0.1 mm of the circle (fewer moves
    /// for the stock simulation to sweep; the loops are in cleared space), 0.05 mm margin.
    pub fn for_radius(r: f64, max_engagement: f64) -> LoopOptions {
        LoopOptions {
            max_engagement,
            max_loop_radius: 0.5 * r,
            min_loop_radius: 0.25 * r,
            margin: 0.05,
            sagitta: 0.1,
        }
    }
}

/// A pass with its heavy stretches looped.
#[derive(Clone, Debug, PartialEq)]
pub struct Looped {
    pub points: Vec<Point2>,
    /// Stretches cut as loops, and their length along the pass, mm.
    pub stretches: usize,
    pub looped_mm: f64,
    /// Length of the over-engaged stretches left straight for want of room, mm.
    pub unlooped_mm: f64,
}

/// The pass `points` (tool centre at radius `r`) as it should be cut from the material `map`
/// holds: unchanged where its engagement keeps within the bound, looped where it would not
/// and there is room. `keep_off`: the regions the tool centre must stay more than r from.
pub fn loop_heavy_stretches(
    points: &[Point2],
    map: &MaterialMap,
    keep_off: &[&RegionIndex],
    r: f64,
    options: &LoopOptions,
) -> Looped {
    let unchanged = Looped {
        points: points.to_vec(),
        stretches: 0,
        looped_mm: 0.0,
        unlooped_mm: 0.0,
    };
    if points.len() < 2 {
        return unchanged;
    }
    let heavy = heavy_stretches(points, map, r, options.max_engagement);
    if heavy.is_empty() {
        return unchanged;
    }
    let mut out = vec![points[0]];
    let mut looped = Looped {
        points: Vec::new(),
        stretches: 0,
        looped_mm: 0.0,
        unlooped_mm: 0.0,
    };
    // The map as the tool leaves each piece written so far.
    let mut state = map.clone();
    let mut at = 0.0;
    for (a, b) in heavy {
        let stretch = sub_polyline(points, a, b);
        let before = sub_polyline(points, at, a);
        cut_along(&mut state, &before);
        out.extend_from_slice(&before[1..]);
        match loops_for(&stretch, &state, keep_off, r, options) {
            Some((loops, straight)) => {
                cut_along(&mut state, &loops);
                out.extend_from_slice(&loops[1..]);
                looped.stretches += 1;
                looped.looped_mm += b - a - straight;
                looped.unlooped_mm += straight;
            }
            None => {
                looped.unlooped_mm += b - a;
                cut_along(&mut state, &stretch);
                out.extend_from_slice(&stretch[1..]);
            }
        }
        at = b;
    }
    let length = polyline_length(points);
    out.extend_from_slice(&sub_polyline(points, at, length)[1..]);
    out.dedup_by(|p, q| (*p - *q).norm() < 1e-9);
    // Nothing looped: the pass as it came, without the points the stretches split it at.
    looped.points = if looped.stretches == 0 {
        points.to_vec()
    } else {
        out
    };
    looped
}

/// The stretches [a, b] along `points` (distances from its start) whose engagement, averaged
/// over a radius of travel about each stamp, exceeds `bound`; each from the first heavy
/// stamp to r/2 past the last, and merged with a neighbour less than r away.
fn heavy_stretches(points: &[Point2], map: &MaterialMap, r: f64, bound: f64) -> Vec<(f64, f64)> {
    let mut copy = map.clone();
    // (distance along the pass at the stamp, cumulative fresh area there)
    let mut stamps: Vec<(f64, f64)> = vec![(0.0, 0.0)];
    let (mut along, mut area) = (0.0, 0.0);
    for w in points.windows(2) {
        copy.cut_stamps(
            &Segment::Line {
                start: w[0],
                end: w[1],
            },
            |fresh, advance, _| {
                along += advance;
                area += fresh;
                stamps.push((along, area));
            },
        );
    }
    let total = along;
    // Area cleared by the stamps with distance in (lo, hi], by binary search.
    let area_to = |d: f64| {
        let k = stamps.partition_point(|s| s.0 <= d);
        stamps[k.saturating_sub(1)].1
    };
    let half = 0.5 * r;
    let mut stretches: Vec<(f64, f64)> = Vec::new();
    for &(d, _) in &stamps[1..] {
        let (lo, hi) = ((d - half).max(0.0), (d + half).min(total));
        if hi - lo < 1e-9 {
            continue;
        }
        let engagement = (area_to(hi) - area_to(lo)) / (hi - lo);
        if engagement <= bound {
            continue;
        }
        // From the first heavy stamp: its window is heavy for the material in its front
        // half, still ahead of the tool. (Starting a radius earlier, in the slot already cut,
        // took 5 % longer on the sample for no lower peak.)
        let (a, b) = (d, (d + half).min(total));
        match stretches.last_mut() {
            Some(last) if a - last.1 < r => last.1 = last.1.max(b),
            _ => stretches.push((a, b)),
        }
    }
    stretches
}

/// The part of the polyline from distance `a` to `b` along it (a ≤ b), with its end points.
fn sub_polyline(points: &[Point2], a: f64, b: f64) -> Vec<Point2> {
    let mut out = vec![point_along(points, a)];
    out.extend(walk(points, a, b).into_iter().map(|(p, _)| p));
    out.dedup_by(|p, q| (*p - *q).norm() < 1e-12);
    if out.len() == 1 {
        out.push(out[0]);
    }
    out
}

/// Takes the moves along `points` off the map.
fn cut_along(map: &mut MaterialMap, points: &[Point2]) {
    for w in points.windows(2) {
        map.cut_stamps(
            &Segment::Line {
                start: w[0],
                end: w[1],
            },
            |_, _, _| {},
        );
    }
}

/// Loops along `stretch` that keep r off `keep_off` (checked segment by segment, exactly)
/// and whose engagement on `map` keeps within the bound, with the length of the stretch
/// along which no loop of `min_loop_radius` fits (cut straight there). The pitch shrinks from
/// the bound until the engagement holds (down to 0.3 of it, where the last try is taken as
/// it is); loops that fail the exact check are planned again smaller. `None` when no loop
/// fits anywhere along the stretch.
fn loops_for(
    stretch: &[Point2],
    map: &MaterialMap,
    keep_off: &[&RegionIndex],
    r: f64,
    options: &LoopOptions,
) -> Option<(Vec<Point2>, f64)> {
    let nearest_to = |points: &[Point2]| {
        keep_off
            .iter()
            .flat_map(|index| {
                points.windows(2).filter_map(|w| {
                    index
                        .boundary()
                        .nearest(&Segment::Line {
                            start: w[0],
                            end: w[1],
                        })
                        .map(|n| n.distance)
                })
            })
            .fold(f64::INFINITY, f64::min)
    };
    // The pass itself may lie a rounding nearer than r (the offsets are of the thinned
    // outline): the loops may come as near as it does, no nearer.
    let least = r.min(nearest_to(stretch)) - 1e-9;
    // The first segment of `points` that comes nearer than that, or starts inside.
    let first_unclear = |points: &[Point2]| {
        (0..points.len().saturating_sub(1)).find(|&i| {
            keep_off.iter().any(|index| {
                index.contains(points[i])
                    || index
                        .boundary()
                        .nearest(&Segment::Line {
                            start: points[i],
                            end: points[i + 1],
                        })
                        .is_some_and(|n| n.distance < least)
            })
        })
    };
    let nearest = |p: Point2| {
        keep_off
            .iter()
            .filter_map(|index| index.boundary().nearest_point(p))
            .min_by(|m, n| m.distance.total_cmp(&n.distance))
    };
    let inside = |p: Point2| keep_off.iter().any(|index| index.contains(p));
    let mut largest = options.max_loop_radius;
    while largest >= options.min_loop_radius {
        // Where a loop of the largest radius fits centred on the pass, there; else moved off
        // the nearest wall by up to its radius; else the largest loop that, moved off the
        // wall by its own radius and the margin (passing within the margin of the pass),
        // keeps r from every wall.
        let place = |b: Point2| -> (Point2, f64) {
            let Some(wall) = nearest(b).filter(|n| n.distance > 1e-9) else {
                return (b, largest);
            };
            let away = (b - wall.on_segment) / wall.distance;
            let room = |c: Point2| {
                if inside(c) {
                    0.0
                } else {
                    nearest(c).map_or(f64::INFINITY, |n| n.distance) - r
                }
            };
            let shift = (largest + r + options.margin - wall.distance).clamp(0.0, largest);
            let centre = b + away * shift;
            if room(centre) >= largest + options.margin {
                return (centre, largest);
            }
            let mut rho = largest;
            while rho >= options.min_loop_radius {
                // The margin off the wall's offset: the loop may leave that thin a skin on
                // the wall, and keeps off it though its centre moves along as it turns.
                let centre = b + away * (rho + options.margin);
                if room(centre) >= rho + 0.5 * options.margin {
                    return (centre, rho);
                }
                rho *= 0.85;
            }
            (b, 0.0)
        };
        let mut pitch = options.max_engagement;
        loop {
            // Where the loops come too near a wall between the points they were placed at
            // (the placement jumps, or the pass turns), the pass there is cut straight; the
            // straight stretch grows until the loops clear, or the loops are planned smaller
            // (no end to the growing).
            let mut straight_at = std::collections::BTreeSet::new();
            let mut cleared = None;
            for _ in 0..64 {
                let loops = trochoid(stretch, pitch, options, &place, &straight_at);
                let Some(i) = first_unclear(&loops.points) else {
                    cleared = Some(loops);
                    break;
                };
                let samples = [loops.sample[i], loops.sample[i + 1]];
                let before = straight_at.len();
                for m in samples {
                    straight_at.insert(m);
                    if straight_at.len() == before {
                        straight_at.insert(m + 1);
                        straight_at.insert(m.saturating_sub(1));
                    }
                }
                if straight_at.len() == before {
                    break;
                }
            }
            let Some(Loops {
                points: loops,
                straight,
                ..
            }) = cleared
            else {
                break;
            };
            if straight >= polyline_length(stretch) - 1e-9 {
                return None;
            }
            let mut copy = map.clone();
            let mut window = Window::without_values(r);
            cut_along_measured(&mut copy, &loops, &mut window);
            if window.max <= options.max_engagement || pitch <= 0.3 * options.max_engagement {
                return Some((loops, straight));
            }
            pitch *= 0.7;
        }
        largest *= 0.7;
    }
    None
}

/// Takes the moves along `points` off the map, measuring their engagement in `window`.
fn cut_along_measured(map: &mut MaterialMap, points: &[Point2], window: &mut Window) {
    for w in points.windows(2) {
        map.cut(
            &Segment::Line {
                start: w[0],
                end: w[1],
            },
            window,
        );
    }
    window.finish();
}

/// Loops along a stretch.
struct Loops {
    points: Vec<Point2>,
    /// Which sample along the stretch each point was placed about (the spirals: the first
    /// and the last).
    sample: Vec<usize>,
    /// Length of the stretch cut straight, mm.
    straight: f64,
}

/// The loops themselves: spiralling out from the stretch's start at most `pitch` per turn,
/// circling counter-clockwise about the centre and at the radius `place` gives each point of
/// the stretch while the point advances `pitch` per turn along it, spiralling back onto its
/// end within a turn. Straight along the stretch at the samples `straight_at` and where the
/// radius is below the smallest loop's. Starts and ends on the stretch.
fn trochoid(
    stretch: &[Point2],
    pitch: f64,
    options: &LoopOptions,
    place: &dyn Fn(Point2) -> (Point2, f64),
    straight_at: &std::collections::BTreeSet<usize>,
) -> Loops {
    let length = polyline_length(stretch);
    let rho = options.max_loop_radius;
    let half_step = (1.0 - options.sagitta / rho).clamp(-1.0, 1.0).acos();
    let per_turn = ((std::f64::consts::PI / half_step.max(1e-3)).ceil() as usize).clamp(8, 64);
    let turns_out = (options.max_loop_radius / pitch).ceil().max(1.0) as usize;
    let turns_along = ((length / pitch).ceil() as usize).max(1);
    let start_dir = stretch
        .windows(2)
        .map(|w| w[1] - w[0])
        .find(|d| d.norm() > 1e-9)
        .unwrap_or(Vector2::x());
    // The first loop leaves the pass to its right, the side a climb cut's material is on.
    let phase = start_dir.y.atan2(start_dir.x) - std::f64::consts::FRAC_PI_2;
    let step = std::f64::consts::TAU / per_turn as f64;
    let mut out = Vec::with_capacity((turns_out + turns_along + 1) * per_turn + 1);
    // Point k of the loops about the placement of `base`, grown to `grown` of it.
    let at_placed = |k: usize, base: Point2, (centre, rho): (Point2, f64), grown: f64| {
        let angle = phase + k as f64 * step;
        base + (centre - base) * grown + Vector2::new(angle.cos(), angle.sin()) * (rho * grown)
    };
    let at = |k: usize, base: Point2, grown: f64| at_placed(k, base, place(base), grown);
    let mut k = 0;
    let (first, last) = (stretch[0], stretch[stretch.len() - 1]);
    let steps_along = turns_along * per_turn;
    let out_steps = turns_out * per_turn;
    // The spirals belong to the stretch's first and last samples: cut straight, those have
    // none.
    if !straight_at.contains(&0) {
        for m in 0..out_steps {
            out.push(at(k, first, m as f64 / out_steps as f64));
            k += 1;
        }
    }
    let mut sample = vec![0; out.len()];
    let mut straight = 0.0;
    let mut previous: Option<f64> = None;
    for m in 0..steps_along {
        let along = length * m as f64 / steps_along as f64;
        let base = point_along(stretch, along);
        // Placed once (it was asked twice, to test the radius and to place the point).
        let placed = (!straight_at.contains(&m)).then(|| place(base));
        let Some(placed) = placed.filter(|(_, rho)| *rho >= options.min_loop_radius) else {
            straight += length / steps_along as f64;
            // Straight on from a straight sample: along the pass, through its corners (a
            // chord across a corner would cut in toward the wall the pass goes round).
            if let Some(from) = previous {
                let corners = walk(stretch, from, along);
                for (p, _) in &corners[..corners.len() - 1] {
                    out.push(*p);
                    sample.push(m);
                }
            }
            out.push(base);
            previous = Some(along);
            sample.push(m);
            k += 1;
            continue;
        };
        out.push(at_placed(k, base, placed, 1.0));
        previous = None;
        sample.push(m);
        k += 1;
    }
    if straight_at.contains(&(steps_along - 1)) {
        let from = length * (steps_along - 1) as f64 / steps_along as f64;
        for (p, _) in walk(stretch, from, length) {
            out.push(p);
            sample.push(steps_along - 1);
        }
    } else {
        for m in 0..=per_turn {
            out.push(at(k, last, 1.0 - m as f64 / per_turn as f64));
            sample.push(steps_along - 1);
            k += 1;
        }
    }
    Loops {
        points: out,
        sample,
        straight,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contour::geometry::Shape;

    fn rectangle(x0: f64, y0: f64, x1: f64, y1: f64) -> Shape {
        Shape {
            contours: vec![crate::rough::region::rectangle(
                Point2::new(x0, y0),
                Point2::new(x1, y1),
            )],
        }
    }

    /// The engagement of `points` cut on a copy of `map`, averaged over `r` of travel.
    fn max_engagement(points: &[Point2], map: &MaterialMap, r: f64) -> (f64, f64) {
        let mut copy = map.clone();
        let before = copy.material_area();
        let mut window = Window::without_values(r);
        for w in points.windows(2) {
            copy.cut(
                &Segment::Line {
                    start: w[0],
                    end: w[1],
                },
                &mut window,
            );
        }
        window.finish();
        (window.max, before - copy.material_area())
    }

    /// A slot through a 60 × 40 block of solid with r = 3: the straight pass takes the whole
    /// diameter; looped, no window takes more than the bound, and the loops clear the slot's
    /// width and more. The loops keep their radius plus r off the walls they were given.
    #[test]
    fn a_slot_through_solid_is_looped_within_the_bound() {
        let r = 3.0;
        let stock = rectangle(0.0, 0.0, 60.0, 40.0);
        let map = MaterialMap::of_stock(&stock, None, r, r / 16.0).expect("map");
        let pass = [Point2::new(-5.0, 20.0), Point2::new(65.0, 20.0)];
        let (straight, straight_area) = max_engagement(&pass, &map, r);
        assert!(straight > 1.9 * r, "{straight}");
        let bound = 0.8 * r;
        // Walls 8.2 mm either side of the pass: loops of up to 8.2 − 3 − 0.05 mm.
        let walls = [
            rectangle(-10.0, 0.0, 70.0, 11.8),
            rectangle(-10.0, 28.2, 70.0, 40.0),
        ]
        .map(|s| RegionIndex::new(&s));
        let options = LoopOptions::for_radius(r, bound);
        let looped = loop_heavy_stretches(&pass, &map, &[&walls[0], &walls[1]], r, &options);
        assert_eq!(looped.stretches, 1);
        assert_eq!(looped.unlooped_mm, 0.0);
        assert!(looped.looped_mm > 59.0, "{}", looped.looped_mm);
        assert_eq!(looped.points[0], pass[0]);
        assert_eq!(*looped.points.last().expect("end"), pass[1]);
        let (engagement, area) = max_engagement(&looped.points, &map, r);
        assert!(engagement <= bound + 1e-9, "{engagement} > {bound}");
        assert!(area > straight_area, "{area} ≤ {straight_area}");
        for w in looped.points.windows(2) {
            for wall in &walls {
                let seg = Segment::Line {
                    start: w[0],
                    end: w[1],
                };
                let d = wall.boundary().nearest(&seg).expect("wall").distance;
                assert!(d >= r - 1e-9, "{d} at {:?}", w[0]);
                assert!(!wall.contains(w[0]));
            }
        }
        // Counter-clockwise loops: the direction of travel turns left, a full turn a loop.
        let turning: f64 = looped
            .points
            .windows(3)
            .map(|w| {
                let (u, v) = (w[1] - w[0], w[2] - w[1]);
                (u.x * v.y - u.y * v.x).atan2(u.dot(&v))
            })
            .sum();
        assert!(turning > std::f64::consts::TAU * 10.0, "{turning}");
    }

    /// A pass along a wall, exactly r off it, through solid: the loops move off the wall, keep
    /// r from it, and hold the bound; the pass is not left straight for want of room.
    #[test]
    fn a_pass_along_a_wall_is_looped_from_the_open_side() {
        let r = 3.0;
        let stock = rectangle(0.0, 0.0, 60.0, 40.0);
        let wall = rectangle(-10.0, -10.0, 70.0, 10.0);
        let map = MaterialMap::of_stock(&stock, Some(&wall), r, r / 16.0).expect("map");
        let pass = [Point2::new(-5.0, 10.0 + r), Point2::new(65.0, 10.0 + r)];
        let bound = r;
        let options = LoopOptions::for_radius(r, bound);
        let index = RegionIndex::new(&wall);
        let looped = loop_heavy_stretches(&pass, &map, &[&index], r, &options);
        assert_eq!((looped.stretches, looped.unlooped_mm), (1, 0.0));
        let (engagement, _) = max_engagement(&looped.points, &map, r);
        assert!(engagement <= bound + 1e-9, "{engagement} > {bound}");
        for w in looped.points.windows(2) {
            let seg = Segment::Line {
                start: w[0],
                end: w[1],
            };
            let d = index.boundary().nearest(&seg).expect("wall").distance;
            assert!(d >= r - 1e-9 && !index.contains(w[0]), "{d} at {:?}", w[0]);
        }
        // The loops keep to the open side: none goes below the pass.
        let lowest = looped
            .points
            .iter()
            .map(|p| p.y)
            .fold(f64::INFINITY, f64::min);
        assert!(lowest >= 10.0 + r - 1e-9, "{lowest}");
    }

    /// Where the walls leave less room than the smallest loop, the slot stays straight and is
    /// counted; a pass within the bound is left alone.
    #[test]
    fn without_room_or_need_the_pass_is_unchanged() {
        let r = 3.0;
        let stock = rectangle(0.0, 0.0, 60.0, 40.0);
        let map = MaterialMap::of_stock(&stock, None, r, r / 16.0).expect("map");
        let pass = [Point2::new(-5.0, 20.0), Point2::new(65.0, 20.0)];
        let walls = [
            rectangle(-10.0, 0.0, 70.0, 16.5),
            rectangle(-10.0, 23.5, 70.0, 40.0),
        ]
        .map(|s| RegionIndex::new(&s));
        let options = LoopOptions::for_radius(r, 0.8 * r);
        let tight = loop_heavy_stretches(&pass, &map, &[&walls[0], &walls[1]], r, &options);
        assert_eq!(tight.stretches, 0);
        assert!(tight.unlooped_mm > 59.0, "{}", tight.unlooped_mm);
        assert_eq!(tight.points, pass.to_vec());
        // A pass along the block's edge, half in air, takes less than the bound.
        let edge = [
            Point2::new(-5.0, 40.0 + r - 2.0),
            Point2::new(65.0, 40.0 + r - 2.0),
        ];
        let light = loop_heavy_stretches(&edge, &map, &[], r, &options);
        assert_eq!((light.stretches, light.unlooped_mm), (0, 0.0));
        assert_eq!(light.points, edge.to_vec());
    }
}
