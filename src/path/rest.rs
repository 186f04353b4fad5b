//! Rest passes where the planned passes leave the scallop over the target: seed 000/001's
//! coverage rule (alg. 5.1, every point within δ of a pass, partial passes only where needed)
//! checked on the balls as placed rather than on the drive surface.
//!
//! A strategy spaces its passes by a model of the surface (the hub's surface of revolution,
//! level sets round a blade, a tip's land as a strip between two crests); where the part
//! departs from the model (a tip rounding over, the land twisting off its crests, the cone
//! at a rim) neighbouring balls leave more than the target between them. Those places are
//! found by measuring, not by a better model:
//!
//! * **Gaps.** The surface is sampled evenly (slivers too); at each sample the scallop is
//!   how far along the normal the nearest swept body begins (the balls swept along the
//!   passes' centres, and the flutes' side where a pass cuts with it): on a surface between
//!   two passes s apart this is r − √(r² − s²/4) ≈ s²/8r, the scallop itself. Samples where
//!   the ball does not fit (concave more tightly) are no pass's to mend. Measured again
//!   after passes are added, only what was over the target or out of reach is measured
//!   ([`GapSamples`]): a pass added only brings a gap down.
//! * **Places.** Samples over the target next to each other; places on one ridge a few
//!   millimetres apart are joined (one pass along both costs less than a link to each).
//! * **Rest curves.** Each place's ridge: the run of the passes beside it (the swept
//!   bodies' mean direction there, in the surface's tangent plane), the place's middle
//!   across it bin by bin, run on past both ends by `overlap`, projected onto the part. A
//!   ball along it halves the spacing where the neighbours were too far apart. (A ball
//!   crossing a ridge closes it only for a stepover's width: tried on places joined across
//!   neighbouring ridges, three rounds left a third of the area.) A place no wider than a
//!   stepover that runs across its passes — a band along an edge where they stop, a low
//!   wall they cross at a slant, each stretch between two passes a place of its own — is
//!   run along its own length instead, the stretches joined: one ball closes the band.
//!   Samples on two faces of an edge are two places (a face no tool reaches beside one it
//!   does), and a curve keeps to its place's face; where it would stay on it for less than
//!   a stepover (a wall lower than that, its passes running up it) it runs across instead,
//!   along the wall.
//!
//! The estimate is the planner's own: the report's scallop is measured afterwards on the
//! posted program by [`crate::verify`], with rays along the normals, by code this does not
//! share.

use std::collections::HashMap;

use nalgebra::Isometry3;
use rayon::prelude::*;

use crate::geom::{Point3, ToolPose, Vector3, closest_point_on_segment};
use crate::mesh::{DrivePoint, Mesh, SectionCurve, SurfaceDistance};

use super::CutSegment;

/// How gaps are found and rest curves drawn.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RestOptions {
    pub ball_radius: f64,
    /// Target scallop height, mm.
    pub scallop_height: f64,
    /// Distance between samples, mm.
    pub sample_spacing: f64,
    /// Largest gap measured, mm: a sample farther from every swept body is not reached
    /// (another strategy's, or out of the tool's reach), not a gap between passes.
    pub reach: f64,
    /// How far a rest curve runs on past its cluster's ends, mm.
    pub overlap: f64,
    /// Distance between a rest curve's points, mm.
    pub step: f64,
    /// A place at most this wide across its length and longer than twice that is run along
    /// its length, whichever way the passes beside it run (a band along an edge the passes
    /// stop at, or a wall the passes cross at a slant): one ball along its middle closes it,
    /// where rest curves along the passes would take one per gap between them. The stepover;
    /// `None`: every place runs along its passes.
    pub thin: Option<f64>,
}

/// A sample of the part left over the target.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Gap {
    pub point: Point3,
    /// The part's outward normal there.
    pub normal: Vector3,
    /// The scallop estimated there, mm.
    pub height: f64,
    pub triangle: u32,
    /// The part's area the sample stands for, mm².
    pub area: f64,
    /// The direction the nearest swept body runs in there (either way).
    pub along: Vector3,
}

/// The bodies the passes sweep: capsules round the ball centres' moves, and stacks of them up
/// the axis where the flutes cut, hashed by the cells their reach overlaps.
pub struct SweptTool {
    radius: f64,
    reach: f64,
    cell: f64,
    capsules: Vec<[Point3; 2]>,
    /// The direction each capsule's pass runs in (a flute's capsule stands up the axis).
    along: Vec<Vector3>,
    cells: HashMap<[i64; 3], Vec<u32>>,
}

impl SweptTool {
    /// Empty, for a ball of `radius`; gaps up to `reach` are measured.
    pub fn new(radius: f64, reach: f64) -> Self {
        Self {
            radius,
            reach,
            cell: (radius + reach).max(1e-3),
            capsules: Vec::new(),
            along: Vec::new(),
            cells: HashMap::new(),
        }
    }

    fn key(&self, p: &Point3) -> [i64; 3] {
        [0, 1, 2].map(|k| (p[k] / self.cell).floor() as i64)
    }

    /// Adds the ball swept along `segment`'s poses and, with `flutes_above_ball` > 0 (a
    /// swarf run: the flutes' side cuts), the flutes up to that far above the ball's centre,
    /// as capsules up the axis of poses interpolated along each move `scallop` apart in
    /// height terms (balls √(2r·h) apart leave h/4 between them). (Stacked along the moves
    /// instead, a capsule every such step up the flutes, the swarf runs' bodies filled the
    /// cells by the thousand and their measure took seconds.)
    pub fn insert(&mut self, segment: &CutSegment, flutes_above_ball: f64, scallop: f64) {
        let step = (2.0 * self.radius * scallop).sqrt().max(1e-3);
        let radius = self.radius;
        let poses = &segment.poses;
        let centre = |pose: &ToolPose| pose.tip + pose.axis.into_inner() * radius;
        // Each move from pose to pose; a lone pose, a move that stays.
        let moves: Vec<(&ToolPose, &ToolPose)> = match poses.len() {
            1 => vec![(&poses[0], &poses[0])],
            _ => poses.windows(2).map(|w| (&w[0], &w[1])).collect(),
        };
        for &(from, to) in &moves {
            let (a, b) = (centre(from), centre(to));
            self.insert_capsule(a, b, b - a);
        }
        if flutes_above_ball <= 0.0 {
            return;
        }
        for (m, &(from, to)) in moves.iter().enumerate() {
            let along = centre(to) - centre(from);
            let pieces = (along.norm() / step).ceil().max(1.0) as usize;
            // The move's first pose is the one before's last.
            for j in usize::from(m > 0)..=pieces {
                let t = j as f64 / pieces as f64;
                let tip = from.tip + (to.tip - from.tip) * t;
                let axis = (from.axis.into_inner() * (1.0 - t) + to.axis.into_inner() * t)
                    .try_normalize(1e-12)
                    .unwrap_or_else(Vector3::z);
                let bottom = tip + axis * radius;
                self.insert_capsule(bottom, bottom + axis * flutes_above_ball, along);
            }
        }
    }

    /// Adds the capsule round `a b`, whose passes run along `along`.
    fn insert_capsule(&mut self, a: Point3, b: Point3, along: Vector3) {
        let index = self.capsules.len() as u32;
        self.capsules.push([a, b]);
        self.along
            .push(along.try_normalize(1e-12).unwrap_or_else(Vector3::zeros));
        let grow = self.radius + self.reach;
        let lo = self.key(&a.inf(&b).map(|v| v - grow));
        let hi = self.key(&a.sup(&b).map(|v| v + grow));
        for x in lo[0]..=hi[0] {
            for y in lo[1]..=hi[1] {
                for z in lo[2]..=hi[2] {
                    self.cells.entry([x, y, z]).or_default().push(index);
                }
            }
        }
    }

