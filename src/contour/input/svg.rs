//! SVG outline reader.
//!
//! Coordinate semantics (deliberately not those of a renderer): coordinates are user units of
//! the ROOT element's viewBox; the viewBox origin (min-x, min-y) is moved to (0, 0); the
//! viewBox→viewport scaling implied by `width`/`height` is ignored; y is flipped
//! (y = −y_svg) and everything is multiplied by [`OutlineOptions::scale`] (1 user unit = 1 mm
//! by default). So `x_mm = scale (x_user − min_x)`, `y_mm = −scale (y_user − min_y)`.
//!
//! Geometry: `path` (all commands, elliptical arcs included), `rect` (with rx/ry), `circle`,
//! `ellipse`, `polygon`, `polyline`; `line` has no area and is ignored. `g`, `a` and `switch`
//! (all children, no conditional processing) are groups; element and group `transform`s
//! compose. Not drawn: `defs`, `symbol`, `clipPath`, `mask`, `marker`, `pattern`, `image`,
//! metadata and elements outside the SVG namespace; `display:none` hides a subtree. Errors:
//! `use`, nested `svg`, `text`. Paint (`fill`, `stroke`) is not looked at: every shape is a
//! region boundary; `fill-rule` (attribute or `style`, inherited, default nonzero) decides holes
//! and islands across all shapes of the drawing. CSS style sheets are not applied.

use std::f64::consts::{FRAC_PI_2, PI, TAU};
use std::str::FromStr;

use nalgebra::Matrix2;
use roxmltree::{Document, Node, ParsingOptions};
use svgtypes::{Length, LengthUnit, PathParser, PathSegment, PointsParser, ViewBox};

use super::curves::{Affine, Cubic, EllipseArc, fit_curve};
use super::fill::{FillRule, build_region};
use super::{Chain, OutlineError, OutlineOptions, RawContour, points_size};
use crate::contour::geometry::{Point2, Shape};

const SVG_NS: &str = "http://www.w3.org/2000/svg";
const MAX_DEPTH: usize = 256;
/// An unclosed subpath counts as closed when it ends this close to its start (× drawing size).
const CLOSE_REL: f64 = 1e-6;

struct Subpath {
    chain: Chain,
    closed: bool,
    label: String,
    rule: FillRule,
}

struct Reader<'a> {
    file: &'a str,
    tol: f64,
    doc: &'a Document<'a>,
    /// Reference sizes for percentages: viewBox (or viewport) width and height.
    pct: Option<(f64, f64)>,
    subpaths: Vec<Subpath>,
    /// Shapes seen so far (for labels of elements without id).
    shapes: usize,
}

/// Reads SVG text into a region (see the module docs for the semantics).
pub(crate) fn read(
    text: &str,
    file: &str,
    options: &OutlineOptions,
) -> Result<Shape, OutlineError> {
    build_region(contours(text, file, options)?, file, options.tolerance)
}

/// The closed contours of the drawing, as drawn (before fill rule and orientation).
pub(crate) fn contours(
    text: &str,
    file: &str,
    options: &OutlineOptions,
) -> Result<Vec<RawContour>, OutlineError> {
    let parse_opts = ParsingOptions {
        allow_dtd: true,
        nodes_limit: 10_000_000,
        ..ParsingOptions::default()
    };
    let doc = Document::parse_with_options(text, parse_opts).map_err(|e| OutlineError::Parse {
        file: file.into(),
        message: format!("not valid XML: {e}"),
    })?;
    let root = doc.root_element();
    if !is_svg_element(&root) || root.tag_name().name() != "svg" {
        return Err(OutlineError::Parse {
            file: file.into(),
            message: format!(
                "the root element is <{}>, not <svg>",
                root.tag_name().name()
            ),
        });
    }
    let viewbox = match root.attribute("viewBox") {
        Some(v) => {
            let vb = ViewBox::from_str(v).map_err(|e| OutlineError::Invalid {
                file: file.into(),
                what: "<svg> viewBox".into(),
                message: format!("cannot parse \"{v}\": {e}"),
            })?;
            let ok =
                [vb.x, vb.y, vb.w, vb.h].iter().all(|c| c.is_finite()) && vb.w > 0.0 && vb.h > 0.0;
            if !ok {
                return Err(OutlineError::Invalid {
                    file: file.into(),
                    what: "<svg> viewBox".into(),
                    message: format!(
                        "\"{v}\" must have finite numbers and a positive width and height"
                    ),
                });
            }
            Some(vb)
        }
        None => None,
    };
    let pct = viewbox.map(|vb| (vb.w, vb.h)).or_else(|| {
        let plain = |name| {
            let l = Length::from_str(root.attribute(name)?).ok()?;
            matches!(l.unit, LengthUnit::None | LengthUnit::Px)
                .then_some(l.number)
                .filter(|v| *v > 0.0 && v.is_finite())
        };
        Some((plain("width")?, plain("height")?))
    });
    let (ox, oy) = viewbox.map_or((0.0, 0.0), |vb| (vb.x, vb.y));
    let s = options.scale;
    let base = Affine::svg(s, 0.0, 0.0, -s, -s * ox, s * oy);
    let mut reader = Reader {
        file,
        tol: options.tolerance,
        doc: &doc,
        pct,
        subpaths: Vec::new(),
        shapes: 0,
    };
    let style = Style::of(&root);
    if style.get("display") == Some("none") {
        return Err(OutlineError::NoClosedShape {
            file: file.into(),
            detail: " (the root element is display:none)".into(),
        });
    }
    let rule = style.fill_rule().unwrap_or_default();
    let ctm = base.compose(&reader.transform_of(&root)?);
    reader.walk(root, &ctm, rule, 0)?;
    reader.finish()
}

fn is_svg_element(n: &Node) -> bool {
    n.is_element() && matches!(n.tag_name().namespace(), None | Some(SVG_NS))
}

/// Presentation properties of one element: the `style` attribute overrides attributes.
struct Style<'a> {
    node: Node<'a, 'a>,
    decls: Vec<(&'a str, &'a str)>,
}

impl<'a> Style<'a> {
    fn of(node: &Node<'a, 'a>) -> Self {
        let decls = node
            .attribute("style")
            .map(|s| {
                s.split(';')
                    .filter_map(|d| {
                        let (k, v) = d.split_once(':')?;
                        let v = v.trim();
                        let v = v.strip_suffix("!important").map_or(v, str::trim);
                        Some((k.trim(), v))
                    })
                    .collect()
            })
            .unwrap_or_default();
        Self { node: *node, decls }
    }

