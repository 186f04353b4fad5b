//! The scallop a finishing toolpath leaves, measured on the part (issue 21 item 4), from the
//! moves alone: nothing of how they were planned.
//!
//! The part's surface is sampled evenly (a barycentric grid on every triangle, a cell per
//! half `spacing`² of area; small triangles pool their area). Each cut move sweeps its ball
//! along the straight segment between two ball centres: a capsule; where its flutes come
//! within twice the target of the part (a flank cut with their side), they sweep too: the
//! sheet their axis sweeps between the two poses, thickened by the radius (triangles of the
//! sheet, each with a prism and three edge capsules). At a sample point p with outward normal
//! n, the material left is the stretch of the ray p + t·n (t ≥ 0) below the first swept body
//! it meets: the scallop height is the least entry t over all of them (0 where p lies inside
//! one, a touch or a cut within the tolerance). A point whose ray meets nothing within
//! `reach` is not reached: the strategy left it (unreachable, or a region no pass covers).
//! The face the part stands on is left out of both (no tool gets there). The bodies are
//! found through a bounding-box tree, nearest along the ray first, and a bounding sphere
//! each; entries are exact. A cusp is sharper than any sample spacing resolves: between
//! neighbouring samples held by different moves, the ridge is found where the two moves'
//! entries are equal and measured there ([`ridges`]), and the highest is the report's
//! maximum.
//!
//! Where the part is concave more tightly than the ball (a blade's root without a fillet as
//! large as the ball, a channel narrower than it), no placement of the ball touches the
//! surface: what stands there is the tool's, not the passes'. A sample is *narrow* when the
//! ball touching it from outside — centred a radius up its normal — would cut into the part
//! elsewhere by more than the target (an exact distance query on the part); the report keeps
//! the scallop of the open samples apart, so that over-target area there means passes too
//! far apart or a region no strategy covered.
//!
//! Given the tool and the machine ([`ToolReach`]), an open sample over the target is
//! *blocked* when no tool axis of a direction set reaches it (the shank and its margin do not
//! fit down a bore, the table's margin keeps the ball off a wall's foot): the report keeps it
//! apart too, so the open figures are what the passes are answerable for.

use rayon::prelude::*;
use serde::Serialize;

use crate::geom::{MoveKind, Point3, Toolpath, Vector3, closest_point_on_segment};
use crate::mesh::Mesh;
use crate::mesh::distance::SurfaceDistance;

use super::reach::ToolReach;

mod ridges;

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
    /// Area over the target where the ball fits but no tool axis the machine allows reaches
    /// (measured only when the tool is given), mm: left out of the open figures.
    pub blocked_area_mm2: f64,
    /// Pairs of neighbouring samples where the ball fits, held by different moves, searched
    /// for the ridge between them (samples a spacing apart read a fraction of a cusp's
    /// height); the highest open ridge found above the target, or above the highest sample
    /// where that is lower (0: none), mm; and the open ridges over the target (each counts the
    /// sample nearer to it as over, or blocked where the ridge is). `open_max_mm` is the
    /// higher of the open samples' and the ridges'.
    pub ridge_pairs: usize,
    pub ridge_max_mm: f64,
    pub ridges_over_target: usize,
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
    /// Over the target where the ball fits and no tool axis reaches, mm².
    pub blocked_mm2: f64,
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

/// What the measure found at a sample (or, for a patch of the surface, the worst of the
/// samples it stands for).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SampleScallop {
    /// Facing down on the table.
    Table,
    /// Reached, and within the target where the ball fits (the largest height there, mm).
    Within(f64),
    /// Concave more tightly than the ball, and nowhere open over the target.
    Narrow,
    /// No swept ball comes near.
    NotReached,
    /// Over the target where the ball fits, but no axis of the tool reaches (the largest such
    /// height, mm).
    Blocked(f64),
    /// Where the ball fits, over the target (the largest such height, mm): what the passes
    /// are answerable for.
    Over(f64),
}

impl SampleScallop {
    /// Over the target first, then not reached, narrow, within, the table.
    fn rank(self) -> (u8, f64) {
        match self {
            SampleScallop::Table => (0, 0.0),
            SampleScallop::Within(h) => (1, h),
            SampleScallop::Narrow => (2, 0.0),
            SampleScallop::NotReached => (3, 0.0),
            SampleScallop::Blocked(h) => (4, h),
            SampleScallop::Over(h) => (5, h),
        }
    }

    fn worse(self, other: SampleScallop) -> SampleScallop {
        let (a, b) = (self.rank(), other.rank());
        if b.0 > a.0 || (b.0 == a.0 && b.1 > a.1) {
            other
        } else {
            self
        }
    }
}

/// Measures the scallop `toolpath`'s cut moves leave on `part`; with `labels` (one per
/// triangle) also split by label.
pub fn measure_scallop(
    part: &Mesh,
    toolpath: &Toolpath,
    options: &ScallopOptions,
    labels: Option<&[&str]>,
) -> ScallopReport {
    measure_scallop_map(part, toolpath, options, labels).0
}

/// A piece of the part's surface and what the measure found there: a triangle of the part
/// too small for samples of its own (the worst of its pool's), or one of the sub-triangles a
/// larger triangle's samples stand at the centres of (the worst of its own and its
/// neighbours' for the sub-triangles between them).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ScallopPatch {
    pub corners: [Point3; 3],
    pub found: SampleScallop,
}

/// [`measure_scallop`], and what it found where, as patches covering the part (for a picture
/// of where the passes leave what; a coarse mesh's long triangles are split as sampled).
pub fn measure_scallop_map(
    part: &Mesh,
    toolpath: &Toolpath,
    options: &ScallopOptions,
    labels: Option<&[&str]>,
) -> (ScallopReport, Vec<ScallopPatch>) {
    let ball = Ball {
        radius: options.radius,
        flutes_above_ball: options.flutes_above_ball,
    };
    measure_scallop_map_of(part, &[(toolpath, ball)], options, labels, None)
}

/// A ball-end mill as the scallop measure sweeps it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ball {
    pub radius: f64,
    /// The flutes' length above the ball's centre, mm (0: the ball alone).
    pub flutes_above_ball: f64,
}

