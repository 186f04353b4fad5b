//! IGES files (5.3, fixed ASCII form) into faces of exact geometry: the raw layer
//! ([`cards`]: 80-column cards, the Global section with its own delimiters, Hollerith strings,
//! directory entries, parameter records as tokens that keep their line) and the typed layer
//! ([`entities`]: 100, 102, 110, 120, 124, 126, 128, 142, 144 in millimetres). Seed 003 ch. 3
//! reads entities 126 and 128 from CAD exports the same way; its parameter counts take K as the
//! number of control points where the standard's K is the last index (K + 1 points), and this
//! reader follows the standard (every 126 and 128 of the test impeller checks out exactly).
//!
//! Faces are the independent trimmed surfaces (144) and the independent surfaces no trimmed
//! surface uses; the status number's blank flag is not a filter (CAD exports blank every
//! surface a 144 references). Other independent entities are listed as skipped. A malformed
//! file is an error naming the line, the entity and the parameter, never a panic.
//!
//! No Rust crate served (measured in the issue 23 note): the ones that read IGES either return
//! sewn solids only, read planes only, carry a licence we cannot take, or bring a whole CAD
//! kernel's data model.

pub mod cards;
pub mod entities;
pub mod write;

use std::collections::{BTreeMap, BTreeSet};

pub use cards::{Global, RawEntity, RawFile, read_raw};
pub use entities::{Curve, Face, Surface, Transform};
pub use write::{ParameterRectangle, write_surfaces};

/// What is wrong with an IGES file, and on which line.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("line {line}: {reason}")]
pub struct IgesError {
    /// 1-based line of the file.
    pub line: usize,
    /// What is wrong.
    pub reason: String,
}

impl IgesError {
    pub(crate) fn at(line: usize, reason: impl Into<String>) -> IgesError {
        IgesError {
            line,
            reason: reason.into(),
        }
    }
}

/// A part read from IGES.
#[derive(Clone, Debug, PartialEq)]
pub struct IgesModel {
    /// The Global section.
    pub global: Global,
    /// Millimetres per model unit (every coordinate below is in mm already).
    pub millimetres_per_unit: f64,
    /// The faces, in directory order.
    pub faces: Vec<Face>,
    /// Independent entities that are not faces, by type: listed, not read.
    pub skipped: BTreeMap<i64, usize>,
}

/// Reads an IGES file's text into faces.
pub fn read_iges(text: &str) -> Result<IgesModel, IgesError> {
    let raw = read_raw(text)?;
    let reader = entities::Reader::new(&raw)?;
    let millimetres_per_unit = raw
        .global
        .millimetres_per_unit()
        .map_err(|reason| IgesError::at(1, reason))?;
    // Surfaces the trimmed surfaces stand on.
    let trimmed_bases: BTreeSet<String> = raw
        .entities
        .iter()
        .filter(|e| e.entity_type == 144)
        .filter_map(|e| e.parameters.get(1).map(|t| t.text.clone()))
        .collect();
    let mut faces = Vec::new();
    let mut skipped = BTreeMap::new();
    for e in raw.entities.iter().filter(|e| e.status.subordinate == 0) {
        match e.entity_type {
            144 => faces.push(reader.trimmed_face(e)?),
            120 | 128 if !trimmed_bases.contains(&e.de.to_string()) => {
                faces.push(Face {
                    de: e.de,
                    line: e.line,
                    surface: reader.surface(e.de, e)?,
                    outer: None,
                    holes: Vec::new(),
                    model_boundaries: Vec::new(),
                });
            }
            // Definitions that only serve others.
            124 | 314 | 406 => {}
            t => *skipped.entry(t).or_insert(0) += 1,
        }
    }
    if faces.is_empty()
        && let Some(solid) = raw
            .entities
            .iter()
            .find(|e| e.entity_type == 186 && e.status.subordinate == 0)
    {
        return Err(IgesError::at(
            solid.line,
            format!(
                "entity 186 ({}) at DE {}: the part is a B-rep solid (186 with its 514 shells and \
                 510 faces), which this reader does not read; export it as trimmed surfaces \
                 (144) instead",
                entity_name(186),
                solid.de
            ),
        ));
    }
    Ok(IgesModel {
        global: raw.global,
        millimetres_per_unit,
        faces,
        skipped,
    })
}

