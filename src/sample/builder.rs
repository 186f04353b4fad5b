//! A growing [`Mesh`] with checked `u32` vertex indices.

use nalgebra::Point3;

use super::{SampleError, invalid};
use crate::mesh::Mesh;

/// Accumulates vertices and triangles in the order the generators emit them.
#[derive(Debug, Default)]
pub(super) struct MeshBuilder {
    pub(super) mesh: Mesh,
}

impl MeshBuilder {
    /// Appends a vertex and returns its index.
    pub(super) fn vertex(&mut self, p: Point3<f64>) -> Result<u32, SampleError> {
        let i = u32::try_from(self.mesh.positions.len())
            .map_err(|_| invalid("resolution", "too many vertices for u32 indices"))?;
        self.mesh.positions.push(p);
        Ok(i)
    }

    /// Appends a loop of vertices and returns their indices in order.
    pub(super) fn vertex_loop(
        &mut self,
        pts: impl IntoIterator<Item = Point3<f64>>,
    ) -> Result<Vec<u32>, SampleError> {
        pts.into_iter().map(|p| self.vertex(p)).collect()
    }

    /// Appends triangles as they are.
    pub(super) fn triangles(&mut self, tris: impl IntoIterator<Item = [u32; 3]>) {
        self.mesh.triangles.extend(tris);
    }

    /// Appends triangles with their orientation reversed (for faces seen from below).
    pub(super) fn triangles_flipped(&mut self, tris: impl IntoIterator<Item = [u32; 3]>) {
        self.mesh
            .triangles
            .extend(tris.into_iter().map(|[a, b, c]| [a, c, b]));
    }

    /// The position of vertex `i`.
    pub(super) fn position(&self, i: u32) -> Point3<f64> {
        self.mesh.positions[i as usize]
    }

    /// The finished mesh.
    pub(super) fn finish(self) -> Mesh {
        self.mesh
    }
}
