//! The loose convex hull of seed 004 §4.1 and its offsets (Fig. 4.4).
//!
//! * [`enclosing_points`] — points whose convex hull contains the part exactly: line end points,
//!   and for each arc piece of at most 90° its end points and the intersection of its end
//!   tangents (the arc lies in that triangle);
//! * [`convex_hull`] — Andrew's monotone chain, counter-clockwise, no collinear vertices;
//! * [`loose_hull`] — algorithm *LooseConvexHull*: legs shorter than `min_leg` are deleted
//!   (the neighbouring legs extended to meet, Fig. 4.2a) or, when adjacent short legs form a
//!   run, combined into one leg perpendicular to the run's mean normal through its extreme
//!   vertex (Fig. 4.2b–d), repeatedly until nothing changes; a run that cannot be replaced
//!   as a whole is tried by pairs and single legs. Every new line is a supporting
//!   line of the polygon, so the loose hull still encloses the part. Unlike the seed, each
//!   change must keep the loose hull within `max_growth` of the true hull (a bound on how much
//!   air the roughing passes cut), and convex;
//! * [`hull_offset`] — the legs moved out by δ, joined by arcs of radius δ centred on the hull
//!   vertices: exactly the hull grown by δ.
//!
//! The search tests each candidate change on what it touches — the turns at its ends and the
//! growth of its one or two new points, an O(log n) query (`GrowthOracle`) — against counts
//! kept for the rest of the polygon, so it decides exactly as the whole-polygon tests would;
//! above `ONE_AT_A_TIME_LEGS` legs it makes independent changes in rounds (see
//! [`loose_hull_counted`]). A dense circle's hull of 3,000 legs took 37–71 s when every
//! candidate was tested vertex by vertex against every leg (issue 17 item 12).

use crate::contour::bvh::SegmentBvh;
use crate::contour::geometry::{Contour, Point2, Segment, Shape, Vector2, Vertex};
use crate::contour::segops::{cross, split_arc};
use std::f64::consts::FRAC_PI_2;

/// Points whose convex hull encloses every contour of `shape` exactly.
pub fn enclosing_points(shape: &Shape) -> Vec<Point2> {
    let mut pts = Vec::new();
    for c in &shape.contours {
        for seg in c.segments() {
            for piece in split_arc(&seg, FRAC_PI_2) {
                match piece {
                    Segment::Line { start, end } => pts.extend([start, end]),
                    Segment::Arc {
                        start,
                        end,
                        center,
                        radius,
                        sweep,
                    } => {
                        let mid = nalgebra::center(&start, &end) - center;
                        let apex = if mid.norm() > 0.0 {
                            center + mid.normalize() * (radius / (0.5 * sweep).cos())
                        } else {
                            start
                        };
                        pts.extend([start, apex, end]);
                    }
                }
            }
        }
    }
    pts
}

/// Convex hull, counter-clockwise, without collinear or repeated vertices.
pub fn convex_hull(points: &[Point2]) -> Vec<Point2> {
    let mut p: Vec<Point2> = points
        .iter()
        .copied()
        .filter(|q| q.x.is_finite() && q.y.is_finite())
        .collect();
    p.sort_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)));
    p.dedup();
    if p.len() < 3 {
        return p;
    }
    let mut hull: Vec<Point2> = Vec::with_capacity(2 * p.len());
    for pass in 0..2 {
        let start = hull.len();
        let iter: Box<dyn Iterator<Item = &Point2>> = if pass == 0 {
            Box::new(p.iter())
        } else {
            Box::new(p.iter().rev())
        };
        for &q in iter {
            while hull.len() >= start + 2
                && cross(
                    hull[hull.len() - 1] - hull[hull.len() - 2],
                    q - hull[hull.len() - 1],
                ) <= 0.0
            {
                hull.pop();
            }
            hull.push(q);
        }
        hull.pop();
    }
    hull
}

