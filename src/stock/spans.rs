//! The material along one dexel: sorted, disjoint, non-empty closed intervals of the ray
//! parameter, and the one operation removal needs (subtract an interval).

use smallvec::SmallVec;

/// One interval of material along a dexel ray, in mm of the ray's coordinate.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Span {
    /// Where the material starts.
    pub start: f64,
    /// Where it ends (`> start`).
    pub end: f64,
}

impl Span {
    /// Length, mm.
    pub fn length(&self) -> f64 {
        self.end - self.start
    }
}

/// The spans of one dexel, sorted and disjoint. Most dexels hold one span (a blank) or two
/// (a pocket cut through), so one is kept inline.
pub type Spans = SmallVec<[Span; 1]>;

/// Removes `[start, end]` from `spans`; returns the length removed. Spans left shorter than
/// `min_length` (slivers below the model's resolution along the ray) are dropped with it, and
/// an overlap shorter than `min_length` is not a cut.
pub fn subtract(spans: &mut Spans, start: f64, end: f64, min_length: f64) -> f64 {
    subtract_recording(spans, start, end, min_length, &mut |_, _| {})
}

/// [`subtract`], telling `removed` each piece of material it takes away (start, end).
pub fn subtract_recording(
    spans: &mut Spans,
    start: f64,
    end: f64,
    min_length: f64,
    removed: &mut impl FnMut(f64, f64),
) -> f64 {
    if end.partial_cmp(&start) != Some(std::cmp::Ordering::Greater) || spans.is_empty() {
        return 0.0;
    }
    // Quick reject: the interval misses every span.
    let (first, last) = (spans[0].start, spans[spans.len() - 1].end);
    if end <= first || start >= last {
        return 0.0;
    }
    let before: f64 = spans.iter().map(Span::length).sum();
    // In place: a dexel's spans live inline or in a buffer kept from cut to cut, so removal
    // allocates only when a cut splits a span and the buffer is full.
    let mut i = 0;
    while i < spans.len() {
        let s = spans[i];
        if s.start >= end {
            break;
        }
        // An overlap shorter than `min_length` is round-off of a cut made before (a tool
        // passing again where it already cut): the span stays as it is.
        if s.end <= start || s.end.min(end) - s.start.max(start) < min_length.max(0.0) {
            i += 1;
            continue;
        }
        removed(s.start.max(start), s.end.min(end));
        let left = (s.start < start && start - s.start >= min_length).then_some(Span {
            start: s.start,
            end: start,
        });
        let right = (s.end > end && s.end - end >= min_length).then_some(Span {
            start: end,
            end: s.end,
        });
        match (left, right) {
            (Some(left), Some(right)) => {
                spans[i] = left;
                spans.insert(i + 1, right);
                i += 2;
            }
            (Some(piece), None) | (None, Some(piece)) => {
                spans[i] = piece;
                i += 1;
            }
            (None, None) => {
                spans.remove(i);
            }
        }
    }
    before - spans.iter().map(Span::length).sum::<f64>()
}

/// `true` when `t` lies in one of the spans.
pub fn contains(spans: &Spans, t: f64) -> bool {
    spans.iter().any(|s| s.start <= t && t <= s.end)
}

/// Total length of the spans, mm.
pub fn length(spans: &Spans) -> f64 {
    spans.iter().map(Span::length).sum()
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn spans(v: &[(f64, f64)]) -> Spans {
        v.iter().map(|&(start, end)| Span { start, end }).collect()
    }

    #[test]
    fn subtracting_splits_trims_and_drops() {
        let mut s = spans(&[(0.0, 10.0)]);
        assert_eq!(subtract(&mut s, 3.0, 4.0, 0.0), 1.0);
        assert_eq!(s, spans(&[(0.0, 3.0), (4.0, 10.0)]));
        assert_eq!(subtract(&mut s, -1.0, 1.0, 0.0), 1.0);
        assert_eq!(s, spans(&[(1.0, 3.0), (4.0, 10.0)]));
        assert_eq!(subtract(&mut s, 2.0, 9.0, 0.0), 1.0 + 5.0);
        assert_eq!(s, spans(&[(1.0, 2.0), (9.0, 10.0)]));
        // A sliver below the minimum length goes too, and counts as removed.
        assert_eq!(subtract(&mut s, 1.05, 9.5, 0.1), 1.0 + 0.5);
        assert_eq!(s, spans(&[(9.5, 10.0)]));
        assert_eq!(subtract(&mut s, 20.0, 30.0, 0.0), 0.0);
        assert_eq!(subtract(&mut s, 5.0, 5.0, 0.0), 0.0);
        assert_eq!(subtract(&mut s, 0.0, 100.0, 0.0), 0.5);
        assert!(s.is_empty());
    }

    proptest! {
        /// Against a brute-force membership test on sample points: what is left is exactly
        /// the old material outside the interval, sorted and disjoint.
        #[test]
        fn subtraction_agrees_with_point_membership(
            cuts in proptest::collection::vec((-5.0..15.0f64, 0.0..6.0f64), 1..6),
        ) {
            let mut s = spans(&[(0.0, 4.0), (5.0, 7.0), (8.0, 10.0)]);
            let mut removed_total = 0.0;
            let mut holes: Vec<(f64, f64)> = Vec::new();
            for &(a, len) in &cuts {
                removed_total += subtract(&mut s, a, a + len, 0.0);
                holes.push((a, a + len));
            }
            for w in s.windows(2) {
                prop_assert!(w[0].end < w[1].start);
            }
            prop_assert!(s.iter().all(|x| x.end > x.start));
            let original = spans(&[(0.0, 4.0), (5.0, 7.0), (8.0, 10.0)]);
            for k in 0..=2000 {
                let t = -1.0 + k as f64 * 0.006_1;
                let in_hole = holes.iter().any(|&(a, b)| a < t && t < b);
                let on_edge = holes.iter().any(|&(a, b)| (t - a).abs() < 1e-12 || (t - b).abs() < 1e-12);
                if on_edge { continue; }
                prop_assert_eq!(contains(&s, t), contains(&original, t) && !in_hole, "t = {}", t);
            }
            prop_assert!((length(&original) - length(&s) - removed_total).abs() < 1e-9);
        }
    }
}
