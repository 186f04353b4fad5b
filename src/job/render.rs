//! Pictures of coloured meshes (`stock.png`): orthographic views rasterised with a depth
//! buffer and flat shading, side by side, with a legend of colour swatches and their values.
//!
//! A viewer is better for turning a part over; the picture is what a user or a CI log looks at
//! first, so it is plain, deterministic (no threads, no clock) and needs no GPU.

use crate::geom::{Point3, Vector3};
use crate::mesh::Mesh;

/// An 8-bit RGB image, white to start with.
pub(crate) struct Canvas {
    pub w: usize,
    pub h: usize,
    pub px: Vec<u8>,
}

impl Canvas {
    pub fn new(w: usize, h: usize) -> Self {
        Canvas {
            w,
            h,
            px: vec![255; w * h * 3],
        }
    }

    pub(crate) fn put(&mut self, x: usize, y: usize, c: [u8; 3]) {
        if x < self.w && y < self.h {
            let k = 3 * (y * self.w + x);
            self.px[k..k + 3].copy_from_slice(&c);
        }
    }

    pub(crate) fn fill(&mut self, x0: usize, y0: usize, w: usize, h: usize, c: [u8; 3]) {
        for y in y0..y0 + h {
            for x in x0..x0 + w {
                self.put(x, y, c);
            }
        }
    }

    /// The canvas as an 8-bit RGB PNG (the `png` crate; the same pixels give the same bytes).
    pub fn png(&self) -> Result<Vec<u8>, png::EncodingError> {
        encode_rgb(self.w, self.h, &self.px)
    }

    /// `text` in a 3×5 pixel font scaled by `scale`, its top left at `(x, y)`; characters the
    /// font lacks are left as spaces.
    pub(crate) fn text(&mut self, x: usize, y: usize, text: &str, scale: usize, c: [u8; 3]) {
        for (k, ch) in text.chars().enumerate() {
            let Some(rows) = glyph(ch) else { continue };
            for (r, bits) in rows.iter().enumerate() {
                for col in 0..3 {
                    if bits & (0b100 >> col) != 0 {
                        let (px, py) = (x + (4 * k + col) * scale, y + r * scale);
                        self.fill(px, py, scale, scale, c);
                    }
                }
            }
        }
    }
}

/// An 8-bit RGB PNG of `w` × `h` pixels.
pub(crate) fn encode_rgb(w: usize, h: usize, px: &[u8]) -> Result<Vec<u8>, png::EncodingError> {
    let mut out = Vec::new();
    let mut encoder = png::Encoder::new(&mut out, w as u32, h as u32);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    let mut writer = encoder.write_header()?;
    writer.write_image_data(px)?;
    writer.finish()?;
    Ok(out)
}

/// 3×5 glyphs, a row per entry, the high bit on the left.
fn glyph(c: char) -> Option<[u8; 5]> {
    Some(match c {
        '0' => [7, 5, 5, 5, 7],
        '1' => [2, 6, 2, 2, 7],
        '2' => [7, 1, 7, 4, 7],
        '3' => [7, 1, 7, 1, 7],
        '4' => [5, 5, 7, 1, 1],
        '5' => [7, 4, 7, 1, 7],
        '6' => [7, 4, 7, 5, 7],
        '7' => [7, 1, 1, 1, 1],
        '8' => [7, 5, 7, 5, 7],
        '9' => [7, 5, 7, 1, 7],
        '.' => [0, 0, 0, 0, 2],
        '-' => [0, 0, 7, 0, 0],
        '+' => [0, 2, 7, 2, 0],
        '<' => [1, 2, 4, 2, 1],
        '>' => [4, 2, 1, 2, 4],
        'm' => [0, 0, 7, 7, 5],
        // Small capitals, enough for the legends' words.
        'a' => [2, 5, 7, 5, 5],
        'c' => [7, 4, 4, 4, 7],
        'd' => [6, 5, 5, 5, 6],
        'e' => [7, 4, 6, 4, 7],
        'h' => [5, 5, 7, 5, 5],
        'n' => [6, 5, 5, 5, 5],
        'o' => [2, 5, 5, 5, 2],
        'r' => [6, 5, 6, 5, 5],
        'u' => [5, 5, 5, 5, 7],
        'w' => [5, 5, 5, 7, 5],
        _ => return None,
    })
}

