//! Verification of a 2.5D tool-centre path against the part and the stock (issue #6): exact
//! overcut (clearance), uncut area, and path lengths.
//!
//! * **Clearance** = min over every move made at cutting depth (passes and feed links) of the
//!   signed distance from the tool centre to the part, minus the tool radius r. It is exact for
//!   every segment pair (line–line, line–arc, arc–arc in closed form, [`crate::contour::segops`]) and uses
//!   a BVH over the part boundary. A valid path has clearance ≥ −1e-6 mm; −c means the tool
//!   cuts c mm into the part. When the tool centre itself enters the part the clearance is
//!   −r − depth, the depth being measured at the path vertices inside the part (0 if only an
//!   edge crosses): a conservative, never-positive value with the right sign.
//! * **Uncut area** = area of (stock − part) not swept by the tool disc along the cutting moves
//!   (rapid links are above the stock). Method: scanlines. On each row y the region and the swept
//!   set are computed EXACTLY as unions of x-intervals — the region from exact boundary crossings
//!   (winding numbers), the swept set from the exact row sections of each segment's sweep (a
//!   line sweeps a capsule, an arc an annular sector plus two end discs) — and the uncut length
//!   is their exact difference. Areas are the midpoint rule over rows of spacing h (reported), so
//!   the only approximation is in y; the region's own area is reported for comparison with its
//!   exact value.
//! * **Pass spacing** ([`pass_spacing`]) = sampled distance from each pass to the nearest
//!   pass on its part side: how far apart consecutive passes really are, so that a method
//!   is not credited for a larger effective stepover.
//!
//! Why the contour-parallel levels cover (used by [`crate::contour::parallel`]): let x be at distance t
//! from the part, p its nearest part point. On the segment x→p the distance to the part falls at
//! unit rate, so for any ℓ ∈ (0, t] the point of that segment at distance ℓ is within t − ℓ of x
//! and is a boundary point of the part grown by ℓ (points just beyond it are farther than ℓ):
//! it lies on the level-ℓ pass. Hence level ℓ sweeps x whenever t − r ≤ ℓ ≤ t.

use crate::contour::cavc::validate_shape;
use crate::contour::error::{ContourError, Result, require_positive};
use crate::contour::geometry::{Point2, Segment, Shape, Vector2};
use crate::contour::region::RegionIndex;
use crate::contour::segops::{bbox, seg_end, seg_start, split_arc};
use crate::contour::toolpath::{CenterPath, Link};
use std::f64::consts::FRAC_PI_2;

/// Result of [`clearance`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Clearance {
    /// min (signed distance tool centre → part) − r over the cutting moves, mm; +∞ for a path
    /// without cutting moves. ≥ −1e-6 for a valid path.
    pub clearance: f64,
    /// Tool-centre position where the minimum is attained.
    pub at: Point2,
    /// The part-boundary point nearest to `at`.
    pub part_point: Point2,
    /// Whether the tool centre enters (or touches) the part.
    pub enters_part: bool,
}

/// Exact overcut check of every cutting move of `path` against `part` (see the module docs).
pub fn clearance(path: &CenterPath, part: &Shape) -> Result<Clearance> {
    validate_shape(part, "part")?;
    let r = path.tool_radius();
    let idx = RegionIndex::new(part);
    let mut best = Clearance {
        clearance: f64::INFINITY,
        at: Point2::origin(),
        part_point: Point2::origin(),
        enters_part: false,
    };
    let mut min_d = f64::INFINITY;
    let mut deepest: Option<(f64, Point2, Point2)> = None;
    for seg in path.depth_segments() {
        if let Some(n) = idx.boundary().nearest(&seg)
            && n.distance < min_d
        {
            min_d = n.distance;
            best.at = n.on_query;
            best.part_point = n.on_segment;
        }
        for p in [seg_start(&seg), seg_end(&seg)] {
            if idx.contains(p) {
                let n = idx.boundary().nearest_point(p);
                let (d, q) = n.map_or((0.0, p), |n| (n.distance, n.on_segment));
                if deepest.is_none_or(|b| d > b.0) {
                    deepest = Some((d, p, q));
                }
            }
        }
    }
    if deepest.is_some() || min_d == 0.0 {
        best.enters_part = true;
        match deepest {
            Some((d, p, q)) if d > 0.0 => {
                best.clearance = -r - d;
                best.at = p;
                best.part_point = q;
            }
            _ => best.clearance = -r,
        }
    } else {
        best.clearance = min_d - r;
    }
    Ok(best)
}

