//! The ground of the `terrain` and `terrain_mesh` reference scenes: a bowl of
//! [`TERRAIN_COLUMNS`]² height samples, [`TERRAIN_CELL`] apart, as a [`HeightField`]
//! (`terrain`) and as a [`TriangleMesh`] of the very same triangles (`terrain_mesh`), so
//! both mid-phase paths (cell walk and hierarchy) have a golden checksum on every target.
//!
//! The storage is one plain struct ([`TerrainData`], about 50 KB, no allocation) the
//! caller owns (a `static` on a microcontroller, a `Box` on a host);
//! [`TerrainData::shapes`] fills it and borrows the two grounds out of it.

use super::Scene;
use crate::error::Error;
use crate::math::Vec3;
use crate::shape::{BvhNode, HeightField, Shape, TriangleMesh};

/// Samples per side of the reference terrain: 16 × 16 cells.
pub const TERRAIN_COLUMNS: u32 = 17;

/// Distance between samples (m): the terrain is 16 m a side.
pub const TERRAIN_CELL: f32 = 1.0;

/// Height samples of the reference terrain.
pub const TERRAIN_SAMPLES: usize = (TERRAIN_COLUMNS * TERRAIN_COLUMNS) as usize;

/// Triangles of the reference terrain: two per cell, 512.
pub const TERRAIN_TRIANGLES: usize = 2 * ((TERRAIN_COLUMNS - 1) * (TERRAIN_COLUMNS - 1)) as usize;

/// Hierarchy nodes the mesh form needs ([`TriangleMesh::nodes_needed`]).
pub const TERRAIN_NODES: usize = TriangleMesh::nodes_needed(TERRAIN_TRIANGLES);

/// Storage of the reference terrain in both forms: heights for the [`HeightField`];
/// vertices, triangles and hierarchy nodes for the [`TriangleMesh`].
#[derive(Clone, Debug)]
pub struct TerrainData {
    heights: [f32; TERRAIN_SAMPLES],
    vertices: [Vec3; TERRAIN_SAMPLES],
    indices: [[u32; 3]; TERRAIN_TRIANGLES],
    nodes: [BvhNode; TERRAIN_NODES],
}

impl Default for TerrainData {
    fn default() -> Self {
        TerrainData::EMPTY
    }
}

/// The two forms of the reference terrain, borrowed from a [`TerrainData`].
#[derive(Clone, Copy, Debug)]
pub struct TerrainShapes<'a> {
    /// The height field (`terrain`).
    pub field: HeightField<'a>,
    /// The same triangles as a mesh with its hierarchy (`terrain_mesh`).
    pub mesh: TriangleMesh<'a>,
}

impl TerrainData {
    /// Zeroed storage (a `const`, so a `static` can start from it).
    pub const EMPTY: TerrainData = TerrainData {
        heights: [0.0; TERRAIN_SAMPLES],
        vertices: [Vec3::ZERO; TERRAIN_SAMPLES],
        indices: [[0; 3]; TERRAIN_TRIANGLES],
        nodes: [BvhNode::EMPTY; TERRAIN_NODES],
    };

    /// Fill the storage (whatever it held) and borrow both forms of the terrain. The
    /// mesh's triangles are the field's, in the field's order: triangle `2·(j·16 + i) + k`
    /// of cell `(i, j)`, vertex `j · 17 + i` at sample `(i, j)`.
    pub fn shapes(&mut self) -> Result<TerrainShapes<'_>, Error> {
        let n = TERRAIN_COLUMNS;
        for (k, (h, v)) in self
            .heights
            .iter_mut()
            .zip(self.vertices.iter_mut())
            .enumerate()
        {
            let (i, j) = (k as u32 % n, k as u32 / n);
            *h = terrain_height(i, j);
            *v = Vec3::new(i as f32 * TERRAIN_CELL, *h, j as f32 * TERRAIN_CELL);
        }
        let cells = n - 1;
        for (t, tri) in self.indices.iter_mut().enumerate() {
            let cell = t as u32 / 2;
            let (i, j) = (cell % cells, cell / cells);
            let v = |di: u32, dj: u32| (j + dj) * n + i + di;
            // The field's split of a cell along its (i, j)–(i+1, j+1) diagonal.
            *tri = if t % 2 == 0 {
                [v(0, 0), v(1, 1), v(1, 0)]
            } else {
                [v(0, 0), v(0, 1), v(1, 1)]
            };
        }
        let field = HeightField::new(&self.heights, n, n, TERRAIN_CELL)?;
        let mesh = TriangleMesh::build(&self.vertices, &self.indices, &mut self.nodes)?;
        Ok(TerrainShapes { field, mesh })
    }
}

impl<'a> TerrainShapes<'a> {
    /// The ground `scene` stands on: the field for [`Scene::Terrain`], the mesh for
    /// [`Scene::TerrainMesh`]; `None` for every other scene (what [`Scene::run_on`]
    /// wants for them).
    pub fn ground(&'a self, scene: Scene) -> Option<Shape<'a>> {
        match scene {
            Scene::Terrain => Some(Shape::HeightField(&self.field)),
            Scene::TerrainMesh => Some(Shape::Mesh(&self.mesh)),
            _ => None,
        }
    }
}

/// Height of sample `(i, j)` (m): a bowl `0.05 r²` about the centre sample (r in m, so
/// 3.2 m at the middle of an edge, 6.4 m at a corner) with a ripple of 0.12 m, so the
/// bodies slide down into a pile instead of off the edge. Plain `+ − ×` and integer
/// truncation: the same bits on every target and math backend.
fn terrain_height(i: u32, j: u32) -> f32 {
    let c = (TERRAIN_COLUMNS / 2) as f32;
    let (x, z) = ((i as f32 - c) * TERRAIN_CELL, (j as f32 - c) * TERRAIN_CELL);
    0.05 * (x * x + z * z) + 0.12 * super::triangle_wave((i + 2 * j) as f32 / 5.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_mesh_holds_the_fields_triangles_in_the_fields_order() {
        let mut data = std::boxed::Box::new(TerrainData::EMPTY);
        let shapes = data.shapes().unwrap();
        assert_eq!(shapes.field.triangle_count() as usize, TERRAIN_TRIANGLES);
        assert_eq!(shapes.mesh.triangle_count() as usize, TERRAIN_TRIANGLES);
        for t in 0..TERRAIN_TRIANGLES as u32 {
            assert_eq!(
                shapes.field.triangle(t),
                shapes.mesh.triangle(t),
                "triangle {t}"
            );
        }
        // The bowl: the centre is the lowest sample, the corners the highest.
        let h = shapes.field.heights();
        let centre = h[TERRAIN_SAMPLES / 2];
        assert!(h.iter().all(|&y| y >= centre));
        assert!(h[0] > 6.3 && h[0] < 6.55, "corner {}", h[0]);
    }
}
