//! The connected pieces of a part, and which of them are stray debris (issue 17 item 8).
//!
//! CAD exports and mesh repairs leave debris: a lone triangle far away, a sliver shell, a
//! fragment of a fillet. Planning a part with debris either refuses it (one stray triangle
//! makes it open) or sizes everything from a bounding box the debris stretches. So the
//! pieces (faces joined across shared edges) are listed, and a piece is **stray** when its
//! surface area is below [`StrayPieceRule::max_area_fraction`] (default 0.1 %) of the largest
//! piece's area.
//!
//! Why area: it is what gets machined, it does not depend on how finely a piece is meshed (a
//! triangle count does), and unlike volume it is defined for open pieces, which debris usually
//! is. Why 0.1 %: on a 100 mm impeller (about 30,000 mm²) that is 30 mm², a 2 mm cube; a real
//! second body (a wall, a boss, a second blade, a clamp) is far larger and stays, so planning
//! then refuses or plans it as it would have. Nothing is dropped silently: every piece set
//! aside is reported with its triangles, area and bounding box.

use serde::Serialize;

use super::Mesh;
use super::topology::{Topology, closed_components};
use crate::geom::{Aabb, triangle_area};

/// When a piece counts as stray. Plain data, with a documented default.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StrayPieceRule {
    /// A piece whose area is below this fraction of the largest piece's area is stray.
    /// Default 1e-3 (0.1 %). 0 makes nothing stray.
    pub max_area_fraction: f64,
}

impl Default for StrayPieceRule {
    fn default() -> Self {
        Self {
            max_area_fraction: 1e-3,
        }
    }
}

impl StrayPieceRule {
    pub fn with_max_area_fraction(self, max_area_fraction: f64) -> Self {
        Self { max_area_fraction }
    }

    fn is_stray(&self, area: f64, largest: f64) -> bool {
        area < self.max_area_fraction * largest
    }
}

/// One connected piece of a mesh (faces joined across shared edges).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Piece {
    pub triangles: usize,
    /// mm².
    pub area: f64,
    pub bounding_box_min: [f64; 3],
    pub bounding_box_max: [f64; 3],
    /// Every edge has two faces wound consistently (a closed shell).
    pub closed: bool,
    /// Tiny against the largest piece by the [`StrayPieceRule`] in force.
    pub stray: bool,
}

/// A mesh separated into its main part and its stray pieces.
#[derive(Clone, Debug)]
pub struct PieceSplit {
    /// The mesh without its stray pieces: faces and vertices in their original order.
    pub main: Mesh,
    /// The pieces kept, largest area first.
    pub kept: Vec<Piece>,
    /// The pieces left out, largest area first.
    pub stray: Vec<Piece>,
}

/// The pieces of `mesh` given its connectivity, largest area first (ties: the piece with the
/// lowest face first), each marked stray or not by `rule`; and the piece of every face as an
/// index into that list.
pub(crate) fn pieces_of(
    mesh: &Mesh,
    topo: &Topology,
    rule: &StrayPieceRule,
) -> (Vec<Piece>, Vec<u32>) {
    let n = topo.component_count;
    let closed = closed_components(&mesh.triangles, topo);
    let mut triangles = vec![0usize; n];
    let mut area = vec![0.0f64; n];
    let mut boxes = vec![Aabb::empty(); n];
    for (t, &c) in topo.face_component.iter().enumerate() {
        let c = c as usize;
        let corners = mesh.corners(t);
        triangles[c] += 1;
        area[c] += triangle_area(&corners[0], &corners[1], &corners[2]);
        for p in &corners {
            boxes[c].grow(p);
        }
    }
    // Components are numbered by their lowest face, so a stable sort breaks ties by it.
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&a, &b| area[b].total_cmp(&area[a]));
    let largest = order.first().map_or(0.0, |&c| area[c]);
    let mut rank = vec![0u32; n];
    let pieces = order
        .iter()
        .enumerate()
        .map(|(r, &c)| {
            rank[c] = r as u32;
            let bx = &boxes[c];
            Piece {
                triangles: triangles[c],
                area: area[c],
                bounding_box_min: bx.min.coords.into(),
                bounding_box_max: bx.max.coords.into(),
                closed: closed[c],
                stray: rule.is_stray(area[c], largest),
            }
        })
        .collect();
    let face_piece = topo
        .face_component
        .iter()
        .map(|&c| rank[c as usize])
        .collect();
    (pieces, face_piece)
}

/// Separates `mesh` into its main part and its stray pieces by `rule`. Positions are never
/// looked at except for the areas and boxes; connectivity decides what a piece is.
pub fn split_stray_pieces(mesh: &Mesh, rule: &StrayPieceRule) -> PieceSplit {
    let topo = Topology::analyse(&mesh.triangles, mesh.positions.len());
    let (pieces, face_piece) = pieces_of(mesh, &topo, rule);
    let kept_faces: Vec<&[u32; 3]> = mesh
        .triangles
        .iter()
        .zip(&face_piece)
        .filter(|&(_, &p)| !pieces[p as usize].stray)
        .map(|(t, _)| t)
        .collect();
    // Vertices keep their relative order, so a mesh without stray pieces comes back equal.
    let mut used = vec![false; mesh.positions.len()];
    for t in &kept_faces {
        for &v in t.iter() {
            used[v as usize] = true;
        }
    }
    let mut new_index = vec![u32::MAX; mesh.positions.len()];
    let mut main = Mesh::default();
    for (v, p) in mesh.positions.iter().enumerate() {
        if used[v] {
            new_index[v] = main.positions.len() as u32;
            main.positions.push(*p);
        }
    }
    main.triangles = kept_faces
        .iter()
        .map(|t| t.map(|v| new_index[v as usize]))
        .collect();
    let (stray, kept) = pieces.into_iter().partition(|p| p.stray);
    PieceSplit { main, kept, stray }
}

