//! The blank a job or a simulation starts from, as a user names it: `box:…`, `cylinder:…`,
//! `offset:M` or `mesh:FILE`. Below the job file and the commands, which both read it.

use std::path::PathBuf;

/// Radial margin of the enclosing cylinder blank, mm.
pub const ENCLOSING_MARGIN: f64 = 2.0;

/// The blank a simulation or a plan starts from.
#[derive(Clone, Debug, PartialEq)]
pub enum BlankSpec {
    /// A box `[x0, y0, z0, x1, y1, z1]`, mm.
    Box([f64; 6]),
    /// A cylinder about the vertical line through the part's box centre: radius, `z0`, `z1`.
    Cylinder { radius: f64, z0: f64, z1: f64 },
    /// The cylinder about that line that holds the part with `margin` mm to spare around it
    /// and 1 mm above, standing on the part's lowest point (`cylinder` with no numbers):
    /// an impeller's bar stock.
    EnclosingCylinder { margin: f64 },
    /// The part grown by this many mm (its verified enclosing offset shape).
    Offset(f64),
    /// A closed mesh file (in the part's units).
    Mesh(PathBuf),
}

impl BlankSpec {
    /// Reads `box:X0,Y0,Z0,X1,Y1,Z1`, `cylinder:R,Z0,Z1`, `offset:M` or `mesh:FILE` (mm); the
    /// error says what was expected.
    pub fn parse(text: &str) -> std::result::Result<BlankSpec, String> {
        let bad = || {
            format!(
                "`{text}`: expected box:X0,Y0,Z0,X1,Y1,Z1 (X0 < X1, …), cylinder:R,Z0,Z1 (R > 0, \
                 Z0 < Z1), cylinder (enclosing the part), offset:M (M > 0) or mesh:FILE"
            )
        };
        if text.trim() == "cylinder" {
            return Ok(BlankSpec::EnclosingCylinder {
                margin: ENCLOSING_MARGIN,
            });
        }
        let (kind, value) = text.split_once(':').ok_or_else(bad)?;
        let numbers = || -> std::result::Result<Vec<f64>, String> {
            value
                .split(',')
                .map(|v| v.trim().parse::<f64>().ok().filter(|x| x.is_finite()))
                .collect::<Option<Vec<f64>>>()
                .ok_or_else(bad)
        };
        match kind.trim() {
            "box" => match numbers()?.as_slice() {
                &[x0, y0, z0, x1, y1, z1] if x0 < x1 && y0 < y1 && z0 < z1 => {
                    Ok(BlankSpec::Box([x0, y0, z0, x1, y1, z1]))
                }
                _ => Err(bad()),
            },
            "cylinder" => match numbers()?.as_slice() {
                &[radius, z0, z1] if radius > 0.0 && z0 < z1 => {
                    Ok(BlankSpec::Cylinder { radius, z0, z1 })
                }
                _ => Err(bad()),
            },
            "offset" => match numbers()?.as_slice() {
                &[m] if m > 0.0 => Ok(BlankSpec::Offset(m)),
                _ => Err(bad()),
            },
            "mesh" if !value.trim().is_empty() => Ok(BlankSpec::Mesh(PathBuf::from(value))),
            _ => Err(bad()),
        }
    }

    /// The spec with the enclosing cylinder sized for `part` (as planned); others as they are.
    pub fn resolved(&self, part: &crate::mesh::Mesh) -> BlankSpec {
        let BlankSpec::EnclosingCylinder { margin } = *self else {
            return self.clone();
        };
        let bounds = part.aabb();
        let centre = bounds.center();
        let radius = part
            .positions
            .iter()
            .map(|p| (p.x - centre.x).hypot(p.y - centre.y))
            .fold(0.0, f64::max);
        BlankSpec::Cylinder {
            radius: radius + margin,
            z0: bounds.min.z,
            z1: bounds.max.z + 1.0,
        }
    }

    /// The spec as a user writes it (a mesh by its file name).
    pub fn describe(&self) -> String {
        match self {
            BlankSpec::EnclosingCylinder { .. } => "cylinder".to_string(),
            BlankSpec::Box(b) => {
                format!("box:{},{},{},{},{},{}", b[0], b[1], b[2], b[3], b[4], b[5])
            }
            BlankSpec::Cylinder { radius, z0, z1 } => format!("cylinder:{radius},{z0},{z1}"),
            BlankSpec::Offset(m) => format!("offset:{m}"),
            BlankSpec::Mesh(p) => format!(
                "mesh:{}",
                p.file_name()
                    .map_or_else(|| p.display().to_string(), |n| n.to_string_lossy().into())
            ),
        }
    }
}
