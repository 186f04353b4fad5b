//! A blade's root (issue 21 item 1, fillets): where the blade or splitter meets the hub, how
//! sharply, and the fillet there, measured as a machinist needs it: the largest ball that
//! finishes the corner.
//!
//! A ball touching the root from along the bisector of hub and blade stays clear of the part
//! while it is no larger than the fillet's radius; larger, it cuts into the blade or the hub
//! beyond the fillet. At samples along the root (the midpoints of the edges the piece shares
//! with the hub, 2 mm apart) the largest clear ball is found by bisection; at a sharp root (a
//! crease) none is, to the bisection's resolution. A faceted fillet's vertices are concave:
//! a ball touching one dips into the facets beside it, which a small allowance (`CLEAR`) lets pass.

use std::collections::HashSet;

use serde::Serialize;

use crate::geom::{Point3, Vector3, bisect};
use crate::mesh::Mesh;
use crate::mesh::distance::SurfaceDistance;
use crate::mesh::topology::edges;

/// Distance between the samples along a root, mm.
const SAMPLE_SPACING: f64 = 2.0;

/// Bisection steps for the corner's ball: the largest tried over 2¹² is the resolution.
const BISECTIONS: usize = 12;

/// A ball counts as clear of the part where nothing comes nearer its centre than its radius
/// less this share of it. A ball touching a faceted fillet at a vertex dips into the facets
/// beside it by (θ/2)²/2 of its radius for facets θ apart: this lets facets up to 11° apart
/// pass (a sharp right-angled root dips 29 %) and overstates a fillet by about 2 %.
const CLEAR: f64 = 0.005;

/// Where a blade or splitter meets the hub.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct RootCorner {
    /// Length of the edges the piece shares with the hub, mm.
    pub length_mm: f64,
    /// How far the surface turns from the hub into the piece at those edges ([`RootEdge`]),
    /// degrees, median over the samples: the corner's full angle at a sharp root, small where
    /// a fillet carries the hub into the blade.
    pub crease_deg: f64,
    /// The largest ball that finishes the corner (the fillet's radius) at the samples, mm:
    /// the median and the smallest. 0 at a sharp root, at most the largest ball tried.
    pub fillet_radius_mm: f64,
    pub fillet_radius_min_mm: f64,
    pub samples: usize,
}

/// One edge a piece shares with the hub.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RootEdge {
    pub ends: [Point3; 2],
    pub hub_normal: Vector3,
    pub piece_normal: Vector3,
    /// The largest angle between the hub triangle's normal and the normals of the piece's
    /// triangles round either end, degrees: a sliver lying in the hub's plane at the blade's
    /// foot does not hide the flank standing beside it.
    pub crease_deg: f64,
}

impl RootEdge {
    pub fn midpoint(&self) -> Point3 {
        Point3::from((self.ends[0].coords + self.ends[1].coords) * 0.5)
    }

    pub fn length(&self) -> f64 {
        (self.ends[1] - self.ends[0]).norm()
    }
}

/// The edges each of `pieces` pieces (`piece_of` by triangle, `None` the hub) shares with the
/// hub, in the mesh's edge order.
pub fn root_edges(mesh: &Mesh, piece_of: &[Option<u32>], pieces: usize) -> Vec<Vec<RootEdge>> {
    let mut around: Vec<Vec<u32>> = vec![Vec::new(); mesh.positions.len()];
    for (t, tri) in mesh.triangles.iter().enumerate() {
        if piece_of[t].is_some() {
            for &v in tri {
                around[v as usize].push(t as u32);
            }
        }
    }
    let mut by_piece: Vec<Vec<RootEdge>> = vec![Vec::new(); pieces];
    for edge in edges(&mesh.triangles) {
        let [(f, _), (g, _)] = edge.faces[..] else {
            continue;
        };
        let (hub, blade, k) = match (piece_of[f as usize], piece_of[g as usize]) {
            (None, Some(k)) => (f, g, k),
            (Some(k), None) => (g, f, k),
            _ => continue,
        };
        let hub_normal = mesh.face_normal(hub as usize);
        let crease = edge
            .vertices
            .iter()
            .flat_map(|&v| &around[v as usize])
            .filter(|&&t| piece_of[t as usize] == Some(k))
            .map(|&t| hub_normal.angle(&mesh.face_normal(t as usize)).to_degrees())
            .fold(0.0, f64::max);
        by_piece[k as usize].push(RootEdge {
            ends: edge.vertices.map(|v| mesh.positions[v as usize]),
            hub_normal,
            piece_normal: mesh.face_normal(blade as usize),
            crease_deg: crease,
        });
    }
    by_piece
}