    fn get(&self, name: &str) -> Option<&'a str> {
        self.decls
            .iter()
            .rev()
            .find(|(k, _)| *k == name)
            .map(|(_, v)| *v)
            .or_else(|| self.node.attribute(name).map(str::trim))
    }

    /// The element's own fill rule (`None`: inherited).
    fn fill_rule(&self) -> Option<FillRule> {
        match self.get("fill-rule")? {
            "evenodd" => Some(FillRule::EvenOdd),
            "nonzero" => Some(FillRule::NonZero),
            _ => None,
        }
    }
}

enum Axis {
    X,
    Y,
    Diag,
}

impl<'a> Reader<'a> {
    fn label(&self, node: &Node) -> String {
        let line = self.doc.text_pos_at(node.range().start).row;
        let name = node.tag_name().name();
        let shape = matches!(
            name,
            "path" | "rect" | "circle" | "ellipse" | "polygon" | "polyline"
        );
        match node.attribute("id") {
            Some(id) => format!("<{name} id=\"{id}\"> (line {line})"),
            // Shapes without id are numbered in document order (the n-th drawn shape).
            None if shape => format!("<{name}> #{} (line {line})", self.shapes),
            None => format!("<{name}> (line {line})"),
        }
    }

    fn invalid(&self, node: &Node, message: String) -> OutlineError {
        OutlineError::Invalid {
            file: self.file.into(),
            what: self.label(node),
            message,
        }
    }

    fn unsupported(&self, node: &Node, message: &str) -> OutlineError {
        OutlineError::Unsupported {
            file: self.file.into(),
            what: self.label(node),
            message: message.into(),
        }
    }

    fn transform_of(&self, node: &Node) -> Result<Affine, OutlineError> {
        let Some(t) = node.attribute("transform") else {
            return Ok(Affine::identity());
        };
        let ts = svgtypes::Transform::from_str(t)
            .map_err(|e| self.invalid(node, format!("cannot parse transform \"{t}\": {e}")))?;
        let a = Affine::svg(ts.a, ts.b, ts.c, ts.d, ts.e, ts.f);
        if !a.is_finite() {
            return Err(self.invalid(node, format!("transform \"{t}\" is not finite")));
        }
        Ok(a)
    }

    fn walk(
        &mut self,
        node: Node<'a, 'a>,
        ctm: &Affine,
        rule: FillRule,
        depth: usize,
    ) -> Result<(), OutlineError> {
        if depth > MAX_DEPTH {
            return Err(self.unsupported(&node, "elements are nested too deeply"));
        }
        for child in node.children().filter(is_svg_element) {
            let style = Style::of(&child);
            if style.get("display") == Some("none") {
                continue;
            }
            let rule_c = style.fill_rule().unwrap_or(rule);
            let name = child.tag_name().name();
            match name {
                "g" | "a" | "switch" => {
                    let ctm_c = ctm.compose(&self.transform_of(&child)?);
                    self.walk(child, &ctm_c, rule_c, depth + 1)?;
                }
                "path" | "rect" | "circle" | "ellipse" | "polygon" | "polyline" => {
                    self.shapes += 1;
                    let ctm_c = ctm.compose(&self.transform_of(&child)?);
                    self.shape(&child, name, &ctm_c, rule_c)?;
                }
                "use" => {
                    return Err(self.unsupported(
                        &child,
                        "<use> references are not supported; unlink the clone first",
                    ));
                }
                "svg" => {
                    return Err(self.unsupported(&child, "nested <svg> elements are not supported"));
                }
                "text" => {
                    return Err(
                        self.unsupported(&child, "text is not supported; convert it to paths")
                    );
                }
                // line: no area. defs, symbol, clipPath, mask, marker, pattern, image, style,
                // metadata, title, desc, gradients, filters…: not drawn.
                _ => {}
            }
        }
        Ok(())
    }

    fn length(&self, node: &Node, name: &str, axis: Axis) -> Result<Option<f64>, OutlineError> {
        let Some(text) = node.attribute(name) else {
            return Ok(None);
        };
        if text.trim() == "auto" {
            return Ok(None);
        }
        let l = Length::from_str(text)
            .map_err(|e| self.invalid(node, format!("cannot parse {name}=\"{text}\": {e}")))?;
        // CSS absolute units at 96 user units per inch.
        let v = match l.unit {
            LengthUnit::None | LengthUnit::Px => l.number,
            LengthUnit::In => l.number * 96.0,
            LengthUnit::Cm => l.number * 96.0 / 2.54,
            LengthUnit::Mm => l.number * 96.0 / 25.4,
            LengthUnit::Pt => l.number * 4.0 / 3.0,
            LengthUnit::Pc => l.number * 16.0,
            LengthUnit::Percent => {
                let (w, h) = self.pct.ok_or_else(|| {
                    self.unsupported(
                        node,
                        &format!("{name}=\"{text}\": a percentage needs a viewBox or width/height"),
                    )
                })?;
                let base = match axis {
                    Axis::X => w,
                    Axis::Y => h,
                    Axis::Diag => ((w * w + h * h) / 2.0).sqrt(),
                };
                l.number / 100.0 * base
            }
            LengthUnit::Em | LengthUnit::Ex => {
                return Err(
                    self.unsupported(node, &format!("{name}=\"{text}\": font-relative units"))
                );
            }
        };
        if !v.is_finite() {
            return Err(self.invalid(node, format!("{name}=\"{text}\" is not finite")));
        }
        Ok(Some(v))
    }

