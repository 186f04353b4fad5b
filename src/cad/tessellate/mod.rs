//! Trimmed faces into one welded triangle mesh within a chord tolerance (issue 23).
//!
//! Per face: the trim loops are sampled into parameter-plane polygons whose edges stay within
//! the tolerance on the surface (`trim`); all faces' boundary vertices are then shared between
//! neighbours (junction vertices inserted, near vertices welded at their mean: `seams`); each
//! face's region is triangulated with its loops as constraint edges and refined until the
//! surface is within the tolerance, its caps and welded folds flipped away (`face`). The whole
//! is then sewn where the file's faces miss each other by more than the weld distance, its
//! remaining caps merged (`caps`) and turned outward. The tolerance is split between these
//! steps so that the measured deviation ([`Tessellation::deviation`]), which includes the
//! welding's moves, stays within the whole of it wherever the file's own faces agree to it.
//! docs/cad.md has the figures on the test impeller.

use std::collections::{BTreeMap, HashMap};

mod caps;
mod face;
mod seams;
#[cfg(test)]
mod tests;
mod trim;

use nalgebra::{Point2, Point3};
use rayon::prelude::*;

use crate::cad::iges::{Face, Surface};
use crate::cad::nurbs::PatchEvaluator;
use crate::mesh::Mesh;
use crate::mesh::topology::DisjointSets;
use face::{Corner, FaceMesh, triangulate_face};

/// A face's surface ready for the many evaluations tessellation makes: a NURBS surface in
/// power-form patches, other surfaces as they are.
pub(super) struct FaceSurface<'a> {
    surface: &'a Surface,
    patches: Option<PatchEvaluator>,
}

impl<'a> FaceSurface<'a> {
    fn new(surface: &'a Surface) -> FaceSurface<'a> {
        let patches = match surface {
            Surface::Nurbs { surface, .. } => PatchEvaluator::new(surface),
            Surface::Revolution { .. } => None,
        };
        FaceSurface { surface, patches }
    }
    pub(super) fn point(&self, u: f64, v: f64) -> Point3<f64> {
        match &self.patches {
            Some(p) => p.point(u, v),
            None => self.surface.point(u, v),
        }
    }
    pub(super) fn domain(&self) -> ((f64, f64), (f64, f64)) {
        self.surface.domain()
    }
}

/// How finely to tessellate.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TessellateOptions {
    /// Largest distance between the surfaces and the mesh, mm.
    pub tolerance: f64,
}

impl Default for TessellateOptions {
    fn default() -> Self {
        TessellateOptions { tolerance: 0.01 }
    }
}

impl TessellateOptions {
    /// Chord tolerance of the boundary polygons: a share of the whole, the rest is left to the
    /// welding's moves and the interior.
    fn boundary_tolerance(&self) -> f64 {
        0.4 * self.tolerance
    }
    /// Vertices closer than this become one, at their mean. The trim curves of neighbouring
    /// faces in CAD exports miss each other by a few micrometres (up to 10 µm on the test
    /// impeller); welding at the tolerance closes those seams and moves each side by about
    /// half the miss.
    fn weld_distance(&self) -> f64 {
        self.tolerance
    }
    /// Edges still open after welding are sewn across gaps up to this.
    fn sewing_distance(&self) -> f64 {
        2.0 * self.tolerance
    }
    /// What the refinement asks of the interior at its test points (centroids, edge midpoints,
    /// where sampling, not a bound, decides; the margin is for the points between).
    fn interior_tolerance(&self) -> f64 {
        0.7 * self.tolerance
    }
}

/// A face the tessellation could not triangulate.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("face {face} (entity at directory line {line}): {reason}")]
pub struct TessellateError {
    /// Index of the face in the model.
    pub face: usize,
    /// Its directory line in the file.
    pub line: usize,
    /// What went wrong.
    pub reason: String,
}