/// [`measure_scallop_map`] of several toolpaths, each cut by its own ball (a finish, then a
/// corner finish with a smaller one): what is left is what none of them sweeps. A sample is
/// narrow where the smallest ball does not fit; `options.radius` and
/// `options.flutes_above_ball` are not used (each path's ball is). With `tool_reach`, open samples
/// over the target that no tool axis reaches are told apart (blocked).
pub fn measure_scallop_map_of(
    part: &Mesh,
    passes: &[(&Toolpath, Ball)],
    options: &ScallopOptions,
    labels: Option<&[&str]>,
    tool_reach: Option<&ToolReach>,
) -> (ScallopReport, Vec<ScallopPatch>) {
    let target = options.target;
    let distance = SurfaceDistance::new(part);
    // No passes: nothing is reached, and narrow is `options.radius`'s.
    let smallest = passes
        .iter()
        .map(|(_, ball)| ball.radius)
        .reduce(f64::min)
        .unwrap_or(options.radius);
    let mut swept: Vec<Swept> = Vec::new();
    let mut radii: Vec<f64> = Vec::new();
    for (toolpath, ball) in passes {
        let bodies = swept_bodies(&distance, toolpath, ball, target);
        radii.extend(std::iter::repeat_n(ball.radius, bodies.len()));
        swept.extend(bodies);
    }
    let tree = BodyTree::new(&swept, &radii);
    let spheres: Vec<(Point3, f64)> = swept
        .iter()
        .zip(&radii)
        .map(|(s, r)| s.bounding_sphere(*r))
        .collect();
    scallop_of_samples(
        part, &distance, &swept, &radii, &tree, &spheres, smallest, options, labels, tool_reach,
    )
}

/// The bodies `ball` sweeps along `toolpath`'s cut moves: a capsule per move, and the flutes'
/// sheet where they cut (see below).
fn swept_bodies(
    distance: &SurfaceDistance,
    toolpath: &Toolpath,
    ball: &Ball,
    target: f64,
) -> Vec<Swept> {
    let Ball {
        radius,
        flutes_above_ball,
    } = *ball;
    // The flutes sweep too where they come within twice the target of the part (a flank cut
    // with their side): the sheet their axis sweeps between the move's two poses, thickened
    // by the radius. The sheet is a bilinear patch; it is split into strips up the axis, two
    // triangles each, few enough that a triangle is within a quarter of the target of the
    // patch (the twist of a strip h high is h·|Δaxis|/4 off its diagonal).
    let flutes = flutes_above_ball > 0.0;
    // Balls this far apart up the axis leave a quarter of the target between two (s²/8r).
    let flute_step = (2.0 * radius * target).sqrt().max(1e-3);
    let balls = (flutes_above_ball / flute_step).ceil() as usize;
    toolpath
        .moves
        .windows(2)
        .filter(|w| w[1].kind == MoveKind::Cut)
        .collect::<Vec<_>>()
        .par_iter()
        .flat_map_iter(|w| {
            let along = |m: &crate::geom::Move, h: f64| {
                m.pose.tip + m.pose.axis.into_inner() * (radius + h)
            };
            // Whether they do is asked of their axis a step above the centre (the distance
            // between two balls that leaves a quarter of the target) and a quarter and half
            // way up, at both ends and every half radius between (a
            // measure, not a safety check: a flank cut runs over many moves, and flutes
            // leaning off the part keep those points away). The step: a flank the flutes cut
            // starts at the ball's equator, and on a low stretch of blade ends a millimetre
            // above it (asked only a quarter way up, the blower's short flanks read as uncut
            // where the flutes had swept them); a ball on a floor has its axis rising off the
            // floor at once. Three points, not the whole axis: a segment query that finds
            // nothing cost the blower's verification twice its time.
            let between = ((w[1].pose.tip - w[0].pose.tip).norm() / (0.5 * radius)).ceil() as usize;
            let flutes_cut = flutes
                && (0..=between.max(1)).any(|k| {
                    let t = k as f64 / between.max(1) as f64;
                    let tip = w[0].pose.tip + (w[1].pose.tip - w[0].pose.tip) * t;
                    let axis = (w[0].pose.axis.into_inner() * (1.0 - t)
                        + w[1].pose.axis.into_inner() * t)
                        .try_normalize(1e-12)
                        .unwrap_or_else(|| w[1].pose.axis.into_inner());
                    [
                        flute_step,
                        0.25 * flutes_above_ball,
                        0.5 * flutes_above_ball,
                    ]
                    .iter()
                    .any(|h| {
                        let q = tip + axis * (radius + h);
                        distance.any_within(&q, radius + 2.0 * target)
                    })
                });
            let mut swept = vec![Swept::Capsule(along(&w[0], 0.0), along(&w[1], 0.0))];
            // Where the axis turns much along the move the sheet needs many strips; a stack
            // of balls up the axis, `flute_step` apart (leaving a quarter of the target
            // between two, s²/8r), is then the cheaper of the two, a rounded triangle costing
            // about five capsules.
            let twist = (w[1].pose.axis.into_inner() - w[0].pose.axis.into_inner()).norm();
            let strips = ((flutes_above_ball * twist / target).ceil() as usize).max(1);
            if flutes_cut && 10 * strips > balls {
                for j in 1..=balls {
                    let h = flutes_above_ball * j as f64 / balls as f64;
                    swept.push(Swept::Capsule(along(&w[0], h), along(&w[1], h)));
                }
            } else if flutes_cut {
                for j in 0..strips {
                    let h0 = flutes_above_ball * j as f64 / strips as f64;
                    let h1 = flutes_above_ball * (j + 1) as f64 / strips as f64;
                    let (p00, p10) = (along(&w[0], h0), along(&w[1], h0));
                    let (p01, p11) = (along(&w[0], h1), along(&w[1], h1));
                    swept.push(Swept::Sheet([p00, p10, p11]));
                    swept.push(Swept::Sheet([p00, p11, p01]));
                }
            }
            swept
        })
        .collect()
}