/// The root corner of each piece `piece_of` names (by triangle; `None` is hub), for the
/// pieces `wanted` says; balls up to `max_radius` are tried.
pub fn root_corners(
    mesh: &Mesh,
    surface: &SurfaceDistance,
    piece_of: &[Option<u32>],
    pieces: usize,
    wanted: impl Fn(usize) -> bool,
    max_radius: f64,
) -> Vec<Option<RootCorner>> {
    root_edges(mesh, piece_of, pieces)
        .iter()
        .enumerate()
        .map(|(k, root)| {
            if root.is_empty() || !wanted(k) {
                return None;
            }
            let length: f64 = root.iter().map(RootEdge::length).sum();
            // Samples at least the spacing apart (the first edge in each cell of a grid).
            let mut taken = HashSet::new();
            let samples: Vec<(f64, f64)> = root
                .iter()
                .filter(|e| {
                    let m = e.midpoint();
                    taken.insert(m.coords.map(|v| (v / SAMPLE_SPACING).floor() as i64))
                })
                .filter_map(|e| {
                    let bisector = (e.hub_normal + e.piece_normal).try_normalize(1e-9)?;
                    let ball = corner_ball(surface, &e.midpoint(), &bisector, max_radius);
                    Some((e.crease_deg, ball))
                })
                .collect();
            let median = |mut v: Vec<f64>| {
                v.sort_by(f64::total_cmp);
                v.get(v.len() / 2).copied().unwrap_or(0.0)
            };
            let radii: Vec<f64> = samples.iter().map(|s| s.1).collect();
            Some(RootCorner {
                length_mm: length,
                crease_deg: median(samples.iter().map(|s| s.0).collect()),
                fillet_radius_mm: median(radii.clone()),
                fillet_radius_min_mm: radii.iter().copied().reduce(f64::min).unwrap_or(0.0),
                samples: samples.len(),
            })
        })
        .collect()
}