    fn shape(
        &mut self,
        node: &Node,
        name: &str,
        tf: &Affine,
        rule: FillRule,
    ) -> Result<(), OutlineError> {
        let label = self.label(node);
        let mut sink = Sink::new(*tf, self.tol, label.clone(), rule);
        let zero = |why: &str| OutlineError::ZeroArea {
            file: self.file.into(),
            what: label.clone(),
            detail: format!(" ({why})"),
        };
        match name {
            "path" => {
                let d = node.attribute("d").unwrap_or("");
                self.path(node, d, &mut sink)?;
            }
            "rect" => {
                let x = self.length(node, "x", Axis::X)?.unwrap_or(0.0);
                let y = self.length(node, "y", Axis::Y)?.unwrap_or(0.0);
                let w = self.length(node, "width", Axis::X)?.unwrap_or(0.0);
                let h = self.length(node, "height", Axis::Y)?.unwrap_or(0.0);
                if !(w > 0.0 && h > 0.0) {
                    return Err(zero("width or height is not positive"));
                }
                let rx = self.length(node, "rx", Axis::X)?.filter(|v| *v >= 0.0);
                let ry = self.length(node, "ry", Axis::Y)?.filter(|v| *v >= 0.0);
                let (rx, ry) = match (rx, ry) {
                    (None, None) => (0.0, 0.0),
                    (Some(a), None) => (a, a),
                    (None, Some(b)) => (b, b),
                    (Some(a), Some(b)) => (a, b),
                };
                let (rx, ry) = (rx.min(w / 2.0), ry.min(h / 2.0));
                // Either radius zero: square corners (SVG 1.1 §9.2).
                let (rx, ry) = if rx > 0.0 && ry > 0.0 {
                    (rx, ry)
                } else {
                    (0.0, 0.0)
                };
                sink.rect(x, y, w, h, rx, ry);
            }
            "circle" => {
                let cx = self.length(node, "cx", Axis::X)?.unwrap_or(0.0);
                let cy = self.length(node, "cy", Axis::Y)?.unwrap_or(0.0);
                let r = self.length(node, "r", Axis::Diag)?.unwrap_or(0.0);
                if r.is_nan() || r <= 0.0 {
                    return Err(zero("radius is not positive"));
                }
                sink.ellipse(cx, cy, r, r);
            }
            "ellipse" => {
                let cx = self.length(node, "cx", Axis::X)?.unwrap_or(0.0);
                let cy = self.length(node, "cy", Axis::Y)?.unwrap_or(0.0);
                let rx = self.length(node, "rx", Axis::X)?;
                let ry = self.length(node, "ry", Axis::Y)?;
                // SVG 2: an "auto" radius takes the other one.
                let (rx, ry) = match (rx, ry) {
                    (Some(a), None) => (a, a),
                    (None, Some(b)) => (b, b),
                    (a, b) => (a.unwrap_or(0.0), b.unwrap_or(0.0)),
                };
                if !(rx > 0.0 && ry > 0.0) {
                    return Err(zero("a radius is not positive"));
                }
                sink.ellipse(cx, cy, rx, ry);
            }
            "polygon" | "polyline" => {
                let pts = node.attribute("points").unwrap_or("");
                let mut first = true;
                for (x, y) in PointsParser::from(pts) {
                    if !(x.is_finite() && y.is_finite()) {
                        return Err(self.invalid(node, "points are not finite".into()));
                    }
                    let p = Point2::new(x, y);
                    if first {
                        sink.move_to(p);
                        first = false;
                    } else {
                        sink.line_to(p);
                    }
                }
                if name == "polygon" {
                    sink.close();
                }
            }
            _ => {}
        }
        sink.finish();
        self.subpaths.append(&mut sink.out);
        Ok(())
    }

    fn path(&self, node: &Node, d: &str, sink: &mut Sink) -> Result<(), OutlineError> {
        // Previous command's second control point (cubic) or control point (quadratic), for the
        // reflections of S/s and T/t.
        let mut last_cubic: Option<Point2> = None;
        let mut last_quad: Option<Point2> = None;
        for seg in PathParser::from(d) {
            let seg = seg.map_err(|e| self.invalid(node, format!("bad path data: {e}")))?;
            let cur = sink.cur;
            let abs = |abs: bool, x: f64, y: f64| {
                if abs {
                    Point2::new(x, y)
                } else {
                    Point2::new(cur.x + x, cur.y + y)
                }
            };
            let (mut nc, mut nq) = (None, None);
            match seg {
                PathSegment::MoveTo { abs: a, x, y } => sink.move_to(abs(a, x, y)),
                PathSegment::LineTo { abs: a, x, y } => sink.line_to(abs(a, x, y)),
                PathSegment::HorizontalLineTo { abs: a, x } => {
                    sink.line_to(Point2::new(if a { x } else { cur.x + x }, cur.y));
                }
                PathSegment::VerticalLineTo { abs: a, y } => {
                    sink.line_to(Point2::new(cur.x, if a { y } else { cur.y + y }));
                }
                PathSegment::CurveTo {
                    abs: a,
                    x1,
                    y1,
                    x2,
                    y2,
                    x,
                    y,
                } => {
                    let c2 = abs(a, x2, y2);
                    sink.cubic_to(abs(a, x1, y1), c2, abs(a, x, y));
                    nc = Some(c2);
                }
                PathSegment::SmoothCurveTo {
                    abs: a,
                    x2,
                    y2,
                    x,
                    y,
                } => {
                    let c1 = last_cubic.map_or(cur, |c| cur + (cur - c));
                    let c2 = abs(a, x2, y2);
                    sink.cubic_to(c1, c2, abs(a, x, y));
                    nc = Some(c2);
                }
                PathSegment::Quadratic {
                    abs: a,
                    x1,
                    y1,
                    x,
                    y,
                } => {
                    let c = abs(a, x1, y1);
                    sink.quad_to(c, abs(a, x, y));
                    nq = Some(c);
                }
                PathSegment::SmoothQuadratic { abs: a, x, y } => {
                    let c = last_quad.map_or(cur, |q| cur + (cur - q));
                    sink.quad_to(c, abs(a, x, y));
                    nq = Some(c);
                }
                PathSegment::EllipticalArc {
                    abs: a,
                    rx,
                    ry,
                    x_axis_rotation,
                    large_arc,
                    sweep,
                    x,
                    y,
                } => {
                    sink.svg_arc(rx, ry, x_axis_rotation, large_arc, sweep, abs(a, x, y));
                }
                PathSegment::ClosePath { .. } => sink.close(),
            }
            last_cubic = nc;
            last_quad = nq;
            if !sink.finite {
                return Err(self.invalid(node, "path coordinates are not finite".into()));
            }
        }
        Ok(())
    }

    fn finish(self) -> Result<Vec<RawContour>, OutlineError> {
        let file = self.file;
        let size = points_size(self.subpaths.iter().flat_map(|s| {
            s.chain
                .vertices
                .iter()
                .map(|v| &v.point)
                .chain([&s.chain.end])
        }));
        let close_eps = CLOSE_REL * size;
        let snap_eps = 1e-9 * size;
        // Subpaths of one element are consecutive and share its label.
        let mut per_label = std::collections::HashMap::<&str, usize>::new();
        for sp in &self.subpaths {
            *per_label.entry(sp.label.as_str()).or_insert(0) += 1;
        }
        let mut contours = Vec::new();
        let mut k_of_label = std::collections::HashMap::<&str, usize>::new();
        for sp in &self.subpaths {
            let k = k_of_label.entry(sp.label.as_str()).or_insert(0);
            *k += 1;
            let what = if per_label.get(sp.label.as_str()).copied().unwrap_or(0) > 1 {
                format!("{}, subpath {}", sp.label, k)
            } else {
                sp.label.clone()
            };
            let start = sp.chain.start();
            let gap = (sp.chain.end - start).norm();
            let mut vertices = sp.chain.vertices.clone();
            if sp.closed {
                if gap > snap_eps {
                    // The closing line of Z.
                    vertices.push(crate::contour::geometry::Vertex {
                        point: sp.chain.end,
                        bulge: 0.0,
                    });
                }
            } else if gap.is_nan() || gap > close_eps {
                let end = sp.chain.end;
                return Err(OutlineError::Open {
                    file: file.into(),
                    what,
                    gap,
                    x: end.x,
                    y: end.y,
                });
            }
            contours.push(RawContour {
                vertices,
                label: what,
                rule: sp.rule,
            });
        }
        if contours.is_empty() {
            return Err(OutlineError::NoClosedShape {
                file: file.into(),
                detail: " (no path, rect, circle, ellipse, polygon or polyline with area)".into(),
            });
        }
        Ok(contours)
    }
}

