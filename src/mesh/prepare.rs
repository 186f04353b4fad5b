//! From a raw triangle soup to the clean mesh the planner works on, with a report of what was
//! found and fixed.
//!
//! Every tolerance here is absolute (mm) or judged per triangle from its own edges, never
//! scaled by the part's bounding box: one stray triangle a kilometre away used to stretch the
//! box a thousandfold, weld the real part's vertices together and drop three quarters of its
//! faces as "zero-area" (issue 17 item 8). Stray pieces themselves are found by
//! [`super::pieces`] and set aside by [`prepare_without_stray_pieces`].

use serde::Serialize;

use super::Mesh;
use super::pieces::{
    Piece, StrayPieceRule, count_stray, describe_stray, pieces_of, split_stray_pieces,
};
use super::topology::{self, Topology};
use super::weld::weld;
use crate::geom::{Point3, triangle_area, triangle_normal};

/// Pieces listed in a [`MeshReport`] (the largest); `components` counts all of them.
pub const MAX_LISTED_PIECES: usize = 100;

/// Why a mesh cannot be prepared at all (topology problems are not errors: they are reported
/// in [`MeshReport`] and the caller decides).
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum PrepareError {
    /// The options are out of range.
    #[error("{0}")]
    Options(String),
    /// Indices out of range or coordinates that are not finite.
    #[error("{0}")]
    BadMesh(String),
    #[error("the file has no triangles")]
    NoTriangles,
    /// Welding merged every triangle away: the part is tiny against the weld tolerance.
    #[error(
        "every triangle has zero area once vertices closer than {weld_tolerance} mm are merged \
         (the part is {diagonal:.3e} mm across: check its units)"
    )]
    AllZeroArea { weld_tolerance: f64, diagonal: f64 },
}

/// Tolerances for [`prepare`]. Lengths are in millimetres: meshes are prepared after reading,
/// when they are already in mm. None depends on the part's overall size.
#[derive(Clone, Copy, Debug)]
pub struct PrepareOptions {
    /// Vertices closer than this (mm) are merged. Default 1e-4 mm (0.1 µm).
    ///
    /// Absolute, because welding decides whether two points are the same point, which is a
    /// question of the file's precision and of the machining tolerance, both in mm, not of the
    /// part's size. 0.1 µm is ten times below 1 µm (far below any finishing tolerance) and
    /// above the rounding of f32 coordinates up to about 1 m from the origin (half an f32 step
    /// is 3e-5 mm at 512–1024 mm). On every shared test mesh the closest distinct vertices are
    /// more than 5e-4 mm apart (measured), so nothing real is merged.
    pub weld_tolerance: f64,
    /// A face is dropped as zero-area when its area is at most this × its own longest edge²
    /// (dimensionless). Default 1e-12: the face's height is below 2e-12 × its longest edge, so
    /// it is flat to rounding and its normal is noise.
    ///
    /// Judged per triangle from its own edges, so a face is judged by its shape wherever it
    /// is and however big the rest is. Deliberately tight: dropping a face that still has
    /// three distinct corners leaves a crack, so only faces without a usable normal go. On the
    /// shared test meshes every dropped face has a repeated corner after welding, and the
    /// flattest kept face has a ratio of 1.4e-5.
    pub degenerate_ratio: f64,
    /// Which pieces are stray debris ([`super::pieces`]); reported by [`prepare`], set aside
    /// by [`prepare_without_stray_pieces`].
    pub stray_pieces: StrayPieceRule,
}

impl Default for PrepareOptions {
    fn default() -> Self {
        Self {
            weld_tolerance: 1e-4,
            degenerate_ratio: 1e-12,
            stray_pieces: StrayPieceRule::default(),
        }
    }
}

impl PrepareOptions {
    pub fn with_weld_tolerance(self, weld_tolerance: f64) -> Self {
        Self {
            weld_tolerance,
            ..self
        }
    }

    pub fn with_degenerate_ratio(self, degenerate_ratio: f64) -> Self {
        Self {
            degenerate_ratio,
            ..self
        }
    }

    pub fn with_stray_pieces(self, stray_pieces: StrayPieceRule) -> Self {
        Self {
            stray_pieces,
            ..self
        }
    }

