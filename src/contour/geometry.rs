//! Shared 2D geometry of the contour module: closed curves of lines and arcs.

pub use crate::geom::{Point2, Vector2};

/// One vertex of a [`Contour`]: the segment to the next vertex is a line when `bulge == 0`,
/// else a circular arc with `bulge = tan(sweep / 4)`, positive counter-clockwise.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Vertex {
    pub point: Point2,
    pub bulge: f64,
}

impl Vertex {
    /// A vertex followed by a straight segment.
    pub fn line(x: f64, y: f64) -> Self {
        Self {
            point: Point2::new(x, y),
            bulge: 0.0,
        }
    }
}

/// A closed curve of lines and arcs; the closing segment runs from the last vertex to the first.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Contour {
    pub vertices: Vec<Vertex>,
}

/// A planar region: pairwise non-crossing closed contours, the region to the left of each
/// (outer boundaries counter-clockwise, holes clockwise).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Shape {
    pub contours: Vec<Contour>,
}

/// One segment of a contour, resolved: a line or an arc with its centre and radius.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Segment {
    Line {
        start: Point2,
        end: Point2,
    },
    /// `sweep` is signed: positive counter-clockwise, |sweep| < 2π.
    Arc {
        start: Point2,
        end: Point2,
        center: Point2,
        radius: f64,
        sweep: f64,
    },
}

impl Segment {
    /// The segment from `a` to `b` with bulge `bulge`.
    pub fn new(a: Point2, b: Point2, bulge: f64) -> Self {
        let chord = b - a;
        let c = chord.norm();
        if bulge == 0.0 || c == 0.0 {
            return Segment::Line { start: a, end: b };
        }
        let sweep = 4.0 * bulge.atan();
        // Sagitta geometry: radius = c (1 + b²) / (4 |b|); the centre lies on the chord's
        // perpendicular bisector, to the left of a→b for a counter-clockwise arc of < π.
        let radius = c * (1.0 + bulge * bulge) / (4.0 * bulge.abs());
        let mid = nalgebra::center(&a, &b);
        let left = Vector2::new(-chord.y, chord.x) / c;
        // Signed distance from the chord midpoint to the centre along `left`: r cos(sweep / 2),
        // with cos(sweep / 2) = (1 − b²) / (1 + b²); a clockwise arc has its centre on the right.
        let signed = bulge.signum() * radius * (1.0 - bulge * bulge) / (1.0 + bulge * bulge);
        Segment::Arc {
            start: a,
            end: b,
            center: mid + left * signed,
            radius,
            sweep,
        }
    }

    /// Length of the segment.
    pub fn length(&self) -> f64 {
        match *self {
            Segment::Line { start, end } => (end - start).norm(),
            Segment::Arc { radius, sweep, .. } => radius * sweep.abs(),
        }
    }
}

impl Contour {
    /// The contour's segments in order, the closing one last.
    pub fn segments(&self) -> impl Iterator<Item = Segment> + '_ {
        let n = self.vertices.len();
        (0..n).map(move |i| {
            let (a, b) = (self.vertices[i], self.vertices[(i + 1) % n]);
            Segment::new(a.point, b.point, a.bulge)
        })
    }

    /// Signed area, exact for arcs: positive when counter-clockwise.
    pub fn signed_area(&self) -> f64 {
        self.segments()
            .map(|s| match s {
                Segment::Line { start, end } => 0.5 * (start.x * end.y - end.x * start.y),
                Segment::Arc {
                    start,
                    end,
                    radius,
                    sweep,
                    ..
                } => {
                    // Chord triangle term plus the circular segment between chord and arc.
                    0.5 * (start.x * end.y - end.x * start.y)
                        + 0.5 * radius * radius * (sweep - sweep.sin())
                }
            })
            .sum()
    }

    /// Total length.
    pub fn length(&self) -> f64 {
        self.segments().map(|s| s.length()).sum()
    }
}