    /// How far from `p` (on the part, outward `normal`) along the normal the nearest swept
    /// body in front of it begins (0 inside one), and the direction that body runs in, when
    /// that is within the reach: the scallop as the verifier and [`super::stepover_for_scallop`]
    /// measure it, `r − √(r² − s²/4)` between balls `s` apart over a plane. (The distance to
    /// the body instead, `√(r² + s²/4) − r`, is less wherever the balls stand off the normal:
    /// by 30 % between passes at the target's stepover, and more in a concave corner, where
    /// the ball finishing it stands on the wall beside.) In front: the body's axis at least
    /// half the radius above `p`'s tangent plane (a ball touching the face stands a radius
    /// above it). Others are a neighbouring face's across a convex edge, or the far side's of
    /// a thin wall (a disc 1 mm thick: the hub's balls 1 mm above its underside), and leave no
    /// scallop on this face.
    pub fn gap(&self, p: &Point3, normal: &Vector3) -> Option<(f64, Vector3)> {
        self.nearest_body(p, normal, 0, -1.0)
            .map(|(d, i)| (d, self.direction(i)))
    }

    /// [`Self::gap`], or a body no farther than `enough` when there is one (not
    /// necessarily the nearest: the first found ends the search, most samples being within
    /// the target), trying the body `hint` names first and naming there the one found (a
    /// sample's neighbour is most often within the target of the same body).
    pub fn gap_or_within(
        &self,
        p: &Point3,
        normal: &Vector3,
        enough: f64,
        hint: &mut Option<u32>,
    ) -> Option<(f64, Vector3)> {
        if let Some(i) = *hint
            && let Some(d) = self.entry(i, p, normal, enough)
        {
            return Some((d, self.direction(i)));
        }
        let (d, i) = self.nearest_body(p, normal, 0, enough)?;
        if d <= enough {
            *hint = Some(i);
        }
        Some((d, self.direction(i)))
    }

    /// Where the ray from `p` along `normal` enters body `i`, when the body is in front of
    /// `p` and the entry no farther than `limit`.
    fn entry(&self, i: u32, p: &Point3, normal: &Vector3, limit: f64) -> Option<f64> {
        let [a, b] = self.capsules[i as usize];
        let nearest = closest_point_on_segment(p, &a, &b) - p;
        if nearest.dot(normal) < 0.5 * self.radius {
            return None;
        }
        // The ray enters no nearer than the body is.
        if nearest.norm() - self.radius > limit {
            return None;
        }
        ray_capsule_entry(p, normal, &a, &b, self.radius).filter(|&d| d <= limit)
    }

    /// Bodies swept so far: those inserted after this are told apart by [`Self::gap_among`].
    pub fn count(&self) -> u32 {
        self.capsules.len() as u32
    }

    /// [`Self::gap`] among the bodies from the `first`th on.
    pub fn gap_among(&self, p: &Point3, normal: &Vector3, first: u32) -> Option<(f64, Vector3)> {
        self.nearest_body(p, normal, first, -1.0)
            .map(|(d, i)| (d, self.direction(i)))
    }

    /// The direction body `i` runs in.
    fn direction(&self, i: u32) -> Vector3 {
        self.along[i as usize]
    }

    /// The body from the `first`th on whose entry along the normal is nearest (the first
    /// inserted of equals), and that entry; or the first found no farther than `enough`.
    fn nearest_body(
        &self,
        p: &Point3,
        normal: &Vector3,
        first: u32,
        enough: f64,
    ) -> Option<(f64, u32)> {
        let mut best: Option<(f64, u32)> = None;
        let cell = self.cells.get(&self.key(p))?;
        // Each cell's bodies are in the order they were inserted.
        for &i in &cell[cell.partition_point(|&i| i < first)..] {
            let limit = best.map_or(self.reach, |(e, _)| e);
            if let Some(d) = self.entry(i, p, normal, limit) {
                if d <= enough {
                    return Some((d, i));
                }
                if best.is_none_or(|(e, j)| d < e || (d == e && i < j)) {
                    best = Some((d, i));
                }
            }
        }
        best
    }
}

/// Where the ray from `p` along unit `direction` first meets the capsule of radius `r` round
/// segment `a b`: 0 when `p` is inside it, `None` when the ray misses it. The capsule is a
/// cylinder between two balls; the ray enters it through one of the three.
fn ray_capsule_entry(
    p: &Point3,
    direction: &Vector3,
    a: &Point3,
    b: &Point3,
    r: f64,
) -> Option<f64> {
    if (closest_point_on_segment(p, a, b) - p).norm_squared() <= r * r {
        return Some(0.0);
    }
    // |m + t·direction| = r for m = p − centre, the smaller root, ahead of p.
    let ball = |centre: &Point3| {
        let m = p - centre;
        let half = m.dot(direction);
        let discriminant = half * half - (m.norm_squared() - r * r);
        (discriminant >= 0.0)
            .then(|| -half - discriminant.sqrt())
            .filter(|&t| t >= 0.0)
    };
    let mut entry = [ball(a), ball(b)]
        .into_iter()
        .flatten()
        .fold(f64::INFINITY, f64::min);
    let axis = b - a;
    let length = axis.norm();
    if length > 0.0 {
        let axis = axis / length;
        // Square to the axis, the ray is a line in the plane: |m⊥ + t·d⊥| = r.
        let m = p - a;
        let (m_across, d_across) = (
            m - axis * m.dot(&axis),
            direction - axis * direction.dot(&axis),
        );
        let (aa, bb, cc) = (
            d_across.norm_squared(),
            m_across.dot(&d_across),
            m_across.norm_squared() - r * r,
        );
        let discriminant = bb * bb - aa * cc;
        if aa > 0.0 && discriminant >= 0.0 {
            let t = (-bb - discriminant.sqrt()) / aa;
            let along = (m + direction * t).dot(&axis);
            if t >= 0.0 && (0.0..=length).contains(&along) {
                entry = entry.min(t);
            }
        }
    }
    entry.is_finite().then_some(entry)
}

/// The samples of `part`'s triangles that `sampled` marks where the passes in `swept` leave
/// more than the target and the ball fits. `views` place a sample among the passes (the
/// identity, and for a pattern of copies the inverse of each copy's placement): its gap is
/// the least over them.
pub fn gaps(
    part: &Mesh,
    surface: &SurfaceDistance,
    sampled: &[bool],
    swept: &SweptTool,
    views: &[Isometry3<f64>],
    options: &RestOptions,
) -> Vec<Gap> {
    GapSamples::new(part, sampled, options).measure(surface, swept, views, options)
}

/// The samples of a surface, measured again and again as passes are added ([`gaps`] once).
/// A pass added only brings a sample's gap down, so a sample once within the target stays
/// within it and is not measured again, nor one where no ball fits: after the first round
/// only what was over the target or out of reach is.
pub struct GapSamples {
    /// Point, outward normal, triangle and the area it stands for.
    samples: Vec<(Point3, Vector3, u32, f64)>,
    /// The samples still to measure, in order, with the count of bodies swept when no body
    /// was within reach of one (`None`: over the target then).
    open: Vec<(u32, Option<u32>)>,
}

/// What measuring a sample found.
enum Sample {
    Within,
    OutOfReach,
    Over(f64, Vector3),
    /// Concave more tightly than the ball.
    Tight,
}

impl GapSamples {
    /// Samples of the triangles `sampled` marks, [`RestOptions::sample_spacing`] apart.
    pub fn new(part: &Mesh, sampled: &[bool], options: &RestOptions) -> Self {
        let samples: Vec<(Point3, Vector3, u32, f64)> = (0..part.triangles.len())
            .filter(|&t| sampled.get(t).copied().unwrap_or(false))
            .collect::<Vec<_>>()
            .par_iter()
            .flat_map_iter(|&t| {
                let normal = part.face_normal(t);
                let mut points = Vec::new();
                surface_samples(part.corners(t), options.sample_spacing, &mut points);
                points
                    .into_iter()
                    .map(move |(point, share)| (point, normal, t as u32, share))
            })
            .collect();
        let open = (0..samples.len() as u32).map(|i| (i, Some(0))).collect();
        Self { samples, open }
    }