/// Outward normal of the leg a → b of a counter-clockwise polygon.
fn normal(a: Point2, b: Point2) -> Vector2 {
    let d = (b - a).normalize();
    Vector2::new(d.y, -d.x)
}

/// Intersection of the line through `p` with direction `u` and the line through `q` with
/// direction `v`; `None` when (nearly) parallel.
fn meet(p: Point2, u: Vector2, q: Point2, v: Vector2) -> Option<Point2> {
    let den = cross(u, v);
    if den.abs() <= 1e-12 * u.norm() * v.norm() {
        return None;
    }
    Some(p + u * (cross(q - p, v) / den))
}

/// The turn a → b → c of a counter-clockwise polygon is strictly convex (false for NaN).
fn turns_left(a: Point2, b: Point2, c: Point2) -> bool {
    cross(b - a, c - b) > 0.0
}

#[cfg(test)]
fn is_convex(poly: &[Point2]) -> bool {
    let n = poly.len();
    n >= 3 && (0..n).all(|i| turns_left(poly[i], poly[(i + 1) % n], poly[(i + 2) % n]))
}

/// Largest distance from any vertex of `poly` to the convex polygon `hull` (0 inside), by
/// brute force: the reference for [`GrowthOracle`].
#[cfg(test)]
fn growth(poly: &[Point2], hull: &[Point2]) -> f64 {
    let n = hull.len();
    poly.iter()
        .map(|&p| {
            (0..n)
                .map(|i| normal(hull[i], hull[(i + 1) % n]).dot(&(p - hull[i])))
                .fold(0.0, f64::max)
        })
        .fold(0.0, f64::max)
}

/// How far a point lies outside the convex hull: the largest signed distance to the lines of
/// its legs, 0 inside — the measure `max_growth` bounds.
///
/// For a point p outside, the distance to the supporting line of normal angle θ is concave in
/// θ where it is positive (a minimum of n(θ)·(p − v) over the hull's points v, each a cosine
/// within a quarter turn of its peak there), and peaks where θ points from p's nearest hull
/// point to p. The largest over the legs is therefore on a leg next to that nearest point, so
/// the legs around the nearest one (found in a BVH) stand in for all of them: O(log n) instead
/// of O(n) per point.
struct GrowthOracle<'a> {
    hull: &'a [Point2],
    bvh: SegmentBvh,
}

/// Legs each side of the nearest leg that [`GrowthOracle::of`] evaluates (the nearest point
/// may be a vertex, and round-off may pick either leg at it).
const GROWTH_WINDOW: usize = 2;

impl<'a> GrowthOracle<'a> {
    fn new(hull: &'a [Point2]) -> Self {
        let n = hull.len();
        let legs = (0..n)
            .map(|i| Segment::Line {
                start: hull[i],
                end: hull[(i + 1) % n],
            })
            .collect();
        Self {
            hull,
            bvh: SegmentBvh::new(legs),
        }
    }

    fn leg_distance(&self, i: usize, p: Point2) -> f64 {
        let n = self.hull.len();
        normal(self.hull[i], self.hull[(i + 1) % n]).dot(&(p - self.hull[i]))
    }

    fn of(&self, p: Point2) -> f64 {
        let n = self.hull.len();
        if n <= 2 * GROWTH_WINDOW + 1 {
            return (0..n).map(|i| self.leg_distance(i, p)).fold(0.0, f64::max);
        }
        let Some(near) = self.bvh.nearest_point(p) else {
            return 0.0;
        };
        (0..=2 * GROWTH_WINDOW)
            .map(|k| (near.index + n + k - GROWTH_WINDOW) % n)
            .map(|i| self.leg_distance(i, p))
            .fold(0.0, f64::max)
    }
}

/// Growth `g` is not within `max_growth` (a NaN bound allows nothing, as `g <= max` would).
fn beyond(g: f64, max_growth: f64) -> bool {
    !matches!(
        g.partial_cmp(&max_growth),
        Some(std::cmp::Ordering::Less | std::cmp::Ordering::Equal)
    )
}