/// One line for a report's warnings about pieces set aside (`None` if there are none): how
/// many, how much, and where the largest of them is, so that a user can find it in CAD.
pub fn set_aside_warning(stray: &[Piece]) -> Option<String> {
    Some(format!(
        "{} set aside, tiny against the largest piece{}",
        count_stray(stray.len()),
        describe_stray(stray)?
    ))
}

/// "1 stray piece", "2 stray pieces".
pub(crate) fn count_stray(n: usize) -> String {
    format!("{n} stray piece{}", if n == 1 { "" } else { "s" })
}

/// " (N triangles, A mm² in all; the largest, a mm², lies in [..] .. [..] mm)" for pieces
/// listed largest first; `None` for none.
pub(crate) fn describe_stray(stray: &[Piece]) -> Option<String> {
    let largest = stray.first()?;
    let triangles: usize = stray.iter().map(|p| p.triangles).sum();
    let area: f64 = stray.iter().map(|p| p.area).sum();
    let [x0, y0, z0] = largest.bounding_box_min;
    let [x1, y1, z1] = largest.bounding_box_max;
    Some(format!(
        " ({triangles} triangles, {area:.4} mm² in all; the largest, {:.4} mm², lies in \
         [{x0:.4}, {y0:.4}, {z0:.4}] .. [{x1:.4}, {y1:.4}, {z1:.4}] mm)",
        largest.area
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::Point3;
    use crate::mesh::fixtures::{cuboid, plate_and_wall};

    /// A 10 mm cube plus one 1 mm triangle a kilometre away.
    fn cube_and_far_triangle() -> Mesh {
        let mut m = cuboid(10.0, 10.0, 10.0);
        let base = m.positions.len() as u32;
        m.positions.extend([
            Point3::new(1e6, 0.0, 0.0),
            Point3::new(1e6 + 1.0, 0.0, 0.0),
            Point3::new(1e6, 1.0, 0.0),
        ]);
        m.triangles.push([base, base + 1, base + 2]);
        m
    }

    #[test]
    fn far_tiny_triangle_is_stray_and_the_cube_is_kept_whole() {
        let m = cube_and_far_triangle();
        let split = split_stray_pieces(&m, &StrayPieceRule::default());
        assert_eq!(split.main, cuboid(10.0, 10.0, 10.0));
        assert_eq!(split.kept.len(), 1);
        assert!(split.kept[0].closed && !split.kept[0].stray);
        assert_eq!(split.kept[0].triangles, 12);
        assert!((split.kept[0].area - 600.0).abs() < 1e-9);
        assert_eq!(split.stray.len(), 1);
        let s = &split.stray[0];
        assert_eq!(s.triangles, 1);
        assert!((s.area - 0.5).abs() < 1e-9);
        assert!(!s.closed && s.stray);
        assert_eq!(s.bounding_box_min, [1e6, 0.0, 0.0]);
        assert_eq!(s.bounding_box_max, [1e6 + 1.0, 1.0, 0.0]);
        let w = set_aside_warning(&split.stray).unwrap();
        assert!(
            w.contains("1 stray piece set aside") && w.contains("1000000.0000"),
            "{w}"
        );
        assert_eq!(set_aside_warning(&[]), None);
    }

    #[test]
    fn a_big_second_body_is_not_stray() {
        // A 100 × 100 × 5 plate and a 10 × 100 × 60 wall beside it: two real bodies.
        let m = plate_and_wall(5.0, 200.0);
        let split = split_stray_pieces(&m, &StrayPieceRule::default());
        assert!(split.stray.is_empty());
        assert_eq!(split.kept.len(), 2);
        assert_eq!(split.main, m);
        // Even a small but real body (a 3 mm cube beside a 100 mm plate, 0.25 % of its
        // area) stays.
        let mut m = cuboid(100.0, 100.0, 10.0);
        let cube = cuboid(3.0, 3.0, 3.0);
        let base = m.positions.len() as u32;
        m.positions.extend(
            cube.positions
                .iter()
                .map(|p| p + crate::geom::Vector3::x() * 150.0),
        );
        m.triangles
            .extend(cube.triangles.iter().map(|t| t.map(|i| i + base)));
        let split = split_stray_pieces(&m, &StrayPieceRule::default());
        assert!(split.stray.is_empty(), "{:?}", split.stray);
        // A rule of 0 makes nothing stray, even the far triangle.
        let split = split_stray_pieces(
            &cube_and_far_triangle(),
            &StrayPieceRule::default().with_max_area_fraction(0.0),
        );
        assert!(split.stray.is_empty());
    }

    #[test]
    fn pieces_are_listed_largest_first_whatever_the_face_order() {
        let mut m = cube_and_far_triangle();
        // Put the triangle first: the order of pieces must not change.
        let last = m.triangles.pop().unwrap();
        m.triangles.insert(0, last);
        let split = split_stray_pieces(&m, &StrayPieceRule::default());
        assert_eq!(split.kept[0].triangles, 12);
        assert_eq!(split.stray[0].triangles, 1);
        assert_eq!(split.main.triangles.len(), 12);
        assert!((split.main.signed_volume() - 1000.0).abs() < 1e-9);
    }
}
