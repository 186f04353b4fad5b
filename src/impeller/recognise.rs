//! An impeller recognised in a mesh: its rotation axis, its order of rotational symmetry
//! (checked on the surface, not assumed), the hub (every surface of revolution about the axis)
//! and the blades standing on it, main blades and splitters told apart by size.
//!
//! * **Axis.** The surface's second moments of area about its centroid: a body with a
//!   rotational symmetry of order three or more has two equal principal moments, and the third
//!   principal direction is its axis (the part's +Z is tried as well, for a part whose moments
//!   happen to be near-equal). The axis points the way the blades stand from the hub.
//! * **Order.** The blades' flanks face round the axis: the area of the triangles weighted by
//!   the tangential part of their normal, as a function of the angle about the axis, has its
//!   strongest harmonics at the blade count and its multiples. Candidates are tried strongest
//!   first: an order N holds when every sampled vertex turned by 2π/N about the axis lands on
//!   the surface within the tolerance (the largest miss and the 99th percentile are reported).
//! * **Hub and blades.** A point of a surface of revolution stays on the surface turned by any
//!   angle; a blade's point turned by part of a pitch lands in the passage. A triangle whose
//!   normal has no tangential part to speak of and whose centroid, turned by 0.1, 0.29 and
//!   0.71 of the pitch (odd fractions, so that a splitter half a pitch away does not receive a
//!   blade's top face), lands on the surface at least twice (a blade may stand where one
//!   lands) is hub; the rest, joined across shared edges, are blade pieces.
//!   Pieces come in sets of the symmetry's order with equal areas: the largest set are the
//!   main blades, smaller sets of at least a tenth of their area splitters, and the rest other
//!   features (fillet slivers, bosses).

use nalgebra::{Matrix3, Rotation3, SymmetricEigen};
use serde::Serialize;

use crate::geom::{Direction, Point3, Vector3};
use crate::mesh::Mesh;
use crate::mesh::distance::SurfaceDistance;

use super::root::{RootCorner, root_corners};

use super::frame::AxisFrame;

/// Why a mesh is not taken for an impeller.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum NotAnImpeller {
    #[error("the mesh has no area")]
    Empty,
    #[error(
        "no rotational symmetry of order 3 to {max_order} about its principal or vertical axis, \
         or of the order and about the axis given (best: order {best_order}, {share_on:.1} % of \
         the sampled points land on the surface turned by a pitch, within {tolerance:.4} mm)"
    )]
    NoSymmetry {
        max_order: usize,
        best_order: usize,
        share_on: f64,
        tolerance: f64,
    },
    #[error("a body of revolution about its axis: there are no blades")]
    NoBlades,
    #[error(
        "symmetric of order {order} about its axis, but with no hub: only {hub_share:.1} % of \
         the surface is of revolution about it"
    )]
    NoHub { order: usize, hub_share: f64 },
    #[error(
        "symmetric of order {order}, but what stands on the hub is not blades in {order}-fold \
         sets ({blades} main pieces)"
    )]
    NotInBlades { order: usize, blades: usize },
}

/// How hard to look.
#[derive(Clone, Debug, PartialEq)]
pub struct RecogniseOptions {
    /// Highest order of symmetry tried.
    pub max_order: usize,
    /// A turned point this near the surface is on it, mm; `None`: 1e-3 of the part's
    /// bounding-box diagonal.
    pub tolerance: Option<f64>,
    /// Share of sampled vertices that must land on the surface for an order to hold.
    pub symmetric_share: f64,
    /// Vertices sampled for the symmetry test (evenly through the vertex list).
    pub sample_points: usize,
    /// The rotation axis, given (part frame, any length): only it is tried, through the
    /// surface's centroid.
    pub axis: Option<[f64; 3]>,
    /// The order of symmetry (the main blades' count), given: only it is tried.
    pub order: Option<usize>,
}

impl Default for RecogniseOptions {
    fn default() -> Self {
        RecogniseOptions {
            max_order: 64,
            tolerance: None,
            symmetric_share: 0.98,
            sample_points: 4000,
            axis: None,
            order: None,
        }
    }
}

/// What a triangle belongs to.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Region {
    Hub,
    /// A main blade, by its index in [`Impeller::pieces`].
    Blade(u32),
    Splitter(u32),
    /// A small piece that is neither (a fillet sliver, a boss).
    Other(u32),
}