/// What the tessellation made and what it found.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct TessellationReport {
    /// Faces tessellated.
    pub faces: usize,
    /// Triangles in the mesh.
    pub triangles: usize,
    /// Vertices in the mesh.
    pub vertices: usize,
    /// Boundary vertices inserted where another face's vertex lay on an edge.
    pub junction_vertices: usize,
    /// Triangles dropped because welding collapsed them (at poles and degenerate sides).
    pub collapsed_triangles: usize,
    /// Caps (triangles thinner than a thousandth of their length) whose middle vertex was
    /// merged into a neighbour.
    pub collapsed_caps: usize,
    /// Vertices of edges left open by welding that sewing merged.
    pub sewn_vertices: usize,
    /// Open edges that sewing split at a vertex of the other side.
    pub sewn_edges: usize,
    /// The widest gap between faces that sewing closed, mm (the file's own faces miss each
    /// other by this much there; the mesh lies between them).
    pub widest_sewn_gap: f64,
    /// Edges with one triangle: where the faces do not close.
    pub open_seam_edges: usize,
    /// Their total length, mm.
    pub open_seam_length: f64,
    /// The open seams as chains of edges, longest first: length (mm) and a point on each.
    pub open_seams: Vec<OpenSeam>,
    /// Edges with more than two triangles.
    pub non_manifold_edges: usize,
}

/// A chain of open edges.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct OpenSeam {
    /// Its length, mm.
    pub length: f64,
    /// Edges in it.
    pub edges: usize,
    /// Where it starts.
    pub at: [f64; 3],
}

/// A tessellated model: the welded mesh, which face every triangle comes from, and what is
/// needed to measure it against the surfaces.
#[derive(Clone, Debug)]
pub struct Tessellation {
    /// The mesh, triangles of each face counter-clockwise about its surface's `S_u × S_v`.
    pub mesh: Mesh,
    /// For every triangle, the index of its face.
    pub face_of_triangle: Vec<u32>,
    /// What was made and found.
    pub report: TessellationReport,
    /// For every triangle, the parameter values of its corners on its face's surface.
    corner_uv: Vec<[Point2<f64>; 3]>,
}

/// Tessellates the faces into one welded mesh.
pub fn tessellate(
    faces: &[Face],
    options: &TessellateOptions,
) -> Result<Tessellation, TessellateError> {
    let surfaces: Vec<FaceSurface> = faces
        .par_iter()
        .map(|f| FaceSurface::new(&f.surface))
        .collect();
    let mut loops: Vec<Vec<trim::BoundaryLoop>> = faces
        .par_iter()
        .zip(&surfaces)
        .map(|(f, s)| trim::face_loops(f, s, options.boundary_tolerance()))
        .collect();
    let junction_vertices = seams::insert_junctions(&mut loops, options.weld_distance());
    let (boundary, ids) = seams::weld_boundaries(&loops, options.weld_distance());
    let meshes: Vec<FaceMesh> = faces
        .par_iter()
        .zip(&surfaces)
        .zip(&loops)
        .zip(&ids)
        .enumerate()
        .map(|(i, (((face, surface), lp), lp_ids))| {
            triangulate_face(surface, lp, lp_ids, &boundary, options.interior_tolerance()).map_err(
                |e| TessellateError {
                    face: i,
                    line: face.line,
                    reason: e.0,
                },
            )
        })
        .collect::<Result<_, _>>()?;

    let boundary_count = boundary.len() as u32;
    let mut soup = FaceTriangles {
        positions: boundary,
        ..FaceTriangles::default()
    };
    let mut collapsed_triangles = 0;
    for (f, m) in meshes.iter().enumerate() {
        let first_interior = soup.positions.len() as u32;
        soup.positions.extend_from_slice(&m.interior);
        let index = |c: Corner| match c {
            Corner::Boundary(id) => id,
            Corner::Interior(k) => first_interior + k,
        };
        for t in &m.triangles {
            let v = t.map(|i| index(m.corners[i as usize]));
            if v[0] == v[1] || v[1] == v[2] || v[0] == v[2] {
                collapsed_triangles += 1;
                continue;
            }
            soup.triangles.push(v);
            soup.face_of_triangle.push(f as u32);
            soup.corner_uv.push(t.map(|i| m.uv[i as usize]));
        }
    }
    let sewing = seams::sew(&mut soup, boundary_count, options.sewing_distance());
    let collapsed_caps = caps::collapse_caps(&mut soup);
    soup.orient_outward(boundary_count, faces.len());
    let mesh = Mesh {
        positions: soup.positions,
        triangles: soup.triangles,
    };
    let report = TessellationReport {
        faces: faces.len(),
        triangles: mesh.triangles.len(),
        vertices: mesh.positions.len(),
        junction_vertices,
        collapsed_triangles,
        collapsed_caps,
        sewn_vertices: sewing.merged_vertices,
        sewn_edges: sewing.split_edges,
        widest_sewn_gap: sewing.widest_gap,
        ..seam_report(&mesh, boundary_count)
    };
    Ok(Tessellation {
        mesh,
        face_of_triangle: soup.face_of_triangle,
        report,
        corner_uv: soup.corner_uv,
    })
}