/// Largest number of scanline rows [`uncut_area`] accepts.
const MAX_ROWS: usize = 20_000_000;

/// Result of [`uncut_area`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct UncutArea {
    /// Area of (stock − part) not swept by the tool disc, mm².
    pub uncut: f64,
    /// Area of (stock − part) by the same quadrature, mm² (compare with the exact value to
    /// judge the row spacing).
    pub region: f64,
    /// Row spacing h used, mm.
    pub row_step: f64,
    /// Number of rows.
    pub rows: usize,
}

/// A cutting move prepared for row sections: lines as is, arcs in pieces of ≤ 90° (so each
/// piece's angular wedge is convex).
#[derive(Clone, Copy, Debug)]
enum Sweep {
    Line {
        a: Point2,
        b: Point2,
    },
    Arc {
        center: Point2,
        radius: f64,
        lo: Point2,
        hi: Point2,
    },
}

impl Sweep {
    /// The swept shape of one piece of at most a quarter turn; an arc is stored
    /// counter-clockwise (`lo` → `hi`) whatever its direction of travel.
    fn of(piece: Segment) -> Self {
        match piece {
            Segment::Line { start, end } => Sweep::Line { a: start, b: end },
            Segment::Arc {
                start,
                end,
                center,
                radius,
                sweep,
            } => {
                let (lo, hi) = if sweep > 0.0 {
                    (start, end)
                } else {
                    (end, start)
                };
                Sweep::Arc {
                    center,
                    radius,
                    lo,
                    hi,
                }
            }
        }
    }
}

/// Area of `stock − part` left unswept by the tool along the cutting moves of `path`, by exact
/// row sections on rows `row_step` apart (default: the stock's larger bounding-box side / 10 000).
pub fn uncut_area(
    path: &CenterPath,
    part: &Shape,
    stock: &Shape,
    row_step: Option<f64>,
) -> Result<UncutArea> {
    validate_shape(part, "part")?;
    validate_shape(stock, "stock")?;
    let r = path.tool_radius();
    let stock_idx = RegionIndex::new(stock);
    let part_idx = RegionIndex::new(part);
    let Some(sb) = stock_idx.boundary().bounds() else {
        return Err(ContourError::EmptyShape { what: "stock" });
    };
    let (w, hgt) = (sb.max.x - sb.min.x, sb.max.y - sb.min.y);
    let h = row_step.unwrap_or(w.max(hgt) / 10_000.0);
    require_positive("row_step", h, "must be a positive finite number of mm")?;
    let rows_f = (hgt / h).ceil();
    if rows_f > MAX_ROWS as f64 {
        return Err(ContourError::InvalidOption {
            name: "row_step",
            value: h,
            reason: "gives more than 20 000 000 rows over the stock",
        });
    }
    let rows = (rows_f as usize).max(1);
    let h = hgt / rows as f64;

    // Cutting moves, split, sorted by the bottom of their swept box.
    let mut sweeps: Vec<(f64, f64, Sweep)> = Vec::new();
    for seg in path.depth_segments() {
        for piece in split_arc(&seg, FRAC_PI_2) {
            let b = bbox(&piece).expanded(r);
            let sw = Sweep::of(piece);
            sweeps.push((b.min.y, b.max.y, sw));
        }
    }
    sweeps.sort_by(|a, b| a.0.total_cmp(&b.0));

    let mut active: Vec<usize> = Vec::new();
    let mut next = 0usize;
    let (mut uncut, mut region) = (0.0, 0.0);
    let mut cover: Vec<(f64, f64)> = Vec::new();
    for i in 0..rows {
        let y = sb.min.y + (i as f64 + 0.5) * h;
        let inside = region_intervals(&stock_idx, &part_idx, y);
        if inside.is_empty() {
            continue;
        }
        while next < sweeps.len() && sweeps[next].0 <= y {
            active.push(next);
            next += 1;
        }
        active.retain(|&k| sweeps[k].1 >= y);
        cover.clear();
        for &k in &active {
            row_section(&sweeps[k].2, r, y, &mut cover);
        }
        cover.sort_by(|a, b| a.0.total_cmp(&b.0));
        let merged = merge(&cover);
        for &(a, b) in &inside {
            region += (b - a) * h;
            uncut += (b - a - covered_length(&merged, a, b)) * h;
        }
    }
    Ok(UncutArea {
        uncut: uncut.max(0.0),
        region,
        row_step: h,
        rows,
    })
}