/// Legs of the polygon up to which [`loose_hull`] makes one change at a time (the seed's
/// greedy order exactly); larger polygons are first reduced in rounds (see
/// [`loose_hull_counted`]).
const ONE_AT_A_TIME_LEGS: usize = 512;

/// Work done by [`loose_hull`], counted in vertices and legs visited (run enumeration, the
/// tests of each candidate change, rebuilding the polygon): a measure of its running time
/// that tests can compare across sizes without timing.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LooseHullWork {
    /// Vertices and legs visited.
    pub visits: usize,
    /// Candidate changes tested.
    pub candidates: usize,
    /// Changes made.
    pub changes: usize,
}

/// The loose convex hull of the counter-clockwise convex polygon `hull` (see the module docs).
pub fn loose_hull(hull: &[Point2], min_leg: f64, max_growth: f64) -> Vec<Point2> {
    loose_hull_counted(hull, min_leg, max_growth).0
}

/// The polygon being loosened: its vertices, which of them lie more than `max_growth` outside
/// the hull, and how many of its turns are not strictly convex. The two counts are kept up to
/// date, so a candidate change is tested on the few vertices and turns it touches: a change
/// passes when the polygon after it has no bad turn and no vertex too far out, exactly the
/// whole-polygon tests (convex, growth ≤ `max_growth`) of the seed's algorithm.
struct Loosening<'a> {
    poly: Vec<Point2>,
    too_far: Vec<bool>,
    bad_turns: usize,
    too_far_count: usize,
    oracle: GrowthOracle<'a>,
    max_growth: f64,
    work: LooseHullWork,
}

/// A change that passed: the `len` legs from leg `first` replaced by the `inserted` points,
/// and the polygon's counts after it.
struct Change {
    first: usize,
    len: usize,
    inserted: Vec<Point2>,
    bad_turns: usize,
    too_far_count: usize,
}

impl Loosening<'_> {
    /// The change replacing legs `first .. first + len`, when the polygon after it is convex and
    /// within `max_growth` of the hull (given the counts of the polygon as it is now).
    fn test(&mut self, first: usize, len: usize) -> Option<Change> {
        self.work.candidates += 1;
        let poly = &self.poly;
        let n = poly.len();
        let at = |i: usize| poly[i % n];
        let inserted = run_replacement(poly, first, len)?;
        self.work.visits += len + 5 + inserted.len() * (2 * GROWTH_WINDOW + 1);
        // Turns centred on vertices first − 1 ..= first + len + 1 are replaced by the turns of
        // the local chain [first − 2, first − 1, inserted…, first + len + 1, first + len + 2].
        let old_bad = (first + n - 1..=first + len + 1)
            .filter(|&c| !turns_left(at(c + n - 1), at(c), at(c + 1)))
            .count();
        let mut chain = vec![at(first + n - 2), at(first + n - 1)];
        chain.extend_from_slice(&inserted);
        chain.extend([at(first + len + 1), at(first + len + 2)]);
        let new_bad = chain
            .windows(3)
            .filter(|w| !turns_left(w[0], w[1], w[2]))
            .count();
        let bad_turns = (self.bad_turns + new_bad).checked_sub(old_bad)?;
        if bad_turns > 0 {
            return None;
        }
        let old_far = (first..=first + len)
            .filter(|&i| self.too_far[i % n])
            .count();
        let new_far = inserted
            .iter()
            .filter(|&&p| beyond(self.oracle.of(p), self.max_growth))
            .count();
        let too_far_count = (self.too_far_count + new_far).checked_sub(old_far)?;
        if too_far_count > 0 {
            return None;
        }
        Some(Change {
            first,
            len,
            inserted,
            bad_turns,
            too_far_count,
        })
    }

    /// Makes the changes (whose runs and neighbours do not overlap); the polygon then starts
    /// after the last one's run, its inserted points last — the seed's order for one change.
    fn apply(&mut self, mut changes: Vec<Change>) {
        let n = self.poly.len();
        let Some(last) = changes.last() else {
            return;
        };
        let start = (last.first + last.len + 1) % n;
        self.bad_turns = last.bad_turns;
        self.too_far_count = last.too_far_count;
        changes.sort_by_key(|c| (c.first % n + n - start) % n);
        let mut poly = Vec::with_capacity(n);
        let mut too_far = Vec::with_capacity(n);
        let mut k = 0;
        let mut next = changes.iter().peekable();
        while k < n {
            let i = (start + k) % n;
            if let Some(c) = next.next_if(|c| c.first % n == i) {
                // The run's vertices first ..= first + len go; the inserted points come in.
                k += c.len + 1;
                poly.extend_from_slice(&c.inserted);
                too_far.extend(c.inserted.iter().map(|_| false));
            } else {
                poly.push(self.poly[i]);
                too_far.push(self.too_far[i]);
                k += 1;
            }
        }
        // The last change's inserted points close the polygon (its run wraps to `start`).
        self.work.visits += n;
        self.work.changes += changes.len();
        self.poly = poly;
        self.too_far = too_far;
    }
}

