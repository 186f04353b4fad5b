//! CL CSV: exact header, one row per original move, values parse back.

use super::{dir, toolpath};
use crate::geom::MoveKind::*;
use crate::post::{CL_CSV_HEADER, write_cl_csv};

#[test]
fn header_rows_and_values() {
    let tp = toolpath(&[
        (Rapid, 6000.0, [1.5, -2.25, 50.0], [0.0, 0.0, 1.0]),
        (Approach, 500.0, [1.5, -2.25, 3.0], dir(10.0, 20.0)),
        (Cut, 1234.5678, [-1e-9, 4.0, -0.0], dir(40.0, -120.0)),
        (Retract, 3000.0, [0.0, 4.0, 30.0], dir(40.0, -120.0)),
    ]);
    let csv = write_cl_csv(&tp);
    assert_eq!(CL_CSV_HEADER, "x,y,z,i,j,k,kind,feed,tool");
    let mut lines = csv.lines();
    assert_eq!(lines.next(), Some("x,y,z,i,j,k,kind,feed,tool"));
    let rows: Vec<&str> = lines.collect();
    assert_eq!(rows.len(), tp.moves.len());
    // -1e-9 is a real value at 9 decimals; only a negative zero is forbidden.
    assert!(
        csv.split([',', '\n'])
            .all(|f| f != "-0.000000000" && f != "-0.000")
    );
    for (row, m) in rows.iter().zip(&tp.moves) {
        let f: Vec<&str> = row.split(',').collect();
        assert_eq!(f.len(), 9);
        let num = |i: usize| f[i].parse::<f64>().unwrap();
        for (i, v) in [m.pose.tip.x, m.pose.tip.y, m.pose.tip.z]
            .iter()
            .enumerate()
        {
            assert!((num(i) - v).abs() <= 5e-10);
        }
        for (i, v) in m.pose.axis.iter().enumerate() {
            assert!((num(3 + i) - v).abs() <= 5e-10);
        }
        for s in &f[..6] {
            assert_eq!(
                s.split('.').nth(1).map(str::len),
                Some(crate::post::cl::CL_DECIMALS),
                "{s}"
            );
        }
        let kind = match m.kind {
            Rapid => "rapid",
            Approach => "approach",
            Cut => "cut",
            Retract => "retract",
        };
        assert_eq!(f[6], kind);
        assert!((num(7) - m.feed).abs() <= 5e-4);
        assert_eq!(f[8], "7");
    }
    assert_eq!(csv, write_cl_csv(&tp), "deterministic");
}

#[test]
fn empty_toolpath_is_just_the_header() {
    assert_eq!(
        write_cl_csv(&Default::default()),
        "x,y,z,i,j,k,kind,feed,tool\n"
    );
}
