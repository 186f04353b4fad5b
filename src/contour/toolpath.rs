//! Tool-centre paths for 2.5D milling with a flat end mill: passes (chains of lines and arcs
//! of the tool CENTRE at the cutting depth) in cutting order, joined by links.
//!
//! These types are method-neutral: the contour-parallel baseline ([`crate::contour::parallel`]) and the
//! multiresolution paths of seed 004 (chapters 3–4) both produce a [`CenterPath`], which is then
//! verified ([`crate::contour::verify`]) and posted as G-code ([`crate::post::contour`]).

use crate::contour::error::{ContourError, Result, require_positive};
use crate::contour::geometry::{Point2, Segment, Vertex};

/// Tolerance for "the link starts where the pass ends", mm.
const JOIN_TOL: f64 = 1e-9;

/// One cutting pass: a chain of lines and arcs traced by the tool centre at the cutting depth.
///
/// `vertices[i].bulge` describes the segment from vertex `i` to vertex `i + 1` (shared
/// convention of [`crate::contour::geometry`]); a closed pass also runs from the last vertex back to the
/// first, an open pass ignores the last vertex's bulge.
#[derive(Clone, Debug, PartialEq)]
pub struct Pass {
    vertices: Vec<Vertex>,
    closed: bool,
    /// Distance from the part this pass was offset by (informative; `NaN` when unknown).
    offset: f64,
}

impl Pass {
    /// An open pass from `vertices[0]` to the last vertex. Needs ≥ 2 vertices.
    pub fn open(mut vertices: Vec<Vertex>, offset: f64) -> Result<Self> {
        if vertices.len() < 2 {
            return Err(ContourError::BadPath(format!(
                "an open pass needs 2 vertices, got {}",
                vertices.len()
            )));
        }
        check_finite(&vertices)?;
        if let Some(last) = vertices.last_mut() {
            last.bulge = 0.0;
        }
        Ok(Self {
            vertices,
            closed: false,
            offset,
        })
    }

    /// A closed pass (returns to `vertices[0]`). Needs ≥ 2 vertices.
    pub fn closed(vertices: Vec<Vertex>, offset: f64) -> Result<Self> {
        if vertices.len() < 2 {
            return Err(ContourError::BadPath(format!(
                "a closed pass needs 2 vertices, got {}",
                vertices.len()
            )));
        }
        check_finite(&vertices)?;
        Ok(Self {
            vertices,
            closed: true,
            offset,
        })
    }

    /// The vertices (see the type's docs for the bulge convention).
    pub fn vertices(&self) -> &[Vertex] {
        &self.vertices
    }

    /// Whether the pass returns to its start.
    pub fn is_closed(&self) -> bool {
        self.closed
    }

    /// The offset distance from the part this pass was generated at (NaN if unknown).
    pub fn offset(&self) -> f64 {
        self.offset
    }

    /// Number of segments (NC blocks when posted).
    pub fn segment_count(&self) -> usize {
        if self.closed {
            self.vertices.len()
        } else {
            self.vertices.len() - 1
        }
    }

    /// The segments in cutting order.
    pub fn segments(&self) -> impl Iterator<Item = Segment> + '_ {
        let n = self.vertices.len();
        (0..self.segment_count()).map(move |i| {
            let (a, b) = (self.vertices[i], self.vertices[(i + 1) % n]);
            Segment::new(a.point, b.point, a.bulge)
        })
    }

    /// Where the tool enters the pass.
    pub fn start(&self) -> Point2 {
        self.vertices[0].point
    }

    /// Where the tool leaves the pass.
    pub fn end(&self) -> Point2 {
        if self.closed {
            self.vertices[0].point
        } else {
            self.vertices[self.vertices.len() - 1].point
        }
    }

    /// The same path run the other way (bulges negated); a closed pass keeps its start.
    pub fn reversed(&self) -> Pass {
        let n = self.vertices.len();
        let vertices = if self.closed {
            // Vertex k is old vertex n − k; its segment runs back along old segment n − k − 1.
            (0..n)
                .map(|k| Vertex {
                    point: self.vertices[(n - k) % n].point,
                    bulge: -self.vertices[(2 * n - k - 1) % n].bulge,
                })
                .collect()
        } else {
            (0..n)
                .map(|k| Vertex {
                    point: self.vertices[n - 1 - k].point,
                    bulge: if k + 1 < n {
                        -self.vertices[n - 2 - k].bulge
                    } else {
                        0.0
                    },
                })
                .collect()
        };
        Pass {
            vertices,
            closed: self.closed,
            offset: self.offset,
        }
    }

    /// Exact length (arc lengths are R·|sweep|).
    pub fn length(&self) -> f64 {
        self.segments().map(|s| s.length()).sum()
    }
}

