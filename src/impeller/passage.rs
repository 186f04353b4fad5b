//! The hub between two neighbouring blades as a passage that flow-line passes run through
//! (issue 21 item 2, hub finishing), spaced by the local scallop (seed 000/001, alg. 5.1).
//!
//! * **Flow surface.** The hub triangles that touch a blade, and every hub triangle joined to
//!   them across an edge bending less than [`CREASE_DEG`]: the surface the blades stand on,
//!   without the bore, rim and back face (surfaces of revolution too, behind a crease).
//! * **Profile.** Its vertices in the meridional half-plane (height along the axis, radius)
//!   lie on one curve, the hub's meridian: ordered along its principal direction, averaged in
//!   bins, measured by arc length `m` from the inlet (the end the axis points to). How far the
//!   vertices lie off it is reported (`profile_fit_mm`).
//! * **Footprints.** Every blade, splitter or other piece meets the hub along the edges whose
//!   ends lie on the profile; in (m, angle) these edges outline the piece's footprint, and a
//!   station m crosses it in one angular interval.
//! * **Passage 0.** At each station, from the first main blade's footprint to the same
//!   footprint turned by one pitch (the next blade, by the symmetry the recognition checked),
//!   less the footprints of splitters and other pieces in between. Up- and downstream of the
//!   blade the passage runs from the footprint's middle at its end to the same turned by a
//!   pitch, so the passages tile the hub there.
//! * **Flow lines** are the curves of constant fraction `f` of the passage's free width,
//!   from the first blade's side (f = 0) to the next blade's (f = 1). Alg. 5.1: the two sides
//!   are full passes; between two lines a line half-way is inserted only over the stations
//!   where the two are farther apart (across the line's direction) than the stepover the ball
//!   leaves the scallop at on the hub's curvature there, and the rule recurses on both halves:
//!   partial passes only where the passage is wide.

use std::f64::consts::{PI, TAU};

use crate::geom::{Point3, Vector3};
use crate::mesh::distance::SurfaceDistance;
use crate::mesh::topology::edges;
use crate::mesh::{DrivePoint, Mesh, SectionCurve};

use super::frame::AxisFrame;
use super::recognise::{Impeller, Region};

/// Hub triangles joined across an edge bending less than this belong to one flow surface.
pub const CREASE_DEG: f64 = 25.0;

/// Share of the blades' and splitters' root vertices that must lie on the hub's meridian.
const MIN_ROOTS_CARRIED: f64 = 0.8;

/// Deepest recursion of the line insertion: 2^16 lines across a passage.
const MAX_DEPTH: u32 = 16;

/// How the passage is sampled and its lines spaced.
#[derive(Clone, Debug, PartialEq)]
pub struct PassageOptions {
    /// Distance between stations along the hub's meridian, mm.
    pub station_step: f64,
    pub ball_radius: f64,
    /// Target scallop height, mm.
    pub scallop_height: f64,
    /// How far a partial pass runs on past where it is needed, mm along the meridian.
    pub overlap: f64,
}

/// One station along the meridian.
#[derive(Clone, Debug, PartialEq)]
pub struct Station {
    /// Arc length along the meridian from the inlet, mm.
    pub along: f64,
    pub height: f64,
    pub radius: f64,
    /// The hub's unit normal in the meridional half-plane (axial, radial components).
    pub normal: [f64; 2],
    /// The free angles of passage 0 here: increasing, disjoint intervals, radians.
    pub free: Vec<[f64; 2]>,
    /// The span direction of the passage's first wall (f = 0) and second wall (f = 1): unit,
    /// as (axial, radial, tangential) components at the angle of the point they are used at.
    pub walls: [[f64; 3]; 2],
}

impl Station {
    fn free_width(&self) -> f64 {
        self.free.iter().map(|[a, b]| b - a).sum()
    }

    /// The angle at fraction `f` of the free width, hopping over the footprints in between.
    pub fn angle_at(&self, f: f64) -> Option<f64> {
        let total = self.free_width();
        if total <= 0.0 {
            return None;
        }
        let mut left = f.clamp(0.0, 1.0) * total;
        for &[a, b] in &self.free {
            if left <= b - a {
                return Some(a + left);
            }
            left -= b - a;
        }
        self.free.last().map(|i| i[1])
    }
}

/// A flow line of the passage: its fraction across, and the runs of stations it is driven
/// along (a full pass has one run over every station where the passage is open).
#[derive(Clone, Debug, PartialEq)]
pub struct FlowLine {
    pub fraction: f64,
    pub runs: Vec<[usize; 2]>,
}

/// The hub of an impeller as passage 0 between its first main blade and the next.
#[derive(Debug)]
pub struct HubPassage {
    meridian: Meridian,
    pub frame: AxisFrame,
    pub pitch: f64,
    pub stations: Vec<Station>,
    /// Largest distance of a flow-surface vertex from the meridian found, mm.
    pub profile_fit_mm: f64,
    pub flow_triangles: usize,
    /// Area of the flow surface, mm² (all passages).
    pub flow_area_mm2: f64,
    /// Per triangle of the mesh: whether it is on the flow surface.
    pub flow: Vec<bool>,
    /// The piece (index in [`Impeller::pieces`]) of the blade passage 0 starts at.
    pub first_blade: usize,
    /// Share of the blades' and splitters' root vertices within the fit of the meridian.
    pub roots_carried: f64,
}

/// A polyline in the meridional half-plane, (height, radius), with its arc length.
#[derive(Debug)]
struct Meridian {
    points: Vec<[f64; 2]>,
    along: Vec<f64>,
}

impl Meridian {
    fn length(&self) -> f64 {
        self.along.last().copied().unwrap_or(0.0)
    }

