//! The `paths.svg` / `paths.png` picture of `wavemill contour`: the contour-parallel path on
//! the left, the wavelet + loose hull path on the right, each over the stock (outline) and the
//! part (grey). Passes blue, feed links green, rapid links dashed red, the loose hull orange.
//!
//! The PNG is rasterised here (no image crate in the dependency set): segments are sampled at
//! a quarter pixel, the part is filled row by row from its exact scanline crossings, and the
//! file is a plain RGB PNG with stored (uncompressed) deflate blocks.

use std::fmt::Write as _;

use crate::contour::geometry::{Point2, Segment, Shape};
use crate::contour::region::RegionIndex;
use crate::contour::segops::point_at;
use crate::contour::toolpath::{CenterPath, Link};

const PASS: [u8; 3] = [30, 90, 200];
const FEED: [u8; 3] = [20, 150, 60];
const RAPID: [u8; 3] = [210, 40, 40];
const HULL: [u8; 3] = [240, 140, 20];
const STOCK: [u8; 3] = [0, 0, 0];
const PART: [u8; 3] = [170, 170, 170];

/// One picture: two panels side by side.
pub(crate) struct Picture<'a> {
    part: &'a Shape,
    stock: &'a Shape,
    panels: [&'a CenterPath; 2],
    hull: &'a [Point2],
    lo: Point2,
    hi: Point2,
}

impl<'a> Picture<'a> {
    pub(crate) fn new(
        part: &'a Shape,
        stock: &'a Shape,
        parallel: &'a CenterPath,
        wavelet: &'a CenterPath,
        hull: &'a [Point2],
    ) -> Self {
        // Everything the tool centre reaches: the stock grown by r plus a little.
        let r = wavelet.tool_radius().max(parallel.tool_radius());
        let b = RegionIndex::new(stock).boundary().bounds();
        let (lo, hi) = b.map_or((Point2::origin(), Point2::new(1.0, 1.0)), |b| {
            (b.min, b.max)
        });
        let pad = 1.2 * r;
        Self {
            part,
            stock,
            panels: [parallel, wavelet],
            hull,
            lo: Point2::new(lo.x - pad, lo.y - pad),
            hi: Point2::new(hi.x + pad, hi.y + pad),
        }
    }

    fn width(&self) -> f64 {
        (self.hi.x - self.lo.x).max(1e-9)
    }

    fn height(&self) -> f64 {
        (self.hi.y - self.lo.y).max(1e-9)
    }