/// x-intervals of (stock − part) on row y, sorted and disjoint.
fn region_intervals(stock: &RegionIndex, part: &RegionIndex, y: f64) -> Vec<(f64, f64)> {
    let mut ev: Vec<(f64, i32, bool)> = stock
        .crossings(y)
        .into_iter()
        .map(|(x, d)| (x, d, true))
        .collect();
    if ev.is_empty() {
        return Vec::new();
    }
    ev.extend(part.crossings(y).into_iter().map(|(x, d)| (x, d, false)));
    ev.sort_by(|a, b| a.0.total_cmp(&b.0));
    // Winding left of everything is 0; crossing an upward edge (dir +1) leaving it to the left
    // lowers the winding of points to the right by 1 (winding(x) = −Σ_{x_c ≤ x} dir).
    let (mut ws, mut wp) = (0i32, 0i32);
    let mut out: Vec<(f64, f64)> = Vec::new();
    let mut start = f64::NAN;
    for (x, d, is_stock) in ev {
        let was_in = ws > 0 && wp <= 0;
        if is_stock {
            ws -= d
        } else {
            wp -= d
        }
        let now_in = ws > 0 && wp <= 0;
        if !was_in && now_in {
            start = x;
        } else if was_in && !now_in && x > start {
            out.push((start, x));
        }
    }
    out
}

fn merge(sorted: &[(f64, f64)]) -> Vec<(f64, f64)> {
    let mut out: Vec<(f64, f64)> = Vec::new();
    for &(a, b) in sorted {
        match out.last_mut() {
            Some(last) if a <= last.1 => last.1 = last.1.max(b),
            _ => out.push((a, b)),
        }
    }
    out
}

/// Length of [a, b] covered by sorted disjoint intervals.
fn covered_length(merged: &[(f64, f64)], a: f64, b: f64) -> f64 {
    let start = merged.partition_point(|iv| iv.1 <= a);
    let mut sum = 0.0;
    for &(lo, hi) in &merged[start..] {
        if lo >= b {
            break;
        }
        sum += hi.min(b) - lo.max(a);
    }
    sum.max(0.0)
}

fn intersect(a: (f64, f64), b: (f64, f64)) -> Option<(f64, f64)> {
    let lo = a.0.max(b.0);
    let hi = a.1.min(b.1);
    (lo <= hi).then_some((lo, hi))
}

/// x-range of the closed disc (c, r) on row y.
fn disc(c: Point2, r: f64, y: f64) -> Option<(f64, f64)> {
    let dy = y - c.y;
    let w2 = r * r - dy * dy;
    (w2 >= 0.0).then(|| {
        let w = w2.sqrt();
        (c.x - w, c.x + w)
    })
}

/// x-range of the closed half-plane n·(p − q) ≥ 0 on row y.
fn halfplane(n: Vector2, q: Point2, y: f64) -> Option<(f64, f64)> {
    let rest = n.y * (y - q.y);
    if n.x > 0.0 {
        Some((q.x - rest / n.x, f64::INFINITY))
    } else if n.x < 0.0 {
        Some((f64::NEG_INFINITY, q.x - rest / n.x))
    } else if rest >= 0.0 {
        Some((f64::NEG_INFINITY, f64::INFINITY))
    } else {
        None
    }
}