    fn validate(&self) -> Result<(), PrepareError> {
        let fraction = self.stray_pieces.max_area_fraction;
        if !(self.weld_tolerance.is_finite() && self.weld_tolerance >= 0.0) {
            Err(PrepareError::Options(format!(
                "weld tolerance {} mm: must be a finite length ≥ 0",
                self.weld_tolerance
            )))
        } else if !(self.degenerate_ratio.is_finite() && self.degenerate_ratio >= 0.0) {
            Err(PrepareError::Options(format!(
                "degenerate ratio {}: must be finite and ≥ 0",
                self.degenerate_ratio
            )))
        } else if !(0.0..=1.0).contains(&fraction) {
            Err(PrepareError::Options(format!(
                "stray piece area fraction {fraction}: must be between 0 and 1"
            )))
        } else {
            Ok(())
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
    /// Pieces that are stray debris by [`PrepareOptions::stray_pieces`] (tiny against the
    /// largest piece); planning sets them aside.
    pub stray_piece_count: usize,
    /// The pieces, largest area first: all of them up to [`MAX_LISTED_PIECES`].
    pub pieces: Vec<Piece>,
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
        if self.stray_piece_count > 0 {
            let listed: Vec<Piece> = self.pieces.iter().filter(|q| q.stray).cloned().collect();
            let shown = if listed.len() < self.stray_piece_count {
                format!(" ({} listed)", listed.len())
            } else {
                String::new()
            };
            let what = describe_stray(&listed).unwrap_or_default();
            p.push(format!(
                "{}{shown}, tiny against the largest piece{what}: left out of planning",
                count_stray(self.stray_piece_count)
            ));
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
/// orientable and turns closed components outward; lists the pieces and marks the stray ones.
/// Never fails on topology: problems are reported, and the caller decides what it can work
/// with.
pub fn prepare(raw: &Mesh, options: &PrepareOptions) -> Result<(Mesh, MeshReport), PrepareError> {
    options.validate()?;
    raw.check_indices_and_coordinates()
        .map_err(PrepareError::BadMesh)?;
    if raw.triangles.is_empty() {
        return Err(PrepareError::NoTriangles);
    }
    let welded = weld(raw, options.weld_tolerance).mesh;

    let degenerate = |a: Point3, b: Point3, c: Point3| {
        let longest: f64 = [
            (b - a).norm_squared(),
            (c - b).norm_squared(),
            (a - c).norm_squared(),
        ]
        .into_iter()
        .fold(0.0, f64::max);
        triangle_area(&a, &b, &c) <= options.degenerate_ratio * longest
    };
    let mut zero_area = 0;
    let mut duplicates = 0;
    let mut seen = std::collections::HashSet::new();
    let mut triangles = Vec::with_capacity(welded.triangles.len());
    for t in &welded.triangles {
        let [a, b, c] = t.map(|i| welded.positions[i as usize]);
        if t[0] == t[1] || t[1] == t[2] || t[0] == t[2] || degenerate(a, b, c) {
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
        return Err(PrepareError::AllZeroArea {
            weld_tolerance: options.weld_tolerance,
            diagonal: raw.aabb().diagonal(),
        });
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
        // Signed volume about a corner of the component itself, so that nothing far away
        // (another piece) costs digits.
        let Some(&first) = faces.first() else {
            return true;
        };
        let o = positions[tris[first as usize][0] as usize];
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
    let (mut pieces, _) = pieces_of(&mesh, &topo, &options.stray_pieces);
    let stray_piece_count = pieces.iter().filter(|p| p.stray).count();
    pieces.truncate(MAX_LISTED_PIECES);
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
        stray_piece_count,
        pieces,
    };
    debug_assert!(mesh.triangles.iter().all(|t| {
        let [a, b, c] = t.map(|i| mesh.positions[i as usize]);
        triangle_normal(&a, &b, &c).norm() > 0.0
    }));
    Ok((mesh, report))
}

/// [`prepare`], then the stray pieces set aside: what planning works on. Returns the part
/// without them, its report, and the pieces left out (all of them, largest first).
///
/// The report describes the part as it will be planned (watertight, genus, volume, box of
/// the kept pieces), except the counts of what reading and cleaning met, which are of the
/// whole file: input triangles and vertices, dropped faces, inconsistent edges, flipped faces.
pub fn prepare_without_stray_pieces(
    raw: &Mesh,
    options: &PrepareOptions,
) -> Result<(Mesh, MeshReport, Vec<Piece>), PrepareError> {
    let (whole, report) = prepare(raw, options)?;
    if report.stray_piece_count == 0 {
        return Ok((whole, report, Vec::new()));
    }
    let split = split_stray_pieces(&whole, &options.stray_pieces);
    // `whole` is welded, clean and oriented, so this only re-analyses what is left.
    let (part, mut kept) = prepare(&split.main, options)?;
    kept.input_triangles = report.input_triangles;
    kept.input_vertices = report.input_vertices;
    kept.dropped_zero_area_faces = report.dropped_zero_area_faces;
    kept.dropped_duplicate_faces = report.dropped_duplicate_faces;
    kept.inconsistent_edges = report.inconsistent_edges;
    kept.flipped_faces = report.flipped_faces;
    Ok((part, kept, split.stray))
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

    /// A mesh plus one triangle with 0.01 mm legs near (1e6, 0, 0) mm.
    fn with_far_triangle(mut m: Mesh) -> Mesh {
        let base = m.positions.len() as u32;
        m.positions.extend([
            Point3::new(1e6, 0.0, 0.0),
            Point3::new(1e6 + 0.01, 0.0, 0.0),
            Point3::new(1e6, 0.01, 0.0),
        ]);
        m.triangles.push([base, base + 1, base + 2]);
        m
    }

    /// Issue 17 item 8: tolerances scaled by the bounding box let a far triangle weld a small
    /// part's vertices together (0.17 mm with the triangle 1 km away) and drop its faces.
    #[test]
    fn a_far_triangle_does_not_change_how_the_part_is_cleaned() {
        // A 2 mm sphere: edges about 0.1 mm, corners near the poles closer still.
        let sphere = uv_sphere(1.0, 32, 64);
        let (alone, alone_report) = prepare(&sphere, &PrepareOptions::default()).unwrap();
        let (both, r) = prepare(&with_far_triangle(sphere), &PrepareOptions::default()).unwrap();
        assert_eq!(
            r.dropped_zero_area_faces,
            alone_report.dropped_zero_area_faces
        );
        assert_eq!(r.triangles, alone.triangles.len() + 1);
        assert_eq!(r.vertices, alone.positions.len() + 3);
        assert_eq!(r.components, 2);
        assert_eq!(r.stray_piece_count, 1);
        assert!(!r.watertight, "the stray triangle is open");
        assert!(r.problems().iter().any(|p| p.contains("1 stray piece,")));
        assert_eq!(r.pieces.len(), 2);
        assert!(!r.pieces[0].stray && r.pieces[1].stray);
        assert_eq!(r.pieces[0].triangles, alone.triangles.len());

        // Set aside, the part is the sphere as prepared alone, with its report.
        let (part, kept, stray) =
            prepare_without_stray_pieces(&both, &PrepareOptions::default()).unwrap();
        assert_eq!(part, alone);
        assert!(kept.watertight && kept.genus == Some(0));
        assert_eq!(kept.stray_piece_count, 0);
        assert_eq!(kept.volume, alone_report.volume);
        assert_eq!(stray.len(), 1);
        assert_eq!(stray[0].triangles, 1);
        assert_eq!(stray[0].bounding_box_min, [1e6, 0.0, 0.0]);
    }

    /// The same part a kilometre from the origin is cleaned the same way (the degenerate test
    /// is per triangle, the weld tolerance in mm).
    #[test]
    fn translation_far_away_changes_nothing() {
        let m = torus(20.0, 5.0, 48, 24);
        let mut far = m.clone();
        for p in &mut far.positions {
            p.x += 1e6;
        }
        let (_, a) = prepare(&m, &PrepareOptions::default()).unwrap();
        let (_, b) = prepare(&far, &PrepareOptions::default()).unwrap();
        assert_eq!((a.triangles, a.vertices), (b.triangles, b.vertices));
        assert!(b.watertight && b.genus == Some(1));
        assert!((a.volume.unwrap() - b.volume.unwrap()).abs() < 1e-6 * a.volume.unwrap());
    }

    #[test]
    fn bad_options_are_refused() {
        let m = torus(20.0, 5.0, 12, 6);
        for o in [
            PrepareOptions::default().with_weld_tolerance(-1.0),
            PrepareOptions::default().with_degenerate_ratio(f64::NAN),
            PrepareOptions::default()
                .with_stray_pieces(StrayPieceRule::default().with_max_area_fraction(2.0)),
        ] {
            assert!(prepare(&m, &o).is_err());
        }
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
        let e = prepare(&m, &PrepareOptions::default()).unwrap_err();
        assert!(
            matches!(&e, PrepareError::BadMesh(m) if m.contains("not a finite length")),
            "{e}"
        );
        assert_eq!(
            prepare(&Mesh::default(), &PrepareOptions::default()).unwrap_err(),
            PrepareError::NoTriangles
        );
        let tiny = crate::mesh::fixtures::cuboid(1e-6, 1e-6, 1e-6);
        let e = prepare(&tiny, &PrepareOptions::default()).unwrap_err();
        assert!(matches!(e, PrepareError::AllZeroArea { .. }), "{e}");
        assert!(e.to_string().contains("check its units"), "{e}");
    }
}