    /// Arc length of the nearest point and the distance to it.
    fn project(&self, q: [f64; 2]) -> (f64, f64) {
        let mut best = (0.0, f64::INFINITY);
        for (k, w) in self.points.windows(2).enumerate() {
            let d = [w[1][0] - w[0][0], w[1][1] - w[0][1]];
            let len2 = d[0] * d[0] + d[1] * d[1];
            let t = if len2 > 0.0 {
                (((q[0] - w[0][0]) * d[0] + (q[1] - w[0][1]) * d[1]) / len2).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let p = [w[0][0] + d[0] * t, w[0][1] + d[1] * t];
            let dist = (q[0] - p[0]).hypot(q[1] - p[1]);
            if dist < best.1 {
                best = (
                    self.along[k] + t * (self.along[k + 1] - self.along[k]),
                    dist,
                );
            }
        }
        best
    }

    /// Like [`Meridian::project`]'s arc length, with the first and last segments run on
    /// past the ends (negative before the inlet, beyond the length after the outlet): a point
    /// high above the inlet still stands upstream of one beside it.
    fn project_run_on(&self, q: [f64; 2]) -> f64 {
        let (m, _) = self.project(q);
        let n = self.points.len();
        let along_segment = |k: usize| {
            let (a, b) = (self.points[k], self.points[k + 1]);
            let d = [b[0] - a[0], b[1] - a[1]];
            let len = d[0].hypot(d[1]);
            if len > 0.0 {
                ((q[0] - a[0]) * d[0] + (q[1] - a[1]) * d[1]) / len
            } else {
                0.0
            }
        };
        if n < 2 {
            m
        } else if m <= 0.0 {
            along_segment(0).min(0.0)
        } else if m >= self.length() {
            self.along[n - 2] + along_segment(n - 2).max(self.along[n - 1] - self.along[n - 2])
        } else {
            m
        }
    }

    /// The point at arc length `m` and the unit tangent there.
    fn at(&self, m: f64) -> ([f64; 2], [f64; 2]) {
        let k = match self.along.partition_point(|&a| a <= m) {
            0 => 0,
            i => (i - 1).min(self.points.len() - 2),
        };
        let (a, b) = (self.points[k], self.points[k + 1]);
        let len = self.along[k + 1] - self.along[k];
        let t = if len > 0.0 {
            ((m - self.along[k]) / len).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let d = [b[0] - a[0], b[1] - a[1]];
        let n = d[0].hypot(d[1]).max(1e-300);
        ([a[0] + d[0] * t, a[1] + d[1] * t], [d[0] / n, d[1] / n])
    }
}

fn wrap(angle: f64) -> f64 {
    let a = angle.rem_euclid(TAU);
    if a > PI { a - TAU } else { a }
}

impl HubPassage {
    /// The passage of `impeller` (recognised in `mesh`), or why the hub is not one.
    pub fn new(
        mesh: &Mesh,
        impeller: &Impeller,
        options: &PassageOptions,
    ) -> Result<HubPassage, String> {
        if impeller.blades != impeller.order {
            return Err(format!(
                "{} main blades in {} pitches: one passage per pitch is needed",
                impeller.blades, impeller.order
            ));
        }
        let frame = impeller.frame();
        let pitch = impeller.pitch();
        let regions = &impeller.regions;
        let is_hub = |t: u32| regions[t as usize] == Region::Hub;
        let face_normals: Vec<Vector3> = (0..mesh.triangles.len())
            .map(|t| mesh.face_normal(t))
            .collect();

        // The flow surface: hub triangles that touch a piece, grown across gentle edges.
        let all_edges = edges(&mesh.triangles);
        let mut flow = vec![false; mesh.triangles.len()];
        let mut stack = Vec::new();
        for e in &all_edges {
            let hub: Vec<u32> = e.faces.iter().map(|f| f.0).filter(|&f| is_hub(f)).collect();
            if hub.len() < e.faces.len() {
                for f in hub {
                    if !flow[f as usize] {
                        flow[f as usize] = true;
                        stack.push(f);
                    }
                }
            }
        }
        let mut neighbours: Vec<Vec<u32>> = vec![Vec::new(); mesh.triangles.len()];
        let cos_crease = CREASE_DEG.to_radians().cos();
        for e in &all_edges {
            if let [(a, _), (b, _)] = e.faces[..]
                && is_hub(a)
                && is_hub(b)
                && face_normals[a as usize].dot(&face_normals[b as usize]) >= cos_crease
            {
                neighbours[a as usize].push(b);
                neighbours[b as usize].push(a);
            }
        }
        while let Some(t) = stack.pop() {
            for &n in &neighbours[t as usize] {
                if !flow[n as usize] {
                    flow[n as usize] = true;
                    stack.push(n);
                }
            }
        }
        // Of what grew, the largest piece (by area) joined across gentle edges: seeds on the
        // other side of a crease (a blade edge's facets that pass for revolution) go.
        let mut sets = crate::mesh::topology::DisjointSets::new(mesh.triangles.len());
        for (t, list) in neighbours.iter().enumerate() {
            if flow[t] {
                for &n in list {
                    if flow[n as usize] {
                        sets.union(t as u32, n);
                    }
                }
            }
        }
        let mut area_of = std::collections::BTreeMap::<u32, f64>::new();
        for t in (0..mesh.triangles.len()).filter(|&t| flow[t]) {
            let [a, b, c] = mesh.corners(t);
            *area_of.entry(sets.find(t as u32)).or_default() +=
                0.5 * (b - a).cross(&(c - a)).norm();
        }
        if let Some((&largest, _)) = area_of.iter().max_by(|a, b| a.1.total_cmp(b.1)) {
            for (t, f) in flow.iter_mut().enumerate() {
                if *f && sets.find(t as u32) != largest {
                    *f = false;
                }
            }
        }

        // The meridian through the flow surface's vertices. Small facets of a blade's edge
        // next to the hub can pass the recognition's test of revolution; fitted once, the
        // triangles off the meridian or facing another way than the surface of revolution are
        // left out, and the meridian fitted again without them.
        let meridional = |p: &Point3| {
            let (r, _, h) = frame.cylindrical(p);
            [h, r]
        };
        let fit_limit = (5.0 * impeller.tolerance_mm).max(0.05);
        let points_of = |flow: &[bool]| -> Vec<[f64; 2]> {
            let mut on_flow = vec![false; mesh.positions.len()];
            for (t, tri) in mesh.triangles.iter().enumerate() {
                if flow[t] {
                    for &v in tri {
                        on_flow[v as usize] = true;
                    }
                }
            }
            mesh.positions
                .iter()
                .zip(&on_flow)
                .filter(|(_, on)| **on)
                .map(|(p, _)| meridional(p))
                .collect()
        };
        // `facing`: leave out triangles whose normals stray from the meridian's (a finely
        // meshed hub's facets follow it; a coarse CAD hub's chords across the passage do not,
        // and on the meridian by their corners they belong to it all the same).
        let refine = |mut flow: Vec<bool>, facing: bool| -> Result<(Vec<bool>, Meridian), String> {
            if !flow.iter().any(|&f| f) {
                return Err("no hub surface touches a blade".into());
            }
            let first_fit = meridian_of(&points_of(&flow))?;
            for (t, f) in flow.iter_mut().enumerate() {
                if !*f {
                    continue;
                }
                let corners = mesh.corners(t);
                let centre =
                    Point3::from((corners[0].coords + corners[1].coords + corners[2].coords) / 3.0);
                let (_, angle, _) = frame.cylindrical(&centre);
                let (m, _) = first_fit.project(meridional(&centre));
                let (_, tangent) = first_fit.at(m);
                let n = face_normals[t];
                let faces_along = (tangent[1] * n.dot(&frame.axis)
                    - tangent[0] * n.dot(&frame.radial(angle)))
                .abs();
                *f = (!facing || faces_along >= cos_crease)
                    && corners
                        .iter()
                        .all(|p| first_fit.project(meridional(p)).1 <= fit_limit);
            }
            let meridian = meridian_of(&points_of(&flow))?;
            Ok((flow, meridian))
        };
        // Where the blades and splitters stand on the hub: the ends of the edges between their
        // triangles and the hub's, in the meridional half-plane.
        let mut on_root = vec![false; mesh.positions.len()];
        for e in &all_edges {
            let standing = e.faces.iter().any(|&(f, _)| {
                matches!(regions[f as usize], Region::Blade(_) | Region::Splitter(_))
            });
            if standing && e.faces.iter().any(|&(f, _)| is_hub(f)) {
                for v in e.vertices {
                    on_root[v as usize] = true;
                }
            }
        }
        let roots: Vec<[f64; 2]> = mesh
            .positions
            .iter()
            .zip(&on_root)
            .filter(|(_, on)| **on)
            .map(|(p, _)| meridional(p))
            .collect();
        let carried = |meridian: &Meridian| {
            let on = roots
                .iter()
                .filter(|q| meridian.project(**q).1 <= fit_limit)
                .count();
            on as f64 / roots.len().max(1) as f64
        };
        // A finely meshed hub grows from the roots across its gentle edges into one piece. A
        // coarse CAD tessellation (long slivers bending sharply across the passage) breaks it
        // into pieces, and the largest may be the rim: then the blades' roots, which lie on
        // the hub whatever its triangles, give the meridian, and the flow surface is the hub
        // triangles on it.
        let (flow, meridian) = match refine(flow, true) {
            Ok((flow, meridian)) if carried(&meridian) >= MIN_ROOTS_CARRIED => (flow, meridian),
            grown => {
                let from_roots = meridian_of(&roots)?;
                let flow: Vec<bool> = (0..mesh.triangles.len())
                    .map(|t| {
                        is_hub(t as u32)
                            && mesh
                                .corners(t)
                                .iter()
                                .all(|p| from_roots.project(meridional(p)).1 <= fit_limit)
                    })
                    .collect();
                let (flow, meridian) = refine(flow, false)?;
                let share = carried(&meridian);
                if share < MIN_ROOTS_CARRIED {
                    return Err(format!(
                        "the hub the blades stand on is not one surface of revolution: {:.0} % of \
                         their roots lie on the meridian found ({}), {:.0} % needed",
                        100.0 * share,
                        match grown {
                            Ok(_) => "grown from the roots".to_string(),
                            Err(e) => e,
                        },
                        100.0 * MIN_ROOTS_CARRIED
                    ));
                }
                (flow, meridian)
            }
        };
        let flow_points = points_of(&flow);
        let flow_triangles = flow.iter().filter(|&&f| f).count();
        let flow_area_mm2: f64 = (0..mesh.triangles.len())
            .filter(|&t| flow[t])
            .map(|t| {
                let [a, b, c] = mesh.corners(t);
                0.5 * (b - a).cross(&(c - a)).norm()
            })
            .sum();
        let profile_fit_mm = flow_points
            .iter()
            .map(|q| meridian.project(*q).1)
            .fold(0.0, f64::max);
        if profile_fit_mm > fit_limit {
            return Err(format!(
                "the hub between the blades is not one surface of revolution: its vertices lie \
                 up to {profile_fit_mm:.3} mm off one meridian (more than {fit_limit:.3} mm)"
            ));
        }

        // The meridian's normal, turned to point out of the part (the flow surface's side).
        let mut outward = 0.0;
        for t in (0..mesh.triangles.len()).filter(|&t| flow[t]) {
            let [a, b, c] = mesh.corners(t);
            let centre = Point3::from((a.coords + b.coords + c.coords) / 3.0);
            let (_, angle, _) = frame.cylindrical(&centre);
            let n = face_normals[t];
            let (m, _) = meridian.project(meridional(&centre));
            let (_, tangent) = meridian.at(m);
            let candidate = [tangent[1], -tangent[0]];
            let area = 0.5 * (b - a).cross(&(c - a)).norm();
            outward += area
                * (candidate[0] * n.dot(&frame.axis) + candidate[1] * n.dot(&frame.radial(angle)));
        }
        let sign = if outward < 0.0 { -1.0 } else { 1.0 };

        // Footprints: each piece's edges lying on the hub, as (m, angle) segments, angles
        // unwrapped about the piece's first such vertex.
        let near = impeller.tolerance_mm.max(0.01);
        let mut vertex_cache: Vec<Option<(f64, f64, f64)>> = vec![None; mesh.positions.len()];
        let mut place = |v: u32| {
            *vertex_cache[v as usize].get_or_insert_with(|| {
                let p = mesh.positions[v as usize];
                let (m, off) = meridian.project(meridional(&p));
                let (_, angle, _) = frame.cylindrical(&p);
                (m, off, angle)
            })
        };
        let piece_count = impeller.pieces.len();
        // Each root edge as (m, angle) at both ends, with the span direction of its flank:
        // in the flank's plane, square to the edge, away from the hub.
        let mut roots: Vec<Vec<([[f64; 2]; 2], Vector3)>> = vec![Vec::new(); piece_count];
        let mut reference: Vec<Option<f64>> = vec![None; piece_count];
        for (t, tri) in mesh.triangles.iter().enumerate() {
            let piece = match regions[t] {
                Region::Hub => continue,
                Region::Blade(k) | Region::Splitter(k) | Region::Other(k) => k as usize,
            };
            for k in 0..3 {
                let (a, b) = (tri[k], tri[(k + 1) % 3]);
                let (ma, da, ta) = place(a);
                let (mb, db, tb) = place(b);
                if da > near || db > near {
                    continue;
                }
                let r = *reference[piece].get_or_insert(ta);
                let (pa, pb) = (mesh.positions[a as usize], mesh.positions[b as usize]);
                let span = face_normals[t]
                    .cross(&(pb - pa))
                    .try_normalize(1e-12)
                    .unwrap_or_else(Vector3::zeros);
                roots[piece].push(([[ma, r + wrap(ta - r)], [mb, r + wrap(tb - r)]], span));
            }
        }
        // Where station m crosses a piece's footprint: the lowest and highest angle, each with
        // the span direction of the flank there.
        let footprint = |piece: usize, m: f64| -> Option<[(f64, Vector3); 2]> {
            let mut span: Option<[(f64, Vector3); 2]> = None;
            for ([a, b], direction) in &roots[piece] {
                let (lo, hi) = (a[0].min(b[0]), a[0].max(b[0]));
                if m < lo || m > hi {
                    continue;
                }
                let angles = if hi - lo > 1e-12 {
                    let t = (m - a[0]) / (b[0] - a[0]);
                    [a[1] + t * (b[1] - a[1]); 2]
                } else {
                    [a[1], b[1]]
                };
                for angle in angles {
                    let here = (angle, *direction);
                    span = Some(match span {
                        None => [here, here],
                        Some([l, h]) => [
                            if angle < l.0 { here } else { l },
                            if angle > h.0 { here } else { h },
                        ],
                    });
                }
            }
            span
        };
        let angles = |s: Option<[(f64, Vector3); 2]>| s.map(|[l, h]| [l.0, h.0]);

        let first_blade = impeller
            .pieces
            .iter()
            .position(|p| p.kind == super::recognise::PieceKind::Blade)
            .ok_or("no main blade")?;
        let length = meridian.length();
        let count = (length / options.station_step.max(1e-3)).ceil().max(1.0) as usize + 1;
        let step = length / (count - 1) as f64;
        let along: Vec<f64> = (0..count).map(|j| j as f64 * step).collect();
        let blade_sides: Vec<Option<[(f64, Vector3); 2]>> =
            along.iter().map(|&m| footprint(first_blade, m)).collect();
        let blade: Vec<Option<[f64; 2]>> = blade_sides.iter().map(|s| angles(*s)).collect();
        let Some(first) = blade.iter().position(Option::is_some) else {
            return Err("the first blade does not meet the hub".into());
        };
        let last = blade.iter().rposition(Option::is_some).unwrap_or(first);
        let middle = |s: Option<[f64; 2]>| s.map_or(0.0, |[a, b]| 0.5 * (a + b));
        let others: Vec<usize> = (0..piece_count)
            .filter(|&k| {
                k != first_blade && impeller.pieces[k].kind != super::recognise::PieceKind::Blade
            })
            .collect();

        let stations = along
            .iter()
            .enumerate()
            .map(|(j, &m)| {
                let side = if j < first {
                    let c = middle(blade[first]);
                    [c, c]
                } else if j > last {
                    let c = middle(blade[last]);
                    [c, c]
                } else {
                    // A gap in the footprint inside the blade's range: its neighbours' middle.
                    blade[j].unwrap_or_else(|| {
                        let c = middle(blade[..j].iter().rev().find_map(|s| *s));
                        [c, c]
                    })
                };
                let (start, end) = (side[1], side[0] + pitch);
                let mut free = if end > start {
                    vec![[start, end]]
                } else {
                    Vec::new()
                };
                for &k in &others {
                    if let Some([lo, hi]) = angles(footprint(k, m)) {
                        let shift = TAU * ((start - lo) / TAU).ceil();
                        subtract(&mut free, [lo + shift, hi + shift]);
                        subtract(&mut free, [lo + shift - TAU, hi + shift - TAU]);
                    }
                }
                let (point, tangent) = meridian.at(m);
                let normal = [sign * tangent[1], -sign * tangent[0]];
                // The span directions of the passage's two walls, in the local frame of the
                // angle they stand at: blade 0's side facing the passage (its highest angle)
                // and the next blade's side facing back (blade 0's lowest, turned a pitch).
                // Off the blade, and where a flank is not found, the hub's normal.
                let local = |angle: f64, v: &Vector3| {
                    let radial = frame.radial(angle);
                    let off_hub = normal[0] * v.dot(&frame.axis) + normal[1] * v.dot(&radial);
                    // A flank standing at less than about 10° off the hub is no wall to follow.
                    if off_hub.abs() < 0.2 {
                        return [normal[0], normal[1], 0.0];
                    }
                    let v = v * off_hub.signum();
                    [
                        v.dot(&frame.axis),
                        v.dot(&radial),
                        v.dot(&frame.axis.cross(&radial)),
                    ]
                };
                let walls = match blade_sides.get(j).copied().flatten() {
                    Some([(lo, lo_span), (hi, hi_span)]) if j >= first && j <= last => {
                        [local(hi, &hi_span), local(lo, &lo_span)]
                    }
                    _ => [[normal[0], normal[1], 0.0]; 2],
                };
                Station {
                    along: m,
                    height: point[0],
                    radius: point[1],
                    normal,
                    free,
                    walls,
                }
            })
            .collect();
        let roots_carried = carried(&meridian);
        Ok(HubPassage {
            meridian,
            frame,
            pitch,
            stations,
            profile_fit_mm,
            flow_triangles,
            flow_area_mm2,
            flow,
            first_blade,
            roots_carried,
        })
    }

    /// The splitters standing in passage 0 (between its first blade and the next), by their
    /// index in [`Impeller::pieces`].
    pub fn splitters(&self, impeller: &Impeller) -> Vec<usize> {
        let blade = impeller.pieces[self.first_blade].angle_deg.to_radians();
        impeller
            .pieces
            .iter()
            .enumerate()
            .filter(|(_, p)| {
                let after = (p.angle_deg.to_radians() - blade).rem_euclid(TAU);
                p.kind == super::recognise::PieceKind::Splitter && after > 0.0 && after < self.pitch
            })
            .map(|(k, _)| k)
            .collect()
    }

    /// The tool axis the walls suggest at `p` (on or near the hub, in any passage): the span
    /// directions of the two walls interpolated across the passage by the fraction of its free
    /// width `p` stands at ("interpolate vector"), so the tool stands along the blade beside
    /// it and turns evenly from one blade's flank to the next.
    pub fn wall_axis(&self, p: &Point3) -> Vector3 {
        let (radius, angle, height) = self.frame.cylindrical(p);
        let (m, _) = self.meridian.project([height, radius]);
        let step = self.meridian.length() / (self.stations.len() - 1).max(1) as f64;
        let j = ((m / step.max(1e-12)).round() as usize).min(self.stations.len() - 1);
        let s = &self.stations[j];
        let f = match (s.free.first(), s.free.last()) {
            (Some(first), Some(_)) if s.free_width() > 0.0 => {
                // Into passage 0's window, from its start.
                let start = first[0];
                let a = start + (angle - start).rem_euclid(self.pitch);
                let before: f64 = s
                    .free
                    .iter()
                    .map(|&[lo, hi]| (a.min(hi) - lo).max(0.0))
                    .sum();
                before / s.free_width()
            }
            _ => 0.5,
        };
        let [w0, w1] = s.walls;
        let local = [
            w0[0] + f * (w1[0] - w0[0]),
            w0[1] + f * (w1[1] - w0[1]),
            w0[2] + f * (w1[2] - w0[2]),
        ];
        let radial = self.frame.radial(angle);
        let axis = self.frame.axis * local[0]
            + radial * local[1]
            + self.frame.axis.cross(&radial) * local[2];
        axis.try_normalize(1e-12)
            .unwrap_or_else(|| (self.frame.axis * s.normal[0] + radial * s.normal[1]).normalize())
    }

    /// How far `p` stands above the hub's surface of revolution (negative below it), mm,
    /// measured in its meridional half-plane, and the unit direction it rises in there (the
    /// hub's normal at the nearest point of the meridian, at `p`'s angle).
    pub fn above_hub(&self, p: &Point3) -> (f64, Vector3) {
        let (radius, angle, height) = self.frame.cylindrical(p);
        let (m, _) = self.meridian.project([height, radius]);
        let (on, tangent) = self.meridian.at(m);
        let step = self.meridian.length() / (self.stations.len() - 1).max(1) as f64;
        let j = ((m / step.max(1e-12)).round() as usize).min(self.stations.len() - 1);
        let normal = self.stations[j].normal;
        // The meridian's own normal at m, turned to the stations' side.
        let mut n = [tangent[1], -tangent[0]];
        if n[0] * normal[0] + n[1] * normal[1] < 0.0 {
            n = [-n[0], -n[1]];
        }
        let above = (height - on[0]) * n[0] + (radius - on[1]) * n[1];
        let up = (self.frame.axis * n[0] + self.frame.radial(angle) * n[1]).normalize();
        (above, up)
    }

    /// The length of the hub's meridian, inlet to outlet, mm.
    pub fn meridian_length(&self) -> f64 {
        self.meridian.length()
    }

    /// Where `p` stands along the hub's meridian (the arc length of its nearest point from
    /// the inlet, mm; the end segments run on past the ends, so negative above the inlet),
    /// and the unit direction the meridian runs there, inlet to outlet, in `p`'s meridional
    /// half-plane.
    pub fn along(&self, p: &Point3) -> (f64, Vector3) {
        let (radius, angle, height) = self.frame.cylindrical(p);
        let m = self.meridian.project_run_on([height, radius]);
        let (_, tangent) = self.meridian.at(m);
        let downstream = self.frame.axis * tangent[0] + self.frame.radial(angle) * tangent[1];
        (m, downstream)
    }

    /// The mean of [`Self::wall_axis`] down the middle of passage 0, as (axial, radial,
    /// tangential) components at the passage's middle angle, and that angle.
    pub fn mean_wall_axis(&self) -> ([f64; 3], f64) {
        let mut sum = Vector3::zeros();
        let mut angles = 0.0;
        let mut count = 0.0;
        for (j, s) in self.stations.iter().enumerate() {
            if let Some(angle) = s.angle_at(0.5) {
                let p = self.point(j, angle).point;
                sum += self.wall_axis(&p);
                angles += angle;
                count += 1.0;
            }
        }
        let middle = if count > 0.0 { angles / count } else { 0.0 };
        let axis = sum.try_normalize(1e-12).unwrap_or(self.frame.axis);
        let radial = self.frame.radial(middle);
        (
            [
                axis.dot(&self.frame.axis),
                axis.dot(&radial),
                axis.dot(&self.frame.axis.cross(&radial)),
            ],
            middle,
        )
    }

    /// The point of the hub's surface of revolution at station `j` and angle `angle`, with the
    /// surface's unit normal there.
    pub fn point(&self, j: usize, angle: f64) -> DrivePoint {
        let s = &self.stations[j];
        let radial = self.frame.radial(angle);
        DrivePoint {
            point: self.frame.point(s.radius, angle, s.height),
            normal: (self.frame.axis * s.normal[0] + radial * s.normal[1]).normalize(),
        }
    }

    /// Distance across the flow between the lines at fractions `a` and `b` at station `j`,
    /// measured square to the lines (their angle to the meridian from the neighbouring
    /// stations), mm.
    fn spacing(&self, j: usize, a: f64, b: f64) -> f64 {
        let s = &self.stations[j];
        let around = s.radius * (b - a).abs() * s.free_width();
        let mid = 0.5 * (a + b);
        let (p, q) = (j.saturating_sub(1), (j + 1).min(self.stations.len() - 1));
        let slope = match (
            self.stations[p].angle_at(mid),
            self.stations[q].angle_at(mid),
        ) {
            (Some(tp), Some(tq)) if q > p => {
                let dm = self.stations[q].along - self.stations[p].along;
                s.radius * (tq - tp) / dm.max(1e-12)
            }
            _ => 0.0,
        };
        around / (1.0 + slope * slope).sqrt()
    }

    /// The stepover at station `j`: a ball of `radius` leaving scallops `scallop` high on the
    /// hub's curvature across the flow (the circle of the station, convex where the normal
    /// leans away from the axis).
    fn allowed(&self, j: usize, radius: f64, scallop: f64) -> f64 {
        let s = &self.stations[j];
        let curvature = (s.normal[1] / s.radius.max(1e-9)).max(0.0);
        stepover_on_convex(radius, scallop, curvature)
    }

    /// The flow lines (alg. 5.1), in order across the passage.
    pub fn flow_lines(&self, options: &PassageOptions) -> Vec<FlowLine> {
        let n = self.stations.len();
        let open: Vec<bool> = self.stations.iter().map(|s| s.free_width() > 0.0).collect();
        let everywhere = runs_of(&open);
        let mut lines = vec![
            FlowLine {
                fraction: 0.0,
                runs: everywhere.clone(),
            },
            FlowLine {
                fraction: 1.0,
                runs: everywhere,
            },
        ];
        let reach = (options.overlap / options.station_step.max(1e-9)).ceil() as usize;
        let allowed: Vec<f64> = (0..n)
            .map(|j| self.allowed(j, options.ball_radius, options.scallop_height))
            .collect();
        let mut pending = vec![(0.0, 1.0, open, 0u32)];
        while let Some((a, b, within, depth)) = pending.pop() {
            let needed: Vec<bool> = (0..n)
                .map(|j| within[j] && self.spacing(j, a, b) > allowed[j])
                .collect();
            if !needed.iter().any(|&x| x) || depth >= MAX_DEPTH {
                continue;
            }
            // Run on past where it is needed, but only where the passage is open.
            let mut span = vec![false; n];
            for j in (0..n).filter(|&j| needed[j]) {
                for s in span
                    .iter_mut()
                    .take((j + reach + 1).min(n))
                    .skip(j.saturating_sub(reach))
                {
                    *s = true;
                }
            }
            for (j, s) in span.iter_mut().enumerate() {
                *s &= self.stations[j].free_width() > 0.0;
            }
            let middle = 0.5 * (a + b);
            lines.push(FlowLine {
                fraction: middle,
                runs: runs_of(&span),
            });
            pending.push((a, middle, span.clone(), depth + 1));
            pending.push((middle, b, span, depth + 1));
        }
        lines.sort_by(|x, y| x.fraction.total_cmp(&y.fraction));
        lines
    }

    /// The drive curves of `lines` on `surface` (the part): each run's hub points projected
    /// onto the part, in the lines' order across the passage, each run starting at its end
    /// nearer to where the one before ended (a zig-zag where neighbouring lines span the same
    /// stations).
    pub fn drive_curves(&self, lines: &[FlowLine], surface: &SurfaceDistance) -> Vec<SectionCurve> {
        let mut curves: Vec<SectionCurve> = Vec::new();
        for line in lines {
            for &[first, last] in &line.runs {
                let mut points: Vec<DrivePoint> = (first..=last)
                    .filter_map(|j| {
                        let angle = self.stations[j].angle_at(line.fraction)?;
                        let on_hub = self.point(j, angle);
                        // The hub's facets lie inside its surface of revolution: the drive
                        // point is the part's nearest point, so the ball leaves nothing there.
                        let point = surface
                            .closest(&on_hub.point, 1.0)
                            .map_or(on_hub.point, |c| c.point);
                        Some(DrivePoint {
                            point,
                            normal: on_hub.normal,
                        })
                    })
                    .collect();
                if points.len() < 2 {
                    continue;
                }
                if let Some(end) = curves.last().and_then(|c| c.points.last()) {
                    let to = |p: &DrivePoint| (p.point - end.point).norm();
                    if to(&points[points.len() - 1]) < to(&points[0]) {
                        points.reverse();
                    }
                }
                curves.push(SectionCurve {
                    points,
                    closed: false,
                });
            }
        }
        curves
    }
}

/// The stepover of a ball of `radius` leaving cusps `scallop` high between neighbouring passes
/// on a surface curved convexly with `curvature` (1/mm, 0 flat) across them, measured along
/// the surface. On a circle of radius ρ the centres lie on the circle of radius C = ρ + r; the
/// cusp at ρ + h is r from both centres, 2α apart: cos α = (C² + (ρ+h)² − r²) / (2C(ρ+h)),
/// and the stepover is 2αρ. Flat: 2√(h(2r − h)), the limit as the curvature goes to 0.
pub fn stepover_on_convex(radius: f64, scallop: f64, curvature: f64) -> f64 {
    let h = scallop.clamp(0.0, radius);
    if curvature <= 1e-9 {
        return 2.0 * (h * (2.0 * radius - h)).sqrt();
    }
    let rho = 1.0 / curvature;
    // 1 − cos α = (r² − (C − ρ − h)²) / (2C(ρ+h)) = h(2r − h) / (2C(ρ+h)), since C − ρ − h is
    // r − h: no cancellation on a nearly flat surface.
    let half = (h * (2.0 * radius - h) / (4.0 * (rho + radius) * (rho + h))).sqrt();
    2.0 * (2.0 * half.min(1.0).asin()) * rho
}

/// The meridian through `points` (height, radius): sorted along their principal direction,
/// averaged in bins, inlet (greater height) first.
fn meridian_of(points: &[[f64; 2]]) -> Result<Meridian, String> {
    if points.len() < 4 {
        return Err("the hub has too few vertices for a meridian".into());
    }
    let n = points.len() as f64;
    let mean = points
        .iter()
        .fold([0.0, 0.0], |s, p| [s[0] + p[0] / n, s[1] + p[1] / n]);
    let (mut sxx, mut sxy, mut syy) = (0.0, 0.0, 0.0);
    for p in points {
        let (x, y) = (p[0] - mean[0], p[1] - mean[1]);
        sxx += x * x;
        sxy += x * y;
        syy += y * y;
    }
    // The principal direction of the 2×2 covariance.
    let angle = 0.5 * (2.0 * sxy).atan2(sxx - syy);
    let direction = [angle.cos(), angle.sin()];
    let along = |p: &[f64; 2]| (p[0] - mean[0]) * direction[0] + (p[1] - mean[1]) * direction[1];
    let (lo, hi) = points
        .iter()
        .map(along)
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), t| {
            (a.min(t), b.max(t))
        });
    if hi - lo <= 0.0 {
        return Err("the hub between the blades has no extent along its meridian".into());
    }
    let bins = (points.len() / 8).clamp(16, 512);
    // Coordinate-wise medians per bin: a few stray vertices do not pull the meridian.
    let mut binned: Vec<Vec<[f64; 2]>> = vec![Vec::new(); bins];
    for p in points {
        let k = (((along(p) - lo) / (hi - lo)) * bins as f64).floor() as usize;
        binned[k.min(bins - 1)].push(*p);
    }
    let median = |values: &mut Vec<f64>| {
        values.sort_by(f64::total_cmp);
        values[values.len() / 2]
    };
    let mut line: Vec<[f64; 2]> = binned
        .iter()
        .filter(|b| !b.is_empty())
        .map(|b| {
            let mut hs: Vec<f64> = b.iter().map(|p| p[0]).collect();
            let mut rs: Vec<f64> = b.iter().map(|p| p[1]).collect();
            [median(&mut hs), median(&mut rs)]
        })
        .collect();
    if line.len() < 2 {
        return Err("the hub between the blades has no extent along its meridian".into());
    }
    // The bins' averages stop about half a bin inside the ends: carry the end segments on
    // to the extreme points' reach along the principal direction.
    let n = line.len();
    for (end, inner) in [(0, 1), (n - 1, n - 2)] {
        let (e, i) = (line[end], line[inner]);
        let d = [e[0] - i[0], e[1] - i[1]];
        let gain = along(&e) - along(&i);
        let target = if end == 0 { lo } else { hi };
        if gain.abs() > 1e-12 {
            let t = (target - along(&i)) / gain;
            line[end] = [i[0] + d[0] * t, i[1] + d[1] * t];
        }
    }
    let (start, end) = (line[0], line[line.len() - 1]);
    if end[0] > start[0] || (end[0] == start[0] && end[1] < start[1]) {
        line.reverse();
    }
    let mut along = vec![0.0];
    for w in line.windows(2) {
        let d = (w[1][0] - w[0][0]).hypot(w[1][1] - w[0][1]);
        along.push(along[along.len() - 1] + d);
    }
    Ok(Meridian {
        points: line,
        along,
    })
}

