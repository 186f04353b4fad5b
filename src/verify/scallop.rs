//! The scallop a finishing toolpath leaves, measured on the part (issue 21 item 4), from the
//! moves alone: nothing of how they were planned.
//!
//! The part's surface is sampled evenly (a barycentric grid on every triangle, a cell per
//! half `spacing`² of area; small triangles pool their area). Each cut move sweeps its ball along the straight segment between two ball
//! centres: a capsule. At a sample point p with outward normal n, the material left is the
//! stretch of the ray p + t·n (t ≥ 0) below the first swept capsule it meets: the scallop
//! height is the least entry t over all capsules (0 where p lies inside one, a touch or a cut
//! within the tolerance). A point whose ray meets no capsule within `reach` is not reached:
//! the strategy left it (unreachable, or a region no pass covers). The face the part stands
//! on is left out of both (no tool gets there). Capsules are found through a uniform grid;
//! entries are exact (the ray against the capsule's cylinder and its two end spheres).
//!
//! Where the part is concave more tightly than the ball (a blade's root without a fillet as
//! large as the ball, a channel narrower than it), no placement of the ball touches the
//! surface: what stands there is the tool's, not the passes'. A sample is *narrow* when the
//! ball touching it from outside — centred a radius up its normal — would cut into the part
//! elsewhere by more than the target (an exact distance query on the part); the report keeps
//! the scallop of the open samples apart, so that over-target area there means passes too
//! far apart or a region no strategy covered.

use rayon::prelude::*;
use serde::Serialize;

use crate::geom::{MoveKind, Point3, Toolpath, Vector3, closest_point_on_segment};
use crate::mesh::Mesh;
use crate::mesh::distance::SurfaceDistance;

/// What the measure found.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ScallopReport {
    pub samples: usize,
    pub sample_spacing_mm: f64,
    /// Area of the samples the moves reach (each sample stands for its share of its
    /// triangle), and of those they do not, mm²; the face on the table is left out.
    pub reached_area_mm2: f64,
    pub unreached_area_mm2: f64,
    pub table_area_mm2: f64,
    /// Scallop height over the reached samples, mm.
    pub max_mm: f64,
    pub p99_mm: f64,
    pub mean_mm: f64,
    /// Reached area whose scallop is above `target`, mm².
    pub over_target_area_mm2: f64,
    /// Of the unreached area, what faces down (more than 60° from up): no tool reaches it
    /// from above whatever the strategy, mm².
    pub unreached_facing_down_mm2: f64,
    /// Area where the part is concave more tightly than the ball: no ball touches it, mm².
    pub narrow_area_mm2: f64,
    /// The scallop over the reached samples where the ball fits, mm, and the area of them
    /// above the target, mm².
    pub open_max_mm: f64,
    pub open_p99_mm: f64,
    pub open_over_target_mm2: f64,
    pub target_mm: f64,
    /// The same split by the labels given per triangle (the impeller's regions).
    #[serde(skip_serializing_if = "std::collections::BTreeMap::is_empty")]
    pub by_region: std::collections::BTreeMap<String, AreaSplit>,
}

/// A labelled part of the surface: its area (the table's apart), the reached area over the
/// target, and the area not reached, mm².
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct AreaSplit {
    pub area_mm2: f64,
    pub over_target_mm2: f64,
    pub unreached_mm2: f64,
    /// Of the area, where the ball does not fit, and of the reached area where it does, the
    /// part over the target, mm².
    pub narrow_mm2: f64,
    pub open_over_target_mm2: f64,
}

/// How the scallop is measured.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ScallopOptions {
    /// Ball radius, mm.
    pub radius: f64,
    /// Target scallop height, mm.
    pub target: f64,
    /// Distance between samples, mm.
    pub spacing: f64,
    /// A sample is reached when a swept ball comes within this far above it, mm.
    pub reach: f64,
    /// The part stands on the plane z = `table_z`: samples there facing down are the table's.
    pub table_z: f64,
    /// The flutes' length above the ball's centre (a cylinder of the ball's radius), mm; 0:
    /// the balls alone.
    pub flutes_above_ball: f64,
}

