//! The parts of a DXF drawing an outline needs: the `$INSUNITS` header variable and the
//! model- and paper-space entities of the ENTITIES section, each as its group pairs.
//!
//! An entity is the pairs from its `(0, TYPE)` pair to the next code-0 pair; a POLYLINE owns the
//! VERTEX entities after it up to its SEQEND (the R12 layout every version still writes). Blocks
//! (the BLOCKS section) are not read: an INSERT of one is refused above, by name.

use super::groups::{Group, Place};

/// An entity's pairs, with its type name and what names it in messages.
#[derive(Debug)]
pub(super) struct Entity {
    pub kind: String,
    pub groups: Vec<Group>,
    /// For a POLYLINE, its VERTEX entities in order.
    pub vertices: Vec<Entity>,
    pub place: Place,
}

impl Entity {
    fn new(kind: &str, place: Place) -> Self {
        Self {
            kind: kind.to_string(),
            groups: Vec::new(),
            vertices: Vec::new(),
            place,
        }
    }

    /// The first pair with `code`.
    pub fn group(&self, code: i32) -> Option<&Group> {
        self.groups.iter().find(|g| g.code == code)
    }

    /// The real of the first pair with `code`, or `default` when there is none; `Err` names
    /// the pair when its value is not a number.
    pub fn real(&self, code: i32, default: f64) -> Result<f64, String> {
        match self.group(code) {
            None => Ok(default),
            Some(g) => g.number(),
        }
    }

    pub fn integer(&self, code: i32, default: i64) -> Result<i64, String> {
        match self.group(code) {
            None => Ok(default),
            Some(g) => g.whole_number(),
        }
    }

    /// A point or vector from the codes `code`, `code + 10`, `code + 20` (x, y, z).
    pub fn point(&self, code: i32, default: [f64; 3]) -> Result<[f64; 3], String> {
        Ok([
            self.real(code, default[0])?,
            self.real(code + 10, default[1])?,
            self.real(code + 20, default[2])?,
        ])
    }

    /// The handle (code 5), as written.
    pub fn handle(&self) -> Option<&str> {
        self.group(5).map(Group::text).filter(|h| !h.is_empty())
    }

    /// The layer (code 8); "0" when absent, as DXF defines.
    pub fn layer(&self) -> &str {
        self.group(8).map_or("0", Group::text)
    }

    /// Paper space (code 67 = 1): layouts for printing, not the part.
    pub fn in_paper_space(&self) -> bool {
        self.group(67).and_then(Group::integer) == Some(1)
    }
}

/// The drawing as far as outlines need it.
#[derive(Debug)]
pub(super) struct Drawing {
    /// `$INSUNITS`; 0 (unitless) when the header does not say.
    pub units: i64,
    pub entities: Vec<Entity>,
}

/// Splits the pairs into the header's units and the ENTITIES section's entities.
pub(super) fn drawing(groups: Vec<Group>) -> Result<Drawing, String> {
    let mut units = 0;
    let mut entities: Vec<Entity> = Vec::new();
    let mut section: Option<String> = None;
    // The entity being filled, and whether it is a VERTEX of the last POLYLINE.
    let mut current: Option<Entity> = None;
    let mut in_polyline = false;
    let mut groups = groups.into_iter().peekable();
    let finish = |current: &mut Option<Entity>, entities: &mut Vec<Entity>, vertex: bool| {
        if let Some(e) = current.take() {
            match entities.last_mut() {
                Some(polyline) if vertex => polyline.vertices.push(e),
                _ => entities.push(e),
            }
        }
    };
    while let Some(g) = groups.next() {
        if g.code == 0 {
            let vertex = current.as_ref().is_some_and(|e| e.kind == "VERTEX") && in_polyline;
            finish(&mut current, &mut entities, vertex);
            match g.text() {
                "SECTION" => {
                    let name = groups.next_if(|n| n.code == 2);
                    let Some(name) = name else {
                        return Err(format!("{}: a SECTION without its name (group 2)", g.place));
                    };
                    section = Some(name.text().to_string());
                    in_polyline = false;
                }
                "ENDSEC" => section = None,
                "EOF" => break,
                kind if section.as_deref() == Some("ENTITIES") => {
                    match kind {
                        "POLYLINE" => in_polyline = true,
                        "VERTEX" => {}
                        "SEQEND" => {
                            in_polyline = false;
                            continue;
                        }
                        _ => in_polyline = false,
                    }
                    // A VERTEX outside a POLYLINE belongs to nothing an outline reads.
                    if kind != "VERTEX" || in_polyline {
                        current = Some(Entity::new(kind, g.place));
                    }
                }
                _ => {}
            }
            continue;
        }
        match section.as_deref() {
            Some("HEADER") if g.is(9, "$INSUNITS") => {
                if let Some(value) = groups.next_if(|n| n.code == 70) {
                    units = value
                        .integer()
                        .ok_or_else(|| format!("{}: $INSUNITS is not an integer", value.place))?;
                }
            }
            Some("ENTITIES") => {
                if let Some(e) = current.as_mut() {
                    e.groups.push(g);
                }
            }
            _ => {}
        }
    }
    let vertex = current.as_ref().is_some_and(|e| e.kind == "VERTEX") && in_polyline;
    finish(&mut current, &mut entities, vertex);
    Ok(Drawing { units, entities })
}