fn check_finite(vertices: &[Vertex]) -> Result<()> {
    match vertices
        .iter()
        .position(|v| !(v.point.x.is_finite() && v.point.y.is_finite() && v.bulge.is_finite()))
    {
        Some(i) => Err(ContourError::BadPath(format!(
            "pass vertex {i} is not finite"
        ))),
        None => Ok(()),
    }
}

/// Which way the passes run. With a clockwise (M3) spindle a pass that keeps the part, and so
/// the material it cuts, on its right is climb milling (the teeth meet the feed; the cutter is
/// left of the wall, as G41): the opposite of the offset loops' orientation.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum CutDirection {
    /// Every pass keeps the part on its right: climb milling everywhere.
    Climb,
    /// Open roughing passes (offset loops cut off by the stock or the hull) are entered at
    /// whichever end is nearer the tool, so neighbouring fragments join by a short link at
    /// depth instead of a retract, rapid and plunge — zig-zag, half of them conventional.
    /// Closed passes and the finishing passes (level r) stay climb.
    #[default]
    Mixed,
}

/// How the tool gets from the end of one pass to the start of the next.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Link {
    /// A straight move at cutting depth and feed rate (it cuts, so it is verified like a pass).
    Feed { from: Point2, to: Point2 },
    /// A straight move at cutting depth through air beside the stock, at the rapid rate
    /// (posted as G1 at the rapid feed: a G0 need not move in a straight line). The planners
    /// make one only where the move stays within the envelope the passes already use (the
    /// stock grown by r) and at least r from the stock, so it cuts nothing.
    Traverse { from: Point2, to: Point2 },
    /// Retract to the safe height, rapid (G0) above `to`, plunge back to cutting depth.
    Rapid { from: Point2, to: Point2 },
}

impl Link {
    /// Start point (end of the previous pass).
    pub fn from(&self) -> Point2 {
        match *self {
            Link::Feed { from, .. } | Link::Traverse { from, .. } | Link::Rapid { from, .. } => {
                from
            }
        }
    }

    /// End point (start of the next pass).
    pub fn to(&self) -> Point2 {
        match *self {
            Link::Feed { to, .. } | Link::Traverse { to, .. } | Link::Rapid { to, .. } => to,
        }
    }

    /// XY length of the link.
    pub fn length(&self) -> f64 {
        (self.to() - self.from()).norm()
    }

    /// The link as a segment, when the tool makes it at cutting depth.
    pub fn depth_segment(&self) -> Option<Segment> {
        match *self {
            Link::Feed { from, to } | Link::Traverse { from, to } => Some(Segment::Line {
                start: from,
                end: to,
            }),
            Link::Rapid { .. } => None,
        }
    }
}

/// A complete 2.5D tool-centre path: passes in cutting order; `links[i]` joins the end of
/// `passes[i]` to the start of `passes[i + 1]`.
#[derive(Clone, Debug, PartialEq)]
pub struct CenterPath {
    tool_radius: f64,
    passes: Vec<Pass>,
    links: Vec<Link>,
}

impl CenterPath {
    /// Checks the invariants: positive finite tool radius, one link between each pair of
    /// consecutive passes, starting where the pass ends and ending where the next one starts.
    pub fn new(tool_radius: f64, passes: Vec<Pass>, links: Vec<Link>) -> Result<Self> {
        require_positive(
            "tool_radius",
            tool_radius,
            "must be a positive finite number of mm",
        )?;
        if links.len() != passes.len().saturating_sub(1) {
            return Err(ContourError::BadPath(format!(
                "{} passes need {} links, got {}",
                passes.len(),
                passes.len().saturating_sub(1),
                links.len()
            )));
        }
        for (i, l) in links.iter().enumerate() {
            let (e, s) = (passes[i].end(), passes[i + 1].start());
            if (l.from() - e).norm() > JOIN_TOL || (l.to() - s).norm() > JOIN_TOL {
                return Err(ContourError::BadPath(format!(
                    "link {i} runs ({}, {}) → ({}, {}) but pass {i} ends at ({}, {}) and pass {} \
                     starts at ({}, {})",
                    l.from().x,
                    l.from().y,
                    l.to().x,
                    l.to().y,
                    e.x,
                    e.y,
                    i + 1,
                    s.x,
                    s.y
                )));
            }
        }
        Ok(Self {
            tool_radius,
            passes,
            links,
        })
    }