/// One connected piece of the non-hub surface.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Piece {
    pub kind: PieceKind,
    pub triangles: usize,
    pub area_mm2: f64,
    /// Angle about the axis of its area centroid, degrees, from the frame's first radial axis.
    pub angle_deg: f64,
    /// Radius and height (along the axis, from the centre) ranges of its vertices, mm.
    pub radius_mm: [f64; 2],
    pub height_mm: [f64; 2],
    /// Where a blade or splitter meets the hub: the crease and the fillet (the largest ball
    /// that finishes the corner); `None` for other pieces and pieces off the hub.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub root: Option<RootCorner>,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum PieceKind {
    Blade,
    Splitter,
    Other,
}

/// An impeller's geometry, as recognised.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Impeller {
    /// The rotation axis (unit, pointing from the hub to the blades' side) and a point on it
    /// (the surface's area centroid), part frame.
    pub axis: [f64; 3],
    pub centre: [f64; 3],
    /// Order of the rotational symmetry found, and how well the turned surface lands on
    /// itself: the 99th percentile and the largest distance of the sampled points, mm.
    pub order: usize,
    pub symmetry_p99_mm: f64,
    pub symmetry_max_mm: f64,
    pub tolerance_mm: f64,
    pub blades: usize,
    pub splitters: usize,
    pub hub_triangles: usize,
    pub hub_area_mm2: f64,
    /// Hub radius range, mm.
    pub hub_radius_mm: [f64; 2],
    /// The shroud: the blades' largest radius in bands of height along the axis, (height,
    /// radius) mm, from the lowest band up.
    pub shroud: Vec<[f64; 2]>,
    pub pieces: Vec<Piece>,
    /// Per triangle of the mesh.
    #[serde(skip)]
    pub regions: Vec<Region>,
}

