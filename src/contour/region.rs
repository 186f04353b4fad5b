//! Queries on a planar region ([`Shape`]): exact point-in-region (winding number), distance to
//! the boundary, and the crossings of a horizontal line with the boundary (the scanline used by
//! the uncut-area measure).
//!
//! Crossings use y-monotone pieces (arcs are split at their top and bottom) and the half-open
//! rule "crosses row y when exactly one end has y' ≤ y", so a row through a vertex is counted
//! once and winding numbers stay exact.

use crate::contour::bvh::SegmentBvh;
use crate::contour::geometry::{Point2, Segment, Shape};
use crate::contour::segops::angle_of;
use std::f64::consts::{FRAC_PI_2, PI};

/// A y-monotone piece of a boundary.
#[derive(Clone, Copy, Debug)]
pub(crate) enum Monotone {
    Line {
        a: Point2,
        b: Point2,
    },
    /// Lies on the half of the circle with x ≥ cx (`right`) or x ≤ cx.
    Arc {
        a: Point2,
        b: Point2,
        center: Point2,
        radius: f64,
        right: bool,
    },
}

impl Monotone {
    fn ends(&self) -> (Point2, Point2) {
        match *self {
            Monotone::Line { a, b } | Monotone::Arc { a, b, .. } => (a, b),
        }
    }

    /// Crossing with row `y` under the half-open rule: (x, +1 upward / −1 downward).
    pub(crate) fn crossing(&self, y: f64) -> Option<(f64, i32)> {
        let (a, b) = self.ends();
        if (a.y <= y) == (b.y <= y) {
            return None;
        }
        let dir = if b.y > a.y { 1 } else { -1 };
        let x = match *self {
            Monotone::Line { a, b } => a.x + (y - a.y) * (b.x - a.x) / (b.y - a.y),
            Monotone::Arc {
                center,
                radius,
                right,
                ..
            } => {
                let dy = y - center.y;
                let w = (radius * radius - dy * dy).max(0.0).sqrt();
                if right { center.x + w } else { center.x - w }
            }
        };
        Some((x, dir))
    }

    fn y_range(&self) -> (f64, f64) {
        let (a, b) = self.ends();
        (a.y.min(b.y), a.y.max(b.y))
    }
}

/// Splits a segment into y-monotone pieces.
pub(crate) fn monotone_pieces(s: &Segment, out: &mut Vec<Monotone>) {
    match *s {
        Segment::Line { start, end } => out.push(Monotone::Line { a: start, b: end }),
        Segment::Arc {
            start,
            end,
            center,
            radius,
            sweep,
        } => {
            let a0 = angle_of(center, start);
            // Parameters t ∈ (0, 1) where the angle a0 + t·sweep hits π/2 + kπ (top/bottom).
            let (lo, hi) = if sweep > 0.0 {
                (a0, a0 + sweep)
            } else {
                (a0 + sweep, a0)
            };
            let kmin = ((lo - FRAC_PI_2) / PI).floor() as i64;
            let kmax = ((hi - FRAC_PI_2) / PI).ceil() as i64;
            let mut cuts: Vec<(f64, Point2)> = Vec::new();
            for k in kmin..=kmax {
                let ang = FRAC_PI_2 + k as f64 * PI;
                let t = (ang - a0) / sweep;
                if t > 0.0 && t < 1.0 {
                    let top = k.rem_euclid(2) == 0;
                    let p = Point2::new(
                        center.x,
                        if top {
                            center.y + radius
                        } else {
                            center.y - radius
                        },
                    );
                    cuts.push((t, p));
                }
            }
            cuts.sort_by(|x, y| x.0.total_cmp(&y.0));
            let mut prev = (0.0, start);
            cuts.push((1.0, end));
            for (t, p) in cuts {
                let mid = a0 + 0.5 * (prev.0 + t) * sweep;
                out.push(Monotone::Arc {
                    a: prev.1,
                    b: p,
                    center,
                    radius,
                    right: mid.cos() >= 0.0,
                });
                prev = (t, p);
            }
        }
    }
}