/// Triangles that remember their face and their corners' parameters on its surface.
#[derive(Clone, Debug, Default)]
pub(super) struct FaceTriangles {
    positions: Vec<Point3<f64>>,
    triangles: Vec<[u32; 3]>,
    face_of_triangle: Vec<u32>,
    corner_uv: Vec<[Point2<f64>; 3]>,
}

impl FaceTriangles {
    /// Drops triangles with a repeated corner.
    fn drop_collapsed(&mut self) {
        let keep: Vec<bool> = self
            .triangles
            .iter()
            .map(|t| t[0] != t[1] && t[1] != t[2] && t[0] != t[2])
            .collect();
        let mut k = keep.iter();
        self.triangles.retain(|_| *k.next().unwrap_or(&true));
        let mut k = keep.iter();
        self.face_of_triangle.retain(|_| *k.next().unwrap_or(&true));
        let mut k = keep.iter();
        self.corner_uv.retain(|_| *k.next().unwrap_or(&true));
    }

    /// One winding for the whole: each face's triangles already agree (counter-clockwise in
    /// its parameter plane), so faces are turned over as wholes until neighbours agree across
    /// their shared boundary edges (CAD faces' own normals need not), then all of them if the
    /// signed volume is negative. Only boundary vertices (below `boundary_count`) are shared.
    fn orient_outward(&mut self, boundary_count: u32, face_count: usize) {
        // Shared edges: (face, runs from the smaller vertex to the larger).
        let mut sides: HashMap<[u32; 2], Vec<(u32, bool)>> = HashMap::new();
        for (t, tri) in self.triangles.iter().enumerate() {
            for k in 0..3 {
                let (a, b) = (tri[k], tri[(k + 1) % 3]);
                if a < boundary_count && b < boundary_count {
                    sides
                        .entry([a.min(b), a.max(b)])
                        .or_default()
                        .push((self.face_of_triangle[t], a < b));
                }
            }
        }
        let mut neighbours: Vec<Vec<(u32, bool)>> = vec![Vec::new(); face_count];
        let mut pairs: Vec<(u32, u32, bool)> = sides
            .into_values()
            .filter(|s| s.len() == 2 && s[0].0 != s[1].0)
            .map(|s| (s[0].0, s[1].0, s[0].1 == s[1].1))
            .collect();
        pairs.sort_unstable();
        pairs.dedup();
        for &(f, g, same) in &pairs {
            neighbours[f as usize].push((g, same));
            neighbours[g as usize].push((f, same));
        }
        // Walk each group of connected faces; `flip[g]` makes g agree with its neighbour (an
        // edge walked the same way by both sides means one of them is turned over).
        let mut flip: Vec<Option<bool>> = vec![None; face_count];
        for start in 0..face_count {
            if flip[start].is_some() {
                continue;
            }
            flip[start] = Some(false);
            let mut stack = vec![start];
            while let Some(f) = stack.pop() {
                let ff = flip[f].unwrap_or(false);
                for &(g, same) in &neighbours[f] {
                    if flip[g as usize].is_none() {
                        flip[g as usize] = Some(ff ^ same);
                        stack.push(g as usize);
                    }
                }
            }
        }
        let o = self
            .positions
            .first()
            .copied()
            .unwrap_or_else(Point3::origin);
        let turned = |t: usize| flip[self.face_of_triangle[t] as usize].unwrap_or(false);
        let volume: f64 = (0..self.triangles.len())
            .map(|t| {
                let [a, b, c] = self.triangles[t].map(|i| self.positions[i as usize] - o);
                let v = a.dot(&b.cross(&c));
                if turned(t) { -v } else { v }
            })
            .sum();
        let all = volume < 0.0;
        for t in 0..self.triangles.len() {
            if turned(t) != all {
                self.triangles[t].swap(1, 2);
                self.corner_uv[t].swap(1, 2);
            }
        }
    }
}