/// The loose hull and the work it took (see [`LooseHullWork`]).
///
/// Up to `ONE_AT_A_TIME_LEGS` legs this is the seed's greedy search: after each change the
/// runs are found again and the first candidate that passes, in the order of
/// `candidate_runs`, is made. Testing a candidate touches only its own legs and neighbours
/// (the polygon's bad turns and far vertices are counted, and the growth of a new point is an
/// O(log n) query), so an iteration costs O(n log n) for sorting the runs. Above that size one
/// change per iteration would make the search quadratic (a dense circle of 3,000 points has
/// 3,000 short legs to merge one by one), so it goes in rounds: the candidates in the same
/// order, each made when it passes and none of the vertices its test reads (its run and two
/// vertices each side) was touched by an earlier change of the round. Such changes are
/// independent, so each keeps the polygon convex and within `max_growth`; a round costs
/// O(n log n) and removes a share of the short legs, until the polygon is small enough for
/// the one-at-a-time search or no candidate passes.
pub fn loose_hull_counted(
    hull: &[Point2],
    min_leg: f64,
    max_growth: f64,
) -> (Vec<Point2>, LooseHullWork) {
    let oracle = GrowthOracle::new(hull);
    let n = hull.len();
    let too_far: Vec<bool> = hull
        .iter()
        .map(|&p| beyond(oracle.of(p), max_growth))
        .collect();
    let bad_turns = (0..n)
        .filter(|&i| !turns_left(hull[(i + n - 1) % n], hull[i], hull[(i + 1) % n]))
        .count();
    let mut state = Loosening {
        poly: hull.to_vec(),
        too_far_count: too_far.iter().filter(|&&f| f).count(),
        too_far,
        bad_turns,
        oracle,
        max_growth,
        work: LooseHullWork {
            visits: n * (2 * GROWTH_WINDOW + 2),
            ..Default::default()
        },
    };
    loop {
        let n = state.poly.len();
        if n <= 3 {
            break;
        }
        let candidates = candidate_runs(&state.poly, min_leg);
        state.work.visits += n + candidates.len();
        let one_at_a_time = n <= ONE_AT_A_TIME_LEGS;
        let mut touched = vec![false; if one_at_a_time { 0 } else { n }];
        let mut changes = Vec::new();
        for &(first, len) in &candidates {
            if len + 2 >= n {
                continue;
            }
            // The vertices a candidate's test reads: its run and two each side.
            let span = (first + n - 2..=first + n + len + 2).map(|i| i % n);
            if !one_at_a_time && span.clone().any(|i| touched[i]) {
                continue;
            }
            if let Some(change) = state.test(first, len) {
                // Later changes of the round are tested against the counts after this one.
                state.bad_turns = change.bad_turns;
                state.too_far_count = change.too_far_count;
                changes.push(change);
                if one_at_a_time {
                    break;
                }
                for i in span {
                    touched[i] = true;
                }
            }
        }
        if changes.is_empty() {
            break;
        }
        state.apply(changes);
    }
    (state.poly, state.work)
}

