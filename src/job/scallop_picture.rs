//! `scallop.glb` and `scallop.png`: the part coloured by what the finishing moves leave on it
//! ([`crate::verify::measure_scallop_map`]), so a user sees at once where the passes leave
//! more than the scallop target and why: green within the target, yellow over it (up to five
//! times), red beyond, blue where the part is concave more tightly than the ball (no ball can
//! leave the target there), purple where no tool axis reaches (over the target), dark grey
//! where no pass comes near, light grey the face on the table. A triangle of the part large enough for several samples is split as it was sampled,
//! so a coarse mesh's long triangles show where along them the passes fall short.

use crate::error::{Error, Result};
use crate::mesh::Mesh;
use crate::verify::{SampleScallop, ScallopPatch};

use super::render;

const WITHIN: [f32; 4] = [0.25, 0.7, 0.3, 1.0];
const OVER: [f32; 4] = [0.95, 0.8, 0.15, 1.0];
const FAR_OVER: [f32; 4] = [0.85, 0.15, 0.1, 1.0];
const NARROW: [f32; 4] = [0.25, 0.45, 0.9, 1.0];
const NOT_REACHED: [f32; 4] = [0.3, 0.3, 0.33, 1.0];
const BLOCKED: [f32; 4] = [0.55, 0.25, 0.7, 1.0];
const TABLE: [f32; 4] = [0.82, 0.82, 0.82, 1.0];

/// Over the target by more than this factor is red.
const FAR_OVER_FACTOR: f64 = 5.0;

/// The colour of a triangle the measure found `found` on, against the scallop `target`.
pub fn scallop_colour(found: SampleScallop, target: f64) -> [f32; 4] {
    match found {
        SampleScallop::Table => TABLE,
        SampleScallop::Within(_) => WITHIN,
        SampleScallop::Over(h) if h > FAR_OVER_FACTOR * target => FAR_OVER,
        SampleScallop::Over(_) => OVER,
        SampleScallop::Narrow => NARROW,
        SampleScallop::NotReached => NOT_REACHED,
        SampleScallop::Blocked(_) => BLOCKED,
    }
}

/// What the colours mean, for the report.
pub fn scallop_legend(target: f64) -> Vec<String> {
    let far = FAR_OVER_FACTOR * target;
    vec![
        format!("green: scallop within the {target} mm target"),
        format!("yellow: over the target, up to {far} mm"),
        format!("red: over {far} mm"),
        "blue: concave more tightly than the ball (no ball leaves the target there)".into(),
        "purple: over the target where no tool axis the machine allows reaches".into(),
        "dark grey: no pass comes near".into(),
        "light grey: the face on the table".into(),
    ]
}

/// `scallop.glb` and `scallop.png` of the part the measure covered with `patches`.
pub fn scallop_pictures(patches: &[ScallopPatch], target: f64) -> Result<Vec<(String, Vec<u8>)>> {
    // For the picture every patch has its own corners, so that its colour stays its own.
    let surface = Mesh {
        positions: patches.iter().flat_map(|p| p.corners).collect(),
        triangles: (0..patches.len() as u32)
            .map(|k| [3 * k, 3 * k + 1, 3 * k + 2])
            .collect(),
    };
    let colours: Vec<[f32; 4]> = patches
        .iter()
        .flat_map(|p| [scallop_colour(p.found, target); 3])
        .collect();
    // The GLB: one node per colour, its corners shared where its patches meet.
    let mut glb = crate::mesh::io::GlbBuilder::new();
    for (name, colour) in [
        ("within target", WITHIN),
        ("over target", OVER),
        ("far over target", FAR_OVER),
        ("narrow", NARROW),
        ("not reached", NOT_REACHED),
        ("blocked", BLOCKED),
        ("table", TABLE),
    ] {
        let of_colour = patches
            .iter()
            .filter(|p| scallop_colour(p.found, target) == colour);
        glb.add_triangles(name, &welded(of_colour), colour, None)
            .map_err(|error| Error::Glb {
                file: "scallop.glb".into(),
                error,
            })?;
    }

    let mut canvas = render::two_views(&surface, &colours);
    let far = FAR_OVER_FACTOR * target;
    render::legend(
        &mut canvas,
        10,
        render::PANEL + 12,
        &[
            (WITHIN, format!("0-{target}mm")),
            (OVER, format!("{target}-{far}mm")),
            (FAR_OVER, format!(">{far}mm")),
            (NARROW, "narrow".into()),
            (BLOCKED, "blocked".into()),
            (NOT_REACHED, "unreached".into()),
        ],
    );
    let png = canvas
        .png()
        .map_err(|e| Error::Internal(format!("scallop.png: {e}")))?;
    Ok(vec![
        ("scallop.glb".into(), glb.build()),
        ("scallop.png".into(), png),
    ])
}

/// `patches` as one mesh, corners with the same coordinates shared.
fn welded<'a>(patches: impl Iterator<Item = &'a ScallopPatch>) -> Mesh {
    let mut index: std::collections::HashMap<[u64; 3], u32> = Default::default();
    let mut mesh = Mesh {
        positions: Vec::new(),
        triangles: Vec::new(),
    };
    for patch in patches {
        let corners = patch.corners.map(|p| {
            let key = [p.x, p.y, p.z].map(f64::to_bits);
            *index.entry(key).or_insert_with(|| {
                mesh.positions.push(p);
                (mesh.positions.len() - 1) as u32
            })
        });
        mesh.triangles.push(corners);
    }
    mesh
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::fixtures::cuboid;

    /// Every kind has its colour; the GLB holds every patch (one node per colour, corners
    /// shared where patches meet) and the PNG is made.
    #[test]
    fn each_patch_is_coloured_by_what_was_found_on_it() {
        let part = cuboid(10.0, 10.0, 5.0);
        let kinds = [
            SampleScallop::Within(0.004),
            SampleScallop::Over(0.02),
            SampleScallop::Over(0.2),
            SampleScallop::Narrow,
            SampleScallop::NotReached,
            SampleScallop::Table,
            SampleScallop::Blocked(0.5),
        ];
        let colours: Vec<[f32; 4]> = kinds.iter().map(|f| scallop_colour(*f, 0.01)).collect();
        assert_eq!(
            colours,
            [WITHIN, OVER, FAR_OVER, NARROW, NOT_REACHED, TABLE, BLOCKED]
        );
        let patches: Vec<ScallopPatch> = (0..part.triangles.len())
            .map(|t| ScallopPatch {
                corners: part.corners(t),
                found: kinds[t % kinds.len()],
            })
            .collect();
        let files = scallop_pictures(&patches, 0.01).expect("pictures");
        let names: Vec<&str> = files.iter().map(|(n, _)| n.as_str()).collect();
        assert_eq!(names, ["scallop.glb", "scallop.png"]);
        assert!(files[1].1.starts_with(b"\x89PNG"));
        let read = crate::mesh::io::read_mesh_bytes(
            &files[0].1,
            crate::mesh::io::Format::Glb,
            "scallop.glb",
            None,
            crate::mesh::io::Units::Millimetres,
        )
        .expect("a GLB");
        assert_eq!(read.mesh.triangles.len(), part.triangles.len());
        // Welded per colour: two triangles of a colour share no more corners than the cube's
        // eight in all.
        let welded = welded(patches.iter());
        assert_eq!(welded.positions.len(), 8);
        for (t, patch) in patches.iter().enumerate() {
            assert_eq!(welded.corners(t), patch.corners);
        }
    }
}