/// Collects the subpaths of one element: SVG user coordinates in, output (mm) chains out.
struct Sink {
    tf: Affine,
    tol: f64,
    label: String,
    rule: FillRule,
    start: Point2,
    cur: Point2,
    chain: Option<Chain>,
    out: Vec<Subpath>,
    finite: bool,
}

impl Sink {
    fn new(tf: Affine, tol: f64, label: String, rule: FillRule) -> Self {
        let o = Point2::origin();
        Self {
            tf,
            tol,
            label,
            rule,
            start: o,
            cur: o,
            chain: None,
            out: Vec::new(),
            finite: true,
        }
    }

    fn finish_subpath(&mut self, closed: bool) {
        if let Some(chain) = self.chain.take()
            && !chain.is_empty()
        {
            self.out.push(Subpath {
                chain,
                closed,
                label: self.label.clone(),
                rule: self.rule,
            });
        }
    }

    fn finish(&mut self) {
        self.finish_subpath(false);
    }

    fn move_to(&mut self, p: Point2) {
        self.finish_subpath(false);
        self.finite &= p.x.is_finite() && p.y.is_finite();
        self.start = p;
        self.cur = p;
    }

    /// The chain being built; a drawing command after Z starts a new subpath at the old start.
    fn chain(&mut self) -> &mut Chain {
        let start = self.tf.apply(self.cur);
        self.chain.get_or_insert_with(|| Chain::new(start))
    }

    fn close(&mut self) {
        self.finish_subpath(true);
        self.cur = self.start;
    }

    fn line_to(&mut self, p: Point2) {
        self.finite &= p.x.is_finite() && p.y.is_finite();
        if p != self.cur {
            let to = self.tf.apply(p);
            self.chain().push(to, 0.0);
        }
        self.cur = p;
    }

    fn cubic_to(&mut self, c1: Point2, c2: Point2, p: Point2) {
        self.finite &= [c1, c2, p]
            .iter()
            .all(|q| q.x.is_finite() && q.y.is_finite());
        if !self.finite {
            return;
        }
        if [c1, c2, p].iter().all(|q| *q == self.cur) {
            return;
        }
        let cubic = Cubic {
            p: [self.cur, c1, c2, p],
        }
        .transformed(&self.tf);
        let to = cubic.p[3];
        let tol = self.tol;
        let vs = fit_curve(&cubic, 0.0, 1.0, tol);
        let chain = self.chain();
        if vs.is_empty() {
            chain.push(to, 0.0);
        } else {
            chain.extend(&vs, to);
        }
        self.cur = p;
    }

    fn quad_to(&mut self, c: Point2, p: Point2) {
        let cubic = Cubic::from_quadratic(self.cur, c, p);
        self.cubic_to(cubic.p[1], cubic.p[2], p);
    }

    /// An SVG elliptical arc from the current point to `p` (SVG 1.1 F.6.5/F.6.6: endpoint to
    /// centre parameterisation with out-of-range radii scaled up).
    fn svg_arc(&mut self, rx: f64, ry: f64, phi_deg: f64, large: bool, sweep: bool, p: Point2) {
        self.finite &= [rx, ry, phi_deg, p.x, p.y].iter().all(|v| v.is_finite());
        if !self.finite {
            return;
        }
        let p1 = self.cur;
        if p1 == p {
            return;
        }
        let (mut rx, mut ry) = (rx.abs(), ry.abs());
        if rx == 0.0 || ry == 0.0 {
            self.line_to(p);
            return;
        }
        let phi = phi_deg.to_radians();
        let (sp, cp) = phi.sin_cos();
        let (hx, hy) = ((p1.x - p.x) / 2.0, (p1.y - p.y) / 2.0);
        let x1 = cp * hx + sp * hy;
        let y1 = -sp * hx + cp * hy;
        let lambda = (x1 * x1) / (rx * rx) + (y1 * y1) / (ry * ry);
        if lambda > 1.0 {
            let s = lambda.sqrt();
            rx *= s;
            ry *= s;
        }
        let num = rx * rx * ry * ry - rx * rx * y1 * y1 - ry * ry * x1 * x1;
        let den = rx * rx * y1 * y1 + ry * ry * x1 * x1;
        let mut coef = if den > 0.0 {
            (num / den).max(0.0).sqrt()
        } else {
            0.0
        };
        if large == sweep {
            coef = -coef;
        }
        let cxp = coef * rx * y1 / ry;
        let cyp = -coef * ry * x1 / rx;
        let cx = cp * cxp - sp * cyp + (p1.x + p.x) / 2.0;
        let cy = sp * cxp + cp * cyp + (p1.y + p.y) / 2.0;
        let ang = |ux: f64, uy: f64| uy.atan2(ux);
        let ux = (x1 - cxp) / rx;
        let uy = (y1 - cyp) / ry;
        let vx = (-x1 - cxp) / rx;
        let vy = (-y1 - cyp) / ry;
        let theta1 = ang(ux, uy);
        let mut dtheta = (ux * vy - uy * vx).atan2(ux * vx + uy * vy);
        if !sweep && dtheta > 0.0 {
            dtheta -= TAU;
        } else if sweep && dtheta < 0.0 {
            dtheta += TAU;
        }
        let m = Matrix2::new(cp, -sp, sp, cp) * Matrix2::new(rx, 0.0, 0.0, ry);
        let arc = EllipseArc {
            center: Point2::new(cx, cy),
            m,
            theta0: theta1,
            dtheta,
        }
        .transformed(&self.tf);
        let to = self.tf.apply(p);
        let tol = self.tol;
        arc.emit(tol, to, self.chain());
        self.cur = p;
    }