/// Measures the scallop `toolpath`'s cut moves leave on `part`; with `labels` (one per
/// triangle) also split by label.
pub fn measure_scallop(
    part: &Mesh,
    toolpath: &Toolpath,
    options: &ScallopOptions,
    labels: Option<&[&str]>,
) -> ScallopReport {
    let ScallopOptions {
        radius,
        target,
        spacing,
        reach,
        table_z,
        flutes_above_ball,
    } = *options;
    let distance = SurfaceDistance::new(part);
    // The flutes sweep too where they come within twice the target of the part (a flank cut
    // with their side): as a stack of balls up the axis, close enough that the stack leaves
    // at most a quarter of the target of the cylinder uncovered (s²/8r between two balls).
    let flute_step = (2.0 * radius * target).sqrt().max(1e-3);
    let flute_balls = if flutes_above_ball > 0.0 {
        (flutes_above_ball / flute_step).ceil() as usize
    } else {
        0
    };
    let capsules: Vec<(Point3, Point3)> = toolpath
        .moves
        .windows(2)
        .filter(|w| w[1].kind == MoveKind::Cut)
        .collect::<Vec<_>>()
        .par_iter()
        .flat_map_iter(|w| {
            let along = |m: &crate::geom::Move, h: f64| {
                m.pose.tip + m.pose.axis.into_inner() * (radius + h)
            };
            // Whether they do is asked of their axis a quarter and half way up, at both ends
            // and every half radius between (a measure, not a safety check: a flank cut runs
            // over many moves, and flutes leaning off the part keep those points away).
            let between = ((w[1].pose.tip - w[0].pose.tip).norm() / (0.5 * radius)).ceil() as usize;
            let flutes_cut = flute_balls > 0
                && (0..=between.max(1)).any(|k| {
                    let t = k as f64 / between.max(1) as f64;
                    let tip = w[0].pose.tip + (w[1].pose.tip - w[0].pose.tip) * t;
                    let axis = (w[0].pose.axis.into_inner() * (1.0 - t)
                        + w[1].pose.axis.into_inner() * t)
                        .try_normalize(1e-12)
                        .unwrap_or_else(|| w[1].pose.axis.into_inner());
                    [0.25, 0.5].iter().any(|f| {
                        let q = tip + axis * (radius + f * flutes_above_ball);
                        distance.any_within(&q, radius + 2.0 * target)
                    })
                });
            let stack = if flutes_cut { flute_balls } else { 0 };
            (0..=stack).map(move |j| {
                let h = flutes_above_ball * j as f64 / stack.max(1) as f64;
                (along(&w[0], h), along(&w[1], h))
            })
        })
        .collect();
    let grid = Grid::new(&capsules, radius, (2.0 * radius).max(reach));

    // Samples: on a triangle of more than `quantum` area, a barycentric grid of k² cells of
    // about that area each; smaller triangles (a finely tessellated STL has
    // millions) pool their area in order, one sample at the centroid of the triangle that
    // completes a quantum, standing for the pool.
    let quantum = 0.5 * spacing * spacing;
    let mut samples: Vec<(Point3, Vector3, f64, usize)> = Vec::new();
    let mut pooled = 0.0;
    for t in 0..part.triangles.len() {
        let [a, b, c] = part.corners(t);
        let n = (b - a).cross(&(c - a));
        let area = 0.5 * n.norm();
        let normal = n.try_normalize(1e-300).unwrap_or_else(Vector3::z);
        if area < quantum {
            pooled += area;
            if pooled >= quantum {
                samples.push((
                    Point3::from((a.coords + b.coords + c.coords) / 3.0),
                    normal,
                    pooled,
                    t,
                ));
                pooled = 0.0;
            }
            continue;
        }
        // By area, not by the longest edge: an STL's long slivers would get thousands.
        let k = (area / quantum).sqrt().ceil().max(1.0) as usize;
        let count = (k * (k + 1) / 2) as f64;
        for i in 0..k {
            for j in 0..k - i {
                // Centres of the sub-triangles pointing up: every sample inside.
                let u = (i as f64 + 1.0 / 3.0) / k as f64;
                let v = (j as f64 + 1.0 / 3.0) / k as f64;
                samples.push((a + (b - a) * u + (c - a) * v, normal, area / count, t));
            }
        }
    }
    let narrow: Vec<bool> = samples
        .par_iter()
        .map(|(p, n, _, _)| distance.any_within(&(p + n * radius), radius - target))
        .collect();
    let heights: Vec<Option<f64>> = samples
        .par_iter()
        .map(|(p, n, _, _)| {
            if n.z < -0.99 && (p.z - table_z).abs() < 1e-6 {
                return Some(f64::NAN);
            }
            let end = p + n * reach;
            let mut best: Option<f64> = None;
            grid.for_each_near(p, &end, |i| {
                let (a, b) = capsules[i];
                if let Some(t) = ray_capsule_entry(p, n, &a, &b, radius)
                    && t <= reach
                    && best.is_none_or(|h| t < h)
                {
                    best = Some(t);
                }
            });
            best
        })
        .collect();
    let mut reached = Vec::new();
    let mut open = Vec::new();
    let (mut reached_area, mut unreached_area, mut table_area, mut over) = (0.0, 0.0, 0.0, 0.0);
    let (mut narrow_area, mut open_over) = (0.0, 0.0);
    let mut sum = 0.0;
    let mut facing_down = 0.0;
    let mut by_label: std::collections::BTreeMap<String, AreaSplit> = Default::default();
    let mut scratch = AreaSplit::default();
    for (((_, normal, area, t), h), narrow) in samples.iter().zip(&heights).zip(&narrow) {
        if h.is_some_and(f64::is_nan) {
            table_area += area;
            continue;
        }
        let split = match labels {
            Some(l) => by_label.entry(l[*t].to_string()).or_default(),
            None => &mut scratch,
        };
        split.area_mm2 += area;
        if *narrow {
            narrow_area += area;
            split.narrow_mm2 += area;
        }
        match h {
            Some(h) => {
                reached_area += area;
                sum += h * area;
                if *h > target {
                    over += area;
                    split.over_target_mm2 += area;
                    if !narrow {
                        open_over += area;
                        split.open_over_target_mm2 += area;
                    }
                }
                reached.push(*h);
                if !narrow {
                    open.push(*h);
                }
            }
            None => {
                unreached_area += area;
                split.unreached_mm2 += area;
                if normal.z < -0.5 {
                    facing_down += area;
                }
            }
        }
    }
    reached.sort_by(f64::total_cmp);
    open.sort_by(f64::total_cmp);
    let p99 = |sorted: &[f64]| {
        sorted
            .get(((sorted.len() as f64 * 0.99) as usize).min(sorted.len().saturating_sub(1)))
            .copied()
            .unwrap_or(0.0)
    };
    ScallopReport {
        samples: samples.len(),
        sample_spacing_mm: spacing,
        reached_area_mm2: reached_area,
        unreached_area_mm2: unreached_area,
        table_area_mm2: table_area,
        max_mm: reached.last().copied().unwrap_or(0.0),
        p99_mm: p99(&reached),
        mean_mm: if reached_area > 0.0 {
            sum / reached_area
        } else {
            0.0
        },
        over_target_area_mm2: over,
        unreached_facing_down_mm2: facing_down,
        narrow_area_mm2: narrow_area,
        open_max_mm: open.last().copied().unwrap_or(0.0),
        open_p99_mm: p99(&open),
        open_over_target_mm2: open_over,
        target_mm: target,
        by_region: by_label,
    }
}