    /// Joins consecutive passes with retract/rapid/plunge links (no cutting between passes).
    pub fn with_rapid_links(tool_radius: f64, passes: Vec<Pass>) -> Result<Self> {
        let links = passes
            .windows(2)
            .map(|w| Link::Rapid {
                from: w[0].end(),
                to: w[1].start(),
            })
            .collect();
        Self::new(tool_radius, passes, links)
    }

    /// Radius of the flat end mill the path is planned for.
    pub fn tool_radius(&self) -> f64 {
        self.tool_radius
    }

    /// The passes in cutting order.
    pub fn passes(&self) -> &[Pass] {
        &self.passes
    }

    /// The links; `links()[i]` joins pass `i` to pass `i + 1`.
    pub fn links(&self) -> &[Link] {
        &self.links
    }

    /// Every move made at cutting depth, in order: pass segments, feed links and traverses.
    pub fn depth_segments(&self) -> Vec<Segment> {
        let mut out = Vec::new();
        for (i, p) in self.passes.iter().enumerate() {
            out.extend(p.segments());
            if let Some(s) = self.links.get(i).and_then(Link::depth_segment) {
                out.push(s);
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contour::segops::{point_at, point_distance};
    use std::f64::consts::PI;

    /// A reversed pass runs through the same points the other way: every point of the
    /// reversed pass at parameter t of segment k is on the original's mirrored segment, the
    /// ends swap (open) or stay (closed), lengths and turning sense flip consistently.
    #[test]
    fn reversed_passes_trace_the_same_curve_backwards() {
        let v = vec![
            Vertex {
                point: Point2::new(0.0, 0.0),
                bulge: 0.4,
            },
            Vertex::line(4.0, 1.0),
            Vertex {
                point: Point2::new(5.0, 3.0),
                bulge: -0.7,
            },
            Vertex::line(1.0, 4.0),
        ];
        for closed in [false, true] {
            let pass = if closed {
                Pass::closed(v.clone(), 2.0)
            } else {
                Pass::open(v.clone(), 2.0)
            }
            .expect("pass");
            let back = pass.reversed();
            assert_eq!(back.segment_count(), pass.segment_count());
            assert!((back.length() - pass.length()).abs() < 1e-12);
            assert_eq!(back.start(), pass.end());
            assert_eq!(back.end(), pass.start());
            assert_eq!(back.reversed(), pass);
            let fwd: Vec<Segment> = pass.segments().collect();
            let bwd: Vec<Segment> = back.segments().collect();
            let m = fwd.len();
            for (k, seg) in bwd.iter().enumerate() {
                let original = &fwd[m - 1 - k];
                for t in [0.0, 0.3, 0.5, 0.9, 1.0] {
                    let p = point_at(seg, t);
                    let q = point_at(original, 1.0 - t);
                    assert!(
                        (p - q).norm() < 1e-12,
                        "closed {closed}, segment {k}, t {t}"
                    );
                    assert!(point_distance(p, original).0 < 1e-12);
                }
            }
        }
    }

    #[test]
    fn pass_lengths_and_links_are_checked() {
        let circle = Pass::closed(
            vec![
                Vertex {
                    point: Point2::new(1.0, 0.0),
                    bulge: 1.0,
                },
                Vertex {
                    point: Point2::new(-1.0, 0.0),
                    bulge: 1.0,
                },
            ],
            1.0,
        )
        .expect("pass");
        assert!((circle.length() - 2.0 * PI).abs() < 1e-12);
        assert_eq!(circle.segment_count(), 2);
        assert_eq!(circle.end(), circle.start());
        let line = Pass::open(
            vec![
                Vertex::line(3.0, 0.0),
                Vertex {
                    point: Point2::new(5.0, 0.0),
                    bulge: 9.0,
                },
            ],
            2.0,
        )
        .expect("pass");
        assert_eq!(
            line.vertices()[1].bulge,
            0.0,
            "last bulge of an open pass is ignored"
        );
        assert_eq!(line.length(), 2.0);
        let ok =
            CenterPath::with_rapid_links(0.5, vec![circle.clone(), line.clone()]).expect("path");
        assert_eq!(ok.links().len(), 1);
        let bad = CenterPath::new(
            0.5,
            vec![circle, line],
            vec![Link::Feed {
                from: Point2::new(1.0, 0.0),
                to: Point2::new(3.0, 0.1),
            }],
        );
        assert!(matches!(bad, Err(ContourError::BadPath(_))));
        assert!(Pass::open(vec![Vertex::line(0.0, 0.0)], 0.0).is_err());
        assert!(CenterPath::new(0.0, vec![], vec![]).is_err());
    }
}