/// The measure itself, on the swept bodies (each with its ball's radius in `radii`, listed in
/// `tree`, held by `spheres`); narrow where the ball of radius `narrow_radius` does not fit.
#[allow(clippy::too_many_arguments)]
fn scallop_of_samples(
    part: &Mesh,
    distance: &SurfaceDistance,
    swept: &[Swept],
    radii: &[f64],
    tree: &BodyTree,
    spheres: &[(Point3, f64)],
    narrow_radius: f64,
    options: &ScallopOptions,
    labels: Option<&[&str]>,
    tool_reach: Option<&ToolReach>,
) -> (ScallopReport, Vec<ScallopPatch>) {
    let ScallopOptions {
        target,
        spacing,
        reach,
        table_z,
        ..
    } = *options;

    // Samples: on a triangle of more than `quantum` area, a barycentric grid of k² cells of
    // about that area each; smaller triangles (a finely tessellated STL has
    // millions) pool their area in order, one sample at the centroid of the triangle that
    // completes a quantum, standing for the pool.
    let quantum = 0.5 * spacing * spacing;
    let mut samples: Vec<(Point3, Vector3, f64, usize)> = Vec::new();
    // The pooled triangles each pool's sample stands for, as a range of `members`.
    let mut members: Vec<usize> = Vec::new();
    let mut stands_for: Vec<(usize, std::ops::Range<usize>)> = Vec::new();
    let mut pool: Vec<usize> = Vec::new();
    let mut pooled = 0.0;
    let mut last_pooled = None;
    // The triangles sampled on a grid: (triangle, k, index of its first sample).
    let mut grids: Vec<(usize, usize, usize)> = Vec::new();
    for t in 0..part.triangles.len() {
        let [a, b, c] = part.corners(t);
        let n = (b - a).cross(&(c - a));
        let area = 0.5 * n.norm();
        let normal = n.try_normalize(1e-300).unwrap_or_else(Vector3::z);
        if area < quantum {
            pool.push(t);
            pooled += area;
            let centroid = Point3::from((a.coords + b.coords + c.coords) / 3.0);
            if pooled >= quantum {
                stands_for.push((samples.len(), members.len()..members.len() + pool.len()));
                samples.push((centroid, normal, pooled, t));
                members.append(&mut pool);
                pooled = 0.0;
            } else {
                last_pooled = Some((centroid, normal, t));
            }
            continue;
        }
        // By area, not by the longest edge: an STL's long slivers would get thousands.
        let k = (area / quantum).sqrt().ceil().max(1.0) as usize;
        let count = (k * (k + 1) / 2) as f64;
        grids.push((t, k, samples.len()));
        for i in 0..k {
            for j in 0..k - i {
                // Centres of the sub-triangles pointing up: every sample inside.
                let u = (i as f64 + 1.0 / 3.0) / k as f64;
                let v = (j as f64 + 1.0 / 3.0) / k as f64;
                samples.push((a + (b - a) * u + (c - a) * v, normal, area / count, t));
            }
        }
    }
    // A pool the triangles ran out before it filled stands at its last triangle.
    if let Some((centroid, normal, t)) = last_pooled
        && pooled > 0.0
    {
        stands_for.push((samples.len(), members.len()..members.len() + pool.len()));
        samples.push((centroid, normal, pooled, t));
        members.append(&mut pool);
    }
    // The ball touching p from outside would cut the part elsewhere by more than the target.
    let narrow_at = |p: &Point3, n: &Vector3| {
        distance.any_within(&(p + n * narrow_radius), narrow_radius - target)
    };
    let narrow: Vec<bool> = samples
        .par_iter()
        .map(|(p, n, _, _)| narrow_at(p, n))
        .collect();
    let bodies = Bodies {
        swept,
        radii,
        tree,
        spheres,
        reach,
    };
    let holders: Vec<Option<(f64, usize)>> = samples
        .par_iter()
        // The body that held the previous sample's least entry, tried first: neighbouring
        // samples are usually held by the same body.
        .map_init(
            || None::<usize>,
            |hint, (p, n, _, _)| {
                if n.z < -0.99 && (p.z - table_z).abs() < 1e-6 {
                    return Some((f64::NAN, usize::MAX));
                }
                let best = bodies.least_entry(p, n, *hint);
                *hint = best.map(|(_, i)| i);
                best
            },
        )
        .collect();
    let mut heights: Vec<Option<f64>> = holders.iter().map(|h| h.map(|(h, _)| h)).collect();
    // Of the open samples over the target, those no axis of the tool reaches.
    let mut blocked: Vec<bool> = samples
        .par_iter()
        .zip(&heights)
        .zip(&narrow)
        .map(|(((p, n, _, _), h), narrow)| {
            tool_reach.is_some_and(|tool| {
                !narrow
                    && h.is_some_and(|h| h > target)
                    && tool.blocked(distance, p, n, narrow_radius, target)
            })
        })
        .collect();
    // The ridges between the samples (see `ridges`): their crossings above the target, or
    // above the highest sample where the ball fits when that is lower, are the report's
    // maximum; a crossing over the target counts the sample nearer to it as over.
    // Blocked samples take part too: whether a ridge is blocked is asked where it is.
    let fits = |i: usize| !narrow[i] && heights[i].is_some_and(|h| !h.is_nan());
    let is_open_over: Vec<bool> = (0..samples.len())
        .map(|i| fits(i) && !blocked[i] && heights[i].is_some_and(|h| h > target))
        .collect();
    let sample_max = (0..samples.len())
        .filter(|&i| fits(i))
        .filter_map(|i| heights[i])
        .fold(0.0, f64::max);
    let points: Vec<(Point3, Vector3)> = samples.iter().map(|(p, n, _, _)| (*p, *n)).collect();
    let ridge_holders: Vec<Option<usize>> = (0..samples.len())
        .map(|i| holders[i].filter(|_| fits(i)).map(|(_, body)| body))
        .collect();
    let (ridge_pairs, peaks) = ridges::ridge_peaks(
        &points,
        &ridge_holders,
        ridges::NEIGHBOUR_SPACINGS * spacing,
        target.min(sample_max),
        &bodies,
        distance,
    );
    // Only where the ball fits; over the target, told apart where no axis reaches.
    let peaks: Vec<(ridges::RidgePeak, bool)> = peaks
        .into_par_iter()
        .filter(|peak| !narrow_at(&peak.point, &peak.normal))
        .map(|peak| {
            let blocked = peak.height > target
                && tool_reach.is_some_and(|tool| {
                    tool.blocked(distance, &peak.point, &peak.normal, narrow_radius, target)
                });
            (peak, blocked)
        })
        .collect();
    let ridge_max = peaks
        .iter()
        .filter(|(_, blocked)| !blocked)
        .map(|(p, _)| p.height)
        .fold(0.0, f64::max);
    // The sample nearer a ridge over the target is over: open where any such ridge beside it
    // is, else blocked where one is and it was not open over by itself.
    let mut ridges_over_target = 0;
    let mut beside_open = vec![false; samples.len()];
    for (peak, peak_blocked) in peaks.iter().filter(|(p, _)| p.height > target) {
        let i = peak.nearer;
        ridges_over_target += usize::from(!peak_blocked);
        heights[i] = heights[i].map(|h| h.max(peak.height));
        if !peak_blocked {
            beside_open[i] = true;
            blocked[i] = false;
        } else if !beside_open[i] && !is_open_over[i] {
            blocked[i] = true;
        }
    }
    let mut reached = Vec::new();
    let mut open = Vec::new();
    let (mut reached_area, mut unreached_area, mut table_area, mut over) = (0.0, 0.0, 0.0, 0.0);
    let (mut narrow_area, mut open_over, mut blocked_area) = (0.0, 0.0, 0.0);
    let mut sum = 0.0;
    let mut facing_down = 0.0;
    let mut by_label: std::collections::BTreeMap<String, AreaSplit> = Default::default();
    let mut scratch = AreaSplit::default();
    let found: Vec<SampleScallop> = heights
        .iter()
        .zip(&narrow)
        .zip(&blocked)
        .map(|((h, narrow), blocked)| match h {
            Some(h) if h.is_nan() => SampleScallop::Table,
            // Narrow and reached: within where it is, else the ball does not fit.
            Some(h) if *narrow && *h > target => SampleScallop::Narrow,
            Some(h) if *narrow => SampleScallop::Within(*h),
            Some(h) if *blocked => SampleScallop::Blocked(*h),
            Some(h) if *h > target => SampleScallop::Over(*h),
            Some(h) => SampleScallop::Within(*h),
            None => SampleScallop::NotReached,
        })
        .collect();
    let patches = scallop_patches(part, &grids, &members, &stands_for, &found);
    for ((((_, normal, area, t), h), narrow), blocked) in
        samples.iter().zip(&heights).zip(&narrow).zip(&blocked)
    {
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
                    if *blocked {
                        blocked_area += area;
                        split.blocked_mm2 += area;
                    } else if !narrow {
                        open_over += area;
                        split.open_over_target_mm2 += area;
                    }
                }
                reached.push(*h);
                if !narrow && !blocked {
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
    let report = ScallopReport {
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
        open_max_mm: open.last().copied().unwrap_or(0.0).max(ridge_max),
        open_p99_mm: p99(&open),
        open_over_target_mm2: open_over,
        blocked_area_mm2: blocked_area,
        ridge_pairs,
        ridge_max_mm: ridge_max,
        ridges_over_target,
        target_mm: target,
        by_region: by_label,
    };
    (report, patches)
}

/// The patches covering `part`: each grid-sampled triangle split into its k² sub-triangles
/// (the k(k+1)/2 pointing up hold its samples, in the order they were taken; each one
/// pointing down takes the worst of its three neighbours), each pooled triangle whole with the
/// worst of its pool's samples (`stands_for[s]`: the range of `members` sample `s` stands
/// for).
fn scallop_patches(
    part: &Mesh,
    grids: &[(usize, usize, usize)],
    members: &[usize],
    stands_for: &[(usize, std::ops::Range<usize>)],
    found: &[SampleScallop],
) -> Vec<ScallopPatch> {
    let mut patches = Vec::new();
    for &(t, k, first) in grids {
        let [a, b, c] = part.corners(t);
        let at = |i: usize, j: usize| {
            a + (b - a) * (i as f64 / k as f64) + (c - a) * (j as f64 / k as f64)
        };
        // Sample (i, j) was taken i-major: row i starts after the rows before it.
        let up = |i: usize, j: usize| found[first + i * k - i * i.saturating_sub(1) / 2 + j];
        for i in 0..k {
            for j in 0..k - i {
                patches.push(ScallopPatch {
                    corners: [at(i, j), at(i + 1, j), at(i, j + 1)],
                    found: up(i, j),
                });
                if i + j + 2 <= k {
                    patches.push(ScallopPatch {
                        corners: [at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)],
                        found: up(i, j).worse(up(i + 1, j)).worse(up(i, j + 1)),
                    });
                }
            }
        }
    }
    let mut pooled: Vec<Option<SampleScallop>> = vec![None; part.triangles.len()];
    for (sample, range) in stands_for {
        for &t in &members[range.clone()] {
            let f = found[*sample];
            pooled[t] = Some(pooled[t].map_or(f, |g| g.worse(f)));
        }
    }
    for (t, f) in pooled.iter().enumerate() {
        if let Some(f) = f {
            patches.push(ScallopPatch {
                corners: part.corners(t),
                found: *f,
            });
        }
    }
    patches
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

/// What a cut move sweeps, each thickened by the tool's radius: the ball's centre moves along
/// a segment (a capsule), the flutes' axis over a sheet (triangles).
#[derive(Clone, Copy, Debug)]
enum Swept {
    Capsule(Point3, Point3),
    Sheet([Point3; 3]),
}

impl Swept {
    /// The box of the segment or triangle, without the radius.
    fn bounds(&self) -> (Point3, Point3) {
        match self {
            Swept::Capsule(a, b) => (a.inf(b), a.sup(b)),
            Swept::Sheet([a, b, c]) => (a.inf(b).inf(c), a.sup(b).sup(c)),
        }
    }

    /// A sphere holding the body of radius `r`: the corners' centroid, and the farthest corner
    /// from it plus `r`.
    fn bounding_sphere(&self, r: f64) -> (Point3, f64) {
        let corners: &[Point3] = match self {
            Swept::Capsule(a, b) => &[*a, *b],
            Swept::Sheet(corners) => corners,
        };
        let centre =
            Point3::from(corners.iter().map(|c| c.coords).sum::<Vector3>() / corners.len() as f64);
        let far = corners
            .iter()
            .map(|c| (c - centre).norm())
            .fold(0.0, f64::max);
        (centre, far + r)
    }

    /// Where the ray `p + t·d` (unit `d`, t ≥ 0) enters the body: 0 inside.
    fn entry(&self, p: &Point3, d: &Vector3, r: f64) -> Option<f64> {
        match self {
            Swept::Capsule(a, b) => ray_capsule_entry(p, d, a, b, r),
            Swept::Sheet(corners) => ray_rounded_triangle_entry(p, d, corners, r),
        }
    }
}

/// Where the ray `p + t·d` (unit `d`, t ≥ 0) enters the points within `r` of triangle `abc`
/// (the triangle's prism of half-thickness `r`, and a capsule round each edge): 0 when `p` is
/// inside, `None` when it misses or the body lies behind.
pub fn ray_rounded_triangle_entry(
    p: &Point3,
    d: &Vector3,
    [a, b, c]: &[Point3; 3],
    r: f64,
) -> Option<f64> {
    // Inside the body is inside an edge capsule (entry 0) or the prism (entered at 0).
    let mut entry: Option<f64> = None;
    for (u, v) in [(a, b), (b, c), (c, a)] {
        if let Some(t) = ray_capsule_entry(p, d, u, v, r)
            && entry.is_none_or(|e| t < e)
        {
            entry = Some(t);
        }
    }
    // The prism: the ray clipped by its two faces and its three sides.
    let Some(normal) = (b - a).cross(&(c - a)).try_normalize(1e-300) else {
        return entry;
    };
    let (mut enter, mut leave) = (0.0_f64, f64::INFINITY);
    let mut clip = |inward: Vector3, offset: f64| {
        // Inside where (x − origin)·inward ≥ offset, x = p + t·d.
        let at = inward.dot(&p.coords) - offset;
        let rate = inward.dot(d);
        if rate.abs() < 1e-300 {
            if at < 0.0 {
                leave = f64::NEG_INFINITY;
            }
        } else if rate > 0.0 {
            enter = enter.max(-at / rate);
        } else {
            leave = leave.min(-at / rate);
        }
    };
    clip(normal, normal.dot(&a.coords) - r);
    clip(-normal, -normal.dot(&a.coords) - r);
    for (u, v, w) in [(a, b, c), (b, c, a), (c, a, b)] {
        let edge = v - u;
        let mut inward = normal.cross(&edge);
        if inward.dot(&(w - u)) < 0.0 {
            inward = -inward;
        }
        clip(inward, inward.dot(&u.coords));
    }
    if enter <= leave && entry.is_none_or(|e| enter < e) {
        entry = Some(enter);
    }
    entry
}

/// A bounding-box tree of the swept bodies (each box grown by its ball's radius), for the
/// rays up the samples' normals: a ray meets a few dozen boxes where a uniform grid coarse
/// enough to hold the bodies listed thousands.
struct BodyTree {
    nodes: Vec<BodyNode>,
    /// The bodies in leaf order.
    order: Vec<u32>,
}

#[derive(Clone, Copy, Debug)]
struct BodyNode {
    lo: Point3,
    hi: Point3,
    /// Inner node: index of the first child (the second follows it). Leaf: first body in
    /// `order`.
    first: u32,
    /// Bodies in the leaf; 0 for an inner node.
    count: u32,
}

/// Bodies per leaf of the tree.
const BODIES_PER_LEAF: usize = 4;

impl BodyTree {
    fn new(swept: &[Swept], radii: &[f64]) -> BodyTree {
        let boxes: Vec<(Point3, Point3)> = swept
            .iter()
            .zip(radii)
            .map(|(body, r)| {
                let (lo, hi) = body.bounds();
                (lo - Vector3::repeat(*r), hi + Vector3::repeat(*r))
            })
            .collect();
        let mut tree = BodyTree {
            nodes: Vec::with_capacity(2 * boxes.len() / BODIES_PER_LEAF + 1),
            order: (0..boxes.len() as u32).collect(),
        };
        if !boxes.is_empty() {
            tree.nodes.push(BodyNode {
                lo: Point3::origin(),
                hi: Point3::origin(),
                first: 0,
                count: 0,
            });
            tree.build(&boxes, 0, 0, boxes.len());
        }
        tree
    }

    /// Median split of `order[start..end]` along the longest side of its boxes' centres.
    fn build(&mut self, boxes: &[(Point3, Point3)], node: usize, start: usize, end: usize) {
        let (mut lo, mut hi) = boxes[self.order[start] as usize];
        let (mut centre_lo, mut centre_hi) =
            (nalgebra::center(&lo, &hi), nalgebra::center(&lo, &hi));
        for &i in &self.order[start..end] {
            let (l, h) = boxes[i as usize];
            lo = lo.inf(&l);
            hi = hi.sup(&h);
            let c = nalgebra::center(&l, &h);
            centre_lo = centre_lo.inf(&c);
            centre_hi = centre_hi.sup(&c);
        }
        self.nodes[node].lo = lo;
        self.nodes[node].hi = hi;
        if end - start <= BODIES_PER_LEAF {
            self.nodes[node].first = start as u32;
            self.nodes[node].count = (end - start) as u32;
            return;
        }
        let spread = centre_hi - centre_lo;
        let axis = (0..3)
            .max_by(|&a, &b| spread[a].total_cmp(&spread[b]))
            .unwrap_or(0);
        let mid = (start + end) / 2;
        // The lower corner plus the upper orders by centre; ties by index keep the tree the
        // same on every run.
        let key = |i: &u32| {
            let (l, h) = boxes[*i as usize];
            l[axis] + h[axis]
        };
        self.order[start..end]
            .select_nth_unstable_by(mid - start, |x, y| key(x).total_cmp(&key(y)).then(x.cmp(y)));
        let first = self.nodes.len();
        let empty = BodyNode {
            lo: Point3::origin(),
            hi: Point3::origin(),
            first: 0,
            count: 0,
        };
        self.nodes.push(empty);
        self.nodes.push(empty);
        self.nodes[node].first = first as u32;
        self.nodes[node].count = 0;
        self.build(boxes, first, start, mid);
        self.build(boxes, first + 1, mid, end);
    }

    /// Calls `visit` with every body whose box meets the ray `p + t·d`, 0 ≤ t ≤ `length`,
    /// nearer boxes first; `visit` returns the length still wanted (the best entry so far),
    /// and boxes the ray meets only beyond it are passed over.
    fn visit_along(
        &self,
        p: &Point3,
        d: &Vector3,
        mut length: f64,
        mut visit: impl FnMut(usize) -> f64,
    ) {
        if self.nodes.is_empty() {
            return;
        }
        // Where the ray is within a node's box: the slabs' overlap, or none.
        let inverse = d.map(|x| 1.0 / x);
        let enters = |n: &BodyNode, length: f64| -> Option<f64> {
            let (mut near, mut far) = (0.0_f64, length);
            for k in 0..3 {
                if d[k] == 0.0 {
                    if p[k] < n.lo[k] || p[k] > n.hi[k] {
                        return None;
                    }
                    continue;
                }
                let (a, b) = ((n.lo[k] - p[k]) * inverse[k], (n.hi[k] - p[k]) * inverse[k]);
                near = near.max(a.min(b));
                far = far.min(a.max(b));
            }
            (near <= far).then_some(near)
        };
        let mut stack: Vec<(f64, u32)> = Vec::with_capacity(64);
        if let Some(t) = enters(&self.nodes[0], length) {
            stack.push((t, 0));
        }
        while let Some((t, index)) = stack.pop() {
            if t > length {
                continue;
            }
            let node = self.nodes[index as usize];
            if node.count > 0 {
                let start = node.first as usize;
                for &i in &self.order[start..start + node.count as usize] {
                    length = visit(i as usize);
                }
            } else {
                let (l, r) = (node.first, node.first + 1);
                let near_l = enters(&self.nodes[l as usize], length);
                let near_r = enters(&self.nodes[r as usize], length);
                // The nearer child is popped first.
                match (near_l, near_r) {
                    (Some(a), Some(b)) if a <= b => stack.extend([(b, r), (a, l)]),
                    (Some(a), Some(b)) => stack.extend([(a, l), (b, r)]),
                    (Some(a), None) => stack.push((a, l)),
                    (None, Some(b)) => stack.push((b, r)),
                    (None, None) => {}
                }
            }
        }
    }
}

/// The swept bodies as the rays up the samples' normals meet them.
struct Bodies<'a> {
    swept: &'a [Swept],
    /// Each body's ball radius.
    radii: &'a [f64],
    tree: &'a BodyTree,
    /// A sphere holding each body.
    spheres: &'a [(Point3, f64)],
    /// Entries farther up the ray than this do not count.
    reach: f64,
}