/// The largest ball, up to `max_radius`, that touches the part at `point` from along
/// `bisector` (its centre `radius` out along it) and comes no nearer to it anywhere else
/// (0 when none does at the bisection's resolution).
pub fn corner_ball(
    surface: &SurfaceDistance,
    point: &Point3,
    bisector: &Vector3,
    max_radius: f64,
) -> f64 {
    let fits = |radius: f64| {
        let centre = point + bisector * radius;
        !surface.any_within(&centre, radius * (1.0 - CLEAR))
    };
    if fits(max_radius) {
        return max_radius;
    }
    bisect(max_radius, 0.0, BISECTIONS, fits)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An L-shaped bar along y (0 to 20): a floor z = 0 for x < 0, a wall x = 0 rising to
    /// z = 10, and between them a fillet of `radius` (0: sharp), as `arc` facets.
    fn filleted_corner(radius: f64, arc: usize) -> Mesh {
        // The profile in (x, z), counter-clockwise seen from +y... as a closed polygon.
        let mut profile = vec![(2.0, -2.0), (2.0, 10.0), (0.0, 10.0)];
        if radius > 0.0 {
            for k in 0..=arc {
                let angle = std::f64::consts::FRAC_PI_2 * k as f64 / arc as f64;
                // From the wall's foot (0, radius) round to the floor's end (-radius, 0).
                profile.push((
                    -radius + radius * angle.cos(),
                    radius - radius * angle.sin(),
                ));
            }
        } else {
            profile.push((0.0, 0.0));
        }
        profile.push((-10.0, 0.0));
        profile.push((-10.0, -2.0));
        let n = profile.len() as u32;
        let mut positions = Vec::new();
        for y in [0.0, 20.0] {
            positions.extend(profile.iter().map(|&(x, z)| Point3::new(x, y, z)));
        }
        let mut triangles = Vec::new();
        for i in 0..n {
            let j = (i + 1) % n;
            triangles.push([i, j, n + j]);
            triangles.push([i, n + j, n + i]);
        }
        // Caps: fans from the convex corner (2, -2), which sees every other vertex.
        for i in 1..n - 1 {
            triangles.push([0, i + 1, i]);
            triangles.push([n, n + i, n + i + 1]);
        }
        let mut mesh = Mesh {
            positions,
            triangles,
        };
        // Outward whichever way the profile ran.
        if mesh.signed_volume() < 0.0 {
            for t in &mut mesh.triangles {
                t.swap(1, 2);
            }
        }
        mesh
    }

    #[test]
    fn the_corner_ball_is_the_fillet_radius_and_nothing_at_a_sharp_root() {
        let bisector = Vector3::new(-1.0, 0.0, 1.0).normalize();
        for (radius, arc) in [(3.0, 48), (1.0, 24)] {
            let mesh = filleted_corner(radius, arc);
            let surface = SurfaceDistance::new(&mesh);
            // Touched half-way round the fillet (a vertex of its facets) along its normal,
            // and where it starts on the floor.
            let half_way = Point3::new(
                -radius * (1.0 - 0.5f64.sqrt()),
                10.0,
                radius * (1.0 - 0.5f64.sqrt()),
            );
            for (point, normal) in [
                (half_way, bisector),
                (Point3::new(-radius, 10.0, 0.0), Vector3::z()),
            ] {
                let found = corner_ball(&surface, &point, &normal, 8.0);
                assert!(
                    (found - radius).abs() < 0.03 * radius,
                    "fillet {radius} at {point:?}: found {found}"
                );
            }
        }
        let sharp = filleted_corner(0.0, 0);
        let surface = SurfaceDistance::new(&sharp);
        let found = corner_ball(&surface, &Point3::new(0.0, 10.0, 0.0), &bisector, 8.0);
        assert!(found < 8.0 / 4000.0, "sharp: {found}");
    }

    /// The bar's faces as pieces: the fillet and the wall piece 0, the floor's top the hub,
    /// the rest piece 1.
    fn corner_pieces(mesh: &Mesh, arc: usize) -> Vec<Option<u32>> {
        let sides = 2 * (arc + 6);
        (0..mesh.triangles.len())
            .map(|t| match t / 2 {
                i if t < sides && (2..3 + arc).contains(&i) => Some(0),
                i if t < sides && i == 3 + arc => None,
                _ => Some(1),
            })
            .collect()
    }

    #[test]
    fn root_corners_measure_the_fillet_and_the_crease() {
        // The first facet of the fillet turns half a facet's angle off the floor tangent to it.
        for (radius, arc, crease) in [(3.0, 48, 90.0 / 96.0), (0.0, 0, 90.0)] {
            let mesh = filleted_corner(radius, arc);
            let surface = SurfaceDistance::new(&mesh);
            let pieces = corner_pieces(&mesh, arc);
            let roots = root_corners(&mesh, &surface, &pieces, 2, |k| k == 0, 8.0);
            let root = roots[0].as_ref().expect("piece 0 stands on the hub");
            assert!(roots[1].is_none());
            assert!((root.length_mm - 20.0).abs() < 1e-9, "{root:?}");
            assert!((root.crease_deg - crease).abs() < 1e-6, "{root:?}");
            assert!(
                (root.fillet_radius_mm - radius).abs() < 0.03 * radius.max(0.1),
                "{root:?}"
            );
            assert_eq!(root.samples, 1);
        }
    }
}