/// A view: the direction from the part towards the eye and the direction shown upwards.
#[derive(Clone, Copy, Debug)]
pub(crate) struct View {
    pub towards_eye: Vector3,
    pub up: Vector3,
}

/// The views `stock.png` shows: from above, and from the front-right, above.
pub(crate) const VIEWS: [([f64; 3], [f64; 3]); 2] = [
    ([0.0, 0.0, 1.0], [0.0, 1.0, 0.0]),
    ([1.0, -1.0, 0.8], [0.0, 0.0, 1.0]),
];

/// Draws `mesh` (coloured per vertex, linear RGB 0..1) from `view` into the panel of `canvas`
/// at `(x0, y0)`, `size` pixels square, filling it with a margin.
pub(crate) fn draw_mesh(
    canvas: &mut Canvas,
    (x0, y0, size): (usize, usize, usize),
    mesh: &Mesh,
    colours: &[[f32; 4]],
    view: &View,
) {
    let eye = view.towards_eye.normalize();
    let right = view.up.cross(&eye).normalize();
    let up = eye.cross(&right);
    let project = |p: &Point3| (p.coords.dot(&right), p.coords.dot(&up), p.coords.dot(&eye));
    let projected: Vec<(f64, f64, f64)> = mesh.positions.iter().map(project).collect();
    let (mut lo, mut hi) = (
        (f64::INFINITY, f64::INFINITY),
        (f64::NEG_INFINITY, f64::NEG_INFINITY),
    );
    for (x, y, _) in &projected {
        lo = (lo.0.min(*x), lo.1.min(*y));
        hi = (hi.0.max(*x), hi.1.max(*y));
    }
    if !(hi.0 > lo.0 || hi.1 > lo.1) {
        return;
    }
    let margin = 0.05 * size as f64;
    let scale = (size as f64 - 2.0 * margin) / (hi.0 - lo.0).max(hi.1 - lo.1);
    // Centred in the panel; y grows downwards in the image.
    let (cx, cy) = (0.5 * (lo.0 + hi.0), 0.5 * (lo.1 + hi.1));
    let to_px = |(x, y, z): (f64, f64, f64)| {
        (
            x0 as f64 + 0.5 * size as f64 + (x - cx) * scale,
            y0 as f64 + 0.5 * size as f64 - (y - cy) * scale,
            z,
        )
    };
    let mut depth = vec![f64::NEG_INFINITY; size * size];
    for t in &mesh.triangles {
        let [a, b, c] = t.map(|i| to_px(projected[i as usize]));
        let area = (b.0 - a.0) * (c.1 - a.1) - (b.1 - a.1) * (c.0 - a.0);
        if area.abs() < 1e-12 {
            continue;
        }
        let normal = {
            let [p, q, r] = t.map(|i| mesh.positions[i as usize]);
            (q - p).cross(&(r - p)).normalize()
        };
        let light = 0.3 + 0.7 * normal.dot(&eye).abs();
        let colour = |i: u32| {
            colours
                .get(i as usize)
                .copied()
                .unwrap_or([0.7, 0.7, 0.7, 1.0])
        };
        let shade = |k: usize| {
            let c = (colour(t[0])[k] + colour(t[1])[k] + colour(t[2])[k]) / 3.0;
            (255.0 * (c * light as f32).clamp(0.0, 1.0)).round() as u8
        };
        let rgb = [shade(0), shade(1), shade(2)];
        let (xmin, xmax) = (a.0.min(b.0).min(c.0), a.0.max(b.0).max(c.0));
        let (ymin, ymax) = (a.1.min(b.1).min(c.1), a.1.max(b.1).max(c.1));
        let (px0, px1) = (
            xmin.floor().max(x0 as f64) as usize,
            xmax.ceil().min((x0 + size) as f64) as usize,
        );
        let (py0, py1) = (
            ymin.floor().max(y0 as f64) as usize,
            ymax.ceil().min((y0 + size) as f64) as usize,
        );
        for py in py0..py1 {
            for px in px0..px1 {
                let (x, y) = (px as f64 + 0.5, py as f64 + 0.5);
                let w0 = ((b.0 - x) * (c.1 - y) - (b.1 - y) * (c.0 - x)) / area;
                let w1 = ((c.0 - x) * (a.1 - y) - (c.1 - y) * (a.0 - x)) / area;
                let w2 = 1.0 - w0 - w1;
                if w0 < 0.0 || w1 < 0.0 || w2 < 0.0 {
                    continue;
                }
                let z = w0 * a.2 + w1 * b.2 + w2 * c.2;
                let k = (py - y0) * size + (px - x0);
                if k < depth.len() && z > depth[k] {
                    depth[k] = z;
                    canvas.put(px, py, rgb);
                }
            }
        }
    }
}

