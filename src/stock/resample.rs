//! The stock seen from a turned frame: a tri-dexel model of the same material whose lines run
//! along the axes of a rotated frame, for planning along a tilted tool axis (indexed 3+2
//! roughing, [`crate::rough::indexed`]), where the planner reads the material along the setup's
//! own vertical.
//!
//! The new lines cross the old ones at no particular point, so the material along each is
//! sampled: every `step` along it, the old model's vote ([`Stock::is_material`]). A run of
//! material samples becomes one span reaching half a step past its end samples, grown by `grow`
//! at both ends (merged where they meet). The old model knows a surface to within its spacing
//! across its lines and the samples to within half a step along the new ones, so with `grow` of
//! a spacing the new model holds the old one's material up to what falls between lines: a
//! planner reading it sees slightly more material than stands, never less (cutting air, not
//! meeting unplanned material). Only the planner reads it; every move it plans is then taken
//! off, and checked on, the original model.

use nalgebra::Rotation3;

use super::spans::{Span, Spans};
use super::{Stock, StockError};
use crate::geom::{Aabb, Point3, Vector3};

impl Stock {
    /// The material of `self` in the frame `rotation` turns the part frame into (a point `p`
    /// of `self` is `rotation * p` in the new model), on lines `spacing` apart, each span
    /// grown by `grow` mm at both ends (module docs). Refused above `max_dexels` lines, or
    /// when there is no material.
    pub fn resampled(
        &self,
        rotation: &Rotation3<f64>,
        spacing: f64,
        grow: f64,
        max_dexels: usize,
    ) -> Result<Stock, StockError> {
        let old = self.material_bounds();
        if old.is_empty() {
            return Err(StockError::Blank("no material left to resample".into()));
        }
        let corners: Vec<Point3> = (0..8)
            .map(|k| {
                let pick = |bit: usize, a: usize| {
                    if k & bit == 0 { old.min[a] } else { old.max[a] }
                };
                rotation * Point3::new(pick(1, 0), pick(2, 1), pick(4, 2))
            })
            .collect();
        let bounds = Aabb::from_points(&corners).inflated(grow + spacing);
        let mut stock = Stock::empty(&bounds, spacing, max_dexels)?;
        let inverse = rotation.inverse();
        // Samples outside the old material's box are air: clip each line to it first.
        let search = old.inflated(self.spacing);
        let step = 0.5 * self.spacing.min(spacing);
        stock.fill(|axis, p| {
            let mut unit = Vector3::zeros();
            unit[axis] = 1.0;
            let mut start = *p;
            start[axis] = 0.0;
            let (origin, direction) = (inverse * start, inverse * unit);
            let Some((t0, t1)) = clip_line(&origin, &direction, &search) else {
                return Spans::new();
            };
            let mut spans = Spans::new();
            let mut run: Option<(f64, f64)> = None;
            let samples = ((t1 - t0) / step).ceil() as usize + 1;
            for k in 0..samples {
                let t = t0 + k as f64 * step;
                if self.is_material(&(origin + t * direction)) {
                    run = Some(run.map_or((t, t), |(a, _)| (a, t)));
                } else if let Some((a, b)) = run.take() {
                    push_merged(&mut spans, a - 0.5 * step - grow, b + 0.5 * step + grow);
                }
            }
            if let Some((a, b)) = run {
                push_merged(&mut spans, a - 0.5 * step - grow, b + 0.5 * step + grow);
            }
            spans
        });
        Ok(stock)
    }
}

/// Appends `[start, end]` to sorted `spans`, merging it with the last span when they meet.
fn push_merged(spans: &mut Spans, start: f64, end: f64) {
    if let Some(last) = spans.last_mut()
        && start <= last.end
    {
        last.end = last.end.max(end);
        return;
    }
    spans.push(Span { start, end });
}

/// The parameter interval of the line `origin + t · direction` inside `bounds` (slab method).
fn clip_line(origin: &Point3, direction: &Vector3, bounds: &Aabb) -> Option<(f64, f64)> {
    let (mut t0, mut t1) = (f64::NEG_INFINITY, f64::INFINITY);
    for a in 0..3 {
        if direction[a].abs() < 1e-12 {
            if origin[a] < bounds.min[a] || origin[a] > bounds.max[a] {
                return None;
            }
            continue;
        }
        let (u, v) = (
            (bounds.min[a] - origin[a]) / direction[a],
            (bounds.max[a] - origin[a]) / direction[a],
        );
        t0 = t0.max(u.min(v));
        t1 = t1.min(u.max(v));
    }
    (t0 <= t1).then_some((t0, t1))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::stock::DEFAULT_MAX_DEXELS;
    use nalgebra::Vector3;

    /// A block turned 30° about a tilted axis holds the same volume (to the sampling's skin of
    /// `grow` + a spacing over its surface) and the same points: inside more than the skin is
    /// material in the turned model, outside more than it is not.
    #[test]
    fn a_turned_block_holds_the_same_material() {
        let bounds =
            Aabb::from_points(&[Point3::new(-10.0, -6.0, 0.0), Point3::new(10.0, 6.0, 8.0)]);
        let spacing = 0.25;
        let block = Stock::block(&bounds, spacing, DEFAULT_MAX_DEXELS).unwrap();
        let rotation = Rotation3::from_axis_angle(
            &nalgebra::Unit::new_normalize(Vector3::new(1.0, 1.0, 0.3)),
            30f64.to_radians(),
        );
        let grow = spacing;
        let turned = block
            .resampled(&rotation, spacing, grow, DEFAULT_MAX_DEXELS)
            .unwrap();
        let area = 2.0 * (20.0 * 12.0 + 20.0 * 8.0 + 12.0 * 8.0);
        let volume = 20.0 * 12.0 * 8.0;
        let v = turned.volume();
        assert!(v >= volume - 0.5 * spacing * area, "{v} against {volume}");
        assert!(
            v <= volume + (grow + spacing) * area,
            "{v} against {volume}"
        );
        let skin = grow + 2.0 * spacing;
        let mut checked = 0;
        for i in -14..=14 {
            for j in -10..=10 {
                for k in -4..=12 {
                    let p = Point3::new(i as f64 * 0.77, j as f64 * 0.71, k as f64 * 0.73);
                    let outside = (0..3)
                        .map(|a| (bounds.min[a] - p[a]).max(p[a] - bounds.max[a]))
                        .fold(f64::NEG_INFINITY, f64::max);
                    let q = rotation * p;
                    if outside < -skin {
                        assert!(turned.is_material(&q), "{p:?} is inside the block");
                        checked += 1;
                    } else if outside > skin {
                        assert!(!turned.is_material(&q), "{p:?} is outside the block");
                        checked += 1;
                    }
                }
            }
        }
        assert!(checked > 5000, "{checked}");
    }

    #[test]
    fn no_material_is_refused() {
        let bounds = Aabb::from_points(&[Point3::origin(), Point3::new(2.0, 2.0, 2.0)]);
        let mut block = Stock::block(&bounds, 0.5, DEFAULT_MAX_DEXELS).unwrap();
        block.remove(&crate::stock::sweep::Capsule {
            a: Point3::new(1.0, 1.0, -10.0),
            b: Point3::new(1.0, 1.0, 10.0),
            radius: 10.0,
        });
        assert!(
            block
                .resampled(&Rotation3::identity(), 0.5, 0.5, DEFAULT_MAX_DEXELS)
                .is_err()
        );
    }
}