/// Recognises the impeller in `mesh` (closed, consistently oriented), or says why it is not one.
pub fn recognise(mesh: &Mesh, options: &RecogniseOptions) -> Result<Impeller, NotAnImpeller> {
    let (area, centroid, moments) = second_moments(mesh);
    if area <= 0.0 {
        return Err(NotAnImpeller::Empty);
    }
    let tolerance = options.tolerance.unwrap_or(1e-3 * mesh.aabb().diagonal());
    let surface = SurfaceDistance::new(mesh);
    let stride = (mesh.positions.len() / options.sample_points.max(1)).max(1);
    let samples: Vec<Point3> = mesh.positions.iter().step_by(stride).copied().collect();

    let mut best: Option<(usize, f64, Vector3)> = None;
    let mut found: Option<(usize, Vector3, Vec<f64>)> = None;
    let axes = match options.axis {
        Some(axis) => vec![Vector3::from(axis)],
        None => candidate_axes(&moments),
    };
    'axes: for axis in axes {
        if axis.norm() == 0.0 || !axis.iter().all(|v| v.is_finite()) {
            continue;
        }
        let frame = AxisFrame::new(centroid, &axis);
        let orders = match options.order {
            Some(order) => vec![order.max(1)],
            None => candidate_orders(mesh, &frame, options.max_order),
        };
        for order in orders {
            let turn = frame.turn(std::f64::consts::TAU / order as f64);
            let misses: Vec<f64> = samples
                .iter()
                .map(|p| {
                    surface
                        .closest(&frame.turned(p, &turn), f64::INFINITY)
                        .map_or(f64::INFINITY, |c| c.distance)
                })
                .collect();
            let on = misses.iter().filter(|&&d| d <= tolerance).count() as f64
                / misses.len().max(1) as f64;
            if best.as_ref().is_none_or(|b| on > b.1) {
                best = Some((order, on, axis));
            }
            if on >= options.symmetric_share {
                found = Some((order, axis, misses));
                break 'axes;
            }
        }
    }
    let Some((order, axis, mut misses)) = found else {
        let (best_order, share, _) = best.unwrap_or((0, 0.0, Vector3::z()));
        return Err(NotAnImpeller::NoSymmetry {
            max_order: options.max_order,
            best_order,
            share_on: 100.0 * share,
            tolerance,
        });
    };
    misses.sort_by(f64::total_cmp);
    let p99 = misses[((misses.len() as f64 * 0.99) as usize).min(misses.len() - 1)];
    let max = misses[misses.len() - 1];

    let mut frame = AxisFrame::new(centroid, &axis);
    let pitch = std::f64::consts::TAU / order as f64;
    // Odd fractions of the pitch: a splitter half a pitch away (or a blade a pitch away) must
    // not receive a blade's top or end face turned onto it.
    let turns: Vec<Rotation3<f64>> = [0.1, 0.29, 0.71]
        .iter()
        .map(|f| frame.turn(f * pitch))
        .collect();
    let n = mesh.triangles.len();
    let is_hub: Vec<bool> = (0..n)
        .map(|t| {
            let [a, b, c] = mesh.corners(t);
            let centre = Point3::from((a.coords + b.coords + c.coords) / 3.0);
            let normal = (b - a).cross(&(c - a)).try_normalize(1e-300);
            let Some(normal) = normal else {
                return false;
            };
            // A faceted surface of revolution, turned, lands off its own facets by up to about
            // the chord's sagitta: L²/(8r) for a facet of longest edge L at radius r.
            let longest = [(a, b), (b, c), (c, a)]
                .iter()
                .map(|(p, q)| (q - p).norm())
                .fold(0.0, f64::max);
            let (radius, _, _) = frame.cylindrical(&centre);
            // Capped at 2 % of the radius (a facet spanning about 23°).
            let reach =
                tolerance + (longest * longest / (4.0 * radius.max(tolerance))).min(0.02 * radius);
            normal.dot(&frame.tangent(&centre)).abs() < 0.5
                && turns
                    .iter()
                    .filter(|r| surface.closest(&frame.turned(&centre, r), reach).is_some())
                    .count()
                    >= 2
        })
        .collect();
    let hub_triangles = is_hub.iter().filter(|&&h| h).count();
    if hub_triangles == n {
        return Err(NotAnImpeller::NoBlades);
    }
    // The blades stand on the hub's side the axis points to.
    let blade_side: f64 = (0..n)
        .filter(|&t| !is_hub[t])
        .map(|t| {
            let [a, b, c] = mesh.corners(t);
            let w = 0.5 * (b - a).cross(&(c - a)).norm();
            w * (Point3::from((a.coords + b.coords + c.coords) / 3.0) - centroid).dot(&frame.axis)
        })
        .sum();
    if blade_side < 0.0 {
        frame = AxisFrame::new(centroid, &-frame.axis);
    }

    let (pieces, piece_of) = blade_pieces(mesh, &is_hub, &frame);
    let kinds = piece_kinds(&pieces, order);
    // The largest ball tried in a root corner: a twentieth of the part's size (a fillet that
    // large is a blade's whole foot).
    let roots = root_corners(
        mesh,
        &surface,
        &piece_of,
        pieces.len(),
        |k| kinds[k] != PieceKind::Other,
        0.05 * mesh.aabb().diagonal(),
    );
    let pieces: Vec<Piece> = pieces
        .into_iter()
        .zip(&kinds)
        .zip(roots)
        .map(|((p, &kind), root)| Piece { kind, root, ..p })
        .collect();
    let regions: Vec<Region> = (0..n)
        .map(|t| match piece_of[t] {
            None => Region::Hub,
            Some(k) => match kinds[k as usize] {
                PieceKind::Blade => Region::Blade(k),
                PieceKind::Splitter => Region::Splitter(k),
                PieceKind::Other => Region::Other(k),
            },
        })
        .collect();

    let mut hub_area = 0.0;
    let mut hub_radius = [f64::INFINITY, f64::NEG_INFINITY];
    let mut blade_points = Vec::new();
    for t in 0..n {
        let corners = mesh.corners(t);
        let [a, b, c] = corners;
        if is_hub[t] {
            hub_area += 0.5 * (b - a).cross(&(c - a)).norm();
            for p in &corners {
                let (r, _, _) = frame.cylindrical(p);
                hub_radius = [hub_radius[0].min(r), hub_radius[1].max(r)];
            }
        } else if matches!(regions[t], Region::Blade(_) | Region::Splitter(_)) {
            blade_points.extend(corners.iter().map(|p| {
                let (r, _, h) = frame.cylindrical(p);
                (h, r)
            }));
        }
    }
    let count = |kind| kinds.iter().filter(|&&k| k == kind).count();
    if hub_area < 0.05 * area {
        return Err(NotAnImpeller::NoHub {
            order,
            hub_share: 100.0 * hub_area / area,
        });
    }
    let blades = count(PieceKind::Blade);
    if blades < 2 || blades % order != 0 {
        return Err(NotAnImpeller::NotInBlades { order, blades });
    }
    Ok(Impeller {
        axis: frame.axis.into(),
        centre: centroid.coords.into(),
        order,
        symmetry_p99_mm: p99,
        symmetry_max_mm: max,
        tolerance_mm: tolerance,
        blades,
        splitters: count(PieceKind::Splitter),
        hub_triangles,
        hub_area_mm2: hub_area,
        hub_radius_mm: hub_radius,
        shroud: shroud_profile(&blade_points, 20),
        pieces,
        regions,
    })
}