/// Where the ray `p + t·d` (unit `d`, t ≥ 0) enters the capsule of radius `r` about segment
/// `ab`: 0 when `p` is inside, `None` when it misses or the capsule lies behind.
pub fn ray_capsule_entry(p: &Point3, d: &Vector3, a: &Point3, b: &Point3, r: f64) -> Option<f64> {
    if (p - closest_point_on_segment(p, a, b)).norm() <= r {
        return Some(0.0);
    }
    let mut entry: Option<f64> = None;
    let mut take = |t: f64| {
        if t >= 0.0 && entry.is_none_or(|e| t < e) {
            entry = Some(t);
        }
    };
    // The lateral surface of the cylinder between the end planes.
    let ba = b - a;
    let oa = p - a;
    let baba = ba.dot(&ba);
    if baba > 0.0 {
        let bard = ba.dot(d);
        let baoa = ba.dot(&oa);
        let k2 = baba - bard * bard;
        let k1 = baba * oa.dot(d) - baoa * bard;
        let k0 = baba * oa.dot(&oa) - baoa * baoa - r * r * baba;
        let disc = k1 * k1 - k2 * k0;
        if k2 > 1e-12 * baba && disc >= 0.0 {
            let t = (-k1 - disc.sqrt()) / k2;
            let y = baoa + t * bard;
            if y > 0.0 && y < baba {
                take(t);
            }
        }
    }
    // The two end spheres.
    for centre in [a, b] {
        let oc = p - centre;
        let half_b = oc.dot(d);
        let c = oc.dot(&oc) - r * r;
        let disc = half_b * half_b - c;
        if disc >= 0.0 {
            take(-half_b - disc.sqrt());
        }
    }
    entry
}