/// Pushes the x-intervals of row y swept by the disc of radius r along `sw`.
fn row_section(sw: &Sweep, r: f64, y: f64, out: &mut Vec<(f64, f64)>) {
    match *sw {
        Sweep::Line { a, b } => {
            // The capsule is convex: its section is the hull of its three pieces' sections.
            let mut lo = f64::INFINITY;
            let mut hi = f64::NEG_INFINITY;
            let mut add = |iv: Option<(f64, f64)>| {
                if let Some((p, q)) = iv {
                    lo = lo.min(p);
                    hi = hi.max(q);
                }
            };
            add(disc(a, r, y));
            add(disc(b, r, y));
            let d = b - a;
            let l = d.norm();
            if l > 0.0 {
                let nrm = Vector2::new(-d.y, d.x) / l;
                let band = halfplane(d, a, y)
                    .and_then(|iv| halfplane(-d, b, y).and_then(|j| intersect(iv, j)))
                    .and_then(|iv| halfplane(nrm, a - nrm * r, y).and_then(|j| intersect(iv, j)))
                    .and_then(|iv| halfplane(-nrm, a + nrm * r, y).and_then(|j| intersect(iv, j)));
                add(band);
            }
            if lo <= hi {
                out.push((lo, hi));
            }
        }
        Sweep::Arc {
            center,
            radius,
            lo,
            hi,
        } => {
            for p in [lo, hi] {
                if let Some(iv) = disc(p, r, y) {
                    out.push(iv);
                }
            }
            // Annular sector: angle within [lo, hi] (counter-clockwise, ≤ 90°, a convex wedge)
            // and R − r ≤ |p − c| ≤ R + r.
            let (ua, ub) = (lo - center, hi - center);
            let n1 = Vector2::new(-ua.y, ua.x);
            let n2 = Vector2::new(ub.y, -ub.x);
            let Some(wedge) = halfplane(n1, center, y)
                .and_then(|iv| halfplane(n2, center, y).and_then(|j| intersect(iv, j)))
            else {
                return;
            };
            let Some(outer) = disc(center, radius + r, y) else {
                return;
            };
            let pieces = match disc(center, radius - r, y) {
                Some((a, b)) if radius > r => [(outer.0, a), (b, outer.1)],
                _ => [outer, (f64::NAN, f64::NAN)],
            };
            for iv in pieces {
                if iv.0.is_nan() {
                    continue;
                }
                if let Some(x) = intersect(iv, wedge) {
                    out.push(x);
                }
            }
        }
    }
}

/// Lengths and counts of a path.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PathStats {
    /// Number of passes.
    pub passes: usize,
    /// Number of pass segments (lines and arcs).
    pub segments: usize,
    /// Sum of pass lengths, mm (exact arc lengths).
    pub cut_length: f64,
    /// Number and total length of links made at cutting depth.
    pub feed_links: usize,
    pub feed_link_length: f64,
    /// Number and total length of traverses at cutting depth through air.
    pub traverse_links: usize,
    pub traverse_length: f64,
    /// Number and total XY length of retract/rapid/plunge links.
    pub rapid_links: usize,
    pub rapid_link_length: f64,
}

/// Counts and exact lengths of a path.
pub fn path_stats(path: &CenterPath) -> PathStats {
    let mut st = PathStats {
        passes: path.passes().len(),
        ..Default::default()
    };
    for p in path.passes() {
        st.segments += p.segment_count();
        st.cut_length += p.length();
    }
    for l in path.links() {
        match l {
            Link::Feed { .. } => {
                st.feed_links += 1;
                st.feed_link_length += l.length();
            }
            Link::Traverse { .. } => {
                st.traverse_links += 1;
                st.traverse_length += l.length();
            }
            Link::Rapid { .. } => {
                st.rapid_links += 1;
                st.rapid_link_length += l.length();
            }
        }
    }
    st
}

/// Result of [`pass_spacing`].
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PassSpacing {
    /// Largest gap found between a pass and the nearest pass on its part side, mm.
    pub max: f64,
    /// Where on a pass the largest gap was found.
    pub max_at: Point2,
    /// 95th percentile of the same gaps, mm.
    pub p95: f64,
    /// Number of pass samples that had a pass on their part side.
    pub samples: usize,
}