/// What an entity type is, by the IGES 5.3 names of the ones CAD exports carry.
pub fn entity_name(entity_type: i64) -> &'static str {
    match entity_type {
        100 => "circular arc",
        102 => "composite curve",
        104 => "conic arc",
        106 => "copious data",
        108 => "plane",
        110 => "line",
        112 => "parametric spline curve",
        114 => "parametric spline surface",
        116 => "point",
        118 => "ruled surface",
        120 => "surface of revolution",
        122 => "tabulated cylinder",
        123 => "direction",
        124 => "transformation matrix",
        126 => "rational B-spline curve",
        128 => "rational B-spline surface",
        130 => "offset curve",
        140 => "offset surface",
        141 => "boundary",
        142 => "curve on a parametric surface",
        143 => "bounded surface",
        144 => "trimmed surface",
        186 => "manifold solid B-rep object",
        190 => "plane surface",
        192 => "right circular cylindrical surface",
        194 => "right circular conical surface",
        196 => "spherical surface",
        198 => "toroidal surface",
        212 => "general note",
        214 => "leader",
        308 => "subfigure definition",
        314 => "colour definition",
        402 => "associativity instance",
        406 => "property",
        408 => "singular subfigure instance",
        502 => "vertex list",
        504 => "edge list",
        508 => "loop",
        510 => "face",
        514 => "shell",
        _ => "unknown to this reader",
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Builds a fixed-format IGES file: the Global section, then each entity's directory entry
    /// and parameter record (`type, params…;` wrapped at 64 columns).
    struct Builder {
        entities: Vec<(i64, i64, usize, &'static str, String)>,
    }

    impl Builder {
        fn new() -> Builder {
            Builder {
                entities: Vec::new(),
            }
        }
        /// Adds an entity (type, form, transform DE, status) with its parameters after the
        /// type; returns its DE.
        fn add(
            &mut self,
            kind: i64,
            transform: usize,
            status: &'static str,
            params: &str,
        ) -> usize {
            self.entities
                .push((kind, 0, transform, status, format!("{kind},{params};")));
            2 * self.entities.len() - 1
        }
        fn text(&self) -> String {
            let card =
                |data: &str, letter: char, seq: usize| format!("{data:<72}{letter}{seq:>7}\n");
            let mut out = card("a test part", 'S', 1);
            let global = "1H,,1H;,4Htest,8Htest.igs,4Htest,3H1.0,32,38,6,308,15,4Htest,1.,2,2HMM,1,0.1,\
                          13H260101.120000,1E-6,1000.,4Hnone,4Hnone,11,0,13H260101.120000;";
            for (k, chunk) in global.as_bytes().chunks(72).enumerate() {
                out += &card(std::str::from_utf8(chunk).unwrap(), 'G', k + 1);
            }
            let mut directory = String::new();
            let mut parameters = String::new();
            let mut p_seq = 1;
            for (k, (kind, form, transform, status, record)) in self.entities.iter().enumerate() {
                let de = 2 * k + 1;
                let lines: Vec<&str> = record
                    .as_bytes()
                    .chunks(64)
                    .map(|c| std::str::from_utf8(c).unwrap())
                    .collect();
                directory += &card(
                    &format!(
                        "{kind:>8}{p_seq:>8}{:>8}{:>8}{:>8}{:>8}{transform:>8}{:>8}{status:>8}",
                        0, 0, 0, 0, 0
                    ),
                    'D',
                    de,
                );
                directory += &card(
                    &format!("{kind:>8}{:>8}{:>8}{:>8}{form:>8}", 0, 0, lines.len()),
                    'D',
                    de + 1,
                );
                for line in &lines {
                    parameters += &format!("{line:<64} {de:>7}P{p_seq:>7}\n");
                    p_seq += 1;
                }
            }
            out += &directory;
            out += &parameters;
            out += &card("S      1G      3D      2P      1", 'T', 1);
            out
        }
    }

    /// A plane patch (bilinear 128, 2×2 net: the point (u, v) is (10u, 20v, 0)) trimmed by a
    /// triangle of three lines in its parameter plane.
    fn add_plane_face(b: &mut Builder) {
        let surface = b.add(
            128,
            0,
            "00010000",
            "1,1,1,1,0,0,1,0,0,0.,0.,1.,1.,0.,0.,1.,1.,1.,1.,1.,1.,0.,0.,0.,10.,0.,0.,0.,20.,0.,10.,\
             20.,0.,0.,1.,0.,1.",
        );
        let lines: Vec<usize> = [
            (0.0, 0.0, 0.5, 0.0),
            (0.5, 0.0, 0.5, 0.5),
            (0.5, 0.5, 0.0, 0.0),
        ]
        .iter()
        .map(|(a, c, d, e)| b.add(110, 0, "00010500", &format!("{a},{c},0.,{d},{e},0.")))
        .collect();
        let composite = b.add(
            102,
            0,
            "00010500",
            &format!("3,{},{},{}", lines[0], lines[1], lines[2]),
        );
        let on_surface = b.add(142, 0, "00010500", &format!("1,{surface},{composite},0,1"));
        b.add(144, 0, "00000000", &format!("{surface},1,0,{on_surface}"));
    }

    /// The plane face reads into exact geometry.
    #[test]
    fn a_small_file_reads_into_exact_geometry() {
        let mut b = Builder::new();
        add_plane_face(&mut b);
        let text = b.text();
        let model = read_iges(&text).unwrap_or_else(|e| panic!("{e}\n{text}"));
        assert_eq!(model.millimetres_per_unit, 1.0);
        assert_eq!(model.faces.len(), 1);
        let face = &model.faces[0];
        // Point (u, v) of the plane is (10u, 20v, 0).
        let p = face.surface.point(0.25, 0.75);
        assert!((p - nalgebra::Point3::new(2.5, 15.0, 0.0)).norm() < 1e-14);
        let outer = face.outer.as_ref().unwrap().sample(1);
        assert_eq!(outer.len(), 4);
        assert_eq!(outer[2], nalgebra::Point3::new(0.5, 0.5, 0.0));
        assert!(model.skipped.is_empty());
    }

    /// A file holding a B-rep solid and no surfaces of its own is refused by name, at the
    /// solid's line; with a face beside it, the solid is listed as skipped.
    #[test]
    fn a_brep_solid_is_refused_by_name() {
        let mut b = Builder::new();
        let solid = b.add(186, 0, "00000000", "3,0,0");
        let text = b.text();
        let error = read_iges(&text).expect_err("a B-rep solid alone");
        let message = error.to_string();
        assert!(
            message.contains("186")
                && message.contains("manifold solid B-rep")
                && message.contains("144"),
            "{message}"
        );
        let line = text
            .lines()
            .position(|l| l.ends_with(&format!("D{solid:>7}")))
            .unwrap()
            + 1;
        assert_eq!(error.line, line, "{message}");
        add_plane_face(&mut b);
        let model = read_iges(&b.text()).expect("a face beside the solid");
        assert_eq!(model.faces.len(), 1);
        assert_eq!(model.skipped.get(&186), Some(&1));
    }

    /// Every kind of damage is refused naming its line and what is wrong.
    #[test]
    fn damaged_files_are_refused_by_line() {
        // A cone: an axis and a generatrix (lines) turned about it.
        let mut b = Builder::new();
        let axis = b.add(110, 0, "00010000", "0.,0.,0.,0.,0.,1.");
        let generatrix = b.add(110, 0, "00010000", "1.,0.,0.,1.,2.,3.");
        b.add(120, 0, "00000000", &format!("{axis},{generatrix},0.,6.28"));
        let good = b.text();
        assert_eq!(read_iges(&good).unwrap().faces.len(), 1);
        let lines: Vec<&str> = good.lines().collect();
        let with = |k: usize, new: &str| {
            let mut l = lines.clone();
            l[k] = new;
            l.join("\n")
        };
        let d1 = lines.iter().position(|l| l.as_bytes()[72] == b'D').unwrap();
        let d_last = lines
            .iter()
            .rposition(|l| l.as_bytes()[72] == b'D')
            .unwrap();
        let pg = lines.iter().position(|l| l.contains("1.,2.")).unwrap();
        let p_line = lines[pg].to_string();
        let cases: Vec<(String, &str, usize)> = vec![
            (with(0, "short"), "columns", 1),
            (
                with(d1, &lines[d1].replacen("     110", "     1x0", 1)),
                "not an integer",
                d1 + 1,
            ),
            (
                with(pg, &p_line.replace(";", ",")),
                "record delimiter",
                pg + 1,
            ),
            (
                with(pg, &p_line.replace("1.,2.", "1.,2Q")),
                "not a finite number",
                pg + 1,
            ),
            (
                with(pg, &p_line.replace("110,1.,0.", "110,99H0.")),
                "Hollerith",
                pg + 1,
            ),
            (
                with(pg, &format!("{}       7P      2", &p_line[..64])),
                "belongs to DE",
                pg + 1,
            ),
            (
                with(
                    d1,
                    &lines[d1].replacen("       1       0", "       9       0", 1),
                ),
                "parameter lines",
                d1 + 1,
            ),
            (
                lines
                    .iter()
                    .enumerate()
                    .filter(|&(k, _)| k != d_last)
                    .map(|(_, l)| *l)
                    .collect::<Vec<_>>()
                    .join("\n"),
                "odd number",
                d_last,
            ),
            (
                with(0, &format!("{:<72}X      1", "x")),
                "section letter",
                1,
            ),
        ];
        for (text, expected, line) in cases {
            let e = read_iges(&text)
                .err()
                .unwrap_or_else(|| panic!("{expected}: read without an error"));
            assert!(e.to_string().contains(expected), "{expected}: {e}");
            assert_eq!(e.line, line, "{expected}: {e}");
        }
        // A generatrix whose counts overrun its record, and an axis placed by a line instead of
        // a transformation matrix (each read as the surface of revolution they make).
        let mut b = Builder::new();
        let axis = b.add(110, 0, "00010000", "0.,0.,0.,0.,0.,1.");
        let curve = b.add(126, 0, "00010000", "900000000,3,0,0,1,0,0.,1.");
        b.add(120, 0, "00000000", &format!("{axis},{curve},0.,6.28"));
        let e = read_iges(&b.text()).unwrap_err().to_string();
        assert!(e.contains("entity 126") && e.contains("parameter 1"), "{e}");
        let mut b = Builder::new();
        let not_a_matrix = b.add(110, 0, "00010000", "0.,0.,0.,1.,0.,0.");
        let axis = b.add(110, not_a_matrix, "00010000", "0.,0.,0.,0.,0.,1.");
        let generatrix = b.add(110, 0, "00010000", "1.,0.,0.,1.,0.,1.");
        b.add(120, 0, "00000000", &format!("{axis},{generatrix},0.,6.28"));
        let e = read_iges(&b.text()).unwrap_err().to_string();
        assert!(e.contains("124 expected"), "{e}");
    }

    /// Composite curves that each list the one below forty times expand to 40⁶ lines: refused
    /// by their count, read member by member, not after billions of curves were built.
    #[test]
    fn a_composite_curve_bomb_is_refused() {
        let mut b = Builder::new();
        let surface = b.add(
            128,
            0,
            "00010000",
            "1,1,1,1,0,0,1,0,0,0.,0.,1.,1.,0.,0.,1.,1.,1.,1.,1.,1.,0.,0.,0.,10.,0.,0.,0.,20.,0.,10.,\
             20.,0.,0.,1.,0.,1.",
        );
        let mut curve = b.add(110, 0, "00010500", "0.,0.,0.,0.5,0.,0.");
        for _ in 0..6 {
            let members = vec![curve.to_string(); 40].join(",");
            curve = b.add(102, 0, "00010500", &format!("40,{members}"));
        }
        let on_surface = b.add(142, 0, "00010500", &format!("1,{surface},{curve},0,1"));
        b.add(144, 0, "00000000", &format!("{surface},1,0,{on_surface}"));
        let e = read_iges(&b.text()).unwrap_err().to_string();
        assert!(e.contains("more than 1000000 simple curves"), "{e}");
    }

    /// The plane face of the first test and the cone of the second in one file.
    fn rich_file() -> String {
        let mut b = Builder::new();
        add_plane_face(&mut b);
        let matrix = b.add(124, 0, "00000000", "0.,-1.,0.,5.,1.,0.,0.,0.,0.,0.,1.,0.");
        let axis = b.add(110, matrix, "00010000", "0.,0.,0.,0.,0.,1.");
        let generatrix = b.add(
            126,
            0,
            "00010000",
            "2,2,1,0,1,0,0.,0.,0.,1.,1.,1.,1.,1.,1.,1.,0.,0.,1.5,0.,1.,2.,0.,2.,0.,1.,0.,0.,1.",
        );
        b.add(120, 0, "00000000", &format!("{axis},{generatrix},0.,3.14"));
        b.text()
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(256))]
        /// Any damage to a valid file gives `Ok` or `Err`, never a panic: bytes replaced,
        /// the file cut short, lines dropped, numbers made huge or negative.
        #[test]
        fn damage_never_panics(
            edits in proptest::collection::vec((0usize..100_000, 0u8..128, 0u8..7), 1..6),
        ) {
            let mut text = rich_file().into_bytes();
            for (at, byte, kind) in edits {
                if text.is_empty() {
                    break;
                }
                let at = at % text.len();
                match kind {
                    0 => text[at] = byte,
                    1 => text.truncate(at),
                    2 => {
                        let end = text[at..].iter().position(|&b| b == b'\n').map_or(text.len(), |k| at + k + 1);
                        text.drain(at..end);
                    }
                    3 => {
                        // A number made as large as its field allows.
                        let start = text[at..].iter().position(|b| b.is_ascii_digit()).map(|k| at + k);
                        if let Some(start) = start {
                            let run = text[start..].iter().take_while(|b| b.is_ascii_digit()).count();
                            text[start..start + run].fill(b'9');
                        }
                    }
                    4 => {
                        let digit = text[at..].iter().position(|b| b.is_ascii_digit());
                        if let Some(k) = digit {
                            text[at + k] = b'-';
                        }
                    }
                    5 => {
                        // Two cards swapped: the format holds, the pointers lie.
                        let cards: Vec<&[u8]> = text.split(|&b| b == b'\n').collect();
                        let (a, b) = (at % cards.len(), (at / 7 + usize::from(byte)) % cards.len());
                        let mut cards: Vec<Vec<u8>> = cards.into_iter().map(<[u8]>::to_vec).collect();
                        cards.swap(a, b);
                        text = cards.join(&b'\n');
                    }
                    _ => text.insert(at, byte),
                }
            }
            let text = String::from_utf8_lossy(&text);
            if let Ok(model) = read_iges(&text) {
                for face in &model.faces {
                    let ((u0, u1), (v0, v1)) = face.surface.domain();
                    let _ = face.surface.point(0.5 * (u0 + u1), 0.5 * (v0 + v1));
                    if let Some(outer) = &face.outer {
                        let _ = outer.sample(2);
                    }
                }
            }
        }
    }

    /// The rich file reads: the plane face and the cone, placed by its 124.
    #[test]
    fn the_rich_file_reads() {
        let model = read_iges(&rich_file()).unwrap();
        assert_eq!(model.faces.len(), 2);
        // The cone's axis, turned a quarter about z and moved 5 along x, runs up x = 5, y = 0.
        let Surface::Revolution { axis, .. } = &model.faces[1].surface else {
            panic!("a surface of revolution");
        };
        assert!((axis.0 - nalgebra::Point3::new(5.0, 0.0, 0.0)).norm() < 1e-12);
        assert!((axis.1 - nalgebra::Point3::new(5.0, 0.0, 1.0)).norm() < 1e-12);
    }
}