/// Area, area centroid and second moments of area about the centroid of the surface.
fn second_moments(mesh: &Mesh) -> (f64, Point3, Matrix3<f64>) {
    let mut area = 0.0;
    let mut first = Vector3::zeros();
    let mut second = Matrix3::zeros();
    for t in 0..mesh.triangles.len() {
        let [a, b, c] = mesh.corners(t).map(|p| p.coords);
        let w = 0.5 * (b - a).cross(&(c - a)).norm();
        let s = a + b + c;
        area += w;
        first += w * s / 3.0;
        // ∫ x xᵀ dA over a triangle = A/12 (a aᵀ + b bᵀ + c cᵀ + s sᵀ).
        second += (w / 12.0)
            * (a * a.transpose() + b * b.transpose() + c * c.transpose() + s * s.transpose());
    }
    if area <= 0.0 {
        return (0.0, Point3::origin(), Matrix3::zeros());
    }
    let m = first / area;
    (area, Point3::from(m), second - area * m * m.transpose())
}

/// The principal direction whose moment stands apart from two near-equal ones, then +Z.
fn candidate_axes(moments: &Matrix3<f64>) -> Vec<Vector3> {
    let eigen = SymmetricEigen::new(*moments);
    let values = eigen.eigenvalues;
    let scale = values
        .iter()
        .fold(0.0f64, |m, v| m.max(v.abs()))
        .max(1e-300);
    // The pair closest together; the third is the axis.
    let (mut lone, mut gap) = (0usize, f64::INFINITY);
    for k in 0..3 {
        let (i, j) = ((k + 1) % 3, (k + 2) % 3);
        let d = (values[i] - values[j]).abs() / scale;
        if d < gap {
            (lone, gap) = (k, d);
        }
    }
    let mut axes = Vec::new();
    if gap < 0.05 {
        let mut axis: Vector3 = eigen.eigenvectors.column(lone).into();
        if axis.z < 0.0 {
            axis = -axis;
        }
        axes.push(axis);
    }
    if axes.first().is_none_or(|a| a.z < 1.0 - 1e-9) {
        axes.push(Vector3::z());
    }
    axes
}

/// Orders to try about `frame`'s axis, from the strongest harmonics of the flanks' angular
/// signature.
fn candidate_orders(mesh: &Mesh, frame: &AxisFrame, max_order: usize) -> Vec<usize> {
    let samples: Vec<(f64, f64)> = (0..mesh.triangles.len())
        .filter_map(|t| {
            let [a, b, c] = mesh.corners(t);
            let cross = (b - a).cross(&(c - a));
            let w = 0.5 * cross.norm();
            let centre = Point3::from((a.coords + b.coords + c.coords) / 3.0);
            let normal = cross.try_normalize(1e-300)?;
            let (_, angle, _) = frame.cylindrical(&centre);
            Some((angle, w * normal.dot(&frame.tangent(&centre)).abs()))
        })
        .collect();
    let mut strength: Vec<(usize, f64)> = (3..=max_order)
        .map(|k| {
            let (mut re, mut im) = (0.0, 0.0);
            for &(angle, w) in &samples {
                re += w * (k as f64 * angle).cos();
                im += w * (k as f64 * angle).sin();
            }
            (k, re.hypot(im))
        })
        .collect();
    strength.sort_by(|a, b| b.1.total_cmp(&a.1).then(a.0.cmp(&b.0)));
    // A surface of order N has harmonics at multiples of N only, so the order divides each
    // strong harmonic (blades and splitters make 2N the strongest): the divisors of the
    // strongest few, largest first, as the largest order that holds is the one.
    let mut orders = Vec::new();
    for &(k, _) in strength.iter().take(4) {
        for d in (3..=k).rev() {
            if k % d == 0 && !orders.contains(&d) {
                orders.push(d);
            }
        }
    }
    orders
}

