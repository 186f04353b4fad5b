//! The recognised impeller as a coloured GLB: the hub grey, each main blade and splitter in a
//! colour of its own (splitters paler), its fillet to the hub (the triangles within one and a
//! half fillet radii of the root, where the fillet turns into the flank) darker, its leading
//! edge redder and its trailing edge bluer, other pieces dark.

use super::edges::{BladeEdges, EdgeSide};
use super::root::root_edges;
use super::{Impeller, Region};
use crate::geom::{Point3, closest_point_on_segment};
use crate::mesh::Mesh;
use crate::mesh::io::{GlbBuilder, GlbError};

/// Blade colours, cycled (linear RGBA).
const PALETTE: [[f32; 4]; 6] = [
    [0.85, 0.25, 0.2, 1.0],
    [0.95, 0.6, 0.1, 1.0],
    [0.2, 0.65, 0.3, 1.0],
    [0.2, 0.45, 0.85, 1.0],
    [0.6, 0.3, 0.8, 1.0],
    [0.1, 0.7, 0.75, 1.0],
];

/// `mesh` (the one `impeller` was recognised in) coloured by region, one node per region.
pub fn impeller_glb(
    mesh: &Mesh,
    impeller: &Impeller,
    edges: Option<&BladeEdges>,
) -> Result<Vec<u8>, GlbError> {
    let mut glb = GlbBuilder::new();
    // Each region with only the vertices it uses.
    let subset = |keep: &dyn Fn(Region) -> bool| {
        Mesh::compacted(
            &mesh.positions,
            mesh.triangles
                .iter()
                .zip(&impeller.regions)
                .filter(|(_, r)| keep(**r))
                .map(|(t, _)| *t),
        )
    };
    glb.add_triangles(
        "hub",
        &subset(&|r| r == Region::Hub),
        [0.6, 0.6, 0.62, 1.0],
        None,
    )?;
    let piece_of: Vec<Option<u32>> = impeller
        .regions
        .iter()
        .map(|r| match *r {
            Region::Hub => None,
            Region::Blade(k) | Region::Splitter(k) | Region::Other(k) => Some(k),
        })
        .collect();
    let roots = root_edges(mesh, &piece_of, impeller.pieces.len());
    let (mut blade, mut splitter) = (0, 0);
    for (k, piece) in impeller.pieces.iter().enumerate() {
        let k = k as u32;
        let (name, colour) = match piece.kind {
            super::PieceKind::Blade => {
                blade += 1;
                (
                    format!("blade {blade}"),
                    PALETTE[(blade - 1) % PALETTE.len()],
                )
            }
            super::PieceKind::Splitter => {
                splitter += 1;
                let [r, g, b, a] = PALETTE[(splitter - 1) % PALETTE.len()];
                (
                    format!("splitter {splitter}"),
                    [0.5 + 0.5 * r, 0.5 + 0.5 * g, 0.5 + 0.5 * b, a],
                )
            }
            super::PieceKind::Other => (format!("other {k}"), [0.25, 0.25, 0.28, 1.0]),
        };
        let in_piece = |r: Region| matches!(r, Region::Blade(i) | Region::Splitter(i) | Region::Other(i) if i == k);
        // Each triangle of the piece: 0 flank, 1 fillet, 2 leading and 3 trailing edge.
        let fillet = piece.root.as_ref().map_or(0.0, |r| r.fillet_radius_mm);
        let root = &roots[k as usize];
        let part_of: Vec<Option<usize>> = (0..mesh.triangles.len())
            .map(|t| {
                if !in_piece(impeller.regions[t]) {
                    return None;
                }
                let [a, b, c] = mesh.corners(t);
                let centre = Point3::from((a.coords + b.coords + c.coords) / 3.0);
                let in_fillet = fillet > 0.0
                    && root.iter().any(|e| {
                        let [p, q] = e.ends;
                        (closest_point_on_segment(&centre, &p, &q) - centre).norm() <= 1.5 * fillet
                    });
                Some(match edges.and_then(|e| e.sides[t]) {
                    _ if in_fillet => 1,
                    Some(EdgeSide::Leading) => 2,
                    Some(EdgeSide::Trailing) => 3,
                    None => 0,
                })
            })
            .collect();
        let [r, g, b, a] = colour;
        let shades = [
            (String::new(), colour),
            (" fillet".to_string(), [0.6 * r, 0.6 * g, 0.6 * b, a]),
            (
                " leading edge".to_string(),
                [0.5 + 0.5 * r, 0.5 * g, 0.5 * b, a],
            ),
            (
                " trailing edge".to_string(),
                [0.5 * r, 0.5 * g, 0.5 + 0.5 * b, a],
            ),
        ];
        for (kind, (suffix, shade)) in shades.iter().enumerate() {
            let triangles: Vec<[u32; 3]> = (0..mesh.triangles.len())
                .filter(|&t| part_of[t] == Some(kind))
                .map(|t| mesh.triangles[t])
                .collect();
            if kind == 0 || !triangles.is_empty() {
                let part = Mesh::compacted(&mesh.positions, triangles);
                glb.add_triangles(&format!("{name}{suffix}"), &part, *shade, None)?;
            }
        }
    }
    Ok(glb.build())
}
