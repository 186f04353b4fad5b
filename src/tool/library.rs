//! A tool library: the shop's tools in a TOML file, one `[[tool]]` table each with the fields of
//! [`ToolAssembly`] (see `data/tools.toml`).

use serde::Deserialize;

use super::{ToolAssembly, ToolError};

/// The tools a shop has, as read (order kept).
#[derive(Clone, Debug, PartialEq)]
pub struct ToolLibrary {
    pub tools: Vec<ToolAssembly>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct LibraryFile {
    #[serde(default)]
    tool: Vec<ToolAssembly>,
}

impl ToolLibrary {
    /// Parses and checks a library; `file` names the source in errors, which also say which
    /// tool (by position and id) is wrong.
    pub fn parse(text: &str, file: &str) -> Result<Self, ToolError> {
        let bad = |reason: String| ToolError::Library {
            file: file.to_string(),
            reason,
        };
        let parsed: LibraryFile =
            toml::from_str(text).map_err(|e| bad(e.to_string().trim_end().to_string()))?;
        if parsed.tool.is_empty() {
            return Err(bad("no [[tool]] tables: the library is empty".into()));
        }
        for (i, tool) in parsed.tool.iter().enumerate() {
            tool.validate()
                .map_err(|e| bad(format!("tool {} (id {}): {e}", i + 1, tool.id)))?;
            if let Some(first) = parsed.tool[..i].iter().position(|t| t.id == tool.id) {
                return Err(bad(format!(
                    "tools {} and {} both have id {}: tool numbers must be unique",
                    first + 1,
                    i + 1,
                    tool.id
                )));
            }
        }
        Ok(Self { tools: parsed.tool })
    }

    /// Reads and checks a library file.
    pub fn read(path: &std::path::Path) -> Result<Self, ToolError> {
        let file = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|e| ToolError::Library {
            file: file.clone(),
            reason: e.to_string(),
        })?;
        Self::parse(&text, &file)
    }

    /// Indices of the tools from the largest cutting diameter to the smallest; among equal
    /// diameters the shorter (stiffer) stickout first, then by id, so the order is total.
    pub fn largest_first(&self) -> Vec<usize> {
        let mut order: Vec<usize> = (0..self.tools.len()).collect();
        order.sort_by(|&a, &b| {
            let (ta, tb) = (&self.tools[a], &self.tools[b]);
            tb.cutter
                .diameter()
                .total_cmp(&ta.cutter.diameter())
                .then(ta.stickout.total_cmp(&tb.stickout))
                .then(ta.id.cmp(&tb.id))
        });
        order
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tool::Cutter;

    fn bundled() -> ToolLibrary {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("data/tools.toml");
        ToolLibrary::read(&path).unwrap()
    }

    #[test]
    fn the_bundled_library_has_every_kind_and_reads_back() {
        let library = bundled();
        assert!(library.tools.len() >= 8);
        for kind in ["ball", "flat", "bull", "taper"] {
            assert!(
                library.tools.iter().any(|t| t.cutter.kind() == kind),
                "no {kind} tool in data/tools.toml"
            );
        }
        assert!(library.tools.iter().any(|t| t.neck.is_some()));
        // Largest first, and a total order.
        let order = library.largest_first();
        let diameters: Vec<f64> = order
            .iter()
            .map(|&i| library.tools[i].cutter.diameter())
            .collect();
        assert!(diameters.windows(2).all(|w| w[0] >= w[1]));
        let mut seen = order.clone();
        seen.sort();
        assert_eq!(seen, (0..library.tools.len()).collect::<Vec<_>>());
    }

    #[test]
    fn bad_libraries_name_the_file_and_the_tool() {
        let err = |text: &str| {
            ToolLibrary::parse(text, "shop.toml")
                .unwrap_err()
                .to_string()
        };
        assert!(err("").contains("shop.toml: no [[tool]]"));
        let e = err("[[tool]]\nid = 1\n");
        assert!(e.starts_with("shop.toml:") && e.contains("cutter"), "{e}");
        let one = "id = 7\ncutter = { kind = \"bull_nose\", diameter = 10, corner_radius = 6, flute_length = 20 }\nshank_diameter = 10\nstickout = 40\nholder = [{ diameter = 30, length = 40 }]\n";
        let e = err(&format!("[[tool]]\n{one}"));
        assert!(
            e.contains("tool 1 (id 7)") && e.contains("corner radius"),
            "{e}"
        );
        let ok = one.replace("corner_radius = 6", "corner_radius = 1");
        let lib = ToolLibrary::parse(&format!("[[tool]]\n{ok}"), "shop.toml").unwrap();
        assert_eq!(
            lib.tools[0].cutter,
            Cutter::BullNose {
                diameter: 10.0,
                corner_radius: 1.0,
                flute_length: 20.0
            }
        );
        let e = err(&format!("[[tool]]\n{ok}[[tool]]\n{ok}"));
        assert!(e.contains("tools 1 and 2 both have id 7"), "{e}");
        let e = err(&format!("[[tool]]\n{ok}colour = \"red\"\n"));
        assert!(e.contains("colour"), "{e}");
        let e = err(&format!(
            "[[tool]]\n{}",
            ok.replace("kind = \"bull_nose\"", "kind = \"drill\"")
        ));
        assert!(e.contains("drill"), "{e}");
    }
}