/// Main blades, splitters and the rest among `pieces` (largest first): pieces of one kind come
/// in sets of the symmetry's order with the same area (within 3 %). The largest such set are
/// the main blades, smaller sets of at least a tenth of their area splitters; the rest other.
fn piece_kinds(pieces: &[Piece], order: usize) -> Vec<PieceKind> {
    let mut kinds = vec![PieceKind::Other; pieces.len()];
    let largest = pieces.first().map_or(0.0, |p| p.area_mm2);
    let mut start = 0;
    let mut blades_found = false;
    while start < pieces.len() {
        let lead = pieces[start].area_mm2;
        let end = pieces[start..]
            .iter()
            .position(|p| p.area_mm2 < 0.97 * lead)
            .map_or(pieces.len(), |k| start + k);
        if (end - start) % order == 0 && lead >= 0.1 * largest {
            let kind = if blades_found {
                PieceKind::Splitter
            } else {
                PieceKind::Blade
            };
            blades_found = true;
            kinds[start..end].iter_mut().for_each(|k| *k = kind);
        } else if !blades_found {
            // The largest pieces are not a symmetric set: no blades to speak of.
            break;
        }
        start = end;
    }
    kinds
}

/// The non-hub triangles joined across shared edges into pieces, largest first (ties by their
/// first triangle), and each triangle's piece.
fn blade_pieces(mesh: &Mesh, is_hub: &[bool], frame: &AxisFrame) -> (Vec<Piece>, Vec<Option<u32>>) {
    use std::collections::HashMap;
    let n = mesh.triangles.len();
    let mut by_edge: HashMap<[u32; 2], Vec<usize>> = HashMap::new();
    for (t, tri) in mesh.triangles.iter().enumerate() {
        if is_hub[t] {
            continue;
        }
        for k in 0..3 {
            let (a, b) = (tri[k], tri[(k + 1) % 3]);
            by_edge.entry([a.min(b), a.max(b)]).or_default().push(t);
        }
    }
    let mut component = vec![usize::MAX; n];
    let mut groups: Vec<Vec<usize>> = Vec::new();
    for start in 0..n {
        if is_hub[start] || component[start] != usize::MAX {
            continue;
        }
        let id = groups.len();
        let mut members = vec![start];
        component[start] = id;
        let mut k = 0;
        while k < members.len() {
            let t = members[k];
            k += 1;
            let tri = mesh.triangles[t];
            for e in 0..3 {
                let (a, b) = (tri[e], tri[(e + 1) % 3]);
                for &u in &by_edge[&[a.min(b), a.max(b)]] {
                    if component[u] == usize::MAX {
                        component[u] = id;
                        members.push(u);
                    }
                }
            }
        }
        groups.push(members);
    }
    let mut pieces: Vec<(Piece, usize, Vec<usize>)> = groups
        .into_iter()
        .map(|members| {
            let mut area = 0.0;
            let mut weighted = Vector3::zeros();
            let mut radius = [f64::INFINITY, f64::NEG_INFINITY];
            let mut height = [f64::INFINITY, f64::NEG_INFINITY];
            for &t in &members {
                let corners = mesh.corners(t);
                let [a, b, c] = corners;
                let w = 0.5 * (b - a).cross(&(c - a)).norm();
                area += w;
                weighted += w * (a.coords + b.coords + c.coords) / 3.0;
                for p in &corners {
                    let (r, _, h) = frame.cylindrical(p);
                    radius = [radius[0].min(r), radius[1].max(r)];
                    height = [height[0].min(h), height[1].max(h)];
                }
            }
            let centre = Point3::from(weighted / area.max(1e-300));
            let (_, angle, _) = frame.cylindrical(&centre);
            let first = members[0];
            let piece = Piece {
                kind: PieceKind::Other,
                triangles: members.len(),
                area_mm2: area,
                angle_deg: angle.to_degrees(),
                radius_mm: radius,
                height_mm: height,
                root: None,
            };
            (piece, first, members)
        })
        .collect();
    pieces.sort_by(|a, b| b.0.area_mm2.total_cmp(&a.0.area_mm2).then(a.1.cmp(&b.1)));
    let mut piece_of = vec![None; n];
    for (k, (_, _, members)) in pieces.iter().enumerate() {
        for &t in members {
            piece_of[t] = Some(k as u32);
        }
    }
    (pieces.into_iter().map(|(p, _, _)| p).collect(), piece_of)
}

