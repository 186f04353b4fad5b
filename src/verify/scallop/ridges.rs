//! The ridges between the samples. A cusp is sharp: at a distance u from where a ball of
//! radius r touched, the material left stands u²/2r, so a sample a little off a ridge reads a
//! fraction of what the ridge holds, and two samples at neighbouring passes' contacts both
//! read nothing with the ridge between them. Evenly spaced samples understate the highest
//! scallop, however densely they are taken.
//!
//! Where two neighbouring samples are held by different swept bodies (their rays enter
//! different moves first), the ridge between them lies where the two bodies' entries are
//! equal: found by bisection along the chord between the samples, projected onto the part,
//! and measured there against every body. Along the chord each body's entry grows away from
//! where it holds, so the lesser of the two is highest at the crossing: nothing between the
//! samples stands higher than the two bodies' entry there, and a crossing at or below the
//! threshold needs no more. Where a third body enters lower at the crossing, the search goes
//! on in the two halves, between each side's body and the third.

use rayon::prelude::*;

use super::Bodies;
use crate::geom::{Point3, Vector3};
use crate::mesh::distance::SurfaceDistance;

/// A crossing of a ridge, above the threshold, between two samples.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct RidgePeak {
    /// On the part, and the part's normal there.
    pub point: Point3,
    pub normal: Vector3,
    /// The material left there: the least entry of any body up the normal, mm.
    pub height: f64,
    /// The sample of the two nearer to it.
    pub nearer: usize,
}

/// How far apart two samples may be to count as neighbours, in sample spacings: a grid
/// triangle's neighbouring samples stand about 1.07 spacings apart (equilateral
/// sub-triangles of half a spacing² each), a sliver's farther along it.
pub(super) const NEIGHBOUR_SPACINGS: f64 = 1.5;

/// Neighbouring samples whose normals turn by more than this (cos 30°) stand on different
/// faces of an edge, not on one surface with a ridge between them.
const SAME_SURFACE_COS: f64 = 0.866;

/// Further bodies a crossing may split the search at, along one pair's chord.
const MAX_SPLITS: u32 = 3;

/// The crossings above `threshold` between neighbouring samples (`points` with their unit
/// normals) held by different bodies (`holders`: `None` where a sample takes no part: not
/// reached, narrow, blocked, the table's), no more than `link` apart. Also the number of
/// pairs searched. The same for any thread count: every pair is searched on its own and the
/// peaks are listed in the order of the pairs.
pub(super) fn ridge_peaks(
    points: &[(Point3, Vector3)],
    holders: &[Option<usize>],
    link: f64,
    threshold: f64,
    bodies: &Bodies,
    distance: &SurfaceDistance,
) -> (usize, Vec<RidgePeak>) {
    let cell = |p: &Point3| [p.x, p.y, p.z].map(|x| (x / link).floor() as i64);
    let mut by_cell: Vec<([i64; 3], u32)> = points
        .iter()
        .enumerate()
        .filter(|(i, _)| holders[*i].is_some())
        .map(|(i, (p, _))| (cell(p), i as u32))
        .collect();
    by_cell.sort_unstable();
    let found: Vec<(usize, Vec<RidgePeak>)> = (0..points.len())
        .into_par_iter()
        .map(|i| {
            let Some(body_i) = holders[i] else {
                return (0, Vec::new());
            };
            let (p, n) = points[i];
            let home = cell(&p);
            let (mut pairs, mut peaks) = (0, Vec::new());
            for dx in -1..=1 {
                for dy in -1..=1 {
                    for dz in -1..=1 {
                        let key = [home[0] + dx, home[1] + dy, home[2] + dz];
                        let start = by_cell.partition_point(|(k, _)| *k < key);
                        for &(k, j) in &by_cell[start..] {
                            if k != key {
                                break;
                            }
                            let j = j as usize;
                            let Some(body_j) = holders[j] else { continue };
                            let (q, m) = points[j];
                            if j <= i
                                || body_j == body_i
                                || (q - p).norm() > link
                                || n.dot(&m) < SAME_SURFACE_COS
                            {
                                continue;
                            }
                            pairs += 1;
                            let chord = Chord {
                                from: (p, n),
                                to: (q, m),
                                samples: (i, j),
                            };
                            chord.search(
                                bodies,
                                distance,
                                (0.0, body_i),
                                (1.0, body_j),
                                threshold,
                                MAX_SPLITS,
                                &mut peaks,
                            );
                        }
                    }
                }
            }
            (pairs, peaks)
        })
        .collect();
    let pairs = found.iter().map(|(n, _)| n).sum();
    (pairs, found.into_iter().flat_map(|(_, p)| p).collect())
}

/// The chord between two neighbouring samples.
struct Chord {
    from: (Point3, Vector3),
    to: (Point3, Vector3),
    samples: (usize, usize),
}

impl Chord {
    /// The point a fraction `t` along, and the normals blended there.
    fn at(&self, t: f64) -> (Point3, Vector3) {
        let (p, n) = self.from;
        let (q, m) = self.to;
        let normal = (n * (1.0 - t) + m * t).try_normalize(1e-12).unwrap_or(n);
        (p + (q - p) * t, normal)
    }

    /// Searches between `low.0` (held by body `low.1`) and `high.0` (by `high.1`) for where
    /// the two bodies' entries are equal, and pushes the crossing when it stands above
    /// `threshold`; a third body lower there splits the search, `splits` more times at most.
    #[allow(clippy::too_many_arguments)]
    fn search(
        &self,
        bodies: &Bodies,
        distance: &SurfaceDistance,
        low: (f64, usize),
        high: (f64, usize),
        threshold: f64,
        splits: u32,
        peaks: &mut Vec<RidgePeak>,
    ) {
        let ((mut lo, a), (mut hi, b)) = (low, high);
        let entry = |body: usize, (x, n): (Point3, Vector3)| {
            bodies.entry(body, &x, &n).unwrap_or(f64::INFINITY)
        };
        // To a ten-thousandth of a millimetre along the chord: the heights near a ridge
        // change by u/r per unit along it, a few millionths of a millimetre here.
        let length = (self.to.0 - self.from.0).norm();
        while (hi - lo) * length > 1e-4 {
            let mid = 0.5 * (lo + hi);
            let at = self.at(mid);
            // Where neither enters, the crossing is no nearer one end than the other: the
            // middle is as good a place as any to measure.
            let (ea, eb) = (entry(a, at), entry(b, at));
            if ea.is_infinite() && eb.is_infinite() {
                (lo, hi) = (mid, mid);
            } else if ea <= eb {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        let t = 0.5 * (lo + hi);
        // On the part: the chord runs under a convex surface and over a concave one.
        let (x, _) = self.at(t);
        let Some(closest) = distance.closest(&x, length) else {
            return;
        };
        let (point, normal) = (closest.point, distance.face_normal(closest.triangle));
        let upper = entry(a, (point, normal)).min(entry(b, (point, normal)));
        if upper <= threshold {
            return;
        }
        let Some((height, c)) = bodies.least_entry(&point, &normal, Some(a)) else {
            return;
        };
        if c != a && c != b && height < upper && splits > 0 {
            self.search(
                bodies,
                distance,
                (low.0, a),
                (t, c),
                threshold,
                splits - 1,
                peaks,
            );
            self.search(
                bodies,
                distance,
                (t, c),
                (high.0, b),
                threshold,
                splits - 1,
                peaks,
            );
        }
        if height > threshold {
            peaks.push(RidgePeak {
                point,
                normal,
                height,
                nearer: if t < 0.5 {
                    self.samples.0
                } else {
                    self.samples.1
                },
            });
        }
    }
}
