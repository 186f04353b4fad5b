//! From a raw triangle soup to the clean mesh the planner works on, with a report of what was
//! found and fixed.

use serde::Serialize;

use super::Mesh;
use super::topology::{self, Topology};
use super::weld::weld;
use crate::geom::{triangle_area, triangle_normal};

/// Tolerances for [`prepare`], relative to the bounding-box diagonal so that they scale with
/// the part.
#[derive(Clone, Copy, Debug)]
pub struct PrepareOptions {
    /// Vertices closer than this × diagonal are merged. Default 1e-7 (0.01 µm on a 100 mm part):
    /// well below any machining tolerance, above the noise of f32 CAD exports.
    pub weld_tolerance: f64,
    /// Faces with area below this × diagonal² are dropped. Default 1e-12.
    pub min_area: f64,
}

impl Default for PrepareOptions {
    fn default() -> Self {
        Self {
            weld_tolerance: 1e-7,
            min_area: 1e-12,
        }
    }
}

/// Everything `wavemill info` prints, and the input summary of a plan report.
#[derive(Clone, Debug, Serialize)]
pub struct MeshReport {
    pub input_triangles: usize,
    pub input_vertices: usize,
    pub triangles: usize,
    pub vertices: usize,
    pub bounding_box_min: [f64; 3],
    pub bounding_box_max: [f64; 3],
    pub dropped_zero_area_faces: usize,
    pub dropped_duplicate_faces: usize,
    pub components: usize,
    pub boundary_edges: usize,
    pub boundary_loops: usize,
    pub non_manifold_edges: usize,
    pub non_manifold_vertices: usize,
    /// Interior edges whose two faces disagreed on winding, before the repair.
    pub inconsistent_edges: usize,
    pub flipped_faces: usize,
    pub non_orientable_components: usize,
    /// Closed 2-manifold, consistently oriented: inside and outside are defined.
    pub watertight: bool,
    /// Sum of the genus of all components (`None` where some component is not a manifold
    /// orientable surface).
    pub genus: Option<i64>,
    /// mm³; only for watertight meshes.
    pub volume: Option<f64>,
    pub surface_area: f64,
    pub units_guess: UnitsGuess,
}

impl MeshReport {
    /// One line per problem a user should know about before planning.
    pub fn problems(&self) -> Vec<String> {
        let mut p = Vec::new();
        if self.non_manifold_edges > 0 {
            p.push(format!(
                "{} non-manifold edges (used by more than two faces)",
                self.non_manifold_edges
            ));
        }
        if self.non_manifold_vertices > 0 {
            p.push(format!(
                "{} non-manifold vertices (faces meet only at a point)",
                self.non_manifold_vertices
            ));
        }
        if self.boundary_edges > 0 {
            p.push(format!(
                "open surface: {} boundary edges in {} holes",
                self.boundary_edges, self.boundary_loops
            ));
        }
        if self.inconsistent_edges > 0 {
            p.push(format!(
                "inconsistent winding on {} edges ({} faces flipped to repair it)",
                self.inconsistent_edges, self.flipped_faces
            ));
        }
        if self.non_orientable_components > 0 {
            p.push(format!(
                "{} components cannot be oriented",
                self.non_orientable_components
            ));
        }
        if self.dropped_zero_area_faces > 0 {
            p.push(format!(
                "{} zero-area faces dropped",
                self.dropped_zero_area_faces
            ));
        }
        if self.dropped_duplicate_faces > 0 {
            p.push(format!(
                "{} duplicate faces dropped",
                self.dropped_duplicate_faces
            ));
        }
        if self.components > 1 {
            p.push(format!("{} separate pieces", self.components));
        }
        p
    }
}

/// A guess at the units the file was written in, from the part's size alone (no mesh format
/// records units). Parts of impellers and blades are 5 mm to 2 m across.
#[derive(Clone, Copy, Debug, Serialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum UnitsGuess {
    /// Under 2 units across: as millimetres too small for this kind of part, as metres 0.5–2 m.
    Metres,
    /// 2–50 units across: millimetres or inches are both plausible.
    MillimetresOrInches,
    Millimetres,
}

impl UnitsGuess {
    pub fn from_diagonal(diagonal: f64) -> Self {
        if diagonal < 2.0 {
            UnitsGuess::Metres
        } else if diagonal < 50.0 {
            UnitsGuess::MillimetresOrInches
        } else {
            UnitsGuess::Millimetres
        }
    }
}