/// Removes `cut` from the sorted disjoint intervals `free`.
fn subtract(free: &mut Vec<[f64; 2]>, cut: [f64; 2]) {
    let mut out = Vec::with_capacity(free.len() + 1);
    for &[a, b] in free.iter() {
        if cut[1] <= a || cut[0] >= b {
            out.push([a, b]);
            continue;
        }
        if cut[0] > a {
            out.push([a, cut[0]]);
        }
        if cut[1] < b {
            out.push([cut[1], b]);
        }
    }
    *free = out;
}

/// The runs of consecutive `true`s, as [first, last].
fn runs_of(flags: &[bool]) -> Vec<[usize; 2]> {
    let mut runs = Vec::new();
    let mut start = None;
    for (j, &f) in flags.iter().enumerate() {
        match (f, start) {
            (true, None) => start = Some(j),
            (false, Some(s)) => {
                runs.push([s, j - 1]);
                start = None;
            }
            _ => {}
        }
    }
    if let Some(s) = start {
        runs.push([s, flags.len() - 1]);
    }
    runs
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::impeller::{EdgeSide, RecogniseOptions, blade_loops, recognise};

    /// The bundled sample impeller, recognised, and its passage for a 4 mm ball at 0.01 mm.
    fn sample() -> (Mesh, Impeller, HubPassage, PassageOptions) {
        let mesh = crate::sample::impeller(&Default::default()).expect("sample impeller");
        let impeller = recognise(&mesh, &RecogniseOptions::default()).expect("an impeller");
        let options = PassageOptions {
            station_step: 0.25,
            ball_radius: 2.0,
            scallop_height: 0.01,
            overlap: 1.6,
        };
        let passage = HubPassage::new(&mesh, &impeller, &options).expect("a passage");
        (mesh, impeller, passage, options)
    }

    /// The sample's flow comes in axially near the bore (radius 8–15 mm) and leaves radially
    /// at the rim (45 mm): the leading edges face up and stand near the bore, the trailing
    /// edges face out at the rim, upstream before downstream at every height.
    #[test]
    fn the_sample_blades_lead_at_the_inlet_and_trail_at_the_rim() {
        let (mesh, impeller, passage, _) = sample();
        let edges = crate::impeller::blade_edges(&mesh, &impeller, &passage);
        // The inlet's edge runs most of the blade's height, the outlet's (low) a few levels.
        assert!(edges.leading.len() >= 12, "{edges:?}");
        assert!(edges.trailing.len() >= 2, "{edges:?}");
        for lead in &edges.leading {
            assert!(lead[2] < 20.0, "{lead:?}");
        }
        for trail in &edges.trailing {
            assert!(trail[2] > 40.0, "{trail:?}");
            assert!(edges.leading.iter().all(|lead| lead[1] + 10.0 < trail[1]));
        }
        assert!(edges.leading_area_mm2 > 0.0 && edges.trailing_area_mm2 > 0.0);
        // Every blade's edges alike (the symmetry), the leading ones by the bore.
        let mut per_blade = std::collections::BTreeMap::new();
        for (t, side) in edges.sides.iter().enumerate() {
            let Some(side) = side else { continue };
            let [a, b, c] = mesh.corners(t);
            let centre = Point3::from((a.coords + b.coords + c.coords) / 3.0);
            let (radius, _, _) = passage.frame.cylindrical(&centre);
            match side {
                EdgeSide::Leading => assert!(radius < 20.0, "{t}: {radius}"),
                EdgeSide::Trailing => assert!(radius > 40.0, "{t}: {radius}"),
            }
            *per_blade
                .entry(format!("{:?} {side:?}", impeller.regions[t]))
                .or_insert(0.0) += 0.5 * (b - a).cross(&(c - a)).norm();
        }
        assert_eq!(per_blade.len(), 2 * impeller.blades, "{per_blade:?}");
        for side in ["Leading", "Trailing"] {
            let (least, most) = per_blade
                .iter()
                .filter(|(k, _)| k.ends_with(side))
                .fold((f64::INFINITY, 0.0f64), |(l, m), (_, a)| {
                    (l.min(*a), m.max(*a))
                });
            assert!(least > 0.0 && most - least < 0.05 * most, "{per_blade:?}");
        }
    }

    /// Alg. 5.1's promise: at every station, neighbouring lines present there are no farther
    /// apart than the stepover the scallop allows there; lines are partial where the passage
    /// narrows; the drive points lie on the part, inside passage 0.
    #[test]
    fn flow_lines_on_the_sample_keep_the_stepover_everywhere_with_partial_passes() {
        let (mesh, _, passage, options) = sample();
        assert!(passage.profile_fit_mm < 0.02, "{}", passage.profile_fit_mm);
        let lines = passage.flow_lines(&options);
        for j in 0..passage.stations.len() {
            if passage.stations[j].free_width() <= 0.0 {
                continue;
            }
            let present: Vec<f64> = lines
                .iter()
                .filter(|l| l.runs.iter().any(|&[a, b]| a <= j && j <= b))
                .map(|l| l.fraction)
                .collect();
            assert!(present.first() == Some(&0.0) && present.last() == Some(&1.0));
            let allowed = passage.allowed(j, options.ball_radius, options.scallop_height);
            for w in present.windows(2) {
                let gap = passage.spacing(j, w[0], w[1]);
                assert!(gap <= allowed + 1e-12, "station {j}: {gap} > {allowed}");
            }
        }
        let full = &lines[0].runs;
        let partial = lines.iter().filter(|l| &l.runs != full).count();
        assert!(partial > lines.len() / 2, "{partial} of {}", lines.len());

        let surface = SurfaceDistance::new(&mesh);
        let curves = passage.drive_curves(&lines, &surface);
        let step = passage.meridian.length() / (passage.stations.len() - 1) as f64;
        for p in curves.iter().flat_map(|c| &c.points) {
            let d = surface
                .closest(&p.point, 1.0)
                .expect("on the part")
                .distance;
            assert!(d < 1e-9, "{d}");
            // Within its station's window of passage 0 (the part's facets lie up to a few
            // micrometres off the surface of revolution the point was taken on).
            let (radius, angle, height) = passage.frame.cylindrical(&p.point);
            let j = (passage.meridian.project([height, radius]).0 / step).round() as usize;
            let free = &passage.stations[j.min(passage.stations.len() - 1)].free;
            let (lo, hi) = (free[0][0], free[free.len() - 1][1]);
            let into = (angle - lo + 0.1).rem_euclid(TAU) - 0.1;
            assert!(
                into > -0.01 && into < hi - lo + 0.01,
                "angle {angle} outside {lo}..{hi}"
            );
        }
    }

    /// Every loop around a blade runs at its level's height above the hub, the levels a
    /// stepover apart at most, from the tip down to the root.
    #[test]
    fn blade_loops_run_at_constant_height_round_the_blade() {
        let (mesh, impeller, passage, _) = sample();
        let loops = blade_loops(&mesh, &impeller, &passage, passage.first_blade, 0.4, 1.6);
        assert!(loops.levels > 10 && loops.level_step <= 0.4);
        let mut heights = Vec::new();
        // Round the blade, but where a low level meets the blade's edge on the hub.
        let closed = loops.curves.iter().filter(|c| c.closed).count();
        assert!(
            closed * 10 >= loops.curves.len() * 9,
            "{closed} of {}",
            loops.curves.len()
        );
        for curve in &loops.curves {
            // The section is linear on each triangle while the height above the curved
            // meridian is not (long facets, and kinks where two points of the meridian are
            // equally near): the loop's median height is its level.
            let mut h: Vec<f64> = curve
                .points
                .iter()
                .map(|p| passage.above_hub(&p.point).0)
                .collect();
            h.sort_by(f64::total_cmp);
            heights.push(h[h.len() / 2]);
        }
        // Levels from the tip down, none skipped (a level may hold more than one curve).
        heights.sort_by(|a, b| b.total_cmp(a));
        assert!(heights[0] >= loops.top - loops.level_step);
        for w in heights.windows(2) {
            let slack = 0.2 * loops.level_step;
            assert!(w[0] - w[1] <= loops.level_step + slack, "{heights:?}");
        }
        assert!(heights.last().is_some_and(|&h| h <= loops.level_step));
    }

    /// The passes along the sample blade's tip lie on its land (triangles facing away from
    /// the hub within 45°, away from the root), and every point of the land is within half a stepover of
    /// one (brute force over their segments, at each land triangle's centroid and corners):
    /// the level loops cross the nearly level land at the rim far apart.
    #[test]
    fn tip_passes_cover_the_blade_land_within_half_a_stepover() {
        let (mesh, impeller, passage, _) = sample();
        let stepover = 0.4;
        let tip = crate::impeller::blade_tip_passes(
            &mesh,
            &impeller,
            &passage,
            passage.first_blade,
            stepover,
        );
        assert!(tip.curves.len() >= 3 && tip.land_area_mm2 > 50.0, "{tip:?}");
        let segments: Vec<[Point3; 2]> = tip
            .curves
            .iter()
            .flat_map(|c| c.points.windows(2).map(|w| [w[0].point, w[1].point]))
            .collect();
        let blade = |t: usize| impeller.regions[t] == Region::Blade(passage.first_blade as u32);
        let top = (0..mesh.triangles.len())
            .filter(|&t| blade(t))
            .flat_map(|t| mesh.corners(t))
            .map(|p| passage.above_hub(&p).0)
            .fold(0.0, f64::max);
        let mut checked = 0;
        let mut worst: f64 = 0.0;
        for t in (0..mesh.triangles.len()).filter(|&t| blade(t)) {
            let [a, b, c] = mesh.corners(t);
            let centroid = Point3::from((a.coords + b.coords + c.coords) / 3.0);
            let (above, up) = passage.above_hub(&centroid);
            if above < 0.15 * top || mesh.face_normal(t).dot(&up) < 0.7 {
                continue;
            }
            for p in [centroid, a, b, c] {
                let d = segments
                    .iter()
                    .map(|[q, r]| (p - crate::geom::closest_point_on_segment(&p, q, r)).norm())
                    .fold(f64::INFINITY, f64::min);
                worst = worst.max(d);
                checked += 1;
            }
        }
        assert!(checked > 100, "{checked}");
        assert!(
            worst <= 0.5 * stepover + 0.05,
            "a land point {worst} mm from every pass"
        );
        // On the land: every pass point on a blade triangle facing away from the hub.
        let surface = crate::mesh::SurfaceDistance::new(&mesh);
        for p in tip.curves.iter().flat_map(|c| &c.points) {
            let near = surface.closest(&p.point, 1e-6).expect("on the part");
            assert!(blade(near.triangle as usize));
            let (_, up) = passage.above_hub(&p.point);
            assert!(p.normal.dot(&up) >= 0.7 - 1e-9, "{p:?}");
        }
    }

    /// Alg. 5.1 round the blade: where the flank leans, the full levels stand farther apart
    /// than the stepover (some points on it farther than half a stepover from every loop);
    /// with the partial loops every point of the flank between the top and bottom loops is
    /// within half a stepover of one (brute force over the loops' segments).
    #[test]
    fn partial_blade_loops_bring_every_point_of_the_flank_within_half_a_stepover() {
        let (mesh, impeller, passage, _) = sample();
        let stepover = 0.4;
        let loops = blade_loops(
            &mesh,
            &impeller,
            &passage,
            passage.first_blade,
            stepover,
            0.4,
        );
        assert!(!loops.partial.is_empty());
        let cell = 1.0;
        let key = |p: &Point3| [p.x, p.y, p.z].map(|c| (c / cell).floor() as i64);
        let grid_of = |curves: &[&SectionCurve]| {
            let mut grid: std::collections::HashMap<[i64; 3], Vec<(Point3, Point3)>> =
                Default::default();
            for curve in curves {
                let n = curve.points.len();
                let count = if curve.closed { n } else { n - 1 };
                for i in 0..count {
                    let (a, b) = (curve.points[i].point, curve.points[(i + 1) % n].point);
                    // In pieces shorter than a cell, each filed by its start.
                    let pieces = ((a - b).norm() / (0.5 * cell)).ceil().max(1.0) as usize;
                    for k in 0..pieces {
                        let from = a + (b - a) * (k as f64 / pieces as f64);
                        let to = a + (b - a) * ((k + 1) as f64 / pieces as f64);
                        grid.entry(key(&from)).or_default().push((from, to));
                    }
                }
            }
            grid
        };
        let nearest = |grid: &std::collections::HashMap<[i64; 3], Vec<(Point3, Point3)>>,
                       p: &Point3| {
            let k = key(p);
            let mut best = f64::INFINITY;
            for dx in -2..=2 {
                for dy in -2..=2 {
                    for dz in -2..=2 {
                        for (a, b) in grid
                            .get(&[k[0] + dx, k[1] + dy, k[2] + dz])
                            .into_iter()
                            .flatten()
                        {
                            best = best
                                .min((p - crate::geom::closest_point_on_segment(p, a, b)).norm());
                        }
                    }
                }
            }
            best
        };
        let full: Vec<&SectionCurve> = loops.curves.iter().collect();
        let all: Vec<&SectionCurve> = loops.curves.iter().chain(&loops.partial).collect();
        let (full_grid, all_grid) = (grid_of(&full), grid_of(&all));
        let top = loops.top - 0.5 * loops.level_step;
        let bottom = top - (loops.levels - 1) as f64 * loops.level_step;
        let (mut worst_full, mut worst_all, mut samples) = (0.0f64, 0.0f64, 0);
        for (t, region) in impeller.regions.iter().enumerate() {
            if *region != Region::Blade(passage.first_blade as u32) {
                continue;
            }
            let [a, b, c] = mesh.corners(t);
            // Points on the flank (not the tip), well inside the band the loops cover.
            let normal = mesh.face_normal(t);
            for p in [
                Point3::from((a.coords + b.coords + c.coords) / 3.0),
                Point3::from((a.coords * 4.0 + b.coords + c.coords) / 6.0),
            ] {
                let (height, up) = passage.above_hub(&p);
                let across = up - normal * normal.dot(&up);
                if across.norm() < 0.3 || height > top - 0.1 || height < bottom + 0.1 {
                    continue;
                }
                samples += 1;
                worst_full = worst_full.max(nearest(&full_grid, &p));
                worst_all = worst_all.max(nearest(&all_grid, &p));
            }
        }
        assert!(samples > 1000, "{samples}");
        assert!(worst_full > 0.6 * stepover, "{worst_full}");
        assert!(
            worst_all <= 0.55 * stepover,
            "{worst_all} (full loops alone {worst_full})"
        );
    }

    #[test]
    fn the_convex_stepover_is_the_flat_one_in_the_limit_and_exact_on_a_circle() {
        let flat = stepover_on_convex(2.0, 0.01, 0.0);
        assert!((flat - 2.0 * (0.01f64 * 3.99).sqrt()).abs() < 1e-12);
        assert!((stepover_on_convex(2.0, 0.01, 1e-7) - flat).abs() < 1e-6);
        assert!((stepover_on_convex(2.0, 0.01, 3e-8) - flat).abs() < 1e-6);
        // On a cylinder of radius 10: two ball centres on the circle of radius 12, the cusp
        // between them must be exactly 10.01 from the axis and 2 from each centre.
        let w = stepover_on_convex(2.0, 0.01, 0.1);
        let half = w / 2.0 / 10.0;
        let centre = nalgebra::Vector2::new(12.0 * half.cos(), 12.0 * half.sin());
        let cusp = nalgebra::Vector2::new(10.01, 0.0);
        assert!(((centre - cusp).norm() - 2.0).abs() < 1e-9);
        assert!(w < flat);
    }

    #[test]
    fn free_intervals_hop_the_footprints_and_fractions_walk_them() {
        let mut free = vec![[0.0, 1.0]];
        subtract(&mut free, [0.4, 0.6]);
        assert_eq!(free, vec![[0.0, 0.4], [0.6, 1.0]]);
        let s = Station {
            along: 0.0,
            height: 0.0,
            radius: 1.0,
            normal: [1.0, 0.0],
            free,
            walls: [[1.0, 0.0, 0.0]; 2],
        };
        assert_eq!(s.angle_at(0.0), Some(0.0));
        assert!((s.angle_at(0.5).unwrap() - 0.4).abs() < 1e-12);
        assert!((s.angle_at(0.75).unwrap() - 0.8).abs() < 1e-12);
        assert_eq!(s.angle_at(1.0), Some(1.0));
        assert_eq!(
            runs_of(&[false, true, true, false, true]),
            vec![[1, 2], [4, 4]]
        );
    }
}