/// The candidate changes of the polygon, in the order they are tried: the runs of legs
/// shorter than `min_leg` (all adjacent pairs when every leg is short), shortest total first
/// (ties: lower first leg); then the pairs and then the single legs within those runs, run by
/// run in the same order. Each is (first leg, number of legs).
fn candidate_runs(poly: &[Point2], min_leg: f64) -> Vec<(usize, usize)> {
    let n = poly.len();
    let legs: Vec<f64> = (0..n).map(|i| leg(poly, i)).collect();
    let short: Vec<bool> = legs.iter().map(|&l| l < min_leg).collect();
    // Runs of consecutive short legs, each given by its first leg and its length. When
    // every leg is short, adjacent pairs are candidates.
    let mut runs: Vec<(usize, usize)> = Vec::new();
    let long = short.iter().position(|s| !s).unwrap_or(0);
    let all_short = short.iter().all(|&s| s);
    if all_short {
        runs.extend((0..n).map(|i| (i, 2)));
    }
    let mut k = 1;
    while !all_short && k <= n {
        let i = (long + k) % n;
        if short[i] {
            let mut len = 0;
            while len < n && short[(i + len) % n] {
                len += 1;
            }
            runs.push((i, len));
            k += len;
        } else {
            k += 1;
        }
    }
    // Shortest total run first: the smallest change of the outline (each total summed leg by
    // leg from the first, once, not in every comparison).
    let mut keyed: Vec<(f64, usize, usize)> = runs
        .iter()
        .map(|&(first, len)| {
            let total: f64 = (0..len).map(|t| legs[(first + t) % n]).sum();
            (total, first, len)
        })
        .collect();
    keyed.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    let runs: Vec<(usize, usize)> = keyed.iter().map(|&(_, f, l)| (f, l)).collect();
    // When a whole run cannot go (too much growth), try its pairs and single legs.
    let mut candidates = runs.clone();
    for width in [2, 1] {
        for &(first, len) in &runs {
            if len > width {
                candidates.extend((0..=len - width).map(|t| ((first + t) % n, width)));
            }
        }
    }
    candidates
}

fn leg(poly: &[Point2], i: usize) -> f64 {
    let n = poly.len();
    (poly[(i + 1) % n] - poly[i % n]).norm()
}

/// The points that replace the vertices `first ..= first + len` when the `len` legs from leg
/// `first` go: one leg deleted (its neighbours extended to meet), or a run combined into one
/// leg along the run's mean normal through its extreme vertex.
fn run_replacement(poly: &[Point2], first: usize, len: usize) -> Option<Vec<Point2>> {
    let n = poly.len();
    let at = |i: usize| poly[i % n];
    let prev_dir = at(first) - at(first + n - 1);
    let next_dir = at(first + len + 1) - at(first + len);
    let mut inserted = Vec::with_capacity(2);
    if len == 1 {
        inserted.push(meet(at(first), prev_dir, at(first + 1), next_dir)?);
    } else {
        let mut nsum = Vector2::zeros();
        for t in 0..len {
            let (a, b) = (at(first + t), at(first + t + 1));
            nsum += normal(a, b) * (b - a).norm();
        }
        let nrm = nsum.try_normalize(1e-15)?;
        let apex = (0..=len)
            .map(|t| at(first + t))
            .max_by(|a, b| nrm.dot(&a.coords).total_cmp(&nrm.dot(&b.coords)))?;
        let dir = Vector2::new(-nrm.y, nrm.x);
        inserted.push(meet(at(first), prev_dir, apex, dir)?);
        inserted.push(meet(apex, dir, at(first + len), next_dir)?);
    }
    Some(inserted)
}