/// Side of one view of [`VIEWS`] in a picture, pixels.
pub(crate) const PANEL: usize = 600;

/// `mesh` (coloured per vertex) from each of [`VIEWS`], side by side, with a strip below for
/// a legend (drawn from `(10, PANEL + 12)`).
pub(crate) fn two_views(mesh: &Mesh, colours: &[[f32; 4]]) -> Canvas {
    let mut canvas = Canvas::new(2 * PANEL, PANEL + 40);
    for (k, (eye, up)) in VIEWS.iter().enumerate() {
        let view = View {
            towards_eye: Vector3::from(*eye),
            up: Vector3::from(*up),
        };
        draw_mesh(&mut canvas, (k * PANEL, 0, PANEL), mesh, colours, &view);
    }
    canvas
}

/// A row of swatches with their labels, from `(x, y)`.
pub(crate) fn legend(canvas: &mut Canvas, x: usize, y: usize, items: &[([f32; 4], String)]) {
    let scale = 3;
    let mut at = x;
    for (colour, label) in items {
        let rgb = [0, 1, 2].map(|k| (255.0 * colour[k].clamp(0.0, 1.0)).round() as u8);
        canvas.fill(at, y, 8 * scale, 5 * scale, rgb);
        canvas.text(at + 10 * scale, y, label, scale, [0, 0, 0]);
        at += (12 + 4 * label.chars().count()) * scale + 6 * scale;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::fixtures::cuboid;

    /// A red cube seen from above fills a centred square of red shades; the rest stays white;
    /// the PNG reads back as drawn.
    #[test]
    fn a_cube_from_above_is_a_centred_square() {
        let cube = cuboid(10.0, 10.0, 10.0);
        let colours = vec![[1.0, 0.0, 0.0, 1.0]; cube.positions.len()];
        let mut canvas = Canvas::new(100, 100);
        let view = View {
            towards_eye: Vector3::z(),
            up: Vector3::y(),
        };
        draw_mesh(&mut canvas, (0, 0, 100), &cube, &colours, &view);
        let at = |x: usize, y: usize| {
            let k = 3 * (y * 100 + x);
            [canvas.px[k], canvas.px[k + 1], canvas.px[k + 2]]
        };
        assert_eq!(at(50, 50), [255, 0, 0], "the top face, lit head-on");
        assert_eq!(at(2, 2), [255, 255, 255]);
        assert_eq!(at(6, 50), [255, 0, 0], "the square reaches the 5 % margin");
        assert_eq!(at(4, 50), [255, 255, 255]);
        let png = canvas.png().unwrap();
        let mut reader = png::Decoder::new(std::io::Cursor::new(png))
            .read_info()
            .unwrap();
        let mut buffer = vec![0; reader.output_buffer_size().unwrap()];
        reader.next_frame(&mut buffer).unwrap();
        assert_eq!(buffer, canvas.px);
    }
}