    /// An axis-aligned ellipse as one closed subpath, starting at (cx + rx, cy), positive angle.
    fn ellipse(&mut self, cx: f64, cy: f64, rx: f64, ry: f64) {
        let arc = EllipseArc {
            center: Point2::new(cx, cy),
            m: Matrix2::new(rx, 0.0, 0.0, ry),
            theta0: 0.0,
            dtheta: TAU,
        };
        let p0 = Point2::new(cx + rx, cy);
        self.move_to(p0);
        let out = arc.transformed(&self.tf);
        let to = self.tf.apply(p0);
        let tol = self.tol;
        out.emit(tol, to, self.chain());
        self.close();
    }

    /// The rectangle outline of SVG's `rect` (corner arcs centred inside the corners).
    fn rect(&mut self, x: f64, y: f64, w: f64, h: f64, rx: f64, ry: f64) {
        self.move_to(Point2::new(x + rx, y));
        self.line_to(Point2::new(x + w - rx, y));
        let corners = [
            (
                x + w - rx,
                y + ry,
                -FRAC_PI_2,
                Point2::new(x + w, y + ry),
                Point2::new(x + w, y + h - ry),
            ),
            (
                x + w - rx,
                y + h - ry,
                0.0,
                Point2::new(x + w - rx, y + h),
                Point2::new(x + rx, y + h),
            ),
            (
                x + rx,
                y + h - ry,
                FRAC_PI_2,
                Point2::new(x, y + h - ry),
                Point2::new(x, y + ry),
            ),
            (
                x + rx,
                y + ry,
                PI,
                Point2::new(x + rx, y),
                Point2::new(x + rx, y),
            ),
        ];
        for (cx, cy, th0, arc_end, line_end) in corners {
            if rx > 0.0 && ry > 0.0 {
                let arc = EllipseArc {
                    center: Point2::new(cx, cy),
                    m: Matrix2::new(rx, 0.0, 0.0, ry),
                    theta0: th0,
                    dtheta: FRAC_PI_2,
                };
                let out = arc.transformed(&self.tf);
                let to = self.tf.apply(arc_end);
                let tol = self.tol;
                out.emit(tol, to, self.chain());
                self.cur = arc_end;
            }
            self.line_to(line_end);
        }
        self.close();
    }
}

#[cfg(test)]
mod tests {
    use std::f64::consts::PI;

    use super::*;
    use crate::contour::geometry::{Contour, Segment};
    use crate::contour::input::test_util::{curve_to_shape_distance, total_area};
    use crate::contour::input::{CrossingKind, read_svg_str};