impl Bodies<'_> {
    /// Where the ray `p + t·n` enters body `i`, if within the reach.
    fn entry(&self, i: usize, p: &Point3, n: &Vector3) -> Option<f64> {
        self.swept[i]
            .entry(p, n, self.radii[i])
            .filter(|t| *t <= self.reach)
    }

    /// The least entry of the ray `p + t·n` into any body, and the body; `hint` is tried
    /// first (a neighbour's body: a small entry found first lets the sphere test pass over
    /// almost every other body).
    fn least_entry(&self, p: &Point3, n: &Vector3, hint: Option<usize>) -> Option<(f64, usize)> {
        let reach = self.reach;
        let mut best: Option<(f64, usize)> = None;
        let mut try_body = |i: usize| {
            // A body can hold the least entry only if its bounding sphere meets the ray
            // short of the best entry so far: a few products for most of them.
            let (centre, bound) = self.spheres[i];
            let length = best.map_or(reach, |(h, _)| h.min(reach));
            let along = (centre - p).dot(n).clamp(0.0, length);
            let off = centre - (p + n * along);
            if off.norm_squared() > bound * bound {
                return length;
            }
            // Ties (two moves' shared end ball) go to the lower index, whatever the order
            // of the walk: the ridges below pair samples by their bodies.
            if let Some(t) = self.entry(i, p, n)
                && best.is_none_or(|(h, j)| t < h || (t == h && i < j))
            {
                best = Some((t, i));
            }
            best.map_or(reach, |(h, _)| h.min(reach))
        };
        let length = match hint {
            Some(i) => try_body(i),
            None => reach,
        };
        self.tree.visit_along(p, n, length, &mut try_body);
        best
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::{Direction, Move, ToolPose, closest_point_on_triangle};

    /// The tree's walk, narrowed by the best entry as it goes, finds the least entry of
    /// every body along rays through a tangle of capsules and sheets: the brute-force least.
    #[test]
    fn the_body_tree_finds_the_least_entry_of_every_body() {
        let mut random = crate::geom::SeededRandom::new(2026);
        let point = |random: &mut crate::geom::SeededRandom, spread: f64| {
            Point3::new(
                random.range(-spread, spread),
                random.range(-spread, spread),
                random.range(-spread, spread),
            )
        };
        let swept: Vec<Swept> = (0..400)
            .map(|i| {
                let a = point(&mut random, 10.0);
                let b = a + point(&mut random, 1.5).coords;
                if i % 3 == 0 {
                    Swept::Sheet([a, b, a + point(&mut random, 1.5).coords])
                } else {
                    Swept::Capsule(a, b)
                }
            })
            .collect();
        let radii: Vec<f64> = (0..swept.len())
            .map(|i| 0.5 + 0.25 * (i % 4) as f64)
            .collect();
        let tree = BodyTree::new(&swept, &radii);
        let reach = 6.0;
        let mut hits = 0;
        for _ in 0..500 {
            let p = point(&mut random, 12.0);
            let d = point(&mut random, 1.0)
                .coords
                .try_normalize(1e-9)
                .unwrap_or_else(Vector3::z);
            let least = |i: usize| swept[i].entry(&p, &d, radii[i]).filter(|t| *t <= reach);
            let brute = (0..swept.len()).filter_map(least).reduce(f64::min);
            let mut best: Option<f64> = None;
            tree.visit_along(&p, &d, reach, |i| {
                if let Some(t) = least(i) {
                    best = Some(best.map_or(t, |b| b.min(t)));
                }
                best.unwrap_or(reach)
            });
            assert_eq!(best, brute);
            hits += usize::from(brute.is_some());
        }
        // Both kinds of answer were asked for.
        assert!(hits > 50 && hits < 450, "{hits} of 500 rays hit");
    }

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

    /// The entry into a rounded triangle agrees with marching along the ray and asking the
    /// exact distance to the triangle, on rays from every side (faces, edges, corners, a
    /// sliver triangle, a triangle the ray starts within the radius of).
    #[test]
    fn the_ray_enters_a_rounded_triangle_where_marching_finds_it() {
        let triangles = [
            [
                Point3::new(0.0, 0.0, 0.0),
                Point3::new(4.0, 0.0, 0.0),
                Point3::new(0.0, 3.0, 0.0),
            ],
            [
                Point3::new(-1.0, 2.0, 1.0),
                Point3::new(3.0, -1.0, 2.5),
                Point3::new(1.0, 4.0, -2.0),
            ],
            // A sliver: nearly a segment.
            [
                Point3::new(0.0, 0.0, 0.0),
                Point3::new(5.0, 0.0, 0.0),
                Point3::new(2.5, 1e-9, 0.0),
            ],
        ];
        let r = 0.7;
        let (step, length) = (1e-3, 12.0);
        let mut hits = 0;
        let mut random = crate::geom::SeededRandom::new(12345);
        let mut unit = || random.unit();
        for corners in &triangles {
            let [a, b, c] = corners;
            for _ in 0..300 {
                let p = Point3::new(
                    -3.0 + 10.0 * unit(),
                    -3.0 + 10.0 * unit(),
                    -4.0 + 8.0 * unit(),
                );
                // Aimed near the triangle (within ±2 of a point on it), or anywhere.
                let (u, v) = (unit(), unit());
                let on = a + (b - a) * (u * (1.0 - v)) + (c - a) * (v * (1.0 - u));
                let aim = on + Vector3::new(unit() - 0.5, unit() - 0.5, unit() - 0.5) * 4.0;
                let d = if unit() < 0.8 {
                    (aim - p).normalize()
                } else {
                    Vector3::new(unit() - 0.5, unit() - 0.5, unit() - 0.5).normalize()
                };
                let distance = |t: f64| {
                    let x = p + d * t;
                    (x - closest_point_on_triangle(&x, a, b, c).0).norm()
                };
                let marched = (0..=(length / step) as usize)
                    .map(|k| k as f64 * step)
                    .find(|&t| distance(t) <= r);
                let entry = ray_rounded_triangle_entry(&p, &d, corners, r);
                match (marched, entry) {
                    (Some(m), Some(e)) => {
                        hits += 1;
                        assert!(e <= m + 1e-9 && e > m - step - 1e-9, "{m} vs {e}");
                    }
                    (None, None) => {}
                    // Beyond the march, or a graze it stepped over: on the body's boundary.
                    (None, Some(e)) if e > length || (distance(e) - r).abs() < 1e-9 => {}
                    (m, e) => panic!("{p:?} {d:?} marched {m:?}, entry {e:?}"),
                }
            }
        }
        assert!(hits > 300, "{hits}");
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

    /// Given the tool, what no axis reaches is told apart from the open area and nothing
    /// else: a machine that holds the tool only pointing down (no ball's lower half toward
    /// the plate's top) blocks all of the top over the target; one that holds it every way
    /// blocks nothing and leaves the figures as measured without the tool.
    #[test]
    fn open_samples_no_axis_reaches_are_blocked_and_left_out_of_the_open_figures() {
        let plate = crate::mesh::fixtures::cuboid(20.0, 20.0, 1.0);
        let path = passes((0..30).map(|k| -2.0 + k as f64 * 0.8));
        let options = ScallopOptions {
            radius: 2.0,
            target: 0.02,
            spacing: 0.1,
            reach: 4.0,
            table_z: -10.0,
            flutes_above_ball: 0.0,
        };
        let ball = Ball {
            radius: 2.0,
            flutes_above_ball: 0.0,
        };
        let body = |role, from, to| crate::tool::Body {
            role,
            from,
            to,
            radius_from: 2.0,
            radius_to: 2.0,
        };
        let bodies = vec![
            body(crate::tool::BodyRole::Flutes, 2.0, 10.0),
            body(crate::tool::BodyRole::Shank, 10.0, 30.0),
        ];
        let (plain, _) = measure_scallop_map_of(&plate, &[(&path, ball)], &options, None, None);
        assert!(plain.open_over_target_mm2 > 10.0 && plain.blocked_area_mm2 == 0.0);

        let every_way = |_: &Vector3| true;
        let free = ToolReach::new(bodies.clone(), 0.5, 2.0, None, &every_way, 200);
        let (freely, _) =
            measure_scallop_map_of(&plate, &[(&path, ball)], &options, None, Some(&free));
        assert_eq!(freely, plain);

        let down = |axis: &Vector3| axis.z < 0.0;
        let upside_down = ToolReach::new(bodies, 0.5, 2.0, None, &down, 200);
        let (blocked, patches) =
            measure_scallop_map_of(&plate, &[(&path, ball)], &options, None, Some(&upside_down));
        assert!((blocked.blocked_area_mm2 - plain.open_over_target_mm2).abs() < 1e-9);
        assert_eq!(blocked.open_over_target_mm2, 0.0);
        assert!(blocked.open_max_mm <= options.target);
        assert_eq!(blocked.over_target_area_mm2, plain.over_target_area_mm2);
        assert_eq!(blocked.max_mm, plain.max_mm);
        assert!(
            patches
                .iter()
                .any(|p| matches!(p.found, SampleScallop::Blocked(_)))
        );
        assert!(
            !patches
                .iter()
                .any(|p| matches!(p.found, SampleScallop::Over(_)))
        );
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

    /// Samples a spacing apart read a fraction of the cusps between passes closer than
    /// that; the ridges between neighbouring samples held by different passes find the
    /// closed-form cusp exactly, also where the passes are several to a spacing (the search
    /// splits at each pass lower between two). Each pass is cut in 1 mm moves: samples held
    /// by two moves of one pass are searched too, and find nothing higher.
    #[test]
    fn the_ridges_between_samples_hold_the_closed_form_cusp() {
        let plate = crate::mesh::fixtures::cuboid(20.0, 20.0, 1.0);
        let r = 2.0;
        let axis = Direction::new_normalize(Vector3::z());
        let path = |w: f64| {
            let mut moves = Vec::new();
            for k in 0..(24.0 / w) as usize {
                let y = -2.0 + k as f64 * w;
                moves.push(Move {
                    pose: ToolPose {
                        tip: Point3::new(-3.0, y, 1.0),
                        axis,
                    },
                    kind: MoveKind::Approach,
                    feed: 1000.0,
                });
                for x in -2..=23 {
                    moves.push(Move {
                        pose: ToolPose {
                            tip: Point3::new(f64::from(x), y, 1.0),
                            axis,
                        },
                        kind: MoveKind::Cut,
                        feed: 1000.0,
                    });
                }
            }
            Toolpath { tool_id: 1, moves }
        };
        let options = |spacing, target| ScallopOptions {
            radius: r,
            target,
            spacing,
            reach: 2.0 * r,
            table_z: 0.0,
            flutes_above_ball: 0.0,
        };
        for (w, spacing) in [(0.7, 0.5), (0.1, 1.0)] {
            let cusp = r - (r * r - (w / 2.0) * (w / 2.0)).sqrt();
            let report = measure_scallop(&plate, &path(w), &options(spacing, 1.0), None);
            assert!(report.max_mm < cusp - 1e-4, "{report:?} vs {cusp}");
            assert!(report.ridge_pairs > 1000, "{report:?}");
            assert!(
                (report.open_max_mm - cusp).abs() < 1e-6
                    && report.ridge_max_mm == report.open_max_mm,
                "{report:?} vs {cusp}"
            );
            assert_eq!(report.ridges_over_target, 0);
        }
        // Over the target, each ridge counts the sample nearer to it as over: with passes
        // 0.7 mm apart under samples 0.5 mm apart, every other sample or so.
        let w = 0.7;
        let cusp = r - (r * r - (w / 2.0) * (w / 2.0)).sqrt();
        let report = measure_scallop(&plate, &path(w), &options(0.5, 0.5 * cusp), None);
        assert!(report.ridges_over_target > 500, "{report:?}");
        assert!(
            report.open_over_target_mm2 > 100.0 && report.open_over_target_mm2 < 400.0,
            "{report:?}"
        );
    }

    /// Two sets of passes measured together leave what neither sweeps: with one ball, exactly
    /// what the passes joined into one path leave; with a smaller ball between a larger one's
    /// passes, the closed-form cusp where the two balls' bottoms cross.
    #[test]
    fn passes_of_two_balls_leave_what_neither_sweeps() {
        let plate = crate::mesh::fixtures::cuboid(20.0, 20.0, 1.0);
        let options = ScallopOptions {
            radius: 2.0,
            target: 0.02,
            spacing: 0.05,
            reach: 4.0,
            table_z: 0.0,
            flutes_above_ball: 0.0,
        };
        let (big, small) = (
            Ball {
                radius: 2.0,
                flutes_above_ball: 0.0,
            },
            Ball {
                radius: 1.0,
                flutes_above_ball: 0.0,
            },
        );
        let (s, w) = (0.8, 1.6);
        let first = passes((0..15).map(|k| -2.0 + k as f64 * w));
        let second = passes((0..15).map(|k| -2.0 + s + k as f64 * w));
        let joined = Toolpath {
            tool_id: 1,
            moves: first.moves.iter().chain(&second.moves).copied().collect(),
        };
        let (together, _) = measure_scallop_map_of(
            &plate,
            &[(&first, big), (&second, big)],
            &options,
            None,
            None,
        );
        let (one, _) = measure_scallop_map(&plate, &joined, &options, None);
        assert_eq!(format!("{together:?}"), format!("{one:?}"));
        let alone = measure_scallop(&plate, &first, &options, None);
        assert!(alone.max_mm > 2.0 * together.max_mm, "{alone:?}");

        // The big ball's bottom z = R − √(R² − y²) and the small one's, s beside it, cross at
        // the cusp (plate top at z = 0 here).
        let bottom = |ball: &Ball, y: f64| ball.radius - (ball.radius.powi(2) - y * y).sqrt();
        let (mut lo, mut hi) = (0.0, s);
        for _ in 0..100 {
            let y = 0.5 * (lo + hi);
            if bottom(&big, y) < bottom(&small, y - s) {
                lo = y;
            } else {
                hi = y;
            }
        }
        let cusp = bottom(&big, lo);
        let (mixed, _) = measure_scallop_map_of(
            &plate,
            &[(&first, big), (&second, small)],
            &options,
            None,
            None,
        );
        assert!(
            (mixed.max_mm - cusp).abs() < 6e-3 && mixed.max_mm <= cusp + 1e-9,
            "{} vs {cusp}",
            mixed.max_mm
        );
        // Above the cusp of two big balls s apart, below that of two small ones.
        let same = |r: f64| r - (r * r - (s / 2.0) * (s / 2.0)).sqrt();
        assert!(cusp > same(2.0) && cusp < same(1.0));
    }

    /// The patches cover the part, each what its sample found: over the plate's top the
    /// cusp (over a 0.02 mm target) at most, its sides not reached, its bottom the table's; a
    /// triangle too small for samples of its own is one patch with its pool's (samples 21 mm
    /// apart stand for 220 mm²: the two halves of the top pool, and the eight sides, 80 mm²,
    /// are the pool the triangles ran out before it filled, counted all the same).
    #[test]
    fn the_patches_cover_the_part_with_what_was_found_there() {
        let plate = crate::mesh::fixtures::cuboid(20.0, 20.0, 1.0);
        let (r, w) = (2.0, 0.8);
        let path = passes((0..30).map(|k| -2.0 + k as f64 * w));
        let options = ScallopOptions {
            radius: r,
            target: 0.02,
            spacing: 0.5,
            reach: 2.0 * r,
            table_z: 0.0,
            flutes_above_ball: 0.0,
        };
        let area = |p: &ScallopPatch| {
            let [a, b, c] = p.corners;
            0.5 * (b - a).cross(&(c - a)).norm()
        };
        let (report, patches) = measure_scallop_map(&plate, &path, &options, None);
        let total: f64 = patches.iter().map(area).sum();
        assert!((total - plate.surface_area()).abs() < 1e-6, "{total}");
        let mut worst: f64 = 0.0;
        for patch in &patches {
            let [a, b, c] = patch.corners;
            let normal = (b - a).cross(&(c - a)).normalize();
            match patch.found {
                SampleScallop::Table => assert!(normal.z < -0.99),
                SampleScallop::NotReached => assert!(normal.z.abs() < 1e-9),
                SampleScallop::Within(h) | SampleScallop::Over(h) => {
                    assert!(normal.z > 0.99);
                    worst = worst.max(h);
                    assert_eq!(h > 0.02, matches!(patch.found, SampleScallop::Over(_)));
                }
                SampleScallop::Narrow => panic!("nothing is narrow on a plate"),
                SampleScallop::Blocked(_) => panic!("no tool was given to block anything"),
            }
        }
        assert_eq!(worst, report.max_mm);
        // The cusps run along x: both kinds lie on the top.
        assert!(
            patches
                .iter()
                .any(|p| matches!(p.found, SampleScallop::Over(_)))
        );
        assert!(
            patches
                .iter()
                .any(|p| matches!(p.found, SampleScallop::Within(_)))
        );

        let coarse = ScallopOptions {
            spacing: 21.0,
            ..options
        };
        let (pooled_report, pooled) = measure_scallop_map(&plate, &path, &coarse, None);
        assert_eq!(pooled_report.samples, 3);
        assert_eq!(pooled.len(), plate.triangles.len());
        assert_eq!(pooled[0].found, pooled[1].found);
        assert_eq!(pooled[0].found, SampleScallop::Table);
        assert_eq!(pooled[2].found, pooled[3].found);
        assert!(
            pooled[4..]
                .iter()
                .all(|p| p.found == SampleScallop::NotReached)
        );
        assert!((pooled_report.unreached_area_mm2 - 80.0).abs() < 1e-9);
        assert!((pooled_report.reached_area_mm2 - 400.0).abs() < 1e-9);
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

    /// An upright tool runs along a wall `height` mm tall with its ball's centre 2 mm up:
    /// the wall's area over the target and not reached with flutes `flutes_above_ball` long.
    fn wall_left(height: f64, flutes_above_ball: f64) -> AreaSplit {
        let (r, target) = (2.0, 0.01);
        let block = crate::mesh::fixtures::cuboid(20.0, 20.0, height);
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
    }

    /// Along a 10 mm wall the flutes sweep it from the ball's centre to its top within the
    /// target, so only the strip under the ball's equator is over the target; with the balls
    /// alone everything above the ball's reach is left.
    #[test]
    fn flutes_along_a_wall_sweep_it_from_the_ball_up() {
        let (r, target): (f64, f64) = (2.0, 0.01);
        let with_flutes = wall_left(10.0, 10.0);
        assert!((with_flutes.area_mm2 - 200.0).abs() < 1e-6);
        assert!(with_flutes.unreached_mm2 < 1e-9, "{with_flutes:?}");
        // Over the target: the strip below the ball's centre where its side stands more than
        // the target off the wall, z < r − √(r² − (r − target)²), in closed form.
        let strip = 20.0 * (r - (r * r - (r - target).powi(2)).sqrt());
        assert!(
            (with_flutes.over_target_mm2 - strip).abs() <= 2.0,
            "{with_flutes:?} against {strip}"
        );
        let balls_alone = wall_left(10.0, 0.0);
        // Above z = 4 nothing of the ball reaches the wall within a radius.
        assert!(
            balls_alone.unreached_mm2 >= 20.0 * 6.0 - 1.0,
            "{balls_alone:?}"
        );
    }

    /// A wall ending a millimetre above the ball's centre (a blade's low stretch by the rim):
    /// the flutes sweep that millimetre too, though their axis a quarter of the way up is
    /// above the wall (which the measure once took for flutes off the part: 1 mm × 20 over the
    /// target).
    #[test]
    fn a_low_wall_is_swept_by_the_flutes_just_above_the_ball() {
        let (r, target): (f64, f64) = (2.0, 0.01);
        let low = wall_left(3.0, 10.0);
        assert!((low.area_mm2 - 60.0).abs() < 1e-6);
        let strip = 20.0 * (r - (r * r - (r - target).powi(2)).sqrt());
        assert!(
            low.unreached_mm2 < 1e-9 && (low.over_target_mm2 - strip).abs() <= 2.0,
            "{low:?} against {strip}"
        );
    }
}