/// The convex polygon grown by `delta` > 0: legs moved out, arcs of radius `delta` around the
/// vertices (Fig. 4.4). Counter-clockwise.
pub fn hull_offset(poly: &[Point2], delta: f64) -> Contour {
    let n = poly.len();
    let mut vertices = Vec::with_capacity(2 * n);
    for i in 0..n {
        let (prev, here, next) = (poly[(i + n - 1) % n], poly[i], poly[(i + 1) % n]);
        let (n0, n1) = (normal(prev, here), normal(here, next));
        let turn = cross(n0, n1).atan2(n0.dot(&n1));
        vertices.push(Vertex {
            point: here + n0 * delta,
            bulge: (turn / 4.0).tan(),
        });
        vertices.push(Vertex {
            point: here + n1 * delta,
            bulge: 0.0,
        });
    }
    Contour { vertices }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contour::parallel::tests::{circle, rect};
    use std::f64::consts::PI;

    fn inside(poly: &[Point2], p: Point2) -> bool {
        let n = poly.len();
        (0..n).all(|i| cross(poly[(i + 1) % n] - poly[i], p - poly[i]) >= -1e-9)
    }

    #[test]
    fn hull_of_arcs_encloses_them() {
        let shape = Shape {
            contours: vec![circle(1.0, 2.0, 5.0, true)],
        };
        let hull = convex_hull(&enclosing_points(&shape));
        assert!(is_convex(&hull));
        for k in 0..360 {
            let a = k as f64 * PI / 180.0;
            let p = Point2::new(1.0 + 5.0 * a.cos(), 2.0 + 5.0 * a.sin());
            assert!(inside(&hull, p), "circle point {k}° outside the hull");
        }
    }

    #[test]
    fn loose_hull_encloses_the_hull_with_fewer_legs_within_its_growth() {
        // A 24-gon: short legs everywhere.
        let poly: Vec<Point2> = (0..24)
            .map(|k| {
                let a = k as f64 * PI / 12.0;
                Point2::new(20.0 * a.cos(), 20.0 * a.sin())
            })
            .collect();
        let hull = convex_hull(&poly);
        assert_eq!(hull.len(), 24);
        let loose = loose_hull(&hull, 8.0, 2.0);
        assert!(loose.len() < hull.len(), "{} legs", loose.len());
        assert!(is_convex(&loose));
        for p in &hull {
            assert!(inside(&loose, *p));
        }
        assert!(growth(&loose, &hull) <= 2.0);
        // No growth allowed: nothing changes.
        assert_eq!(loose_hull(&hull, 8.0, 0.0), hull);
        // A rectangle with one chamfer-like short leg loses it.
        let chamfered = vec![
            Point2::new(0.0, 0.0),
            Point2::new(10.0, 0.0),
            Point2::new(10.0, 9.0),
            Point2::new(9.0, 10.0),
            Point2::new(0.0, 10.0),
        ];
        let l = loose_hull(&chamfered, 2.0, 1.0);
        assert_eq!(l.len(), 4);
        assert!(
            l.iter()
                .any(|p| (p - Point2::new(10.0, 10.0)).norm() < 1e-12)
        );
    }

    /// The one-change-per-iteration search as it was written before issue 17 (whole-polygon
    /// convexity and growth tests after every candidate): the reference for the counted
    /// search.
    fn seed_search(hull: &[Point2], min_leg: f64, max_growth: f64) -> Vec<Point2> {
        let mut poly = hull.to_vec();
        'outer: loop {
            let n = poly.len();
            if n <= 3 {
                break;
            }
            for (first, len) in candidate_runs(&poly, min_leg) {
                if len + 2 >= n {
                    continue;
                }
                let Some(inserted) = run_replacement(&poly, first, len) else {
                    continue;
                };
                let mut candidate: Vec<Point2> =
                    (first + len + 1..first + n).map(|i| poly[i % n]).collect();
                candidate.extend(inserted);
                if is_convex(&candidate) && growth(&candidate, hull) <= max_growth {
                    poly = candidate;
                    continue 'outer;
                }
            }
            break;
        }
        poly
    }

    /// Deterministic pseudo-random numbers in [0, 1) (xorshift).
    struct Rng(u64);
    impl Rng {
        fn next(&mut self) -> f64 {
            self.0 ^= self.0 << 13;
            self.0 ^= self.0 >> 7;
            self.0 ^= self.0 << 17;
            (self.0 >> 11) as f64 / (1u64 << 53) as f64
        }
    }

    fn random_hull(rng: &mut Rng, n: usize) -> Vec<Point2> {
        let (a, b) = (20.0 + 40.0 * rng.next(), 10.0 + 40.0 * rng.next());
        let pts: Vec<Point2> = (0..n)
            .map(|_| {
                let t = rng.next() * 2.0 * PI;
                let r = 1.0 - 0.02 * rng.next();
                Point2::new(a * r * t.cos(), b * r * t.sin())
            })
            .collect();
        convex_hull(&pts)
    }

    #[test]
    fn growth_oracle_agrees_with_brute_force() {
        let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
        for _ in 0..20 {
            let hull = random_hull(&mut rng, 300);
            let oracle = GrowthOracle::new(&hull);
            for _ in 0..200 {
                let p = Point2::new(140.0 * rng.next() - 70.0, 140.0 * rng.next() - 70.0);
                assert_eq!(oracle.of(p), growth(&[p], &hull), "at {p:?}");
            }
        }
    }

    /// Issue 17 item 12: the counted search makes the same changes as the seed's search on
    /// polygons it handles one change at a time.
    #[test]
    fn loose_hull_matches_the_seed_search_on_random_polygons() {
        let mut rng = Rng(0x2545_f491_4f6c_dd1d);
        for case in 0..60 {
            let points = 8 + (rng.next() * 300.0) as usize;
            let hull = random_hull(&mut rng, points);
            let min_leg = 2.0 + 20.0 * rng.next();
            let max_growth = 4.0 * rng.next();
            assert_eq!(
                loose_hull(&hull, min_leg, max_growth),
                seed_search(&hull, min_leg, max_growth),
                "case {case}: {} legs, min leg {min_leg}, growth {max_growth}",
                hull.len()
            );
        }
    }

    fn circle_hull(n: usize) -> Vec<Point2> {
        let pts: Vec<Point2> = (0..n)
            .map(|k| {
                let a = k as f64 * 2.0 * PI / n as f64;
                Point2::new(50.0 * a.cos(), 50.0 * a.sin())
            })
            .collect();
        convex_hull(&pts)
    }

    /// Issue 17 item 12: a 3,000-point circle took 37 s (every candidate was tested against
    /// every hull leg for every vertex, one change per pass over the polygon). The work now
    /// grows about linearly: four times the points, at most about five times the work (a
    /// quadratic search would need sixteen).
    #[test]
    fn dense_circle_loose_hull_work_is_near_linear() {
        let (min_leg, max_growth) = (9.6, 2.4);
        let mut visits = Vec::new();
        for n in [2000, 8000] {
            let hull = circle_hull(n);
            let (loose, work) = loose_hull_counted(&hull, min_leg, max_growth);
            assert!(is_convex(&loose));
            assert!(growth(&loose, &hull) <= max_growth);
            for p in &hull {
                assert!(inside(&loose, *p));
            }
            assert!(loose.len() < 30, "{n}: {} legs", loose.len());
            visits.push(work.visits as f64);
        }
        let ratio = visits[1] / visits[0];
        assert!(ratio < 5.0, "work {visits:?}: ratio {ratio}");
    }

    #[test]
    fn hull_offset_is_the_grown_polygon() {
        let sq = rect(0.0, 0.0, 10.0, 4.0, true);
        let poly: Vec<Point2> = sq.vertices.iter().map(|v| v.point).collect();
        let off = hull_offset(&poly, 2.0);
        // Perimeter + 2π δ, area + perimeter δ + π δ².
        assert!((off.length() - (28.0 + 4.0 * PI)).abs() < 1e-9);
        assert!((off.signed_area() - (40.0 + 28.0 * 2.0 + PI * 4.0)).abs() < 1e-9);
    }
}