    fn doc(body: &str) -> String {
        format!(r#"<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 100 100">{body}</svg>"#)
    }

    fn read(body: &str) -> Result<Shape, OutlineError> {
        read_svg_str(&doc(body), "t.svg", &OutlineOptions::default())
    }

    fn bbox(s: &Shape) -> [f64; 4] {
        let mut b = [
            f64::INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NEG_INFINITY,
        ];
        for c in &s.contours {
            for seg in c.segments() {
                let q = crate::contour::input::segmath::seg_bbox(&seg);
                b = [
                    b[0].min(q[0]),
                    b[1].min(q[1]),
                    b[2].max(q[2]),
                    b[3].max(q[3]),
                ];
            }
        }
        b
    }

    fn close(a: [f64; 4], b: [f64; 4], eps: f64) -> bool {
        a.iter().zip(b).all(|(x, y)| (x - y).abs() <= eps)
    }

    #[test]
    fn rounded_rect_area_and_length_are_exact() {
        let (w, h, r) = (40.0, 25.0, 6.0);
        let s = read(&format!(
            r#"<rect x="3" y="4" width="{w}" height="{h}" rx="{r}"/>"#
        ))
        .unwrap();
        assert_eq!(s.contours.len(), 1);
        let c = &s.contours[0];
        assert!(
            (c.signed_area() - (w * h - (4.0 - PI) * r * r)).abs() < 1e-10,
            "{}",
            c.signed_area()
        );
        assert!((c.length() - (2.0 * (w + h) - 8.0 * r + 2.0 * PI * r)).abs() < 1e-10);
        // 4 lines + 4 exact quarter arcs.
        assert_eq!(c.vertices.len(), 8);
        assert_eq!(c.vertices.iter().filter(|v| v.bulge != 0.0).count(), 4);
        // rx larger than half the height is clamped; only ry given: rx = ry.
        let s = read(r#"<rect width="10" height="4" ry="100"/>"#).unwrap();
        // Full stadium: 10×4 with radius 2 ends... rx = min(100, 5) = 5, ry = 2: elliptic ends.
        let a = s.contours[0].signed_area();
        assert!(
            (a - (40.0 - (4.0 - PI) * 5.0 * 2.0)).abs() < 0.01 * 30.0,
            "{a}"
        );
    }

    #[test]
    fn elliptic_rect_corners_within_tolerance() {
        let s = read(r#"<rect x="0" y="0" width="50" height="30" rx="10" ry="4"/>"#).unwrap();
        // Top-right corner in SVG: centre (40, 4), θ ∈ [−π/2, 0]; in output y = −y_svg.
        let e = EllipseArc {
            center: Point2::new(40.0, -4.0),
            m: Matrix2::new(10.0, 0.0, 0.0, -4.0),
            theta0: -FRAC_PI_2,
            dtheta: FRAC_PI_2,
        };
        assert!(curve_to_shape_distance(&e, 0.0, 1.0, &s) <= 0.001);
        let expected = 50.0 * 30.0 - (4.0 - PI) * 10.0 * 4.0;
        assert!((s.contours[0].signed_area() - expected).abs() < 0.001 * 200.0);
    }

    #[test]
    fn circle_area_is_exact_and_ccw() {
        let s = read(r#"<circle cx="50" cy="40" r="7.5"/>"#).unwrap();
        let c = &s.contours[0];
        assert_eq!(c.vertices.len(), 2);
        assert!(
            (c.signed_area() - PI * 56.25).abs() < 1e-12,
            "{}",
            c.signed_area()
        );
        assert!((c.length() - 15.0 * PI).abs() < 1e-12);
        // Centre at (50, −40) after the flip.
        let b = bbox(&s);
        assert!(close(b, [42.5, -47.5, 57.5, -32.5], 1e-12), "{b:?}");
    }

    #[test]
    fn ellipse_and_scaled_circle_within_tolerance() {
        for (body, m) in [
            (
                r#"<ellipse cx="20" cy="30" rx="15" ry="6"/>"#,
                Matrix2::new(15.0, 0.0, 0.0, -6.0),
            ),
            // Non-uniform scale turns the circle into an ellipse with semi-axes 20 and 10.
            (
                r#"<circle cx="10" cy="30" r="10" transform="scale(2 1)"/>"#,
                Matrix2::new(20.0, 0.0, 0.0, -10.0),
            ),
        ] {
            let s = read(body).unwrap();
            let e = EllipseArc {
                center: Point2::new(20.0, -30.0),
                m,
                theta0: 0.0,
                dtheta: 2.0 * PI,
            };
            let d = curve_to_shape_distance(&e, 0.0, 1.0, &s);
            assert!(d <= 0.001, "{body}: {d}");
            let area = PI * m[(0, 0)] * m[(1, 1)].abs();
            let c = &s.contours[0];
            assert!(
                (c.signed_area() - area).abs() <= 0.001 * c.length(),
                "{body}"
            );
            // Few arcs: biarcs, not a polyline.
            assert!(c.vertices.len() < 120, "{}", c.vertices.len());
        }
    }

    #[test]
    fn arc_command_endpoint_and_centre() {
        // Quarter-circle sector: from (10, 0) to (0, 10) around (0, 0) (small arc, positive
        // angle direction in SVG coordinates).
        let s = read(r#"<path d="M 10 0 A 10 10 0 0 1 0 10 L 0 0 Z"/>"#).unwrap();
        let c = &s.contours[0];
        assert!(
            (c.signed_area() - 25.0 * PI).abs() < 1e-10,
            "{}",
            c.signed_area()
        );
        let arc = c.segments().find_map(|sg| match sg {
            Segment::Arc { center, radius, .. } => Some((center, radius)),
            _ => None,
        });
        let (center, radius) = arc.unwrap();
        assert!(center.coords.norm() < 1e-12 && (radius - 10.0).abs() < 1e-12);
        // Large arc the other way round: three quarters of the disk.
        let s = read(r#"<path d="M 10 0 A 10 10 0 1 0 0 10 L 0 0 Z"/>"#).unwrap();
        assert!((s.contours[0].signed_area() - 75.0 * PI).abs() < 1e-10);
        // Radii too small are scaled up: a half disk of radius 10.
        let s = read(r#"<path d="M 0 0 A 1 1 0 0 1 20 0 Z"/>"#).unwrap();
        assert!((s.contours[0].signed_area() - 50.0 * PI).abs() < 1e-10);
        // Relative arc with rotation: an ellipse made of two arcs, semi-axes 20 and 8,
        // rotated by 30°; area π·20·8 within tolerance × length.
        let (a, b) = (20.0, 8.0);
        let (c30, s30) = (30f64.to_radians().cos(), 30f64.to_radians().sin());
        let (x0, y0) = (50.0 + a * c30, 50.0 + a * s30);
        let s = read(&format!(
            r#"<path d="M {x0} {y0} a {a} {b} 30 0 1 {} {} a {a} {b} 30 0 1 {} {} z"/>"#,
            -2.0 * a * c30,
            -2.0 * a * s30,
            2.0 * a * c30,
            2.0 * a * s30
        ))
        .unwrap();
        let c = &s.contours[0];
        assert!(
            (c.signed_area() - PI * a * b).abs() <= 0.001 * c.length(),
            "{}",
            c.signed_area()
        );
        let rot = Matrix2::new(c30, -s30, s30, c30) * Matrix2::new(a, 0.0, 0.0, b);
        let flip = Matrix2::new(1.0, 0.0, 0.0, -1.0);
        let e = EllipseArc {
            center: Point2::new(50.0, -50.0),
            m: flip * rot,
            theta0: 0.0,
            dtheta: 2.0 * PI,
        };
        assert!(curve_to_shape_distance(&e, 0.0, 1.0, &s) <= 0.001);
    }

    #[test]
    fn cubic_and_quadratic_paths_within_tolerance() {
        let s = read(r#"<path d="M 10 80 C 40 10 65 10 95 80 Q 50 120 10 80 Z"/>"#).unwrap();
        let cubic = Cubic {
            p: [(10.0, 80.0), (40.0, 10.0), (65.0, 10.0), (95.0, 80.0)]
                .map(|(x, y)| Point2::new(x, -y)),
        };
        assert!(curve_to_shape_distance(&cubic, 0.0, 1.0, &s) <= 0.001);
        let quad = Cubic::from_quadratic(
            Point2::new(95.0, -80.0),
            Point2::new(50.0, -120.0),
            Point2::new(10.0, -80.0),
        );
        assert!(curve_to_shape_distance(&quad, 0.0, 1.0, &s) <= 0.001);
    }

    #[test]
    fn smooth_and_relative_commands_match_their_explicit_forms() {
        let pairs = [
            (
                "M0 0 C 0 10 10 10 10 0 S 20 -10 20 0 L 20 20 L 0 20 Z",
                "M0 0 C 0 10 10 10 10 0 C 10 -10 20 -10 20 0 L 20 20 L 0 20 Z",
            ),
            (
                "M0 0 Q 5 10 10 0 T 20 0 L 20 -20 L 0 -20 Z",
                "M0 0 Q 5 10 10 0 Q 15 -10 20 0 L 20 -20 L 0 -20 Z",
            ),
            ("m 5 5 h 10 v 10 h -10 z", "M 5 5 L 15 5 L 15 15 L 5 15 Z"),
            (
                "M 5 5 c 0 10 10 10 10 0 s 10 -10 10 0 l 0 20 l -20 0 z",
                "M 5 5 C 5 15 15 15 15 5 C 15 -5 25 -5 25 5 L 25 25 L 5 25 Z",
            ),
            // S after a non-curve: first control point is the current point.
            (
                "M 0 0 L 10 0 S 20 10 10 10 Z",
                "M 0 0 L 10 0 C 10 0 20 10 10 10 Z",
            ),
        ];
        for (a, b) in pairs {
            let sa = read(&format!(r#"<path d="{a}"/>"#)).unwrap();
            let sb = read(&format!(r#"<path d="{b}"/>"#)).unwrap();
            assert_eq!(sa.contours.len(), sb.contours.len());
            for (ca, cb) in sa.contours.iter().zip(&sb.contours) {
                assert_eq!(ca.vertices.len(), cb.vertices.len(), "{a}");
                for (va, vb) in ca.vertices.iter().zip(&cb.vertices) {
                    assert!(
                        (va.point - vb.point).norm() < 1e-9 && (va.bulge - vb.bulge).abs() < 1e-9,
                        "{a}"
                    );
                }
            }
        }
    }

    #[test]
    fn transforms_compose_in_document_order() {
        // Rotate first (element), then translate (group): x ∈ [80, 100], y_svg ∈ [0, 10].
        let s = read(r#"<g transform="translate(100,0)"><rect width="10" height="20" transform="rotate(90)"/></g>"#).unwrap();
        assert!(
            close(bbox(&s), [80.0, -10.0, 100.0, 0.0], 1e-12),
            "{:?}",
            bbox(&s)
        );
        // Within one attribute the rightmost applies first: same result.
        let s = read(r#"<rect width="10" height="20" transform="translate(100,0) rotate(90)"/>"#)
            .unwrap();
        assert!(close(bbox(&s), [80.0, -10.0, 100.0, 0.0], 1e-12));
        // Rotation about a centre: (x, y) ↦ (10 − y, x) for rotate(90, 5, 5).
        let s = read(r#"<rect width="10" height="2" transform="rotate(90 5 5)"/>"#).unwrap();
        assert!(
            close(bbox(&s), [8.0, -10.0, 10.0, 0.0], 1e-12),
            "{:?}",
            bbox(&s)
        );
        // Nested groups with scale, skewX, skewY and matrix.
        let s = read(r#"<g transform="scale(2,3)"><g transform="skewX(45)"><rect width="10" height="10"/></g></g>"#).unwrap();
        assert!((total_area(&s) - 600.0).abs() < 1e-9);
        assert!(
            close(bbox(&s), [0.0, -30.0, 40.0, 0.0], 1e-9),
            "{:?}",
            bbox(&s)
        );
        let s = read(r#"<rect width="10" height="10" transform="skewY(45)"/>"#).unwrap();
        assert!(
            close(bbox(&s), [0.0, -20.0, 10.0, 0.0], 1e-9),
            "{:?}",
            bbox(&s)
        );
        let s = read(r#"<g transform="matrix(1 0 0 1 5 7)"><circle r="1" transform="matrix(0 2 -2 0 0 0)"/></g>"#).unwrap();
        assert!(
            close(bbox(&s), [3.0, -9.0, 7.0, -5.0], 1e-12),
            "{:?}",
            bbox(&s)
        );
        assert!((total_area(&s) - 4.0 * PI).abs() < 1e-12);
    }

    #[test]
    fn viewbox_offset_and_viewport_scale() {
        let text = r#"<svg xmlns="http://www.w3.org/2000/svg" viewBox="100 50 200 100" width="2000mm" height="1000mm"><rect x="110" y="60" width="10" height="20"/></svg>"#;
        let s = read_svg_str(text, "v.svg", &OutlineOptions::default()).unwrap();
        // Width/height scaling ignored; the viewBox origin maps to (0, 0).
        assert!(
            close(bbox(&s), [10.0, -30.0, 20.0, -10.0], 1e-12),
            "{:?}",
            bbox(&s)
        );
        let s = read_svg_str(
            text,
            "v.svg",
            &OutlineOptions {
                scale: 0.5,
                ..Default::default()
            },
        )
        .unwrap();
        assert!(close(bbox(&s), [5.0, -15.0, 10.0, -5.0], 1e-12));
        assert!((total_area(&s) - 50.0).abs() < 1e-12);
        // Without a viewBox: user units as they are.
        let s = read_svg_str(r#"<svg xmlns="http://www.w3.org/2000/svg" width="5cm"><rect x="1" y="2" width="3" height="4"/></svg>"#, "n.svg", &OutlineOptions::default()).unwrap();
        assert!(close(bbox(&s), [1.0, -6.0, 4.0, -2.0], 1e-12));
    }

    #[test]
    fn y_flip_reverses_orientation() {
        // Counter-clockwise in SVG coordinates (positive shoelace with y down) …
        let svg = doc(r#"<path d="M 0 0 L 10 0 L 10 10 L 0 10 Z"/>"#);
        let raw = contours(&svg, "f.svg", &OutlineOptions::default()).unwrap();
        let c = Contour {
            vertices: raw[0].vertices.clone(),
        };
        // … is clockwise after y = −y_svg.
        assert!((c.signed_area() + 100.0).abs() < 1e-12);
        assert_eq!(c.vertices[1].point, Point2::new(10.0, 0.0));
        assert_eq!(c.vertices[2].point, Point2::new(10.0, -10.0));
        // The region builder then orients the outer boundary counter-clockwise.
        let s = read_svg_str(&svg, "f.svg", &OutlineOptions::default()).unwrap();
        assert!((s.contours[0].signed_area() - 100.0).abs() < 1e-12);
        // Arcs flip too: an SVG arc with sweep-flag 1 is clockwise in the output.
        let raw = contours(
            &doc(r#"<path d="M 10 0 A 10 10 0 0 1 0 10 L 0 0 Z"/>"#),
            "f.svg",
            &OutlineOptions::default(),
        )
        .unwrap();
        assert!(raw[0].vertices[0].bulge < 0.0);
    }

    #[test]
    fn fill_rules_decide_holes_and_islands() {
        // Three nested squares in one path, all drawn the same way round.
        let d = "M0 0 H60 V60 H0 Z M10 10 H50 V50 H10 Z M20 20 H40 V40 H20 Z";
        let s = read(&format!(r#"<path d="{d}"/>"#)).unwrap();
        assert_eq!(s.contours.len(), 1);
        assert!((total_area(&s) - 3600.0).abs() < 1e-9);
        for body in [
            format!(r#"<path fill-rule="evenodd" d="{d}"/>"#),
            format!(r#"<path style="fill:none; fill-rule : evenodd" d="{d}"/>"#),
            format!(r#"<g fill-rule="evenodd"><g><path d="{d}"/></g></g>"#),
            format!(r#"<g style="fill-rule:evenodd"><path d="{d}"/></g>"#),
        ] {
            let s = read(&body).unwrap();
            let areas: Vec<f64> = s.contours.iter().map(|c| c.signed_area()).collect();
            assert_eq!(areas, vec![3600.0, -1600.0, 400.0], "{body}");
        }
        // An element's own rule overrides the inherited one.
        let s = read(&format!(
            r#"<g fill-rule="evenodd"><path fill-rule="nonzero" d="{d}"/></g>"#
        ))
        .unwrap();
        assert_eq!(s.contours.len(), 1);
        // Nonzero with a reversed middle square: hole, and the inner square is an island.
        let d2 = "M0 0 H60 V60 H0 Z M10 10 V50 H50 V10 Z M20 20 H40 V40 H20 Z";
        let s = read(&format!(r#"<path d="{d2}"/>"#)).unwrap();
        let areas: Vec<f64> = s.contours.iter().map(|c| c.signed_area()).collect();
        assert_eq!(areas, vec![3600.0, -1600.0, 400.0]);
    }

    #[test]
    fn open_paths_and_polylines() {
        let e = read(r#"<path id="p7" d="M 0 0 L 10 0 L 10 10"/>"#).unwrap_err();
        let msg = e.to_string();
        assert!(
            matches!(e, OutlineError::Open { .. })
                && msg.contains("p7")
                && msg.contains("14.142136"),
            "{msg}"
        );
        // Ends within 1e-6 × size of the start: closed.
        assert_eq!(
            read(r#"<path d="M 0 0 L 10 0 L 10 10 L 0.000000001 0"/>"#)
                .unwrap()
                .contours
                .len(),
            1
        );
        assert!(matches!(
            read(r#"<polyline points="0,0 10,0 10,10"/>"#),
            Err(OutlineError::Open { .. })
        ));
        let s = read(r#"<polyline points="0,0 10,0 10,10 0,0"/>"#).unwrap();
        assert!((total_area(&s) - 50.0).abs() < 1e-12);
        let s = read(r#"<polygon points="0,0 10,0 10,10"/>"#).unwrap();
        assert!((total_area(&s) - 50.0).abs() < 1e-12);
        // A second subpath that is open names its subpath.
        let msg = read(r#"<path d="M 0 0 H 10 V 10 Z M 20 20 H 30"/>"#)
            .unwrap_err()
            .to_string();
        assert!(msg.contains("subpath 2"), "{msg}");
    }

    #[test]
    fn unsupported_and_ignored_elements() {
        let e =
            read(r##"<rect id="r" width="5" height="5"/><use href="#r" x="10"/>"##).unwrap_err();
        assert!(
            matches!(e, OutlineError::Unsupported { .. }) && e.to_string().contains("<use"),
            "{e}"
        );
        assert!(matches!(
            read(r#"<text>hi</text>"#),
            Err(OutlineError::Unsupported { .. })
        ));
        // line has no area; defs and display:none are not drawn; foreign namespaces ignored.
        let s = read(
            r#"<line x1="0" y1="0" x2="50" y2="50"/>
               <defs><rect width="99" height="99"/></defs>
               <g style="display:none"><rect width="98" height="98"/></g>
               <rect width="10" height="10"/>"#,
        )
        .unwrap();
        assert_eq!(s.contours.len(), 1);
        assert!((total_area(&s) - 100.0).abs() < 1e-12);
        assert!(matches!(
            read(r#"<line x1="0" y1="0" x2="50" y2="50"/>"#),
            Err(OutlineError::NoClosedShape { .. })
        ));
    }

    #[test]
    fn units_and_percentages() {
        // 25.4 mm = 96 user units; 50 % of a 100-wide viewBox.
        let s = read(r#"<rect width="25.4mm" height="50%"/>"#).unwrap();
        assert!(
            close(bbox(&s), [0.0, -50.0, 96.0, 0.0], 1e-9),
            "{:?}",
            bbox(&s)
        );
        assert!(matches!(
            read(r#"<rect width="2em" height="5"/>"#),
            Err(OutlineError::Unsupported { .. })
        ));
    }

    #[test]
    fn bad_inputs_give_clear_errors() {
        let o = OutlineOptions::default();
        assert!(matches!(
            read_svg_str("", "e.svg", &o),
            Err(OutlineError::Empty { .. })
        ));
        assert!(matches!(
            read_svg_str("<svg", "e.svg", &o),
            Err(OutlineError::Parse { .. })
        ));
        assert!(matches!(
            read_svg_str("<html/>", "e.svg", &o),
            Err(OutlineError::Parse { .. })
        ));
        assert!(matches!(
            read(r#"<rect width="0" height="5"/>"#),
            Err(OutlineError::ZeroArea { .. })
        ));
        assert!(matches!(
            read(r#"<path d="M 0 0 L 10 0 Z"/>"#),
            Err(OutlineError::ZeroArea { .. })
        ));
        assert!(matches!(
            read(r#"<path d="M 0 0 L 10 0 L 1e999 5 Z"/>"#),
            Err(OutlineError::Invalid { .. })
        ));
        let e = read(r#"<path d="M 0 0 L 10 0 X 5"/>"#).unwrap_err();
        assert!(e.to_string().contains("bad path data"), "{e}");
        assert!(matches!(
            read(r#"<rect width="5" height="5" transform="rotate(x)"/>"#),
            Err(OutlineError::Invalid { .. })
        ));
        // Two paths crossing: both named.
        let e = read(r#"<rect id="a" width="10" height="10"/><rect id="b" x="5" y="5" width="10" height="10"/>"#).unwrap_err();
        let m = e.to_string();
        assert!(
            matches!(
                e,
                OutlineError::Crossing {
                    kind: CrossingKind::Cross,
                    ..
                }
            ) && m.contains("id=\"a\"")
                && m.contains("id=\"b\""),
            "{m}"
        );
        let bad = OutlineOptions {
            scale: 0.0,
            ..Default::default()
        };
        assert!(matches!(
            read_svg_str(&doc("<rect width='1' height='1'/>"), "o.svg", &bad),
            Err(OutlineError::Options { .. })
        ));
        let big = " ".repeat(50 * 1024 * 1024 + 1);
        assert!(matches!(
            read_svg_str(&big, "big.svg", &o),
            Err(OutlineError::TooLarge { .. })
        ));
    }

    #[test]
    fn tolerance_option_trades_blocks_for_accuracy() {
        let body = r#"<ellipse cx="0" cy="0" rx="40" ry="15"/>"#;
        let e = EllipseArc {
            center: Point2::origin(),
            m: Matrix2::new(40.0, 0.0, 0.0, -15.0),
            theta0: 0.0,
            dtheta: 2.0 * PI,
        };
        let mut counts = Vec::new();
        for tol in [0.001, 0.01, 0.1] {
            let o = OutlineOptions {
                tolerance: tol,
                ..Default::default()
            };
            let s = read_svg_str(&doc(body), "t.svg", &o).unwrap();
            assert!(curve_to_shape_distance(&e, 0.0, 1.0, &s) <= tol);
            counts.push(s.contours[0].vertices.len());
        }
        assert!(counts[0] > counts[1] && counts[1] > counts[2], "{counts:?}");
    }

    #[test]
    fn doctype_and_entities_are_accepted() {
        let text = r#"<?xml version="1.0"?><!DOCTYPE svg PUBLIC "-//W3C//DTD SVG 1.1//EN" "http://www.w3.org/Graphics/SVG/1.1/DTD/svg11.dtd" [<!ENTITY w "10">]><svg xmlns="http://www.w3.org/2000/svg"><rect width="&w;" height="2"/></svg>"#;
        let s = read_svg_str(text, "d.svg", &OutlineOptions::default()).unwrap();
        assert!((total_area(&s) - 20.0).abs() < 1e-12);
    }

    #[test]
    fn output_is_deterministic() {
        let body = r#"<path d="M 10 80 C 40 10 65 10 95 80 Q 50 120 10 80 Z"/><ellipse cx="50" cy="60" rx="9" ry="4"/>"#;
        assert_eq!(read(body).unwrap(), read(body).unwrap());
    }
}
