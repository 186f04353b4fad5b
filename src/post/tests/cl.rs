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

#[test]
fn cl_data_reads_back_and_bad_lines_are_named() {
    use crate::post::read_cl_csv;
    let tp = toolpath(&[
        (Rapid, 6000.0, [1.5, -2.25, 50.0], [0.0, 0.0, 1.0]),
        (Approach, 500.0, [1.5, -2.25, 3.0], dir(10.0, 20.0)),
        (Cut, 1234.5678, [-1e-9, 4.0, -0.0], dir(40.0, -120.0)),
        (Retract, 3000.0, [0.0, 4.0, 30.0], dir(40.0, -120.0)),
    ]);
    let csv = write_cl_csv(&tp);
    let back = read_cl_csv(&csv, "cl.csv").unwrap();
    assert_eq!(back.moves.len(), tp.moves.len());
    for (a, b) in back.moves.iter().zip(&tp.moves) {
        assert_eq!(a.kind, b.kind);
        assert!((a.pose.tip - b.pose.tip).norm() < 1e-9);
        assert!((a.pose.axis.into_inner() - b.pose.axis.into_inner()).norm() < 2e-9);
        assert!((a.feed - b.feed).abs() < 1e-3);
    }
    let row = csv.lines().nth(2).unwrap();
    for (text, line, says) in [
        (String::new(), 1, "empty"),
        ("x,y,z\n".to_string(), 1, "header"),
        (format!("{CL_CSV_HEADER}\n"), 1, "no moves"),
        (format!("{CL_CSV_HEADER}\n{row}\n1,2,3\n"), 3, "9 fields"),
        (
            format!("{CL_CSV_HEADER}\n{row}\n\n1,2,nan,0,0,1,cut,10,1\n"),
            4,
            "finite",
        ),
        (
            format!("{CL_CSV_HEADER}\n1,2,3,0,0,2,cut,10,1\n"),
            2,
            "unit",
        ),
        (
            format!("{CL_CSV_HEADER}\n1,2,3,0,0,1,drill,10,1\n"),
            2,
            "kind",
        ),
        (format!("{CL_CSV_HEADER}\n1,2,3,0,0,1,cut,0,1\n"), 2, "feed"),
        (
            format!("{CL_CSV_HEADER}\n1,2,3,0,0,1,cut,5,1\n1,2,3,0,0,1,cut,5,2\n"),
            3,
            "one tool",
        ),
    ] {
        let e = read_cl_csv(&text, "p.csv").unwrap_err();
        assert_eq!(e.line, line, "{e}");
        assert!(
            e.to_string().starts_with(&format!("p.csv: line {line}: ")),
            "{e}"
        );
        assert!(e.reason.contains(says), "{e}");
    }
}
