//! Charts: the pieces of the surface between feature lines, and the input patch each level
//! face belongs to.
//!
//! The input's sharp edges cut it into charts (smooth patches). The base keeps every feature
//! line ([`super::feature_lines`]), so its sharp edges cut it into the same charts, and each
//! base face — with all the faces it is later split into — belongs to exactly one input chart.
//! Smooth vertices are projected onto their own chart only: a vertex on one side of a thin
//! blade cannot land on the other side, or on the blade's tip strip, however close they are.

use std::collections::HashMap;

use crate::geom::{Point3, Vector3};
use crate::mesh::Mesh;
use crate::mesh::SurfaceDistance;
use crate::mesh::topology::edges;

use super::feature_lines::FeatureSpans;

/// Labels faces by flood fill across the edges `sharp` does not mark; returns the labels
/// (0, 1, … in order of first face) and their count.
pub(super) fn label_charts(
    triangles: &[[u32; 3]],
    is_sharp: impl Fn(u32, u32) -> bool,
) -> (Vec<u32>, usize) {
    let mut label = vec![u32::MAX; triangles.len()];
    let mut across: Vec<Vec<u32>> = vec![Vec::new(); triangles.len()];
    for e in edges(triangles) {
        if e.faces.len() == 2 && !is_sharp(e.vertices[0], e.vertices[1]) {
            let (f, g) = (e.faces[0].0, e.faces[1].0);
            across[f as usize].push(g);
            across[g as usize].push(f);
        }
    }
    let mut count = 0u32;
    let mut stack = Vec::new();
    for start in 0..triangles.len() {
        if label[start] != u32::MAX {
            continue;
        }
        label[start] = count;
        stack.push(start as u32);
        while let Some(f) = stack.pop() {
            for &g in &across[f as usize] {
                if label[g as usize] == u32::MAX {
                    label[g as usize] = count;
                    stack.push(g);
                }
            }
        }
        count += 1;
    }
    (label, count as usize)
}

/// The input split into charts, each with its own closest-point structure.
pub(super) struct InputCharts {
    /// Chart of every input triangle.
    pub(super) of_triangle: Vec<u32>,
    surfaces: Vec<SurfaceDistance>,
    /// Directed input edge → the triangle that has it.
    half_edges: HashMap<[u32; 2], u32>,
}

impl InputCharts {
    pub(super) fn new(input: &Mesh, input_sharp: &[[u32; 2]]) -> Self {
        let sharp = crate::multires::Creases::from_edges(input_sharp.iter().copied());
        let (of_triangle, count) = label_charts(&input.triangles, |a, b| sharp.contains(a, b));
        let mut members: Vec<Vec<u32>> = vec![Vec::new(); count];
        for (t, &c) in of_triangle.iter().enumerate() {
            members[c as usize].push(t as u32);
        }
        let surfaces = members
            .iter()
            .map(|faces| SurfaceDistance::new(&submesh(input, faces)))
            .collect();
        let mut half_edges = HashMap::with_capacity(input.triangles.len() * 3);
        for (t, tri) in input.triangles.iter().enumerate() {
            for k in 0..3 {
                half_edges.insert([tri[k], tri[(k + 1) % 3]], t as u32);
            }
        }
        Self {
            of_triangle,
            surfaces,
            half_edges,
        }
    }

    /// The closest point to `p` on chart `chart`, preferring triangles that face along
    /// `normal` (the level's normal at the vertex) if they are at most twice as far: a point
    /// just inside a thin rounded wall belongs on the near side, but a bad normal (on a
    /// sliver) must not send it across the chart.
    pub(super) fn closest(&self, chart: u32, p: &Point3, normal: &Vector3) -> Option<Point3> {
        let surface = self.surfaces.get(chart as usize)?;
        let nearest = surface.closest(p, f64::INFINITY)?;
        let reach = 2.0 * nearest.distance;
        let facing = surface
            .closest_where(p, reach, |t| surface.face_normal(t).dot(normal) > 0.0)
            .filter(|c| c.distance <= reach);
        Some(facing.unwrap_or(nearest).point)
    }

    /// The input chart of each base face: across each sharp edge of a base chart lies a run
    /// of input feature edges, and the input triangle on the same side of that run is in the
    /// matching input chart (both meshes are oriented alike). Base charts with no sharp edge
    /// (whole smooth components) take the chart most of their vertices are closest to.
    pub(super) fn of_base_faces(
        &self,
        base: &Mesh,
        base_sharp: &crate::multires::Creases,
        spans: &FeatureSpans,
        whole_input: &SurfaceDistance,
    ) -> Vec<u32> {
        let (base_label, count) = label_charts(&base.triangles, |a, b| base_sharp.contains(a, b));
        let mut votes: Vec<HashMap<u32, usize>> = vec![HashMap::new(); count];
        for (f, tri) in base.triangles.iter().enumerate() {
            for k in 0..3 {
                let (a, b) = (tri[k], tri[(k + 1) % 3]);
                if let Some(edge) = spans.base_input_edge_from(a, b)
                    && let Some(&t) = self.half_edges.get(&edge)
                {
                    *votes[base_label[f] as usize]
                        .entry(self.of_triangle[t as usize])
                        .or_default() += 1;
                }
            }
        }
        for (f, tri) in base.triangles.iter().enumerate() {
            let chart = base_label[f] as usize;
            if !votes[chart].is_empty() {
                continue;
            }
            let mut smooth_votes = HashMap::new();
            for &v in tri {
                if let Some(c) = whole_input.closest(&base.positions[v as usize], f64::INFINITY) {
                    *smooth_votes
                        .entry(self.of_triangle[c.triangle as usize])
                        .or_insert(0usize) += 1;
                }
            }
            for (c, n) in smooth_votes {
                *votes[chart].entry(c).or_default() += n;
            }
        }
        let chosen: Vec<u32> = votes
            .iter()
            .map(|v| {
                v.iter()
                    .max_by(|x, y| x.1.cmp(y.1).then(y.0.cmp(x.0)))
                    .map_or(0, |(&c, _)| c)
            })
            .collect();
        base_label.iter().map(|&l| chosen[l as usize]).collect()
    }
}

/// The triangles `faces` of `mesh` as a mesh of their own.
fn submesh(mesh: &Mesh, faces: &[u32]) -> Mesh {
    let mut index = HashMap::new();
    let mut out = Mesh::default();
    for &f in faces {
        let tri = mesh.triangles[f as usize].map(|v| {
            *index.entry(v).or_insert_with(|| {
                out.positions.push(mesh.positions[v as usize]);
                (out.positions.len() - 1) as u32
            })
        });
        out.triangles.push(tri);
    }
    out
}