    /// SVG text, user units = mm, y flipped back to SVG's downward axis.
    pub(crate) fn svg(&self) -> String {
        let (w, h) = (self.width(), self.height());
        let mut out = String::new();
        let _ = writeln!(
            out,
            r#"<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 {:.4} {:.4}" width="{:.0}mm" height="{:.0}mm">"#,
            2.0 * w,
            h + 0.08 * h,
            2.0 * w,
            h * 1.08
        );
        let titles = ["contour-parallel", "wavelet + loose convex hull"];
        for (k, path) in self.panels.iter().enumerate() {
            let dx = k as f64 * w;
            let map = |p: Point2| (p.x - self.lo.x + dx, self.hi.y - p.y + 0.08 * h);
            let stroke = 0.002 * w.max(h);
            let _ = writeln!(
                out,
                r#"<text x="{:.4}" y="{:.4}" font-size="{:.4}" font-family="sans-serif">{}</text>"#,
                dx + 0.02 * w,
                0.05 * h,
                0.04 * h,
                titles[k]
            );
            let shape_d = |shape: &Shape| {
                let mut d = String::new();
                for c in &shape.contours {
                    let segs: Vec<Segment> = c.segments().collect();
                    push_path(&mut d, &segs, &map, true);
                }
                d
            };
            let _ = writeln!(
                out,
                r#"<path d="{}" fill="none" stroke="black" stroke-width="{stroke:.4}"/>"#,
                shape_d(self.stock)
            );
            let _ = writeln!(
                out,
                r#"<path d="{}" fill="rgb(170,170,170)" fill-rule="nonzero" stroke="none"/>"#,
                shape_d(self.part)
            );
            if k == 1 && self.hull.len() >= 3 {
                let pts: Vec<String> = self
                    .hull
                    .iter()
                    .map(|p| {
                        let (x, y) = map(*p);
                        format!("{x:.4},{y:.4}")
                    })
                    .collect();
                let _ = writeln!(
                    out,
                    r#"<polygon points="{}" fill="none" stroke="rgb(240,140,20)" stroke-width="{stroke:.4}"/>"#,
                    pts.join(" ")
                );
            }
            let mut d = String::new();
            for p in path.passes() {
                let segs: Vec<Segment> = p.segments().collect();
                push_path(&mut d, &segs, &map, p.is_closed());
            }
            let _ = writeln!(
                out,
                r#"<path d="{d}" fill="none" stroke="rgb(30,90,200)" stroke-width="{stroke:.4}"/>"#
            );
            for l in path.links() {
                let (a, b) = (map(l.from()), map(l.to()));
                let style = match l {
                    Link::Feed { .. } => "stroke=\"rgb(20,150,60)\"".to_string(),
                    Link::Traverse { .. } => format!(
                        "stroke=\"rgb(20,150,60)\" stroke-dasharray=\"{:.4}\"",
                        4.0 * stroke
                    ),
                    Link::Rapid { .. } => format!(
                        "stroke=\"rgb(210,40,40)\" stroke-dasharray=\"{:.4}\"",
                        4.0 * stroke
                    ),
                };
                let _ = writeln!(
                    out,
                    r#"<line x1="{:.4}" y1="{:.4}" x2="{:.4}" y2="{:.4}" {style} stroke-width="{stroke:.4}"/>"#,
                    a.0, a.1, b.0, b.1
                );
            }
        }
        out.push_str("</svg>\n");
        out
    }

    /// PNG bytes, `width` pixels wide for the two panels together.
    pub(crate) fn png(&self, width: usize) -> Result<Vec<u8>, png::EncodingError> {
        let width = width.max(16);
        let scale = width as f64 / (2.0 * self.width());
        let height = ((self.height() * scale).ceil() as usize).max(8);
        let mut img = Raster::new(width, height);
        for (k, path) in self.panels.iter().enumerate() {
            let dx = k as f64 * self.width();
            let to_px = |p: Point2| ((p.x - self.lo.x + dx) * scale, (self.hi.y - p.y) * scale);
            // Part fill from exact crossings at each row centre.
            let part = RegionIndex::new(self.part);
            for row in 0..height {
                let y = self.hi.y - (row as f64 + 0.5) / scale;
                let mut winding = 0;
                let mut start = 0.0;
                for (x, w) in part.crossings(y) {
                    let before = winding;
                    winding += w;
                    if before == 0 && winding != 0 {
                        start = x;
                    } else if before != 0 && winding == 0 {
                        let (a, _) = to_px(Point2::new(start, y));
                        let (b, _) = to_px(Point2::new(x, y));
                        img.span(row, a, b, PART);
                    }
                }
            }
            for c in &self.stock.contours {
                for seg in c.segments() {
                    img.segment(&seg, &to_px, STOCK);
                }
            }
            if k == 1 {
                let n = self.hull.len();
                for i in 0..n {
                    let seg = Segment::Line {
                        start: self.hull[i],
                        end: self.hull[(i + 1) % n],
                    };
                    img.segment(&seg, &to_px, HULL);
                }
            }
            for p in path.passes() {
                for seg in p.segments() {
                    img.segment(&seg, &to_px, PASS);
                }
            }
            for l in path.links() {
                let seg = Segment::Line {
                    start: l.from(),
                    end: l.to(),
                };
                img.segment(
                    &seg,
                    &to_px,
                    if matches!(l, Link::Feed { .. } | Link::Traverse { .. }) {
                        FEED
                    } else {
                        RAPID
                    },
                );
            }
        }
        img.encode()
    }
}