/// The largest radius of `points` (height, radius) in `bands` equal bands of height.
fn shroud_profile(points: &[(f64, f64)], bands: usize) -> Vec<[f64; 2]> {
    let (lo, hi) = points
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &(h, _)| {
            (lo.min(h), hi.max(h))
        });
    if hi.partial_cmp(&lo) != Some(std::cmp::Ordering::Greater) {
        return Vec::new();
    }
    let width = (hi - lo) / bands as f64;
    let mut top = vec![f64::NEG_INFINITY; bands];
    for &(h, r) in points {
        let k = (((h - lo) / width) as usize).min(bands - 1);
        top[k] = top[k].max(r);
    }
    top.iter()
        .enumerate()
        .filter(|(_, r)| r.is_finite())
        .map(|(k, &r)| [lo + (k as f64 + 0.5) * width, r])
        .collect()
}

/// The axis of `impeller` as a direction.
pub fn axis_of(impeller: &Impeller) -> Direction {
    Direction::new_normalize(Vector3::from(impeller.axis))
}

impl Impeller {
    /// Cylindrical coordinates about the impeller's axis.
    pub fn frame(&self) -> AxisFrame {
        AxisFrame::new(Point3::from(self.centre), &Vector3::from(self.axis))
    }

    /// The angle between neighbouring passages, radians.
    pub fn pitch(&self) -> f64 {
        std::f64::consts::TAU / self.order as f64
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::fixtures::{box_between, joined};

    /// A prism of `sides` faces about the z axis, radius `r`, from `z0` to `z1`, outward.
    fn prism(sides: usize, r: f64, z0: f64, z1: f64) -> Mesh {
        let mut positions = vec![Point3::new(0.0, 0.0, z0), Point3::new(0.0, 0.0, z1)];
        for k in 0..sides {
            let a = std::f64::consts::TAU * k as f64 / sides as f64;
            positions.push(Point3::new(r * a.cos(), r * a.sin(), z0));
            positions.push(Point3::new(r * a.cos(), r * a.sin(), z1));
        }
        let ring = |k: usize, top: usize| (2 + 2 * (k % sides) + top) as u32;
        let mut triangles = Vec::new();
        for k in 0..sides {
            triangles.push([0, ring(k + 1, 0), ring(k, 0)]);
            triangles.push([1, ring(k, 1), ring(k + 1, 1)]);
            triangles.push([ring(k, 0), ring(k + 1, 0), ring(k + 1, 1)]);
            triangles.push([ring(k, 0), ring(k + 1, 1), ring(k, 1)]);
        }
        Mesh {
            positions,
            triangles,
        }
    }

    /// A flat blade: radial from `r0` to `r1`, 2 mm thick, from z = 4 (inside the hub) to 15,
    /// turned by `angle` about z.
    fn blade(r0: f64, r1: f64, angle: f64) -> Mesh {
        let mut b = box_between(Point3::new(r0, -1.0, 4.0), Point3::new(r1, 1.0, 15.0));
        let turn = Rotation3::from_axis_angle(&Vector3::z_axis(), angle);
        for p in &mut b.positions {
            *p = turn * *p;
        }
        b
    }

    /// A hub (a 96-sided prism, r 20, 5 high) with six blades and six splitters between them,
    /// the whole turned off the vertical: order 6 about the turned axis, pointing to the
    /// blades; six main blades and six splitters; the hub's top, side and bottom are hub.
    #[test]
    fn a_hub_with_blades_and_splitters_is_recognised_about_a_tilted_axis() {
        let sixth = std::f64::consts::TAU / 6.0;
        let mut parts = vec![prism(96, 20.0, 0.0, 5.0)];
        for k in 0..6 {
            parts.push(blade(8.0, 30.0, k as f64 * sixth));
            parts.push(blade(18.0, 30.0, (k as f64 + 0.5) * sixth));
        }
        let mut mesh = joined(parts);
        let tilt = Rotation3::from_axis_angle(
            &nalgebra::Unit::new_normalize(Vector3::new(1.0, 2.0, 0.0)),
            0.4,
        );
        for p in &mut mesh.positions {
            *p = tilt * *p;
        }
        let found = recognise(&mesh, &RecogniseOptions::default()).expect("an impeller");
        assert_eq!(found.order, 6, "{found:?}");
        assert_eq!(
            (found.blades, found.splitters),
            (6, 6),
            "{:?}",
            found.pieces
        );
        let expected = tilt * Vector3::z();
        assert!(
            (Vector3::from(found.axis) - expected).norm() < 1e-9,
            "{:?}",
            found.axis
        );
        assert!(found.symmetry_max_mm < 1e-9, "{}", found.symmetry_max_mm);
        // The prism's 96 × 4 triangles are all hub; no blade triangle is.
        assert_eq!(found.hub_triangles, 96 * 4);
        assert!(found.regions[..96 * 4].iter().all(|r| *r == Region::Hub));
        assert!((found.hub_radius_mm[1] - 20.0).abs() < 1e-9);
        // The shroud: the blades reach r = 30 in every band.
        assert!(
            found.shroud.iter().all(|[_, r]| *r > 29.0),
            "{:?}",
            found.shroud
        );
    }

    /// Given an axis or an order, only those are tried: the six-fold part is also three-fold
    /// (a third of a turn maps it onto itself), not four-fold, and not about x.
    #[test]
    fn a_given_axis_or_order_is_checked_not_taken() {
        let sixth = std::f64::consts::TAU / 6.0;
        let mut parts = vec![prism(96, 20.0, 0.0, 5.0)];
        for k in 0..6 {
            parts.push(blade(8.0, 30.0, k as f64 * sixth));
        }
        let mesh = joined(parts);
        let given = |axis, order| RecogniseOptions {
            axis,
            order,
            ..RecogniseOptions::default()
        };
        let three = recognise(&mesh, &given(Some([0.0, 0.0, 2.0]), Some(3))).expect("3-fold");
        assert_eq!((three.order, three.blades), (3, 6));
        assert!(matches!(
            recognise(&mesh, &given(None, Some(4))),
            Err(NotAnImpeller::NoSymmetry { .. })
        ));
        assert!(matches!(
            recognise(&mesh, &given(Some([1.0, 0.0, 0.0]), None)),
            Err(NotAnImpeller::NoSymmetry { .. })
        ));
    }

    /// Not impellers: a body of revolution (no blades), a box (4-fold, but its sides are one
    /// piece, not blades), a part with no symmetry.
    #[test]
    fn bodies_without_blades_or_hub_or_symmetry_are_refused() {
        let options = RecogniseOptions::default();
        assert_eq!(
            recognise(&prism(96, 20.0, 0.0, 5.0), &options),
            Err(NotAnImpeller::NoBlades)
        );
        let block = box_between(Point3::new(-10.0, -10.0, 0.0), Point3::new(10.0, 10.0, 6.0));
        // Its top and bottom are planar (of revolution about z), its sides one piece.
        let refused = recognise(&block, &options);
        assert!(
            matches!(
                refused,
                Err(NotAnImpeller::NotInBlades {
                    order: 4,
                    blades: 0
                })
            ),
            "{refused:?}"
        );
        let odd = box_between(Point3::new(0.0, 0.0, 0.0), Point3::new(10.0, 7.0, 3.0));
        let lopsided = joined([
            odd,
            box_between(Point3::new(10.0, 0.0, 0.0), Point3::new(13.0, 2.0, 9.0)),
        ]);
        assert!(matches!(
            recognise(&lopsided, &options),
            Err(NotAnImpeller::NoSymmetry { .. })
        ));
    }
}