/// A uniform grid of capsules by their bounding boxes.
struct Grid {
    cell: f64,
    origin: Point3,
    dims: [usize; 3],
    starts: Vec<u32>,
    items: Vec<u32>,
}

impl Grid {
    fn new(capsules: &[(Point3, Point3)], radius: f64, cell: f64) -> Grid {
        let mut lo = Point3::new(f64::INFINITY, f64::INFINITY, f64::INFINITY);
        let mut hi = Point3::new(f64::NEG_INFINITY, f64::NEG_INFINITY, f64::NEG_INFINITY);
        for (a, b) in capsules {
            for p in [a, b] {
                lo = lo.inf(p);
                hi = hi.sup(p);
            }
        }
        if capsules.is_empty() {
            lo = Point3::origin();
            hi = Point3::origin();
        }
        let origin = lo - Vector3::repeat(radius + cell);
        let extent = hi - origin + Vector3::repeat(radius + cell);
        let dims = [0, 1, 2].map(|k| ((extent[k] / cell).ceil() as usize).clamp(1, 1024));
        let cell_of = |p: &Point3, k: usize| {
            (((p[k] - origin[k]) / cell).floor().max(0.0) as usize).min(dims[k] - 1)
        };
        let mut lists: Vec<Vec<u32>> = vec![Vec::new(); dims[0] * dims[1] * dims[2]];
        for (i, (a, b)) in capsules.iter().enumerate() {
            let (l, h) = (
                a.inf(b) - Vector3::repeat(radius),
                a.sup(b) + Vector3::repeat(radius),
            );
            for x in cell_of(&l, 0)..=cell_of(&h, 0) {
                for y in cell_of(&l, 1)..=cell_of(&h, 1) {
                    for z in cell_of(&l, 2)..=cell_of(&h, 2) {
                        lists[(x * dims[1] + y) * dims[2] + z].push(i as u32);
                    }
                }
            }
        }
        let mut starts = Vec::with_capacity(lists.len() + 1);
        let mut items = Vec::new();
        for list in lists {
            starts.push(items.len() as u32);
            items.extend(list);
        }
        starts.push(items.len() as u32);
        Grid {
            cell,
            origin,
            dims,
            starts,
            items,
        }
    }

