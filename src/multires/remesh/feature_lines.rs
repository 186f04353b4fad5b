//! The input's feature lines, followed exactly by the hierarchy's sharp edges.
//!
//! The base mesh's sharp edges (creases and boundary edges) run through input vertices: the
//! collapse moves a feature vertex only along its feature line, onto another input vertex
//! ([`super::super::simplify`]). So each base sharp edge stands for a run of input feature
//! edges — a polyline on the input. Every later level splits a sharp edge at the arc-length
//! midpoint of its run; the two halves take the two halves of the run. Sharp vertices thus
//! sit exactly on the input's feature lines, evenly spread along them, and can never jump to a
//! neighbouring feature line (the other edge of a blade tip a quarter millimetre away): the
//! closest-point alternative did, and folded the levels.

use std::collections::HashMap;

use crate::geom::Point3;
use crate::mesh::Mesh;

use super::RemeshError;

/// A run of input feature edges: its input vertices in order and their arc lengths.
#[derive(Clone, Debug)]
struct Run {
    vertices: Vec<u32>,
    points: Vec<Point3>,
    arc_length: Vec<f64>,
}

impl Run {
    /// The point at arc length `s` (clamped to the run).
    fn at(&self, s: f64) -> Point3 {
        let total = self.arc_length.last().copied().unwrap_or(0.0);
        let s = s.clamp(0.0, total);
        // First index whose arc length is ≥ s; the point lies on the segment ending there.
        let i = self.arc_length.partition_point(|&a| a < s).max(1);
        if i >= self.points.len() {
            return self.points.last().copied().unwrap_or_else(Point3::origin);
        }
        let (s0, s1) = (self.arc_length[i - 1], self.arc_length[i]);
        let t = if s1 > s0 { (s - s0) / (s1 - s0) } else { 0.0 };
        self.points[i - 1] + (self.points[i] - self.points[i - 1]) * t
    }
}

/// The part of a run one sharp edge `[a, b]` (`a < b`) of a level stands for: arc length at
/// `a` and at `b` (either order).
#[derive(Clone, Copy, Debug, PartialEq)]
struct Span {
    run: u32,
    at_low: f64,
    at_high: f64,
}

/// The sharp edges of the current level and the input runs they follow.
#[derive(Clone, Debug)]
pub(super) struct FeatureSpans {
    runs: Vec<Run>,
    spans: HashMap<[u32; 2], Span>,
}

impl FeatureSpans {
    /// Matches every sharp edge of the base (`base_sharp`, `[min, max]`, creases and boundary
    /// edges) with the input run between its endpoints' input vertices (`origin`), walking
    /// along the input's sharp edges (`input_sharp`).
    ///
    /// # Errors
    /// When a base sharp edge has no such run: the base's feature lines do not follow the
    /// input's (a bug in the base mesh, reported rather than fitted wrongly).
    pub(super) fn new(
        input: &Mesh,
        input_sharp: &[[u32; 2]],
        base_sharp: &[[u32; 2]],
        origin: &[u32],
    ) -> Result<Self, RemeshError> {
        let n = input.positions.len();
        let mut neighbours = vec![Vec::new(); n];
        for &[a, b] in input_sharp {
            neighbours[a as usize].push(b);
            neighbours[b as usize].push(a);
        }
        for list in &mut neighbours {
            list.sort_unstable();
        }
        let mut in_base = vec![false; n];
        for &v in origin {
            in_base[v as usize] = true;
        }
        let mut runs = Vec::with_capacity(base_sharp.len());
        let mut spans = HashMap::with_capacity(base_sharp.len());
        for &[a, b] in base_sharp {
            let (from, to) = (origin[a as usize], origin[b as usize]);
            let vertices = shortest_walk(&neighbours, &in_base, from, to)
                .ok_or(RemeshError::FeatureLines { edge: [from, to] })?;
            let points: Vec<Point3> = vertices
                .iter()
                .map(|&v| input.positions[v as usize])
                .collect();
            let mut arc_length = Vec::with_capacity(points.len());
            let mut s = 0.0;
            for (i, p) in points.iter().enumerate() {
                if i > 0 {
                    s += (p - points[i - 1]).norm();
                }
                arc_length.push(s);
            }
            spans.insert(
                [a, b],
                Span {
                    run: runs.len() as u32,
                    at_low: 0.0,
                    at_high: s,
                },
            );
            runs.push(Run {
                vertices,
                points,
                arc_length,
            });
        }
        Ok(Self { runs, spans })
    }

    /// On the base level: the input edge of sharp edge `{a, b}`'s run that leaves `a`'s end,
    /// directed away from `a` (input vertex indices); `None` if `{a, b}` is not sharp.
    pub(super) fn base_input_edge_from(&self, a: u32, b: u32) -> Option<[u32; 2]> {
        let span = self.spans.get(&[a.min(b), a.max(b)])?;
        let run = &self.runs[span.run as usize];
        let v = &run.vertices;
        let a_at_start = (if a < b { span.at_low } else { span.at_high }) == 0.0;
        if v.len() < 2 {
            return None;
        }
        Some(if a_at_start {
            [v[0], v[1]]
        } else {
            [v[v.len() - 1], v[v.len() - 2]]
        })
    }

    /// Splits every sharp edge at its run's arc-length midpoint, for the level whose coarse
    /// edges are `edges` (`[min, max]`, sorted; odd vertex of edge k is `coarse_vertices + k`).
    /// Writes the odd vertices' positions into `positions`; the spans become the next level's.
    pub(super) fn split(
        &mut self,
        edges: &[[u32; 2]],
        coarse_vertices: usize,
        positions: &mut [Point3],
    ) {
        let mut spans = HashMap::with_capacity(self.spans.len() * 2);
        for (&[a, b], span) in &self.spans {
            let Ok(k) = edges.binary_search(&[a, b]) else {
                continue;
            };
            let odd = (coarse_vertices + k) as u32;
            let middle = 0.5 * (span.at_low + span.at_high);
            positions[odd as usize] = self.runs[span.run as usize].at(middle);
            // The odd vertex has a higher index than every coarse vertex.
            spans.insert(
                [a, odd],
                Span {
                    run: span.run,
                    at_low: span.at_low,
                    at_high: middle,
                },
            );
            spans.insert(
                [b, odd],
                Span {
                    run: span.run,
                    at_low: span.at_high,
                    at_high: middle,
                },
            );
        }
        self.spans = spans;
    }
}

/// The shortest walk along sharp edges from `from` to `to` that passes through no other base
/// vertex (`in_base`), as input vertices from `from` to `to`.
fn shortest_walk(
    neighbours: &[Vec<u32>],
    in_base: &[bool],
    from: u32,
    to: u32,
) -> Option<Vec<u32>> {
    let mut best: Option<Vec<u32>> = None;
    for &first in &neighbours[from as usize] {
        let mut walk = vec![from];
        let (mut previous, mut current) = (from, first);
        loop {
            walk.push(current);
            if in_base[current as usize] || walk.len() > neighbours.len() {
                break;
            }
            // A vertex inside a run has exactly two sharp edges (the collapse removes no
            // other feature vertex); go on along the one we did not come from.
            let next = neighbours[current as usize]
                .iter()
                .copied()
                .find(|&x| x != previous);
            match next {
                Some(x) if neighbours[current as usize].len() == 2 => {
                    previous = current;
                    current = x;
                }
                _ => break,
            }
        }
        if current == to && best.as_ref().is_none_or(|b| walk.len() < b.len()) {
            best = Some(walk);
        }
    }
    best
}