/// Point-location and distance index of a region.
#[derive(Clone, Debug)]
pub struct RegionIndex {
    bvh: SegmentBvh,
    pieces: Vec<Monotone>,
    /// Uniform buckets over y: `buckets[k]` lists the pieces whose y-range meets bucket k.
    y0: f64,
    dy: f64,
    buckets: Vec<Vec<u32>>,
}

impl RegionIndex {
    /// Indexes the boundary of `shape`.
    pub fn new(shape: &Shape) -> Self {
        let segs: Vec<Segment> = shape.contours.iter().flat_map(|c| c.segments()).collect();
        let mut pieces = Vec::new();
        for s in &segs {
            monotone_pieces(s, &mut pieces);
        }
        let (mut ylo, mut yhi) = (f64::INFINITY, f64::NEG_INFINITY);
        for p in &pieces {
            let (a, b) = p.y_range();
            ylo = ylo.min(a);
            yhi = yhi.max(b);
        }
        let nb = pieces.len().clamp(1, 4096);
        let (y0, dy) = if ylo < yhi {
            (ylo, (yhi - ylo) / nb as f64)
        } else {
            (0.0, 1.0)
        };
        let mut buckets = vec![Vec::new(); nb];
        for (i, p) in pieces.iter().enumerate() {
            let (a, b) = p.y_range();
            let k0 = (((a - y0) / dy).floor().max(0.0) as usize).min(nb - 1);
            let k1 = (((b - y0) / dy).floor().max(0.0) as usize).min(nb - 1);
            for bucket in &mut buckets[k0..=k1] {
                bucket.push(i as u32);
            }
        }
        Self {
            bvh: SegmentBvh::new(segs),
            pieces,
            y0,
            dy,
            buckets,
        }
    }

    /// The boundary segments (BVH-indexed).
    pub fn boundary(&self) -> &SegmentBvh {
        &self.bvh
    }

    /// Crossings of the horizontal line at `y` with the boundary: (x, ±1), unsorted.
    pub fn crossings(&self, y: f64) -> Vec<(f64, i32)> {
        let nb = self.buckets.len();
        let k = (y - self.y0) / self.dy;
        if k.is_nan() || k < 0.0 || k > nb as f64 {
            return Vec::new();
        }
        let k = (k.floor() as usize).min(nb - 1);
        self.buckets[k]
            .iter()
            .filter_map(|&i| self.pieces[i as usize].crossing(y))
            .collect()
    }

    /// Winding number of the boundary around `p` (1 inside a region, 0 outside).
    pub fn winding(&self, p: Point2) -> i32 {
        self.crossings(p.y)
            .iter()
            .filter(|c| c.0 > p.x)
            .map(|c| c.1)
            .sum()
    }

    /// Whether `p` is in the region (winding number > 0; boundary points are decided by the
    /// half-open rule).
    pub fn contains(&self, p: Point2) -> bool {
        self.winding(p) > 0
    }

    /// Exact distance from `p` to the boundary (∞ for an empty shape).
    pub fn boundary_distance(&self, p: Point2) -> f64 {
        self.bvh
            .nearest_point(p)
            .map_or(f64::INFINITY, |n| n.distance)
    }

    /// Signed distance: positive outside the region, negative inside.
    pub fn signed_distance(&self, p: Point2) -> f64 {
        let d = self.boundary_distance(p);
        if self.contains(p) { -d } else { d }
    }
}

/// Where and why `inner` does not lie inside `outer`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NotInside {
    pub at: Point2,
    pub reason: &'static str,
}

