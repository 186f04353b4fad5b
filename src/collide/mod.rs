//! Collision and clearance between the tool and the part.
//!
//! * the exact f64 closest points and signed distance it measures with (the gouge guarantee)
//!   are [`crate::mesh::distance`], below every stage that needs them;
//! * `tool_bodies`: the tool assembly as parry3d shapes, tested against the part with
//!   BVH-accelerated `intersection_test` and `closest_points` (f32, with margins that cover
//!   f32 error).
//!
//! This is one of the two modules where glam types exist (parry3d speaks glam); nothing glam
//! leaves it.

pub(crate) mod tool_bodies;

pub use tool_bodies::{
    BodyClearance, ColliderError, Collision, F32_SLACK, Margins, PartCollider, PreparedTool, Table,
};