    /// Leaves out of the measure the samples whose point `keep` refuses.
    pub fn retain(&mut self, keep: impl Fn(&Point3) -> bool) {
        let samples = &self.samples;
        self.open.retain(|&(i, _)| keep(&samples[i as usize].0));
    }

    /// The samples over the target where the ball fits, in order.
    pub fn measure(
        &mut self,
        surface: &SurfaceDistance,
        swept: &SweptTool,
        views: &[Isometry3<f64>],
        options: &RestOptions,
    ) -> Vec<Gap> {
        let radius = options.ball_radius;
        let target = options.scallop_height;
        let measured: Vec<Sample> = self
            .open
            .par_iter()
            .map_init(
                || vec![None; views.len()],
                |hints, &(i, out_of_reach_among)| {
                    let (point, normal, _, _) = self.samples[i as usize];
                    // Out of reach of every body before: only a body since can reach it.
                    // (Before any measure every sample is "out of reach of none": the search
                    // below settles it.)
                    if let Some(first) = out_of_reach_among
                        && first > 0
                        && views.iter().all(|view| {
                            swept
                                .gap_among(
                                    &view.transform_point(&point),
                                    &view.transform_vector(&normal),
                                    first,
                                )
                                .is_none()
                        })
                    {
                        return Sample::OutOfReach;
                    }
                    // Most samples are within the target among some view's bodies: the first
                    // that says so settles it, the nearest is sought only over the target.
                    let mut nearest: Option<(f64, Vector3)> = None;
                    for (view, hint) in views.iter().zip(hints.iter_mut()) {
                        let Some((h, d)) = swept.gap_or_within(
                            &view.transform_point(&point),
                            &view.transform_vector(&normal),
                            target,
                            hint,
                        ) else {
                            continue;
                        };
                        if h <= target {
                            return Sample::Within;
                        }
                        if nearest.is_none_or(|(e, _)| h < e) {
                            nearest = Some((h, view.inverse_transform_vector(&d)));
                        }
                    }
                    let Some((height, along)) = nearest else {
                        return Sample::OutOfReach;
                    };
                    if surface.any_within(&(point + normal * radius), radius - target) {
                        Sample::Tight
                    } else {
                        Sample::Over(height, along)
                    }
                },
            )
            .collect();
        let mut found = Vec::new();
        let mut open = Vec::new();
        let swept_now = swept.count();
        for (&(i, _), sample) in self.open.iter().zip(measured) {
            let (point, normal, triangle, area) = self.samples[i as usize];
            match sample {
                Sample::Within | Sample::Tight => {}
                Sample::OutOfReach => open.push((i, Some(swept_now))),
                Sample::Over(height, along) => {
                    open.push((i, None));
                    found.push(Gap {
                        point,
                        normal,
                        height,
                        triangle,
                        area,
                        along,
                    });
                }
            }
        }
        self.open = open;
        found
    }
}

/// Samples of triangle `corners` about `spacing` apart, each with the area it stands for: in
/// columns across its longest side, a spacing wide or less, and up each column's middle
/// line a spacing apart or less. (A barycentric grid set by the area runs millimetres apart
/// along a sliver: the fans round the blower's bore top, 5 mm long and 0.1 mm wide, kept a
/// 0.035 mm ridge unseen between their samples.)
fn surface_samples(corners: [Point3; 3], spacing: f64, out: &mut Vec<(Point3, f64)>) {
    let [a, b, c] = corners;
    let sides = [(b - a).norm(), (c - b).norm(), (a - c).norm()];
    let longest = (0..3)
        .max_by(|&i, &j| sides[i].total_cmp(&sides[j]))
        .unwrap_or(0);
    // The longest side runs from p to q, r across it; u along p q, v toward r.
    let [p, q, r] = [0, 1, 2].map(|i| corners[(longest + i) % 3]);
    let length = sides[longest];
    // A triangle with no extent stands for no area.
    let Some(along) = (q - p).try_normalize(0.0) else {
        return;
    };
    let to_r = r - p;
    let u_r = to_r.dot(&along).clamp(0.0, length);
    let up = to_r - along * to_r.dot(&along);
    let height = up.norm();
    // The triangle's extent toward r at u: rising to r's foot, falling to q.
    let extent = |u: f64| {
        if u <= u_r {
            if u_r > 0.0 { height * u / u_r } else { height }
        } else if length > u_r {
            height * (length - u) / (length - u_r)
        } else {
            height
        }
    };
    let foot = |u: f64| p + along * u;
    let direction_up = up.try_normalize(0.0).unwrap_or_else(Vector3::zeros);
    // The extent is linear on either side of r's foot: a strip's area by the trapezoid rule
    // on each side.
    let strip_area = |u0: f64, u1: f64| {
        let trapezoid = |x0: f64, x1: f64| 0.5 * (x1 - x0) * (extent(x0) + extent(x1));
        if u0 < u_r && u_r < u1 {
            trapezoid(u0, u_r) + trapezoid(u_r, u1)
        } else {
            trapezoid(u0, u1)
        }
    };
    let columns = (length / spacing).ceil().max(1.0) as usize;
    let width = length / columns as f64;
    for i in 0..columns {
        let (u0, u1) = (i as f64 * width, (i + 1) as f64 * width);
        let u = 0.5 * (u0 + u1);
        let top = extent(u);
        let rows = (top / spacing).ceil().max(1.0) as usize;
        let share = strip_area(u0, u1) / rows as f64;
        for k in 0..rows {
            let v = (k as f64 + 0.5) / rows as f64 * top;
            out.push((foot(u) + direction_up * v, share));
        }
    }
}

/// Neighbouring samples whose normals differ by more than this are on two faces of an edge:
/// a rest curve keeps to one face, and a place on a face no tool reaches (an underside
/// beside the edge) stays apart from the one on the face beside it that a tool does.
const SAME_FACE_DEG: f64 = 35.0;

/// The gaps in clusters: joined when within `join` of each other and on one face (normals
/// within 35°), each cluster's members in the order of `gaps`, clusters in the order of their
/// first member.
pub fn clusters(gaps: &[Gap], join: f64) -> Vec<Vec<usize>> {
    let same_face = SAME_FACE_DEG.to_radians().cos();
    let key = |p: &Point3| [0, 1, 2].map(|k| (p[k] / join).floor() as i64);
    let mut cells: HashMap<[i64; 3], Vec<usize>> = HashMap::new();
    for (i, g) in gaps.iter().enumerate() {
        cells.entry(key(&g.point)).or_default().push(i);
    }
    let mut groups = Groups::new(gaps.len());
    for (i, g) in gaps.iter().enumerate() {
        let [x, y, z] = key(&g.point);
        for dx in -1..=1 {
            for dy in -1..=1 {
                for dz in -1..=1 {
                    let Some(near) = cells.get(&[x + dx, y + dy, z + dz]) else {
                        continue;
                    };
                    for &j in near {
                        if j < i
                            && (gaps[j].point - g.point).norm() <= join
                            && gaps[j].normal.dot(&g.normal) >= same_face
                        {
                            groups.join(i, j);
                        }
                    }
                }
            }
        }
    }
    groups.members()
}

