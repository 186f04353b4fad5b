//! Stretches of a polyline picked by a flag per point: the arc length along it, flags grown
//! by a distance along it, and the runs of set flags. Partial passes (a loop needed only in
//! places, a pass kept only where it cuts something new) are cut out of whole ones this way.

use std::ops::Range;

use super::Point3;

/// The arc length from the first point to each point of `points`.
pub fn arc_lengths(points: &[Point3]) -> Vec<f64> {
    let mut along = Vec::with_capacity(points.len());
    let mut total = 0.0;
    for (i, p) in points.iter().enumerate() {
        if i > 0 {
            total += (p - points[i - 1]).norm();
        }
        along.push(total);
    }
    along
}

/// `flags` with every point within `overlap` of arc length (`along`) of a set one set too,
/// both ways.
pub fn run_on(flags: &[bool], along: &[f64], overlap: f64) -> Vec<bool> {
    let mut grown = flags.to_vec();
    let mut last: Option<f64> = None;
    for i in 0..flags.len() {
        if flags[i] {
            last = Some(along[i]);
        } else if last.is_some_and(|s| along[i] - s <= overlap) {
            grown[i] = true;
        }
    }
    let mut next: Option<f64> = None;
    for i in (0..flags.len()).rev() {
        if flags[i] {
            next = Some(along[i]);
        } else if next.is_some_and(|s| s - along[i] <= overlap) {
            grown[i] = true;
        }
    }
    grown
}

/// The maximal runs of consecutive set `flags`, in order.
pub fn runs_of_set(flags: &[bool]) -> Vec<Range<usize>> {
    let mut runs = Vec::new();
    let mut i = 0;
    while i < flags.len() {
        if !flags[i] {
            i += 1;
            continue;
        }
        let start = i;
        while i < flags.len() && flags[i] {
            i += 1;
        }
        runs.push(start..i);
    }
    runs
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn flags_run_on_by_arc_length_and_split_into_runs() {
        let points: Vec<Point3> = (0..8)
            .map(|i| Point3::new(f64::from(i), 0.0, 0.0))
            .collect();
        let along = arc_lengths(&points);
        assert_eq!(along, [0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0]);
        let flags = [false, false, false, true, false, false, false, true];
        let grown = run_on(&flags, &along, 1.0);
        assert_eq!(grown, [false, false, true, true, true, false, true, true]);
        assert_eq!(runs_of_set(&grown), [2..5, 6..8]);
        assert!(runs_of_set(&[false; 3]).is_empty());
    }
}