    /// Calls `visit` with every capsule whose box meets the box of segment `pq` (a capsule
    /// may come more than once).
    fn for_each_near(&self, p: &Point3, q: &Point3, mut visit: impl FnMut(usize)) {
        let cell_of = |v: f64, k: usize| -> Option<usize> {
            let c = ((v - self.origin[k]) / self.cell).floor();
            (c >= 0.0 && (c as usize) < self.dims[k]).then_some(c as usize)
        };
        let (l, h) = (p.inf(q), p.sup(q));
        let range = |k: usize| {
            let lo = cell_of(l[k], k).unwrap_or(if l[k] < self.origin[k] {
                0
            } else {
                self.dims[k]
            });
            let hi = cell_of(h[k], k).unwrap_or(if h[k] < self.origin[k] {
                0
            } else {
                self.dims[k] - 1
            });
            lo..=hi.min(self.dims[k] - 1)
        };
        for x in range(0) {
            for y in range(1) {
                for z in range(2) {
                    let c = (x * self.dims[1] + y) * self.dims[2] + z;
                    for &i in &self.items[self.starts[c] as usize..self.starts[c + 1] as usize] {
                        visit(i as usize);
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::{Direction, Move, ToolPose};

    #[test]
    fn the_ray_enters_a_capsule_where_the_closed_form_says() {
        let (a, b) = (Point3::new(0.0, 0.0, 3.0), Point3::new(10.0, 0.0, 3.0));
        let up = Vector3::z();
        // Under the cylinder: enters at 3 − 2.
        let t = ray_capsule_entry(&Point3::new(5.0, 0.0, 0.0), &up, &a, &b, 2.0);
        assert!((t.unwrap() - 1.0).abs() < 1e-12);
        // Off to the side by 1: 3 − √3.
        let t = ray_capsule_entry(&Point3::new(5.0, 1.0, 0.0), &up, &a, &b, 2.0);
        assert!((t.unwrap() - (3.0 - 3f64.sqrt())).abs() < 1e-12);
        // Beyond the end, under the end sphere: 3 − √(4 − 1).
        let t = ray_capsule_entry(&Point3::new(11.0, 0.0, 0.0), &up, &a, &b, 2.0);
        assert!((t.unwrap() - (3.0 - 3f64.sqrt())).abs() < 1e-12);
        // Inside, and missed.
        assert_eq!(
            ray_capsule_entry(&Point3::new(5.0, 0.0, 2.0), &up, &a, &b, 2.0),
            Some(0.0)
        );
        assert_eq!(
            ray_capsule_entry(&Point3::new(5.0, 3.0, 0.0), &up, &a, &b, 2.0),
            None
        );
        assert_eq!(
            ray_capsule_entry(&Point3::new(5.0, 0.0, 6.0), &up, &a, &b, 2.0),
            None
        );
    }

    fn passes(ys: impl Iterator<Item = f64>) -> Toolpath {
        let axis = Direction::new_normalize(Vector3::z());
        let mut moves = Vec::new();
        for y in ys {
            for (x, kind) in [(-5.0, MoveKind::Approach), (25.0, MoveKind::Cut)] {
                moves.push(Move {
                    pose: ToolPose {
                        tip: Point3::new(x, y, 1.0),
                        axis,
                    },
                    kind,
                    feed: 1000.0,
                });
            }
        }
        Toolpath { tool_id: 1, moves }
    }

    /// Straight passes a stepover w apart over a flat plate leave the closed-form cusp
    /// h = r − √(r² − (w/2)²) between them; the sides stand below the balls' reach, the
    /// bottom on the table.
    #[test]
    fn passes_over_a_plate_leave_the_closed_form_scallop() {
        let plate = crate::mesh::fixtures::cuboid(20.0, 20.0, 1.0);
        let (r, w) = (2.0, 0.8);
        let path = passes((0..30).map(|k| -2.0 + k as f64 * w));
        let options = |target| ScallopOptions {
            radius: r,
            target,
            spacing: 0.05,
            reach: 2.0 * r,
            table_z: 0.0,
            flutes_above_ball: 0.0,
        };
        let labels: Vec<&str> = (0..12)
            .map(|t| if t < 4 { "flat" } else { "sides" })
            .collect();
        let report = measure_scallop(&plate, &path, &options(0.02), Some(&labels));
        let cusp = r - (r * r - (w / 2.0) * (w / 2.0)).sqrt();
        // The samples (0.05 mm apart across the passes) fall within 0.025 mm of a cusp, where
        // the scallop's flank slopes by (w/2)/√(r² − (w/2)²) ≈ 0.2.
        assert!((report.max_mm - cusp).abs() < 6e-3, "{report:?} vs {cusp}");
        assert!(report.max_mm <= cusp + 1e-9);
        assert!(report.over_target_area_mm2 > 0.0 && report.over_target_area_mm2 < 400.0);
        assert!((report.table_area_mm2 - 400.0).abs() < 1e-6);
        assert!((report.reached_area_mm2 - 400.0).abs() < 1e-6, "{report:?}");
        assert!(
            (report.unreached_area_mm2 - 80.0).abs() < 1e-6,
            "{report:?}"
        );
        // The top reached, the sides not (the bottom is the table's).
        let sides = &report.by_region["sides"];
        assert!((sides.unreached_mm2 - 80.0).abs() < 1e-6 && sides.over_target_mm2 == 0.0);
        assert!((report.by_region["flat"].area_mm2 - 400.0).abs() < 1e-6);

        // Passes over half the plate: the other half, beyond the last ball's reach, is not
        // reached.
        let half = measure_scallop(
            &plate,
            &passes((0..13).map(|k| k as f64 * w)),
            &options(0.05),
            None,
        );
        let last = 12.0 * w + r;
        assert!(
            (half.unreached_area_mm2 - 80.0 - 20.0 * (20.0 - last)).abs() < 0.5,
            "{half:?}"
        );
    }

    /// An L-shaped bar, 20 long in y: a 20 × 5 floor and a 10 × 15 wall standing on it, the
    /// concave edge along y at x = 10, z = 5.
    fn step() -> Mesh {
        let profile = [
            (0.0, 0.0),
            (20.0, 0.0),
            (20.0, 5.0),
            (10.0, 5.0),
            (10.0, 15.0),
            (0.0, 15.0),
        ];
        let mut positions = Vec::new();
        for y in [0.0, 20.0] {
            positions.extend(profile.iter().map(|&(x, z)| Point3::new(x, y, z)));
        }
        // The profile is star-shaped from its first corner: fans close both ends.
        let mut triangles: Vec<[u32; 3]> = Vec::new();
        for k in 1..5u32 {
            triangles.push([0, k, k + 1]);
            triangles.push([6, 6 + k + 1, 6 + k]);
        }
        for k in 0..6u32 {
            let next = (k + 1) % 6;
            triangles.push([k, 6 + next, next]);
            triangles.push([k, 6 + k, 6 + next]);
        }
        Mesh {
            positions,
            triangles,
        }
    }

    /// On the step, a ball of radius r fits nowhere within r − target of the concave edge:
    /// a strip that wide on the floor and on the wall, 20 long each; the open scallop leaves
    /// it out.
    #[test]
    fn the_ball_does_not_fit_within_its_radius_of_a_concave_edge() {
        let part = step();
        assert!((part.signed_volume() - (20.0 * 5.0 + 10.0 * 10.0) * 20.0).abs() < 1e-9);
        let (r, target) = (2.0, 0.05);
        // Passes along y over the floor 0.2 apart, the ball touching it, the first touching
        // the wall too.
        let axis = Direction::new_normalize(Vector3::z());
        let mut moves = Vec::new();
        for k in 0..50 {
            let x = 10.0 + r + k as f64 * 0.2;
            for (y, kind) in [(-3.0, MoveKind::Approach), (23.0, MoveKind::Cut)] {
                moves.push(Move {
                    pose: ToolPose {
                        tip: Point3::new(x, y, 5.0),
                        axis,
                    },
                    kind,
                    feed: 1000.0,
                });
            }
        }
        let path = Toolpath { tool_id: 1, moves };
        let labels: Vec<&str> = (0..part.triangles.len())
            .map(|t| match t {
                12 | 13 => "floor",
                14 | 15 => "wall",
                _ => "rest",
            })
            .collect();
        let report = measure_scallop(
            &part,
            &path,
            &ScallopOptions {
                radius: r,
                target,
                spacing: 0.05,
                reach: 2.0 * r,
                table_z: 0.0,
                flutes_above_ball: 0.0,
            },
            Some(&labels),
        );
        let strip = 2.0 * 20.0 * (r - target);
        assert!(
            (report.narrow_area_mm2 - strip).abs() < 2.0 * 20.0 * 0.05,
            "{} vs {strip}",
            report.narrow_area_mm2
        );
        let (floor, wall) = (&report.by_region["floor"], &report.by_region["wall"]);
        for split in [floor, wall] {
            assert!(
                (split.narrow_mm2 - strip / 2.0).abs() < 20.0 * 0.05,
                "{split:?}"
            );
        }
        // On the floor, what the passes leave over the target is in the corner: the balls
        // 0.2 apart leave 0.0025 between them.
        assert!(floor.over_target_mm2 > 20.0, "{floor:?}");
        assert_eq!(floor.open_over_target_mm2, 0.0, "{floor:?}");
        assert_eq!(report.by_region["rest"].narrow_mm2, 0.0);
        // On the wall the first ball, touching it at its centre's height, leaves more than
        // the target from 0.44 above that up to 2 (where the rays miss): open, over target.
        let open_over = 20.0 * (2.0 - (r * r - (r - target).powi(2)).sqrt());
        assert!(
            (wall.open_over_target_mm2 - open_over).abs() < 20.0 * 0.1,
            "{wall:?} vs {open_over}"
        );
    }

    /// An upright tool runs along a 10 mm wall with its ball's centre 2 mm up: the flutes
    /// sweep the wall from there to its top within the target (their stack of balls leaves at
    /// most a quarter of it), so only the strip under the ball's equator is over the target;
    /// with the balls alone everything above the ball's reach is left.
    #[test]
    fn flutes_along_a_wall_sweep_it_from_the_ball_up() {
        let (r, target) = (2.0, 0.01);
        let block = crate::mesh::fixtures::cuboid(20.0, 20.0, 10.0);
        // The face x = 20 is triangles 10 and 11.
        let labels: Vec<&str> = (0..12)
            .map(|t| if t >= 10 { "wall" } else { "rest" })
            .collect();
        let axis = Direction::new_normalize(Vector3::z());
        let moves = [(-5.0, MoveKind::Approach), (25.0, MoveKind::Cut)]
            .into_iter()
            .map(|(y, kind)| Move {
                pose: ToolPose {
                    tip: Point3::new(20.0 + r, y, 0.0),
                    axis,
                },
                kind,
                feed: 1000.0,
            })
            .collect();
        let path = Toolpath { tool_id: 1, moves };
        let measure = |flutes_above_ball| {
            measure_scallop(
                &block,
                &path,
                &ScallopOptions {
                    radius: r,
                    target,
                    spacing: 0.1,
                    reach: r,
                    table_z: 0.0,
                    flutes_above_ball,
                },
                Some(&labels),
            )
            .by_region["wall"]
                .clone()
        };
        let with_flutes = measure(10.0);
        assert!((with_flutes.area_mm2 - 200.0).abs() < 1e-6);
        assert!(with_flutes.unreached_mm2 < 1e-9, "{with_flutes:?}");
        // Over the target: the strip below the ball's centre where its side stands more than
        // the target off the wall, z < r − √(r² − (r − target)²), in closed form.
        let strip = 20.0 * (r - (r * r - (r - target).powi(2)).sqrt());
        assert!(
            (with_flutes.over_target_mm2 - strip).abs() <= 2.0,
            "{with_flutes:?} against {strip}"
        );
        let balls_alone = measure(0.0);
        // Above z = 4 nothing of the ball reaches the wall within a radius.
        assert!(
            balls_alone.unreached_mm2 >= 20.0 * 6.0 - 1.0,
            "{balls_alone:?}"
        );
    }
}