/// Places on one ridge joined: two places whose middles are within `join_along` of each
/// other, whose passes run the same way (within 25°) and which lie within `join_across` of
/// each other's line across it and off it: one pass along both costs less than a link to
/// each. Given `thin`, a place at most that wide runs its own length's way instead of its
/// passes' (see [`RestOptions::thin`]), and joins the places along that. Places in the order of their
/// first member, members in order.
pub fn ridges(
    gaps: &[Gap],
    places: &[Vec<usize>],
    join_along: f64,
    join_across: f64,
    thin: Option<f64>,
) -> Vec<Vec<usize>> {
    let frames: Vec<Option<(Point3, Vector3, Vector3)>> = places
        .iter()
        .map(|members| place_frame(gaps, members, thin))
        .collect();
    let mut groups = Groups::new(places.len());
    let same_way = SAME_WAY_DEG.to_radians().cos();
    for i in 0..places.len() {
        let Some((mi, ni, di)) = frames[i] else {
            continue;
        };
        for (j, frame) in frames.iter().enumerate().take(i) {
            let Some((mj, _, dj)) = *frame else {
                continue;
            };
            let d = mj - mi;
            if d.norm() > join_along || di.dot(&dj).abs() < same_way {
                continue;
            }
            let across = ni.cross(&di);
            if d.dot(&across).abs() <= join_across && d.dot(&ni).abs() <= join_across {
                groups.join(i, j);
            }
        }
    }
    groups
        .members()
        .into_iter()
        .map(|joined| {
            let mut members: Vec<usize> = joined
                .iter()
                .flat_map(|&k| places[k].iter().copied())
                .collect();
            members.sort_unstable();
            members
        })
        .collect()
}

/// Places whose ways differ by less than this run the same way, degrees.
const SAME_WAY_DEG: f64 = 25.0;

/// Items joined into groups (union–find), each group rooted at its smallest item.
struct Groups {
    parent: Vec<usize>,
}

impl Groups {
    fn new(count: usize) -> Self {
        Self {
            parent: (0..count).collect(),
        }
    }

    fn root(&mut self, mut i: usize) -> usize {
        while self.parent[i] != i {
            self.parent[i] = self.parent[self.parent[i]];
            i = self.parent[i];
        }
        i
    }

    fn join(&mut self, a: usize, b: usize) {
        let (a, b) = (self.root(a), self.root(b));
        // The smaller item roots: the groups come in the order of their first items.
        self.parent[a.max(b)] = a.min(b);
    }

    /// The groups, each's items in order, in the order of their first items.
    fn members(mut self) -> Vec<Vec<usize>> {
        let mut slot_of_root: HashMap<usize, usize> = HashMap::new();
        let mut out: Vec<Vec<usize>> = Vec::new();
        for i in 0..self.parent.len() {
            let root = self.root(i);
            let slot = *slot_of_root.entry(root).or_insert_with(|| {
                out.push(Vec::new());
                out.len() - 1
            });
            out[slot].push(i);
        }
        out
    }
}

/// A place's middle, mean normal and the direction a rest curve runs along it (in the
/// tangent plane): its passes' (the samples' swept bodies' directions taken the same way
/// round as the first's), or, given `thin`, its own length's where it is at most that wide,
/// longer than twice that, and runs more than [`SAME_WAY_DEG`] off its passes.
fn place_frame(
    gaps: &[Gap],
    members: &[usize],
    thin: Option<f64>,
) -> Option<(Point3, Vector3, Vector3)> {
    let first = gaps[*members.first()?].along;
    let middle = Point3::from(
        members
            .iter()
            .map(|&i| gaps[i].point.coords)
            .sum::<Vector3>()
            / members.len() as f64,
    );
    let normal = members
        .iter()
        .map(|&i| gaps[i].normal)
        .sum::<Vector3>()
        .try_normalize(1e-9)?;
    let along = members
        .iter()
        .map(|&i| {
            let d = gaps[i].along;
            if d.dot(&first) < 0.0 { -d } else { d }
        })
        .sum::<Vector3>();
    let along = (along - normal * along.dot(&normal)).try_normalize(1e-9)?;
    // The samples' principal direction in the tangent plane, as an angle from `along`.
    let across = normal.cross(&along);
    let (mut aa, mut ab, mut bb) = (0.0, 0.0, 0.0);
    for &i in members {
        let d = gaps[i].point - middle;
        let (a, b) = (d.dot(&along), d.dot(&across));
        aa += a * a;
        ab += a * b;
        bb += b * b;
    }
    let angle = 0.5 * (2.0 * ab).atan2(aa - bb);
    let Some(thin) = thin.filter(|_| angle.abs() > SAME_WAY_DEG.to_radians()) else {
        return Some((middle, normal, along));
    };
    let length = along * angle.cos() + across * angle.sin();
    let width = normal.cross(&length);
    let extent = |direction: &Vector3| {
        let (lo, hi) = members
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &i| {
                let t = (gaps[i].point - middle).dot(direction);
                (lo.min(t), hi.max(t))
            });
        hi - lo
    };
    let wide = extent(&width);
    if wide <= thin && extent(&length) >= 2.0 * wide {
        Some((middle, normal, length))
    } else {
        Some((middle, normal, along))
    }
}

/// The rest curve along the ridge of a cluster of `gaps` (indices `members`): see the module
/// docs. `None` when the cluster gives no direction to run in or nothing projects onto the
/// part.
pub fn rest_curve(
    gaps: &[Gap],
    members: &[usize],
    part: &Mesh,
    surface: &SurfaceDistance,
    options: &RestOptions,
) -> Option<SectionCurve> {
    let (middle, normal, along) = place_frame(gaps, members, options.thin)?;
    let curve = curve_along(gaps, members, part, surface, options, middle, along);
    // A curve that leaves the place's face within a stepover (a wall lower than that, the
    // planes running up it: the blower's rim, 0.25 mm) cuts the place with one pose or
    // none; across, along the wall, it may stay on the face. The longer stretch on it wins.
    let on_face =
        |curve: &Option<SectionCurve>| curve.as_ref().map_or(0.0, |c| face_run(c, &normal));
    if on_face(&curve) >= 2.0 * options.overlap {
        return curve;
    }
    let across = curve_along(
        gaps,
        members,
        part,
        surface,
        options,
        middle,
        normal.cross(&along),
    );
    if on_face(&across) > on_face(&curve) {
        across
    } else {
        curve
    }
}

/// The longest stretch of `curve` on the face whose normal is `normal` (within
/// [`SAME_FACE_DEG`]), mm.
fn face_run(curve: &SectionCurve, normal: &Vector3) -> f64 {
    let same_face = SAME_FACE_DEG.to_radians().cos();
    let (mut longest, mut run) = (0.0_f64, 0.0);
    for pair in curve.points.windows(2) {
        if pair.iter().all(|p| p.normal.dot(normal) >= same_face) {
            run += (pair[1].point - pair[0].point).norm();
            longest = longest.max(run);
        } else {
            run = 0.0;
        }
    }
    longest
}

