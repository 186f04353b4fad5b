//! The recognised impeller as a coloured GLB: the hub grey, each main blade and splitter in a
//! colour of its own (splitters paler), other pieces dark.

use super::{Impeller, Region};
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
pub fn impeller_glb(mesh: &Mesh, impeller: &Impeller) -> Result<Vec<u8>, GlbError> {
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
        let piece_mesh = subset(
            &|r| matches!(r, Region::Blade(i) | Region::Splitter(i) | Region::Other(i) if i == k),
        );
        glb.add_triangles(&name, &piece_mesh, colour, None)?;
    }
    Ok(glb.build())
}