/// Welds, drops zero-area and duplicate faces, repairs the winding where the surface is
/// orientable and turns closed components outward. Never fails on topology: problems are
/// reported, and the caller decides what it can work with.
pub fn prepare(raw: &Mesh, options: &PrepareOptions) -> Result<(Mesh, MeshReport), String> {
    raw.check_indices_and_coordinates()?;
    if raw.triangles.is_empty() {
        return Err("the file has no triangles".into());
    }
    let diagonal = raw.aabb().diagonal();
    let welded = weld(raw, options.weld_tolerance * diagonal).mesh;

    let min_area = options.min_area * diagonal * diagonal;
    let mut zero_area = 0;
    let mut duplicates = 0;
    let mut seen = std::collections::HashSet::new();
    let mut triangles = Vec::with_capacity(welded.triangles.len());
    for t in &welded.triangles {
        let [a, b, c] = t.map(|i| welded.positions[i as usize]);
        if t[0] == t[1] || t[1] == t[2] || t[0] == t[2] || triangle_area(&a, &b, &c) <= min_area {
            zero_area += 1;
            continue;
        }
        let mut key = *t;
        key.sort_unstable();
        if !seen.insert(key) {
            duplicates += 1;
            continue;
        }
        triangles.push(*t);
    }
    if triangles.is_empty() {
        return Err("every triangle has zero area".into());
    }
    // Drop vertices no face uses, keeping order.
    let mut new_index = vec![u32::MAX; welded.positions.len()];
    let mut positions = Vec::new();
    for t in &mut triangles {
        for i in t.iter_mut() {
            if new_index[*i as usize] == u32::MAX {
                new_index[*i as usize] = positions.len() as u32;
                positions.push(welded.positions[*i as usize]);
            }
            *i = new_index[*i as usize];
        }
    }

    let topo = Topology::analyse(&triangles, positions.len());
    let outward = |tris: &[[u32; 3]], faces: &[u32]| {
        let o = raw.aabb().center();
        let v: f64 = faces
            .iter()
            .map(|&f| {
                let [a, b, c] = tris[f as usize].map(|i| positions[i as usize] - o);
                a.dot(&b.cross(&c))
            })
            .sum();
        v > 0.0
    };
    let orientation = topology::orient(&mut triangles, &topo, outward);
    let genus = topology::component_genus(&triangles, &topo, positions.len());
    let mesh = Mesh {
        positions,
        triangles,
    };
    let watertight = topo.is_closed_manifold() && orientation.non_orientable_components == 0;
    let aabb = mesh.aabb();
    let report = MeshReport {
        input_triangles: raw.triangles.len(),
        input_vertices: raw.positions.len(),
        triangles: mesh.triangles.len(),
        vertices: mesh.positions.len(),
        bounding_box_min: aabb.min.coords.into(),
        bounding_box_max: aabb.max.coords.into(),
        dropped_zero_area_faces: zero_area,
        dropped_duplicate_faces: duplicates,
        components: topo.component_count,
        boundary_edges: topo.boundary_edges,
        boundary_loops: topo.boundary_loops,
        non_manifold_edges: topo.non_manifold_edges,
        non_manifold_vertices: topo.non_manifold_vertices,
        inconsistent_edges: topo.inconsistent_edges,
        flipped_faces: orientation.flipped_faces,
        non_orientable_components: orientation.non_orientable_components,
        watertight,
        genus: genus.iter().copied().sum(),
        volume: watertight.then(|| mesh.signed_volume()),
        surface_area: mesh.surface_area(),
        units_guess: UnitsGuess::from_diagonal(aabb.diagonal()),
    };
    debug_assert!(mesh.triangles.iter().all(|t| {
        let [a, b, c] = t.map(|i| mesh.positions[i as usize]);
        triangle_normal(&a, &b, &c).norm() > 0.0
    }));
    Ok((mesh, report))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::fixtures::{torus, uv_sphere};

    #[test]
    fn clean_torus_reports_genus_one_and_its_volume() {
        let m = torus(20.0, 5.0, 48, 24);
        let (out, r) = prepare(&m, &PrepareOptions::default()).unwrap();
        assert!(r.watertight);
        assert_eq!(r.genus, Some(1));
        assert_eq!(r.components, 1);
        assert_eq!(out.triangles.len(), m.triangles.len());
        let exact = 2.0 * std::f64::consts::PI.powi(2) * 20.0 * 25.0;
        assert!((r.volume.unwrap() - exact).abs() / exact < 0.02);
        assert!(r.problems().is_empty());
    }

    #[test]
    fn inside_out_sphere_with_junk_is_repaired() {
        let mut m = uv_sphere(10.0, 12, 24);
        for t in &mut m.triangles {
            t.swap(1, 2);
        }
        let first = m.triangles[0];
        m.triangles.push(first); // duplicate
        m.triangles.push([0, 0, 1]); // collapsed
        m.triangles.push([first[2], first[1], first[0]]); // duplicate with reversed winding
        let (out, r) = prepare(&m, &PrepareOptions::default()).unwrap();
        assert_eq!(r.dropped_duplicate_faces, 2);
        assert_eq!(r.dropped_zero_area_faces, 1);
        assert!(r.watertight);
        assert!(out.signed_volume() > 0.0);
        assert_eq!(r.flipped_faces, out.triangles.len());
    }

    #[test]
    fn units_guess_follows_size() {
        assert_eq!(UnitsGuess::from_diagonal(0.09), UnitsGuess::Metres);
        assert_eq!(
            UnitsGuess::from_diagonal(12.0),
            UnitsGuess::MillimetresOrInches
        );
        assert_eq!(UnitsGuess::from_diagonal(120.0), UnitsGuess::Millimetres);
    }

    #[test]
    fn errors_name_the_problem() {
        let mut m = uv_sphere(1.0, 4, 6);
        m.positions[2].x = f64::NAN;
        assert!(
            prepare(&m, &PrepareOptions::default())
                .unwrap_err()
                .contains("non-finite")
        );
        assert!(
            prepare(&Mesh::default(), &PrepareOptions::default())
                .unwrap_err()
                .contains("no triangles")
        );
    }
}