/// The rest curve through `middle` along `along`, following the samples' ridge.
fn curve_along(
    gaps: &[Gap],
    members: &[usize],
    part: &Mesh,
    surface: &SurfaceDistance,
    options: &RestOptions,
    middle: Point3,
    along: Vector3,
) -> Option<SectionCurve> {
    let same_face = SAME_FACE_DEG.to_radians().cos();
    // Each sample: how far along, its offsets across and off the tangent plane (a place
    // along a curved edge bows off its chord), and its weight, how far over the target.
    let placed: Vec<(f64, Vector3, f64)> = members
        .iter()
        .map(|&i| {
            let d = gaps[i].point - middle;
            let s = d.dot(&along);
            (s, d - along * s, gaps[i].height - options.scallop_height)
        })
        .collect();
    let (lo, hi) = placed.iter().fold(
        (f64::INFINITY, f64::NEG_INFINITY),
        |(lo, hi), &(s, _, _)| (lo.min(s), hi.max(s)),
    );
    let (start, end) = (lo - options.overlap, hi + options.overlap);
    let steps = ((end - start) / options.step.max(1e-3)).ceil().max(1.0) as usize;
    let at = |k: usize| start + (end - start) * k as f64 / steps as f64;
    // Bin by bin, the samples' middle weighted by how far over the target they are (the
    // ridge); between bins with samples, straight across; past them, the end bins'.
    let bin = options.step.max(0.5 * options.sample_spacing);
    let known: Vec<(usize, Vector3)> = (0..=steps)
        .filter_map(|k| {
            let s = at(k);
            let (sum, weight) = placed
                .iter()
                .filter(|(t, _, _)| (t - s).abs() <= bin)
                .fold((Vector3::zeros(), 0.0), |(sum, weight), &(_, off, w)| {
                    (sum + off * w, weight + w)
                });
            (weight > 0.0).then(|| (k, sum / weight))
        })
        .collect();
    let (first, last) = (known.first()?, known.last()?);
    let mut next = 0;
    let points: Vec<DrivePoint> = (0..=steps)
        .filter_map(|k| {
            while next < known.len() && known[next].0 < k {
                next += 1;
            }
            let offset = if k <= first.0 {
                first.1
            } else if k >= last.0 {
                last.1
            } else if known[next].0 == k {
                known[next].1
            } else {
                let ((k0, o0), (k1, o1)) = (known[next - 1], known[next]);
                o0 + (o1 - o0) * ((k - k0) as f64 / (k1 - k0) as f64)
            };
            let guess = middle + along * at(k) + offset;
            // On the face of the place's nearest sample: by an edge the nearest point may be
            // on the face beside (a blade tip's land by its flank), and a drive point there
            // puts the ball beside the place, not on it.
            let face = members
                .iter()
                .map(|&i| &gaps[i])
                .min_by(|x, y| {
                    (x.point - guess)
                        .norm_squared()
                        .total_cmp(&(y.point - guess).norm_squared())
                })?
                .normal;
            let on = surface.closest_where(&guess, options.ball_radius, |t| {
                part.face_normal(t as usize).dot(&face) >= same_face
            })?;
            // Run on past the face's end, the nearest point on it stays at the end.
            if (on.point - guess).dot(&along).abs() > 0.5 * options.step {
                return None;
            }
            Some(DrivePoint {
                point: on.point,
                normal: part.face_normal(on.triangle as usize),
            })
        })
        .collect();
    (points.len() >= 2).then_some(SectionCurve {
        points,
        closed: false,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::{Direction, ToolPose};
    use crate::mesh::fixtures::cuboid;
    use nalgebra::Translation3;

    const RADIUS: f64 = 2.0;
    const TARGET: f64 = 0.01;

    fn options() -> RestOptions {
        RestOptions {
            ball_radius: RADIUS,
            scallop_height: TARGET,
            sample_spacing: 0.1,
            reach: 0.2,
            overlap: 0.4,
            step: 0.25,
            thin: Some(0.4),
        }
    }

    /// A pass of a vertical ball touching the plate's top (z = 5) along x at `y`.
    fn pass_along_x(y: f64) -> CutSegment {
        let axis = Direction::new_normalize(Vector3::z());
        let poses: Vec<ToolPose> = (0..=60)
            .map(|i| ToolPose {
                tip: Point3::new(-5.0 + 0.5 * i as f64, y, 5.0),
                axis,
            })
            .collect();
        CutSegment {
            pass_directions: vec![Vector3::x(); poses.len()],
            poses,
            leads: false,
        }
    }

    /// A 20 × 20 plate, its top sampled, and passes along x over the top 0.3 mm apart (a
    /// scallop of 0.0056 mm) for y in `[0, end]`, except `wide` apart between `at` and
    /// `at + wide`.
    fn plate_with_a_wide_gap(at: f64, wide: f64, end: f64) -> (Mesh, Vec<bool>, SweptTool) {
        let part = cuboid(20.0, 20.0, 5.0);
        let top: Vec<bool> = (0..part.triangles.len())
            .map(|t| part.face_normal(t).z > 0.9)
            .collect();
        let mut swept = SweptTool::new(RADIUS, options().reach);
        let mut y = 0.0;
        while y <= end + 1e-9 {
            swept.insert(&pass_along_x(y), 0.0, TARGET);
            y += if (y - at).abs() < 1e-9 { wide } else { 0.3 };
        }
        (part, top, swept)
    }

    /// The ray's entry into a capsule agrees with marching along the ray in small steps.
    #[test]
    fn ray_capsule_entry_agrees_with_marching() {
        let mut seeded = crate::geom::SeededRandom::new(12345);
        let mut random = || seeded.range(-1.0, 1.0);
        let (mut hits, mut misses) = (0, 0);
        for _ in 0..400 {
            let mut point = || Point3::new(3.0 * random(), 3.0 * random(), 3.0 * random());
            let (p, a, b) = (point(), point(), point());
            let direction = Vector3::new(random(), random(), random()).normalize();
            let r = 0.5 + random().abs();
            let inside = |t: f64| {
                (closest_point_on_segment(&(p + direction * t), &a, &b) - (p + direction * t))
                    .norm()
                    <= r
            };
            let step = 1e-4;
            let marched = (0..100_000).map(|k| k as f64 * step).find(|&t| inside(t));
            match (ray_capsule_entry(&p, &direction, &a, &b, r), marched) {
                (Some(t), Some(m)) => {
                    assert!((t - m).abs() <= step, "{t} {m}");
                    hits += 1;
                }
                (None, None) => misses += 1,
                (entry, marched) => panic!("{entry:?} against {marched:?}"),
            }
        }
        assert!(hits > 50 && misses > 50, "{hits} {misses}");
    }

    /// Measured again after passes are added, the samples give what a fresh measure does:
    /// the band closed by a pass along it, and a place where no ball reached before, which a
    /// pass now reaches without closing.
    #[test]
    fn samples_measured_again_find_what_a_fresh_measure_finds() {
        let (part, top, mut swept) = plate_with_a_wide_gap(8.1, 0.6, 12.0);
        let surface = SurfaceDistance::new(&part);
        let views = [Isometry3::identity()];
        let mut samples = GapSamples::new(&part, &top, &options());
        let first = samples.measure(&surface, &swept, &views, &options());
        assert_eq!(
            first,
            gaps(&part, &surface, &top, &swept, &views, &options())
        );
        // The band, and past the last pass (y ≈ 12.3) where its ball reaches.
        let band = |g: &Gap| g.point.y > 8.1 && g.point.y < 8.7;
        assert!(first.iter().any(band));
        assert!(
            first
                .iter()
                .all(|g| band(g) || (g.point.y > 12.0 && g.point.y < 13.3))
        );
        swept.insert(&pass_along_x(8.4), 0.0, TARGET);
        swept.insert(&pass_along_x(14.0), 0.0, TARGET);
        let again = samples.measure(&surface, &swept, &views, &options());
        let fresh = gaps(&part, &surface, &top, &swept, &views, &options());
        assert_eq!(again, fresh);
        assert!(again.iter().all(|g| g.point.y > 12.0 && g.point.y < 15.0));
        assert!(again.iter().any(|g| g.point.y > 14.2));
    }

    /// Every point of a triangle is near a sample, a sliver's too, and the samples' areas
    /// add up to the triangle's.
    #[test]
    fn samples_cover_slivers_and_well_shaped_triangles_alike() {
        let spacing = 0.2;
        let triangles = [
            // A fan sliver round an annulus: 5 mm long, 0.1 mm wide.
            [
                Point3::new(0.0, 0.0, 0.0),
                Point3::new(5.0, 0.0, 0.0),
                Point3::new(5.0, 0.1, 0.0),
            ],
            [
                Point3::new(0.0, 0.0, 1.0),
                Point3::new(2.0, 0.3, 1.0),
                Point3::new(0.7, 1.9, 1.5),
            ],
            // Obtuse and long.
            [
                Point3::new(0.0, 0.0, 0.0),
                Point3::new(8.0, 0.0, 0.0),
                Point3::new(4.0, 0.05, 0.2),
            ],
        ];
        for corners in triangles {
            let mut samples = Vec::new();
            surface_samples(corners, spacing, &mut samples);
            let [a, b, c] = corners;
            let area = 0.5 * (b - a).cross(&(c - a)).norm();
            let total: f64 = samples.iter().map(|(_, share)| share).sum();
            assert!(
                (total - area).abs() < 1e-9 * area.max(1.0),
                "{total} {area}"
            );
            let mut farthest: f64 = 0.0;
            for i in 0..=200 {
                for j in 0..=200 - i {
                    let p = a + (b - a) * (i as f64 / 200.0) + (c - a) * (j as f64 / 200.0);
                    let nearest = samples
                        .iter()
                        .map(|(s, _)| (s - p).norm())
                        .fold(f64::INFINITY, f64::min);
                    farthest = farthest.max(nearest);
                }
            }
            assert!(farthest < 1.0 * spacing, "{farthest}");
            // Not many more than one a spacing squared.
            assert!(samples.len() as f64 <= 2.0 * area / (spacing * spacing) + 40.0);
        }
    }

    #[test]
    fn the_gap_between_passes_too_far_apart_is_the_closed_form_scallop_and_only_there() {
        let (part, top, swept) = plate_with_a_wide_gap(8.1, 0.6, 20.0);
        let surface = SurfaceDistance::new(&part);
        let found = gaps(
            &part,
            &surface,
            &top,
            &swept,
            &[Isometry3::identity()],
            &options(),
        );
        assert!(!found.is_empty());
        for g in &found {
            assert!(g.point.y > 8.1 && g.point.y < 8.7, "{:?}", g.point);
            assert!(g.along.x.abs() > 0.999);
        }
        // Between balls s apart, at y from the middle the nearest centre is s/2 − |y| across
        // and r up: the ray up enters its ball at r − √(r² − (s/2 − |y|)²), at most
        // r − √(r² − s²/4) mid-way.
        for g in &found {
            let across = 0.3 - (g.point.y - 8.4).abs();
            let expected = RADIUS - (RADIUS * RADIUS - across * across).sqrt();
            assert!(
                (g.height - expected).abs() < 1e-9,
                "{} against {expected}",
                g.height
            );
            assert!(expected > TARGET);
        }
        // Every sample of the band over the target is found: the band |y − 8.4| < 0.1003 is
        // two sample rows wide on each side of the middle, the whole plate long.
        let band = 0.3 - (RADIUS * RADIUS - (RADIUS - TARGET).powi(2)).sqrt();
        let rows = found
            .iter()
            .map(|g| (g.point.y * 1e6).round() as i64)
            .collect::<std::collections::BTreeSet<_>>();
        assert!(rows.len() as f64 >= (2.0 * band / 0.1).floor(), "{rows:?}");
    }

    #[test]
    fn a_rest_curve_runs_along_the_ridge_and_closes_the_gap() {
        let (part, top, mut swept) = plate_with_a_wide_gap(8.1, 0.6, 20.0);
        let surface = SurfaceDistance::new(&part);
        let views = [Isometry3::identity()];
        let found = gaps(&part, &surface, &top, &swept, &views, &options());
        let groups = clusters(&found, 1.5 * options().sample_spacing);
        assert_eq!(groups.len(), 1);
        let curve = rest_curve(&found, &groups[0], &part, &surface, &options()).expect("a curve");
        for p in &curve.points {
            assert!((p.point.y - 8.4).abs() < 0.02, "{:?}", p.point);
            assert!((p.point.z - 5.0).abs() < 1e-9 && p.normal.z > 0.999);
        }
        let xs: Vec<f64> = curve.points.iter().map(|p| p.point.x).collect();
        let (lo, hi) = (
            xs.iter().copied().fold(f64::INFINITY, f64::min),
            xs.iter().copied().fold(f64::NEG_INFINITY, f64::max),
        );
        assert!(lo < 0.1 && hi > 19.9, "{lo}..{hi}");
        // A ball along it: nothing over the target is left.
        let axis = Direction::new_normalize(Vector3::z());
        let rest = CutSegment {
            poses: curve
                .points
                .iter()
                .map(|p| ToolPose { tip: p.point, axis })
                .collect(),
            pass_directions: vec![Vector3::x(); curve.points.len()],
            leads: false,
        };
        swept.insert(&rest, 0.0, TARGET);
        assert!(gaps(&part, &surface, &top, &swept, &views, &options()).is_empty());
    }

    #[test]
    fn views_measure_a_sample_against_the_copies_of_the_passes() {
        // Passes over y ≤ 10 only; the view shifting y by −10 stands for their copy 10 mm on.
        let (part, top, swept) = plate_with_a_wide_gap(8.1, 0.6, 10.0);
        let surface = SurfaceDistance::new(&part);
        let views = [
            Isometry3::identity(),
            Isometry3::from_parts(Translation3::new(0.0, -10.0, 0.0), Default::default()),
        ];
        let found = gaps(&part, &surface, &top, &swept, &views, &options());
        let groups = clusters(&found, 1.5 * options().sample_spacing);
        assert_eq!(groups.len(), 2);
        let middle_y =
            |g: &Vec<usize>| g.iter().map(|&i| found[i].point.y).sum::<f64>() / g.len() as f64;
        let mut ys: Vec<f64> = groups.iter().map(middle_y).collect();
        ys.sort_by(f64::total_cmp);
        assert!(
            (ys[0] - 8.4).abs() < 0.05 && (ys[1] - 18.4).abs() < 0.05,
            "{ys:?}"
        );
    }

    #[test]
    fn the_flutes_sweep_where_asked() {
        // A vertical tool whose flutes run along the plate's side x = 20 at y = 10.
        let axis = Direction::new_normalize(Vector3::z());
        let poses: Vec<ToolPose> = (0..=10)
            .map(|i| ToolPose {
                tip: Point3::new(20.0 + RADIUS, 5.0 + i as f64, -1.0),
                axis,
            })
            .collect();
        let segment = CutSegment {
            pass_directions: vec![Vector3::y(); poses.len()],
            poses,
            leads: false,
        };
        let at_side = Point3::new(20.0, 10.0, 4.0);
        let mut balls = SweptTool::new(RADIUS, 0.2);
        balls.insert(&segment, 0.0, TARGET);
        assert!(balls.gap(&at_side, &Vector3::x()).is_none());
        let mut flutes = SweptTool::new(RADIUS, 0.2);
        flutes.insert(&segment, 8.0, TARGET);
        let (gap, along) = flutes
            .gap(&at_side, &Vector3::x())
            .expect("the flutes come near");
        assert!(gap < 1e-9, "{gap}");
        // The flutes' bodies run the way the pass does, not up the axis.
        assert!((along - Vector3::y()).norm() < 1e-9, "{along:?}");
    }

    /// Between two poses a millimetre apart, tilting 10° as the tool moves, the flutes'
    /// side sweeps the wall beside them everywhere the move passes: the gap the bodies leave
    /// (interpolated along the move) is within a quarter of the target, and a gap a pose's
    /// bodies alone would leave (1 mm apart: 0.06 mm) is not there.
    #[test]
    fn the_flutes_sweep_between_the_poses() {
        let upright = Direction::new_normalize(Vector3::z());
        let leaning = Direction::new_normalize(Vector3::new(-(10f64.to_radians()).tan(), 0.0, 1.0));
        // The wall x = 20 - the leaning tool's flutes at height h stand off it by less than
        // the radius by h·sin 10°: take the wall where the upright tool's flutes touch it.
        let poses = vec![
            ToolPose {
                tip: Point3::new(20.0 + RADIUS, 0.0, -1.0),
                axis: upright,
            },
            ToolPose {
                tip: Point3::new(20.0 + RADIUS, 1.0, -1.0),
                axis: leaning,
            },
        ];
        let segment = CutSegment {
            pass_directions: vec![Vector3::y(); 2],
            poses,
            leads: false,
        };
        let mut flutes = SweptTool::new(RADIUS, 0.2);
        flutes.insert(&segment, 8.0, TARGET);
        for k in 0..=20 {
            let y = 0.05 * k as f64;
            let (gap, _) = flutes
                .gap(&Point3::new(20.0, y, 2.0), &Vector3::x())
                .expect("the flutes come near");
            assert!(gap <= 0.25 * TARGET + 1e-12, "y {y}: {gap}");
        }
    }

    /// The search that stops at the first body within the target agrees with the nearest
    /// body's: within exactly when the nearest is, and over it, the same gap and direction
    /// (passes at scattered spacings and heights over a plate, samples all over it).
    #[test]
    fn stopping_at_the_first_body_within_agrees_with_the_nearest() {
        let mut swept = SweptTool::new(RADIUS, 0.2);
        let mut y = -5.0;
        let mut k = 0;
        while y < 25.0 {
            let mut pass = pass_along_x(y);
            let lift = 0.003 * (k % 5) as f64;
            for pose in &mut pass.poses {
                pose.tip.z += lift;
            }
            swept.insert(&pass, 0.0, TARGET);
            y += 0.25 + 0.05 * (k % 7) as f64;
            k += 1;
        }
        let mut hint = None;
        let (mut within, mut over) = (0, 0);
        for i in 0..80 {
            for j in 0..80 {
                let p = Point3::new(0.23 * i as f64, -0.4 + 0.31 * j as f64, 5.0);
                let nearest = swept.gap(&p, &Vector3::z());
                let quick = swept.gap_or_within(&p, &Vector3::z(), TARGET, &mut hint);
                match nearest {
                    Some((h, _)) if h <= TARGET => {
                        within += 1;
                        assert!(quick.is_some_and(|(q, _)| q <= TARGET), "{p:?}");
                    }
                    _ => {
                        over += 1;
                        assert_eq!(quick, nearest, "{p:?}");
                    }
                }
            }
        }
        assert!(within > 100 && over > 100, "{within} within, {over} over");
    }

    #[test]
    fn places_on_one_ridge_join_and_neighbouring_ridges_do_not() {
        // Specks along x (the passes' way) on a plate's top: two on the ridge y = 0, 3 mm
        // apart, one on the next ridge at y = 0.4 beside the first, one on y = 0 far on.
        let speck = |x: f64, y: f64| Gap {
            point: Point3::new(x, y, 5.0),
            normal: Vector3::z(),
            height: 0.012,
            triangle: 0,
            area: 0.005,
            along: if x > 5.0 { -Vector3::x() } else { Vector3::x() },
        };
        let found = vec![
            speck(0.0, 0.0),
            speck(3.0, 0.02),
            speck(0.0, 0.4),
            speck(9.0, 0.0),
        ];
        let places: Vec<Vec<usize>> = (0..found.len()).map(|i| vec![i]).collect();
        let joined = ridges(&found, &places, 4.0, 0.2, None);
        assert_eq!(joined, vec![vec![0, 1], vec![2], vec![3]]);
        // With the passes along y, the ridges run along y: the specks 0.4 apart in y join,
        // those apart in x do not.
        let across: Vec<Gap> = found
            .iter()
            .map(|g| Gap {
                along: Vector3::y(),
                ..*g
            })
            .collect();
        assert_eq!(
            ridges(&across, &places, 4.0, 0.2, None),
            vec![vec![0, 2], vec![1], vec![3]]
        );
    }

    /// A pass of balls with centres at `centres` (the axis along +z; only the ball counts).
    fn pass_through(centres: &[Point3], along: Vector3) -> CutSegment {
        let axis = Direction::new_normalize(Vector3::z());
        CutSegment {
            poses: centres
                .iter()
                .map(|c| ToolPose {
                    tip: c - Vector3::z() * RADIUS,
                    axis,
                })
                .collect(),
            pass_directions: vec![along; centres.len()],
            leads: false,
        }
    }

    /// A ball along `curve` (touching it at each point, running along y) into `swept`.
    fn sweep_along(swept: &mut SweptTool, curve: &SectionCurve) {
        let centres: Vec<Point3> = curve
            .points
            .iter()
            .map(|p| p.point + p.normal * RADIUS)
            .collect();
        swept.insert(&pass_through(&centres, Vector3::y()), 0.0, TARGET);
    }

    #[test]
    fn the_balls_over_a_thin_plate_leave_no_gap_on_its_underside() {
        // A plate 1 mm thick, its top passed 0.3 mm apart; measured out to 2 mm, the underside
        // is 1 mm from the balls (through the plate), and none of them is in front of it.
        let part = cuboid(20.0, 20.0, 1.0);
        let mut swept = SweptTool::new(RADIUS, 2.0);
        for k in 0..=66 {
            let y = 0.3 * k as f64 - 4.0;
            let centres: Vec<Point3> = (0..=50)
                .map(|i| Point3::new(-5.0 + 0.6 * i as f64, y, 1.0 + RADIUS))
                .collect();
            swept.insert(&pass_through(&centres, Vector3::x()), 0.0, TARGET);
        }
        let surface = SurfaceDistance::new(&part);
        let underside: Vec<bool> = (0..part.triangles.len())
            .map(|t| part.face_normal(t).z < -0.9)
            .collect();
        let wide = RestOptions {
            reach: 2.0,
            ..options()
        };
        let views = [Isometry3::identity()];
        assert!(gaps(&part, &surface, &underside, &swept, &views, &wide).is_empty());
        // The same balls' distance from the underside, facing or not, is 1 mm.
        let p = Point3::new(10.0, 10.0, 0.0);
        assert!(swept.gap(&p, &-Vector3::z()).is_none());
        let (through, _) = swept.gap(&p, &Vector3::z()).expect("within reach");
        assert!((through - 1.0).abs() < 0.01, "{through}");
    }

    /// A slab 0.3 mm thick whose side x = 20 (a low wall) the passes cross downwards at
    /// y = 0, 2, …, 20, 2 mm apart: between each two a place 2 mm long and 0.3 high.
    fn low_wall_crossed_by_passes() -> (Mesh, Vec<bool>, SweptTool, RestOptions) {
        // The wall in strips 0.2 mm wide (sampled evenly), the top and bottom fans to them.
        let h = 0.3;
        let mut positions = vec![
            Point3::new(0.0, 0.0, 0.0),
            Point3::new(0.0, 20.0, 0.0),
            Point3::new(0.0, 20.0, h),
            Point3::new(0.0, 0.0, h),
        ];
        for k in 0..=100 {
            positions.push(Point3::new(20.0, 0.2 * k as f64, 0.0));
            positions.push(Point3::new(20.0, 0.2 * k as f64, h));
        }
        let (bottom, top) = (|k: u32| 4 + 2 * k, |k: u32| 5 + 2 * k);
        let mut triangles = vec![
            [0, 3, 2],
            [0, 2, 1],
            [0, bottom(0), top(0)],
            [0, top(0), 3],
            [1, top(100), bottom(100)],
            [1, 2, top(100)],
            [3, top(100), 2],
            [0, 1, bottom(100)],
        ];
        for k in 0..100 {
            triangles.push([bottom(k), bottom(k + 1), top(k + 1)]);
            triangles.push([bottom(k), top(k + 1), top(k)]);
            triangles.push([3, top(k), top(k + 1)]);
            triangles.push([0, bottom(k + 1), bottom(k)]);
        }
        let part = Mesh {
            positions,
            triangles,
        };
        let wall: Vec<bool> = (0..part.triangles.len())
            .map(|t| part.face_normal(t).x > 0.9)
            .collect();
        let options = RestOptions {
            reach: 0.5,
            ..options()
        };
        let mut swept = SweptTool::new(RADIUS, options.reach);
        for k in 0..=10 {
            let y = 2.0 * k as f64;
            let down: Vec<Point3> = (0..=6)
                .map(|i| Point3::new(20.0 + RADIUS, y, 0.3 - 0.05 * i as f64))
                .collect();
            swept.insert(&pass_through(&down, -Vector3::z()), 0.0, TARGET);
        }
        (part, wall, swept, options)
    }

    /// A place between two passes running down a wall lower than a stepover: along its
    /// passes a curve would cross the wall in 0.3 mm, so it runs along the wall, on it.
    #[test]
    fn a_place_on_a_wall_lower_than_a_stepover_is_run_along_the_wall() {
        let (part, wall, mut swept, options) = low_wall_crossed_by_passes();
        // Not the thin places' rule: the passage's rest runs its places along its passes.
        let options = RestOptions {
            thin: None,
            ..options
        };
        let surface = SurfaceDistance::new(&part);
        let views = [Isometry3::identity()];
        let found = gaps(&part, &surface, &wall, &swept, &views, &options);
        let places = ridges(
            &found,
            &clusters(&found, 1.5 * options.sample_spacing),
            4.0,
            0.2,
            None,
        );
        let place = places
            .iter()
            .find(|members| {
                members
                    .iter()
                    .all(|&i| found[i].point.y > 8.0 && found[i].point.y < 10.0)
            })
            .expect("the place between the passes at y = 8 and 10");
        let curve = rest_curve(&found, place, &part, &surface, &options).expect("a curve");
        let ys: Vec<f64> = curve.points.iter().map(|p| p.point.y).collect();
        let (lo, hi) = ys
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &y| {
                (lo.min(y), hi.max(y))
            });
        assert!(lo < 8.5 && hi > 9.5, "{ys:?}");
        assert!(curve.points.iter().all(|p| p.normal.x > 0.999));
        sweep_along(&mut swept, &curve);
        assert!(
            gaps(&part, &surface, &wall, &swept, &views, &options)
                .iter()
                .all(|g| g.point.y < 8.0 || g.point.y > 10.0)
        );
    }

    #[test]
    fn a_low_wall_the_passes_cross_is_run_along_its_length_in_one_pass() {
        let (part, wall, mut swept, options) = low_wall_crossed_by_passes();
        let surface = SurfaceDistance::new(&part);
        let views = [Isometry3::identity()];
        let found = gaps(&part, &surface, &wall, &swept, &views, &options);
        let places = clusters(&found, 1.5 * options.sample_spacing);
        assert_eq!(places.len(), 10, "one between each two passes");
        // Along their passes (down the wall) the places stay ten; along their length they
        // join into one, and its curve runs the wall's length at mid-height.
        assert_eq!(ridges(&found, &places, 4.0, 0.2, None).len(), 10);
        let joined = ridges(&found, &places, 4.0, 0.2, options.thin);
        assert_eq!(joined.len(), 1);
        let curve = rest_curve(&found, &joined[0], &part, &surface, &options).expect("a curve");
        // (Run on past the wall's ends, it rounds the corners onto the slab's ends.)
        for p in curve
            .points
            .iter()
            .filter(|p| p.point.y > 0.0 && p.point.y < 20.0)
        {
            assert!(
                (p.point.x - 20.0).abs() < 1e-9 && p.normal.x > 0.999,
                "{p:?}"
            );
            assert!((p.point.z - 0.15).abs() < 0.05, "{p:?}");
        }
        let ys: Vec<f64> = curve.points.iter().map(|p| p.point.y).collect();
        let (lo, hi) = (ys[0].min(ys[ys.len() - 1]), ys[0].max(ys[ys.len() - 1]));
        assert!(lo < 0.5 && hi > 19.5, "{ys:?}");
        // It keeps to the wall: past its ends it stops rather than turn the corners.
        assert!(curve.points.iter().all(|p| p.normal.x > 0.999));
        // A ball along it closes the wall.
        sweep_along(&mut swept, &curve);
        assert!(gaps(&part, &surface, &wall, &swept, &views, &options).is_empty());
    }

    #[test]
    fn samples_on_two_faces_of_an_edge_are_two_places() {
        let sample = |point: Point3, normal: Vector3| Gap {
            point,
            normal,
            height: 0.05,
            triangle: 0,
            area: 0.01,
            along: Vector3::y(),
        };
        // Along the edge x = 20, z = 5 of a box: on its top and on its side, 0.1 mm apart.
        let mut found = Vec::new();
        for k in 0..10 {
            let y = 0.1 * k as f64;
            found.push(sample(Point3::new(19.95, y, 5.0), Vector3::z()));
            found.push(sample(Point3::new(20.0, y, 4.95), Vector3::x()));
        }
        let places = clusters(&found, 0.15);
        assert_eq!(places.len(), 2);
        for place in &places {
            let first = found[place[0]].normal;
            assert!(place.iter().all(|&i| found[i].normal == first));
        }
    }

    #[test]
    fn a_rest_curve_along_a_band_round_a_curved_wall_keeps_to_the_wall() {
        // A disc 0.3 mm thick, radius 10 (a 360-gon), and a band round a quarter of its rim,
        // crossed by passes running down it (their direction: −z).
        let (radius, height, sides) = (10.0, 0.3, 360u32);
        let mut positions = vec![Point3::origin(), Point3::new(0.0, 0.0, height)];
        for k in 0..sides {
            let a = std::f64::consts::TAU * k as f64 / sides as f64;
            let (x, y) = (radius * a.cos(), radius * a.sin());
            positions.push(Point3::new(x, y, 0.0));
            positions.push(Point3::new(x, y, height));
        }
        let mut triangles = Vec::new();
        for k in 0..sides {
            let (b0, t0) = (2 + 2 * k, 3 + 2 * k);
            let (b1, t1) = (2 + 2 * ((k + 1) % sides), 3 + 2 * ((k + 1) % sides));
            triangles.extend([[b0, b1, t1], [b0, t1, t0], [0, b1, b0], [1, t0, t1]]);
        }
        let part = Mesh {
            positions,
            triangles,
        };
        let surface = SurfaceDistance::new(&part);
        let mut found = Vec::new();
        for k in 0..=900 {
            let a = (k as f64 * 0.1).to_radians() - std::f64::consts::FRAC_PI_4;
            let radial = Vector3::new(a.cos(), a.sin(), 0.0);
            for z in [0.05, 0.15, 0.25] {
                // On the polygon's side (inside the circle by at most its sagitta).
                let on = surface.closest(&(Point3::from(radial * radius) + Vector3::z() * z), 1.0);
                let on = on.expect("on the wall").point;
                found.push(Gap {
                    point: on,
                    normal: radial,
                    height: 0.05,
                    triangle: 0,
                    area: 0.01,
                    along: -Vector3::z(),
                });
            }
        }
        let members: Vec<usize> = (0..found.len()).collect();
        let curve = rest_curve(&found, &members, &part, &surface, &options()).expect("a curve");
        // Its chord's middle is 10 (1 − cos 45°) = 2.9 mm inside the wall; the curve is on it.
        for p in &curve.points {
            let r = p.point.x.hypot(p.point.y);
            assert!((r - radius).abs() < 0.01, "{p:?} at radius {r}");
            assert!((p.point.z - 0.15).abs() < 0.01, "{p:?}");
            assert!(p.normal.z.abs() < 1e-9, "{p:?}");
        }
        let angle = |p: &DrivePoint| p.point.y.atan2(p.point.x).to_degrees();
        let (first, last) = (
            angle(&curve.points[0]),
            angle(&curve.points[curve.points.len() - 1]),
        );
        assert!(
            first.min(last) < -44.0 && first.max(last) > 44.0,
            "{first}..{last}"
        );
    }
}
