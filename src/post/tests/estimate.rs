//! Time estimate from posted blocks.

use super::pose;
use crate::geom::{Move, MoveKind};
use crate::post::{Joints, estimate_time};

fn block(kind: MoveKind, feed: f64, j: Joints) -> (Move, Joints) {
    (
        Move {
            pose: pose([0.0; 3], [0.0, 0.0, 1.0]),
            kind,
            feed,
        },
        j,
    )
}

#[test]
fn times_per_kind() {
    let j = |x: f64, z: f64, a: f64, c: f64| Joints { x, y: 0.0, z, a, c };
    let program = [
        block(MoveKind::Rapid, 5000.0, j(0.0, 500.0, 0.0, 0.0)),
        block(MoveKind::Rapid, 5000.0, j(0.0, 0.0, 0.0, 0.0)), // 500 mm at 5000 ⇒ 6 s
        block(MoveKind::Approach, 600.0, j(0.0, -10.0, 0.0, 0.0)), // 10 mm at 600 ⇒ 1 s
        block(MoveKind::Cut, 1000.0, j(100.0, -10.0, 0.0, 0.0)), // 100 mm at 1000 ⇒ 6 s
        block(MoveKind::Cut, 1000.0, j(100.0, -10.0, 0.0, 90.0)), // pure rotary 90° at F1000 vs 3600°/min ⇒ 5.4 s
        block(MoveKind::Cut, 1000.0, j(101.0, -10.0, 0.0, 270.0)), // 1 mm but 180° ⇒ 3 s at 3600°/min
        block(MoveKind::Retract, 3000.0, j(101.0, 40.0, 0.0, 270.0)), // 50 mm ⇒ 1 s
    ];
    let t = estimate_time(&program, 3600.0);
    let close = |u: f64, v: f64| (u - v).abs() < 1e-9;
    assert!(close(t.rapid_s, 6.0), "{t:?}");
    assert!(close(t.approach_s, 1.0), "{t:?}");
    assert!(close(t.cut_s, 6.0 + 5.4 + 3.0), "{t:?}");
    assert!(close(t.retract_s, 1.0), "{t:?}");
    assert!(close(t.total_s(), 22.4));
    assert_eq!(t.invalid_feed_blocks, 0);
}