/// How far apart consecutive passes are: every `step` mm along each pass (except where it is
/// within `margin` of the finishing distance r), the distance to the nearest point of another
/// pass that is at least `margin` nearer to the part — the radial engagement the tool meets
/// there. Points of the other passes are the closest points of their segments (exact), so a
/// pass whose closest point is not nearer the part is not counted at that sample. Sampled,
/// for reports: use `margin` ≈ a quarter of the stepover.
pub fn pass_spacing(
    path: &CenterPath,
    part: &Shape,
    step: f64,
    margin: f64,
) -> Result<PassSpacing> {
    validate_shape(part, "part")?;
    if !(step.is_finite() && step > 0.0 && margin.is_finite() && margin >= 0.0) {
        return Err(ContourError::InvalidOption {
            name: "step",
            value: step,
            reason: "step must be a positive and margin a non-negative number of mm",
        });
    }
    let r = path.tool_radius();
    let idx = RegionIndex::new(part);
    let mut segs = Vec::new();
    let mut owner = Vec::new();
    for (i, p) in path.passes().iter().enumerate() {
        for seg in p.segments() {
            segs.push(seg);
            owner.push(i);
        }
    }
    // Each segment's distance range to the part: at least its nearest distance, at most that
    // plus its length (the distance is 1-Lipschitz). Most segments near a sample belong to
    // passes no nearer the part and are settled by the range alone; only the others need the
    // distance of their closest point — on a dense outline (a 3,000-point circle) that query
    // for every segment within reach of every sample made this the slowest step.
    let ranges: Vec<(f64, f64)> = segs
        .iter()
        .map(|seg| {
            let lo = idx
                .boundary()
                .nearest(seg)
                .map_or(f64::INFINITY, |n| n.distance);
            (lo, lo + seg.length())
        })
        .collect();
    let bvh = crate::contour::bvh::SegmentBvh::new(segs);
    let reach = 4.0 * r + 2.0 * margin;
    let mut gaps: Vec<f64> = Vec::new();
    let (mut max_at, mut largest) = (Point2::origin(), f64::NEG_INFINITY);
    for (i, pass) in path.passes().iter().enumerate() {
        for seg in pass.segments() {
            let count = (seg.length() / step).ceil().max(1.0) as usize;
            for k in 0..count {
                let x = crate::contour::segops::point_at(&seg, (k as f64 + 0.5) / count as f64);
                let dx = idx.boundary_distance(x);
                if dx <= r + margin {
                    continue;
                }
                let mut best = f64::INFINITY;
                for j in bvh.candidates_near(&crate::geom::Aabb2::point(x), reach) {
                    let (lo, hi) = ranges[j];
                    if owner[j] == i || lo > dx - margin {
                        continue;
                    }
                    let (d, q) = crate::contour::segops::point_distance(x, &bvh.segments()[j]);
                    if d < best && (hi <= dx - margin || idx.boundary_distance(q) <= dx - margin) {
                        best = d;
                    }
                }
                if best.is_finite() {
                    if best > largest {
                        (largest, max_at) = (best, x);
                    }
                    gaps.push(best);
                }
            }
        }
    }
    gaps.sort_by(f64::total_cmp);
    let n = gaps.len();
    Ok(PassSpacing {
        max: gaps.last().copied().unwrap_or(0.0),
        max_at,
        p95: if n == 0 {
            0.0
        } else {
            gaps[((0.95 * (n - 1) as f64).round() as usize).min(n - 1)]
        },
        samples: n,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contour::geometry::{Contour, Vertex};
    use crate::contour::parallel::tests::{assert_far_side_first, circle, disc_in_square, rect};
    use crate::contour::parallel::{ParallelOptions, contour_parallel};
    use crate::contour::segops::point_distance;
    use crate::contour::toolpath::Pass;
    use std::f64::consts::PI;

    /// L-shaped part (one reflex corner at (8, 8)) in a stock with a 10 mm margin.
    fn l_part() -> (Shape, Shape) {
        let l = Contour {
            vertices: vec![
                Vertex::line(0.0, 0.0),
                Vertex::line(20.0, 0.0),
                Vertex::line(20.0, 8.0),
                Vertex::line(8.0, 8.0),
                Vertex::line(8.0, 20.0),
                Vertex::line(0.0, 20.0),
            ],
        };
        (
            Shape { contours: vec![l] },
            Shape {
                contours: vec![rect(-10.0, -10.0, 30.0, 30.0, true)],
            },
        )
    }

    #[test]
    fn correct_path_has_zero_overcut_and_no_uncut_area() {
        let (part, stock) = disc_in_square(20.0, 30.0);
        let path = contour_parallel(&part, &stock, &ParallelOptions::new(3.0, 4.0)).expect("plan");
        let c = clearance(&path, &part).expect("clearance");
        assert!(c.clearance >= -1e-6 && c.clearance < 1e-6, "{c:?}");
        assert!(!c.enters_part);
        let u = uncut_area(&path, &part, &stock, None).expect("uncut");
        // The quadrature reproduces the exact region area, and nothing is left.
        let exact = 3600.0 - PI * 400.0;
        assert!(
            (u.region - exact).abs() < 2e-6 * exact,
            "{} vs {exact}",
            u.region
        );
        assert!(u.uncut < 1e-6, "{u:?}");
        assert_eq!(u.rows, 10_000);
    }

    #[test]
    fn path_offset_by_r_minus_0_1_overcuts_by_0_1() {
        let (part, stock) = l_part();
        let wrong = contour_parallel(&part, &stock, &ParallelOptions::new(1.9, 1.9)).expect("plan");
        let as_r2 =
            CenterPath::new(2.0, wrong.passes().to_vec(), wrong.links().to_vec()).expect("path");
        let c = clearance(&as_r2, &part).expect("clearance");
        assert!((c.clearance + 0.1).abs() < 1e-9, "{c:?}");
        assert!(!c.enters_part);
        let right = contour_parallel(&part, &stock, &ParallelOptions::new(2.0, 2.0)).expect("plan");
        let c = clearance(&right, &part).expect("clearance");
        assert!(c.clearance >= -1e-6, "{c:?}");
    }

    #[test]
    fn tool_centre_inside_the_part_is_negative_beyond_r() {
        let part = Shape {
            contours: vec![rect(0.0, 0.0, 10.0, 10.0, true)],
        };
        // A pass entering the square to 3 mm deep (vertex at (5, 3)).
        let pass = Pass::open(
            vec![
                Vertex::line(5.0, -4.0),
                Vertex::line(5.0, 3.0),
                Vertex::line(-4.0, 3.0),
            ],
            f64::NAN,
        )
        .expect("pass");
        let path = CenterPath::with_rapid_links(1.0, vec![pass]).expect("path");
        let c = clearance(&path, &part).expect("clearance");
        assert!(c.enters_part);
        assert!((c.clearance - (-1.0 - 3.0)).abs() < 1e-12, "{c:?}");
        // Fully outside: exact distance; a circle arc pass around the corner (10, 10) at 2.5.
        let arc = Pass::open(
            vec![
                Vertex {
                    point: Point2::new(12.5, 10.0),
                    bulge: (PI / 8.0).tan(),
                },
                Vertex::line(10.0, 12.5),
            ],
            2.5,
        )
        .expect("pass");
        let c = clearance(
            &CenterPath::with_rapid_links(1.0, vec![arc]).expect("path"),
            &part,
        )
        .expect("c");
        assert!((c.clearance - 1.5).abs() < 1e-12 && !c.enters_part, "{c:?}");
    }

    #[test]
    fn skipping_one_pass_leaves_the_known_annulus() {
        // Concentric circles: part radius 10, stock disc radius 30, r = 2, s = 3 → passes at
        // radii 12, 15, …, 30. Without the pass at radius 21 (offset 11) the band between
        // 18 + 2 and 24 − 2 is left: π (22² − 20²).
        let part = Shape {
            contours: vec![circle(0.0, 0.0, 10.0, true)],
        };
        let stock = Shape {
            contours: vec![circle(0.0, 0.0, 30.0, true)],
        };
        let path = contour_parallel(&part, &stock, &ParallelOptions::new(2.0, 3.0)).expect("plan");
        let offsets: Vec<f64> = path.passes().iter().map(|p| p.offset()).collect();
        assert_eq!(offsets, vec![20.0, 17.0, 14.0, 11.0, 8.0, 5.0, 2.0]);
        let full = uncut_area(&path, &part, &stock, None).expect("uncut");
        assert!(
            uncut_area(&path, &part, &stock, Some(1e-9)).is_err(),
            "row budget"
        );
        assert!(full.uncut < 1e-6, "{full:?}");
        assert!((full.region - PI * 800.0).abs() < 2e-3, "{full:?}");
        let kept: Vec<Pass> = path
            .passes()
            .iter()
            .filter(|p| p.offset() != 11.0)
            .cloned()
            .collect();
        let skipped = CenterPath::with_rapid_links(2.0, kept).expect("path");
        let u = uncut_area(&skipped, &part, &stock, None).expect("uncut");
        let want = PI * (22.0f64.powi(2) - 20.0f64.powi(2));
        assert!(
            (u.uncut - want).abs() < 1e-4 * want,
            "{} vs {want}",
            u.uncut
        );
    }

    /// Area of {u, v ∈ [0, c], u² + v² ≤ r²} for c ≤ r ≤ c√2.
    fn quarter_disc_in_square(c: f64, r: f64) -> f64 {
        let w = (r * r - c * c).sqrt();
        let f = |u: f64| 0.5 * (u * (r * r - u * u).sqrt() + r * r * (u / r).asin());
        c * w + f(c) - f(w)
    }

    /// Square pocket of side `l` in a 20 mm square part; the stock is the part's outline.
    fn square_pocket(l: f64) -> (Shape, Shape) {
        let (a, b) = (10.0 - l / 2.0, 10.0 + l / 2.0);
        (
            Shape {
                contours: vec![rect(0.0, 0.0, 20.0, 20.0, true), rect(a, a, b, b, false)],
            },
            Shape {
                contours: vec![rect(0.0, 0.0, 20.0, 20.0, true)],
            },
        )
    }

    #[test]
    fn square_pocket_corner_and_cusp_areas_are_exact() {
        let r = 1.0;
        let corners = 4.0 * (1.0 - PI / 4.0) * r * r;
        // s = 1.7 r < (1 + 1/√2) r: consecutive square passes overlap at the corners; only the
        // pocket's own corners (unreachable by a disc) stay. Levels 1, 2.7, 4.4; pocket
        // half-side 4.9 so the last square (half-side 0.5 ≤ r) is swept solid.
        let (part, stock) = square_pocket(9.8);
        let path = contour_parallel(&part, &stock, &ParallelOptions::new(r, 1.7)).expect("plan");
        assert_eq!(path.passes().len(), 3);
        assert_far_side_first(&path, 1.7);
        assert_eq!(
            path.passes()[0].offset(),
            1.0 + 2.0 * 1.7,
            "centre-out in a pocket"
        );
        let u = uncut_area(&path, &part, &stock, Some(0.002)).expect("uncut");
        assert!((u.region - 9.8 * 9.8).abs() < 1e-6, "{u:?}");
        assert!(
            (u.uncut - corners).abs() < 2e-3 * corners,
            "{} vs {corners}",
            u.uncut
        );
        // s = 1.9 r: at each corner of each of the 2 gaps a cusp of c² − A(c, r), c = s − r.
        let (part, stock) = square_pocket(10.6);
        let path = contour_parallel(&part, &stock, &ParallelOptions::new(r, 1.9)).expect("plan");
        assert_eq!(path.passes().len(), 3);
        let c = 0.9;
        let want = corners + 8.0 * (c * c - quarter_disc_in_square(c, r));
        // The passes alone (rapid links, nothing cut between passes) leave exactly that …
        let passes_only = CenterPath::with_rapid_links(r, path.passes().to_vec()).expect("path");
        let u = uncut_area(&passes_only, &part, &stock, Some(0.002)).expect("uncut");
        assert!(
            (u.uncut - want).abs() < 2e-3 * want,
            "{} vs {want}",
            u.uncut
        );
        // … and the planned path's feed links (1.9 mm sideways from the inner square's corner
        // across to the next square, sweeping y ≥ 3.8 there) clear one of the eight cusps.
        let one_cusp = c * c - quarter_disc_in_square(c, r);
        let u = uncut_area(&path, &part, &stock, Some(0.002)).expect("uncut");
        assert!(
            (u.uncut - (want - one_cusp)).abs() < 2e-3 * want,
            "{} vs {}",
            u.uncut,
            want - one_cusp
        );
        assert!(clearance(&path, &part).expect("c").clearance >= -1e-6);
    }

    #[test]
    fn concave_part_with_stepover_r_leaves_only_the_unreachable_corner() {
        let (part, stock) = l_part();
        let r = 2.0;
        let path = contour_parallel(&part, &stock, &ParallelOptions::new(r, r)).expect("plan");
        assert_far_side_first(&path, r);
        let u = uncut_area(&path, &part, &stock, Some(0.004)).expect("uncut");
        assert!((u.region - (1600.0 - 256.0)).abs() < 1e-6, "{u:?}");
        let want = (1.0 - PI / 4.0) * r * r;
        assert!(
            (u.uncut - want).abs() < 2e-3 * want,
            "{} vs {want}",
            u.uncut
        );
        let c = clearance(&path, &part).expect("c");
        assert!(c.clearance.abs() < 1e-6, "{c:?}");
    }

    #[test]
    fn row_sections_match_brute_force_membership() {
        let mut random = crate::geom::SeededRandom::new(99);
        let mut rnd = move |lo: f64, hi: f64| random.range(lo, hi);
        for case in 0..200 {
            let a = Point2::new(rnd(-3.0, 3.0), rnd(-3.0, 3.0));
            let b = Point2::new(rnd(-3.0, 3.0), rnd(-3.0, 3.0));
            let seg = Segment::new(a, b, if case % 4 == 0 { 0.0 } else { rnd(-2.5, 2.5) });
            let r = rnd(0.2, 2.0);
            for piece in split_arc(&seg, FRAC_PI_2) {
                let sw = Sweep::of(piece);
                for _ in 0..5 {
                    let y = rnd(-6.0, 6.0);
                    let mut ivs = Vec::new();
                    row_section(&sw, r, y, &mut ivs);
                    for k in 0..400 {
                        let x = -8.0 + 16.0 * (k as f64 + 0.5) / 400.0;
                        let d = point_distance(Point2::new(x, y), &piece).0;
                        let inside = ivs.iter().any(|iv| iv.0 <= x && x <= iv.1);
                        if (d - r).abs() > 1e-9 {
                            assert_eq!(
                                inside,
                                d < r,
                                "case {case}: x {x} y {y} d {d} r {r} {ivs:?}"
                            );
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn planning_is_deterministic() {
        let (part, stock) = l_part();
        let mut part2 = part.clone();
        part2.contours.push(circle(4.0, 4.0, 2.0, false));
        let o = ParallelOptions::new(1.0, 1.5);
        let a = contour_parallel(&part2, &stock, &o).expect("plan");
        let b = contour_parallel(&part2, &stock, &o).expect("plan");
        assert_eq!(a, b);
        let bits = |p: &CenterPath| -> Vec<u64> {
            p.passes()
                .iter()
                .flat_map(|q| {
                    q.vertices()
                        .iter()
                        .flat_map(|v| [v.point.x.to_bits(), v.point.y.to_bits(), v.bulge.to_bits()])
                })
                .collect()
        };
        assert_eq!(bits(&a), bits(&b));
        let ua = uncut_area(&a, &part2, &stock, Some(0.01)).expect("u");
        let ub = uncut_area(&b, &part2, &stock, Some(0.01)).expect("u");
        assert_eq!(ua.uncut.to_bits(), ub.uncut.to_bits());
    }

    /// The baseline's concentric circles are exactly one stepover apart.
    #[test]
    fn pass_spacing_of_concentric_offsets_is_the_stepover() {
        use crate::contour::parallel::{ParallelOptions, contour_parallel};
        let (part, stock) = disc_in_square(10.0, 16.0);
        let path = contour_parallel(&part, &stock, &ParallelOptions::new(2.0, 1.5)).expect("plan");
        let sp = pass_spacing(&path, &part, 0.5, 0.4).expect("spacing");
        assert!(sp.samples > 100);
        assert!((sp.p95 - 1.5).abs() < 1e-9, "p95 {}", sp.p95);
        assert!((sp.max - 1.5).abs() < 1e-9, "max {}", sp.max);
        assert!(pass_spacing(&path, &part, 0.0, 0.4).is_err());
    }
}