/// Open and non-manifold edges of the mesh, the open ones chained into seams. Only edges
/// between boundary vertices (below `boundary_count`) can be either.
fn seam_report(mesh: &Mesh, boundary_count: u32) -> TessellationReport {
    let mut count: HashMap<[u32; 2], usize> = HashMap::new();
    for tri in &mesh.triangles {
        for k in 0..3 {
            let (a, b) = (tri[k], tri[(k + 1) % 3]);
            if a < boundary_count && b < boundary_count {
                *count.entry([a.min(b), a.max(b)]).or_insert(0) += 1;
            }
        }
    }
    let mut open: Vec<[u32; 2]> = count
        .iter()
        .filter(|(_, n)| **n == 1)
        .map(|(e, _)| *e)
        .collect();
    open.sort_unstable();
    let length =
        |[a, b]: [u32; 2]| (mesh.positions[a as usize] - mesh.positions[b as usize]).norm();
    // Chains: connected components of the open edges.
    let mut sets = DisjointSets::new(mesh.positions.len());
    for &[a, b] in &open {
        sets.union(a, b);
    }
    let mut by_root: BTreeMap<u32, OpenSeam> = BTreeMap::new();
    for &e in &open {
        let root = sets.find(e[0]);
        let p = mesh.positions[root as usize];
        let seam = by_root.entry(root).or_insert(OpenSeam {
            length: 0.0,
            edges: 0,
            at: [p.x, p.y, p.z],
        });
        seam.length += length(e);
        seam.edges += 1;
    }
    let mut open_seams: Vec<OpenSeam> = by_root.into_values().collect();
    open_seams.sort_by(|a, b| b.length.total_cmp(&a.length));
    TessellationReport {
        open_seam_edges: open.len(),
        open_seam_length: open.iter().map(|&e| length(e)).sum::<f64>() + 0.0,
        open_seams,
        non_manifold_edges: count.values().filter(|&&n| n > 2).count(),
        ..TessellationReport::default()
    }
}

/// The measured distance between a tessellation and its surfaces.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct Deviation {
    /// Largest distance found, mm.
    pub max: f64,
    /// Root mean square over the samples, mm.
    pub rms: f64,
    /// Samples taken.
    pub samples: usize,
    /// The face where the largest was found.
    pub worst_face: usize,
}

impl Tessellation {
    /// Measures the deviation two-sided: on every triangle, at `k(k+1)/2`-ish barycentric
    /// samples (`order` steps per side), the distance between the mesh point and the surface
    /// point at the same parameters. That distance bounds both the mesh point's distance to
    /// the surface and the surface point's distance to the mesh, and the samples cover the
    /// whole trimmed region (up to the boundary chords, which sampling bounded).
    pub fn deviation(&self, faces: &[Face], order: usize) -> Deviation {
        let order = order.max(1);
        let per_triangle = |t: usize| -> (f64, f64, usize) {
            let surface = &faces[self.face_of_triangle[t] as usize].surface;
            let uv = self.corner_uv[t];
            let p = self.mesh.corners(t);
            let (mut max, mut sum2, mut n) = (0.0f64, 0.0, 0);
            for i in 0..=order {
                for j in 0..=order - i {
                    let (a, b) = (i as f64 / order as f64, j as f64 / order as f64);
                    let c = 1.0 - a - b;
                    let q = uv[0].coords * a + uv[1].coords * b + uv[2].coords * c;
                    let m = p[0].coords * a + p[1].coords * b + p[2].coords * c;
                    let d = (surface.point(q.x, q.y).coords - m).norm();
                    max = max.max(d);
                    sum2 += d * d;
                    n += 1;
                }
            }
            (max, sum2, n)
        };
        let results: Vec<(f64, f64, usize)> = (0..self.mesh.triangles.len())
            .into_par_iter()
            .map(per_triangle)
            .collect();
        let mut deviation = Deviation::default();
        let mut sum2 = 0.0;
        for (t, (max, s2, n)) in results.into_iter().enumerate() {
            if max > deviation.max {
                deviation.max = max;
                deviation.worst_face = self.face_of_triangle[t] as usize;
            }
            sum2 += s2;
            deviation.samples += n;
        }
        deviation.rms = (sum2 / deviation.samples.max(1) as f64).sqrt();
        deviation
    }

    /// The parameter values of triangle `t`'s corners on its face's surface.
    pub fn corner_parameters(&self, t: usize) -> [Point2<f64>; 3] {
        self.corner_uv[t]
    }
}