/// Appends the SVG path commands of a chain of segments (arcs as SVG arcs).
fn push_path(d: &mut String, segs: &[Segment], map: &dyn Fn(Point2) -> (f64, f64), close: bool) {
    let Some(first) = segs.first() else { return };
    let (x, y) = map(point_at(first, 0.0));
    let _ = write!(d, "M{x:.4},{y:.4}");
    for seg in segs {
        let (x, y) = map(point_at(seg, 1.0));
        match *seg {
            Segment::Line { .. } => {
                let _ = write!(d, "L{x:.4},{y:.4}");
            }
            Segment::Arc { radius, sweep, .. } => {
                // y is flipped, so a counter-clockwise arc is drawn with sweep-flag 0.
                let large = u8::from(sweep.abs() > std::f64::consts::PI);
                let flag = u8::from(sweep < 0.0);
                let _ = write!(d, "A{radius:.4},{radius:.4} 0 {large} {flag} {x:.4},{y:.4}");
            }
        }
    }
    if close {
        d.push('Z');
    }
}

/// An RGB raster on white.
struct Raster {
    w: usize,
    h: usize,
    px: Vec<u8>,
}

impl Raster {
    fn new(w: usize, h: usize) -> Self {
        Self {
            w,
            h,
            px: vec![255; w * h * 3],
        }
    }

    fn set(&mut self, x: f64, y: f64, c: [u8; 3]) {
        if x < 0.0 || y < 0.0 {
            return;
        }
        let (i, j) = (x as usize, y as usize);
        if i < self.w && j < self.h {
            let k = 3 * (j * self.w + i);
            self.px[k..k + 3].copy_from_slice(&c);
        }
    }

    fn span(&mut self, row: usize, a: f64, b: f64, c: [u8; 3]) {
        let (lo, hi) = (a.min(b).max(0.0), a.max(b).min(self.w as f64));
        let mut x = lo.round();
        while x < hi {
            self.set(x, row as f64, c);
            x += 1.0;
        }
    }

    fn segment(&mut self, seg: &Segment, to_px: &dyn Fn(Point2) -> (f64, f64), c: [u8; 3]) {
        let (a, b) = (to_px(point_at(seg, 0.0)), to_px(point_at(seg, 1.0)));
        // Pixel length of the segment (arcs: scale the chord by the arc/chord ratio).
        let chord = ((b.0 - a.0).powi(2) + (b.1 - a.1).powi(2)).sqrt();
        let geo_chord = (point_at(seg, 1.0) - point_at(seg, 0.0)).norm();
        let px_len = if geo_chord > 0.0 {
            chord * seg.length() / geo_chord
        } else {
            seg.length()
        };
        let n = ((4.0 * px_len).ceil() as usize).clamp(1, 1_000_000);
        for k in 0..=n {
            let (x, y) = to_px(point_at(seg, k as f64 / n as f64));
            self.set(x, y, c);
        }
    }

    /// The raster as an 8-bit RGB PNG (the `png` crate; deterministic for the same pixels).
    fn encode(&self) -> Result<Vec<u8>, png::EncodingError> {
        super::render::encode_rgb(self.w, self.h, &self.px)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// What is drawn is what a PNG reader reads back, pixel for pixel.
    #[test]
    fn the_png_decodes_to_the_raster() {
        let mut img = Raster::new(17, 9);
        img.set(3.2, 4.7, PASS);
        img.span(8, 1.0, 15.5, PART);
        let bytes = img.encode().expect("encode");
        let mut reader = png::Decoder::new(std::io::Cursor::new(bytes))
            .read_info()
            .expect("a PNG");
        let mut pixels = vec![0; reader.output_buffer_size().expect("size")];
        let info = reader.next_frame(&mut pixels).expect("one frame");
        assert_eq!((info.width, info.height), (17, 9));
        assert_eq!(info.color_type, png::ColorType::Rgb);
        assert_eq!(&pixels[..info.buffer_size()], &img.px[..]);
    }
}