/// Checks that the region `inner` lies strictly inside the region `outer` (a part inside its
/// stock): the boundaries stay more than `gap` apart, every contour of `inner` starts inside
/// `outer`, and no contour of `outer` (a hole of the stock) starts inside `inner`. With the
/// boundaries apart every contour lies in one face of the other region, so one point per
/// contour decides.
pub fn check_inside(inner: &Shape, outer: &Shape, gap: f64) -> Result<(), NotInside> {
    let (inner_index, outer_index) = (RegionIndex::new(inner), RegionIndex::new(outer));
    for seg in inner.contours.iter().flat_map(|c| c.segments()) {
        if let Some(n) = outer_index.boundary().nearest(&seg)
            && n.distance <= gap
        {
            return Err(NotInside {
                at: n.on_query,
                reason: "touches or crosses the stock outline",
            });
        }
    }
    for c in &inner.contours {
        if let Some(v) = c.vertices.first()
            && !outer_index.contains(v.point)
        {
            return Err(NotInside {
                at: v.point,
                reason: "lies outside the stock outline",
            });
        }
    }
    for c in &outer.contours {
        if let Some(v) = c.vertices.first()
            && inner_index.contains(v.point)
        {
            return Err(NotInside {
                at: v.point,
                reason: "surrounds a hole of the stock outline",
            });
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contour::geometry::{Contour, Vertex};

    fn square(x0: f64, y0: f64, side: f64) -> Contour {
        crate::contour::parallel::tests::rect(x0, y0, x0 + side, y0 + side, true)
    }

    #[test]
    fn part_inside_stock_check() {
        let stock = Shape {
            contours: vec![square(0.0, 0.0, 10.0)],
        };
        let inside = Shape {
            contours: vec![square(2.0, 2.0, 3.0)],
        };
        assert_eq!(check_inside(&inside, &stock, 1e-9), Ok(()));
        let crossing = Shape {
            contours: vec![square(8.0, 2.0, 3.0)],
        };
        let e = check_inside(&crossing, &stock, 1e-9).unwrap_err();
        assert_eq!(e.reason, "touches or crosses the stock outline");
        assert!((e.at.x - 10.0).abs() < 1e-12, "{e:?}");
        let outside = Shape {
            contours: vec![square(20.0, 2.0, 3.0)],
        };
        let e = check_inside(&outside, &stock, 1e-9).unwrap_err();
        assert_eq!(e.reason, "lies outside the stock outline");
        // A stock with a hole where the part is: the part surrounds the hole.
        let hole = crate::contour::parallel::tests::rect(3.0, 3.0, 4.0, 4.0, false);
        let holed = Shape {
            contours: vec![square(0.0, 0.0, 10.0), hole],
        };
        let e = check_inside(&inside, &holed, 1e-9).unwrap_err();
        assert_eq!(e.reason, "surrounds a hole of the stock outline");
    }

    fn disc(cx: f64, cy: f64, r: f64, ccw: bool) -> Contour {
        let b = if ccw { 1.0 } else { -1.0 };
        Contour {
            vertices: vec![
                Vertex {
                    point: Point2::new(cx + r, cy),
                    bulge: b,
                },
                Vertex {
                    point: Point2::new(cx - r, cy),
                    bulge: b,
                },
            ],
        }
    }

    #[test]
    fn winding_of_an_annulus_and_its_scanline_widths() {
        let shape = Shape {
            contours: vec![disc(0.0, 0.0, 3.0, true), disc(0.0, 0.0, 1.0, false)],
        };
        let idx = RegionIndex::new(&shape);
        assert!(!idx.contains(Point2::new(0.0, 0.0)));
        assert!(idx.contains(Point2::new(2.0, 0.5)));
        assert!(!idx.contains(Point2::new(3.5, 0.0)));
        // A row through the centre crosses 4 times; through the top vertex (y = 3) counted once
        // up and once down, or not at all — never unbalanced.
        for y in [0.0, 0.5, 1.0, 2.999, 3.0, -3.0, -1.0] {
            let c = idx.crossings(y);
            assert_eq!(c.iter().map(|c| c.1).sum::<i32>(), 0, "row {y}");
        }
        let mut c = idx.crossings(0.5);
        c.sort_by(|a, b| a.0.total_cmp(&b.0));
        let xs: Vec<f64> = c.iter().map(|c| c.0).collect();
        let w3 = (9.0f64 - 0.25).sqrt();
        let w1 = (1.0f64 - 0.25).sqrt();
        for (x, e) in xs.iter().zip([-w3, -w1, w1, w3]) {
            assert!((x - e).abs() < 1e-12);
        }
        assert!((idx.signed_distance(Point2::new(2.0, 0.0)) + 1.0).abs() < 1e-12);
        assert!((idx.signed_distance(Point2::new(0.0, 0.0)) - 1.0).abs() < 1e-12);
    }
}