#[cfg(test)]
mod tests {
    use super::super::groups::read_groups;
    use super::*;

    fn parse(text: &str) -> Drawing {
        drawing(read_groups(text.as_bytes()).unwrap()).unwrap()
    }

    #[test]
    fn header_units_entities_and_polyline_vertices() {
        let d = parse(concat!(
            "0\nSECTION\n2\nHEADER\n9\n$ACADVER\n1\nAC1009\n9\n$INSUNITS\n70\n4\n0\nENDSEC\n",
            "0\nSECTION\n2\nBLOCKS\n0\nBLOCK\n0\nLINE\n10\n9\n0\nENDBLK\n0\nENDSEC\n",
            "0\nSECTION\n2\nENTITIES\n",
            "0\nLINE\n5\n1A\n8\nCut\n10\n1\n20\n2\n11\n3\n21\n4\n",
            "0\nPOLYLINE\n66\n1\n70\n1\n0\nVERTEX\n10\n0\n20\n0\n42\n0.5\n0\nVERTEX\n10\n1\n20\n0\n0\nSEQEND\n",
            "0\nVERTEX\n10\n7\n20\n7\n",
            "0\nCIRCLE\n67\n1\n10\n0\n20\n0\n40\n2\n",
            "0\nENDSEC\n0\nEOF\n"
        ));
        assert_eq!(d.units, 4);
        let kinds: Vec<&str> = d.entities.iter().map(|e| e.kind.as_str()).collect();
        assert_eq!(
            kinds,
            ["LINE", "POLYLINE", "CIRCLE"],
            "the block's LINE is not read"
        );
        let line = &d.entities[0];
        assert_eq!((line.handle(), line.layer()), (Some("1A"), "Cut"));
        assert_eq!(line.point(11, [0.0; 3]).unwrap(), [3.0, 4.0, 0.0]);
        assert_eq!(line.place, Place::Line(33));
        let polyline = &d.entities[1];
        assert_eq!(
            polyline.vertices.len(),
            2,
            "the stray VERTEX after SEQEND is not its"
        );
        assert_eq!(polyline.vertices[0].real(42, 0.0).unwrap(), 0.5);
        assert_eq!(polyline.layer(), "0");
        assert!(d.entities[2].in_paper_space() && !line.in_paper_space());
        assert!(line.real(8, 0.0).is_err(), "a layer name is not a number");
    }

    #[test]
    fn a_file_with_only_entities_and_no_end() {
        let d = parse("0\nSECTION\n2\nENTITIES\n0\nCIRCLE\n40\n3\n");
        assert_eq!((d.units, d.entities.len()), (0, 1));
        assert_eq!(d.entities[0].real(40, 0.0).unwrap(), 3.0);
        assert!(drawing(read_groups(b"0\nSECTION\n8\nX\n").unwrap()).is_err());
    }
}
