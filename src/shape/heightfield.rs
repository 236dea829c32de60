//! Height field terrain (a mid phase's geometry, like [`super::TriangleMesh`]): the caller
//! owns a row-major grid of heights; the field borrows it. Its triangles are implicit in
//! the grid, so it needs no hierarchy: box queries walk the covered cells, ray casts the
//! cells under the ray.

use super::{Ray, RayHit, Triangle};
use crate::error::{Error, Input, MAX_COORDINATE};
use crate::math::{scalar, Aabb, Vec3};

/// Most cells a [`HeightField`] may have (2¹⁹ = 524,288): two triangles each, so triangle
/// indices stay below 2²⁰, the bound of [`super::MAX_MESH_TRIANGLES`]. Split larger
/// terrain into several fields.
pub const MAX_HEIGHT_FIELD_CELLS: usize = 1 << 19;

/// The ray cast widens the cells it walks by this fraction of the largest coordinate (m)
/// of the field's box and the ray origin, plus as much again in metres, so the rounding of
/// [`Triangle::cast_ray`] (whose hit may lie a few ulps outside the triangle) never makes
/// the walk skip a triangle it would report (the same margin as the mesh's box test).
const RAY_TOL: f32 = 1.0e-5;

/// A direction whose largest component is below this (m per unit `t`) meets no triangle:
/// [`Triangle::cast_ray`] finds it parallel to every triangle a field can have (see
/// [`HeightField::cast_ray`]).
const TINY_DIRECTION: f32 = 1.0e-24;

/// A height field: caller-owned heights (m) on a square grid in the local XZ plane, Y up.
/// Pure geometry, in the field's local frame; a body's shape as [`crate::Shape::HeightField`].
///
/// `columns` samples run along local +X and `rows` along local +Z, row-major: sample
/// `(i, j)` (column `i`, row `j`) is the vertex `(i · cell_size, heights[j · columns + i],
/// j · cell_size)`, so the grid's corner sits at the local origin and the field covers
/// `[0, (columns − 1) · cell_size] × [0, (rows − 1) · cell_size]` in x and z. Each
/// coordinate is computed as one `f32` product, `(i as f32) · cell_size`, the same bits
/// in every query.
///
/// # Memory
///
/// The heights are the caller's (4 bytes per sample); the field is a slice reference, its
/// grid size and cell size and its bounding box (56 bytes on a 64-bit target). Queries
/// use no storage.
///
/// # Layout
///
/// `(columns − 1) × (rows − 1)` cells; cell `(i, j)` has the corners `p00 = (i, j)`,
/// `p10 = (i + 1, j)`, `p01 = (i, j + 1)` and `p11 = (i + 1, j + 1)` and is split along
/// its diagonal `p00–p11` into two triangles, counter-clockwise seen from +Y (so
/// [`Triangle::normal`] has a positive y: up, for any heights):
///
/// ```text
///   seen from above (+Y towards you)
///
///    o ───────────────→ +X (column i)
///    │   p00 ─────── p10
///    │    │ ╲    k = 0 │       k = 0: (p00, p11, p10)
///    │    │   ╲        │       k = 1: (p00, p01, p11)
///    │    │ k = 1 ╲    │
///    │   p01 ─────── p11
///    ↓
///   +Z (row j)
/// ```
///
/// Triangle `t = 2 · (j · (columns − 1) + i) + k`: cells row by row, two triangles each.
///
/// # Example
///
/// ```
/// use carom::shape::HeightField;
/// use carom::{Aabb, Ray, Vec3};
///
/// # fn main() -> Result<(), carom::Error> {
/// // 3 × 2 samples, 1 m apart: two cells, four triangles; a ridge along x = 1.
/// let heights = [
///     0.0, 1.0, 0.0, // row 0 (z = 0)
///     0.0, 1.0, 0.0, // row 1 (z = 1)
/// ];
/// let field = HeightField::new(&heights, 3, 2, 1.0)?;
/// assert_eq!(field.triangle_count(), 4);
/// assert_eq!(field.aabb(), Aabb::new(Vec3::ZERO, Vec3::new(2.0, 1.0, 1.0)));
/// assert!(field.triangle(0).unwrap().normal().y > 0.0); // counter-clockwise from above
///
/// // Triangles whose bounding boxes overlap a box, in increasing index order.
/// let mut found = [false; 4];
/// field.query_aabb(&Aabb::new(Vec3::new(1.5, 0.0, 0.0), Vec3::new(1.6, 0.1, 0.1)), |t| {
///     found[t as usize] = true
/// });
/// assert_eq!(found, [false, false, true, true]); // the second cell's two
///
/// // The nearest point where a ray meets the terrain, and which triangle it is.
/// let down = Ray::new(Vec3::new(0.75, 3.0, 0.25), -Vec3::Y)?;
/// let (t, hit) = field.cast_ray(&down, 100.0).expect("the ray meets the slope");
/// assert_eq!(t, 0); // cell (0, 0), the p10 side of its diagonal
/// assert!((hit.t - 2.25).abs() < 1e-6); // the slope is 0.75 m high there
/// assert!(field.cast_ray(&down, 2.0).is_none()); // too short
/// # Ok(())
/// # }
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HeightField<'a> {
    /// The `columns · rows` heights in use (m), row-major.
    heights: &'a [f32],
    columns: u32,
    rows: u32,
    cell_size: f32,
    /// Bounds of every vertex (m).
    aabb: Aabb,
}

impl<'a> HeightField<'a> {
    /// Check a grid of heights and make a field of it: `columns × rows` samples `cell_size`
    /// metres apart, row-major in `heights` (see the type's docs). Entries of `heights`
    /// past `columns · rows` are ignored. Computes the field's bounding box (one pass over
    /// the heights); borrows the heights, copies nothing.
    ///
    /// # Errors
    ///
    /// Checked in this order; counts and sizes in exact integer arithmetic (no overflow,
    /// on 32-bit targets too):
    ///
    /// 1. fewer than 2 columns or rows (no cell, so no triangle):
    ///    [`Error::NotPositive`]`(`[`Input::TriangleCount`]`)`; more than
    ///    [`MAX_HEIGHT_FIELD_CELLS`] cells, `(columns − 1) · (rows − 1)`:
    ///    [`Error::OutOfRange`]`(`[`Input::TriangleCount`]`)`;
    /// 2. `heights` shorter than `columns · rows`:
    ///    [`Error::BufferTooSmall`]`(columns · rows)`;
    /// 3. each height in use, in order: non-finite:
    ///    [`Error::NonFinite`]`(`[`Input::Point`]`)`; beyond ±[`MAX_COORDINATE`]:
    ///    [`Error::OutOfRange`]`(`[`Input::Point`]`)`;
    /// 4. `cell_size` non-finite: [`Error::NonFinite`]`(`[`Input::Distance`]`)`; zero or
    ///    negative: [`Error::NotPositive`]`(`[`Input::Distance`]`)`; outside
    ///    [[`MIN_SIZE`](super::MIN_SIZE), [`MAX_SIZE`](super::MAX_SIZE)]:
    ///    [`Error::OutOfRange`]`(`[`Input::Distance`]`)`;
    /// 5. the grid's extent, `(columns − 1) · cell_size` or `(rows − 1) · cell_size` (as
    ///    the `f32` vertex coordinate it is), beyond [`MAX_COORDINATE`]:
    ///    [`Error::OutOfRange`]`(`[`Input::Distance`]`)`.
    pub fn new(
        heights: &'a [f32],
        columns: u32,
        rows: u32,
        cell_size: f32,
    ) -> Result<HeightField<'a>, Error> {
        if columns < 2 || rows < 2 {
            return Err(Error::NotPositive(Input::TriangleCount));
        }
        // Both factors are below 2³², so the u64 products cannot overflow.
        let cells = u64::from(columns - 1) * u64::from(rows - 1);
        if cells > MAX_HEIGHT_FIELD_CELLS as u64 {
            return Err(Error::OutOfRange(Input::TriangleCount));
        }
        // cells ≤ 2¹⁹ and each side ≥ 1 cell bounds columns · rows = cells + columns +
        // rows − 1 by 2²⁰ + 3: it fits a u32 and a usize.
        let samples = u64::from(columns) * u64::from(rows);
        let needed = u32::try_from(samples).map_err(|_| Error::OutOfRange(Input::TriangleCount))?;
        let used = usize::try_from(needed).map_err(|_| Error::BufferTooSmall(needed))?;
        let heights = heights.get(..used).ok_or(Error::BufferTooSmall(needed))?;
        let (mut lo, mut hi) = (0.0f32, 0.0f32);
        for (k, &h) in heights.iter().enumerate() {
            if !h.is_finite() {
                return Err(Error::NonFinite(Input::Point));
            }
            if scalar::abs(h) > MAX_COORDINATE {
                return Err(Error::OutOfRange(Input::Point));
            }
            if k == 0 {
                (lo, hi) = (h, h);
            } else {
                lo = scalar::min(lo, h);
                hi = scalar::max(hi, h);
            }
        }
        super::size(cell_size, Input::Distance)?;
        let width = (columns - 1) as f32 * cell_size;
        let depth = (rows - 1) as f32 * cell_size;
        if width > MAX_COORDINATE || depth > MAX_COORDINATE {
            return Err(Error::OutOfRange(Input::Distance));
        }
        Ok(HeightField {
            heights,
            columns,
            rows,
            cell_size,
            aabb: Aabb::new(Vec3::new(0.0, lo, 0.0), Vec3::new(width, hi, depth)),
        })
    }

    /// Number of samples along local +X (at least 2).
    #[inline]
    pub fn columns(&self) -> u32 {
        self.columns
    }

    /// Number of samples along local +Z (at least 2).
    #[inline]
    pub fn rows(&self) -> u32 {
        self.rows
    }

    /// Distance between neighbouring samples along x and z (m).
    #[inline]
    pub fn cell_size(&self) -> f32 {
        self.cell_size
    }

    /// The `columns · rows` heights in use (m), row-major; entries past them in the slice
    /// given to [`HeightField::new`] are not included.
    #[inline]
    pub fn heights(&self) -> &'a [f32] {
        self.heights
    }

    /// Number of triangles: `2 · (columns − 1) · (rows − 1)`, at most
    /// `2 ·` [`MAX_HEIGHT_FIELD_CELLS`].
    #[inline]
    pub fn triangle_count(&self) -> u32 {
        2 * self.cells_x() * self.cells_z()
    }

    /// Bounds of the whole field (m): x and z from 0 to the grid's extent, y from the
    /// lowest height to the highest. Computed by [`HeightField::new`].
    #[inline]
    pub fn aabb(&self) -> Aabb {
        self.aabb
    }

    /// Triangle `t` (vertices in m, in the order of the layout in the type's docs,
    /// counter-clockwise seen from +Y); `None` past the last.
    pub fn triangle(&self, t: u32) -> Option<Triangle> {
        if t >= self.triangle_count() {
            return None;
        }
        let cell = t / 2;
        let nx = self.cells_x();
        self.cell_triangle(cell.checked_rem(nx)?, cell.checked_div(nx)?, t % 2)
    }

    /// The other triangle on edge `edge` (0: v0–v1, 1: v1–v2, 2: v2–v0, in the order
    /// [`HeightField::triangle`] gives the vertices) of triangle `t`: the cell's other
    /// triangle across the diagonal, or the next cell's triangle across a cell side; `None`
    /// on the grid's border or for an index out of range. It is the one other triangle
    /// holding both of the edge's end points (the same bits: both cells compute a shared
    /// vertex from the same sample and column and row coordinates).
    ///
    /// Cell `(i, j)` holds triangle 0 `[p00, p11, p10]` and triangle 1 `[p00, p01, p11]`.
    pub(crate) fn edge_neighbour(&self, t: u32, edge: usize) -> Option<u32> {
        if t >= self.triangle_count() {
            return None;
        }
        let (nx, nz) = (self.cells_x(), self.cells_z());
        let cell = t / 2;
        let (i, j) = (cell.checked_rem(nx)?, cell.checked_div(nx)?);
        // Triangle k of cell (i, j): fewer than 2 · 2²⁰ triangles, no overflow.
        let index = |i: u32, j: u32, k: u32| 2 * (j * nx + i) + k;
        match (t % 2, edge) {
            // The diagonal p00–p11.
            (0, 0) => Some(t + 1),
            // The side x = x(i + 1), p11–p10: triangle 1 of the cell on the right.
            (0, 1) => (i + 1 < nx).then(|| index(i + 1, j, 1)),
            // The side z = z(j), p10–p00: triangle 1 of the cell before.
            (0, _) => (j > 0).then(|| index(i, j - 1, 1)),
            // The side x = x(i), p00–p01: triangle 0 of the cell on the left.
            (_, 0) => (i > 0).then(|| index(i - 1, j, 0)),
            // The side z = z(j + 1), p01–p11: triangle 0 of the cell after.
            (_, 1) => (j + 1 < nz).then(|| index(i, j + 1, 0)),
            // The diagonal p11–p00.
            _ => Some(t - 1),
        }
    }

    /// Call `f` with the index of every triangle whose bounding box (of its vertices)
    /// overlaps or touches `aabb` (m, [`Aabb::overlaps`]), each once, in increasing index
    /// order. A box with a NaN overlaps nothing.
    ///
    /// Only the cells whose x and z ranges meet the box's (found by division, then
    /// checked exactly against the vertex coordinates) are visited, a row at a time; a
    /// box entirely above or below the field visits none. At most every cell once.
    pub fn query_aabb(&self, aabb: &Aabb, mut f: impl FnMut(u32)) {
        if !(aabb.max.y >= self.aabb.min.y && aabb.min.y <= self.aabb.max.y) {
            return;
        }
        let (nx, nz) = (self.cells_x(), self.cells_z());
        let Some((i0, i1)) = self.candidate_cells(aabb.min.x, aabb.max.x, nx) else {
            return;
        };
        let Some((j0, j1)) = self.candidate_cells(aabb.min.z, aabb.max.z, nz) else {
            return;
        };
        for j in j0..=j1 {
            let (z0, z1) = (self.coord(j), self.coord(j + 1));
            if !(z0 <= aabb.max.z && aabb.min.z <= z1) {
                continue;
            }
            for i in i0..=i1 {
                let (x0, x1) = (self.coord(i), self.coord(i + 1));
                if !(x0 <= aabb.max.x && aabb.min.x <= x1) {
                    continue;
                }
                // Both triangles span the cell's x and z ranges (each holds p00 and p11).
                let [h00, h10, h01, h11] = self.cell_heights(i, j);
                let first = 2 * (j * nx + i);
                for (k, h) in [h10, h01].into_iter().enumerate() {
                    let lo = scalar::min(scalar::min(h00, h11), h);
                    let hi = scalar::max(scalar::max(h00, h11), h);
                    if lo <= aabb.max.y && aabb.min.y <= hi {
                        f(first + k as u32);
                    }
                }
            }
        }
    }

    /// The nearest point where `ray` meets a triangle within `max_t` metres, and that
    /// triangle's index: the smallest `t` [`Triangle::cast_ray`] reports over all
    /// triangles (two-sided), ties to the lowest triangle index. `None` for a miss, a
    /// negative or NaN `max_t`, or a ray with a non-finite origin or direction (or a
    /// direction with no component above 1e-24, which every triangle finds parallel).
    ///
    /// The ray is first clipped to the field's box, grown by a small margin (1e-5 of the
    /// largest coordinate of the box and the ray's origin, plus 10 µm). Then the cells
    /// under it are walked one column (or row, along whichever of x and z the ray moves
    /// further) at a time, nearest first: in each, the cells the ray's XZ projection
    /// crosses, grown by the same margin, so rounding never hides a triangle
    /// [`Triangle::cast_ray`] would report. The walk stops at the first column that starts
    /// (less the margin) past the nearest hit so far, and visits each cell at most once:
    /// the answer equals the brute-force one over every triangle. A vertical ray visits
    /// the cell under it (and its neighbours when it is within the margin of their edge).
    ///
    /// The direction is taken as [`Ray::new`] makes it, of unit length; any finite one
    /// works (the answer scales with it), up to where [`Triangle::cast_ray`]'s products
    /// overflow (components near `f32::MAX`), which yields no meaningful hit either way.
    ///
    /// Work: in each column crossed (before the nearest hit, while the ray is within the
    /// field's height range), the cells the ray crosses there and one more on either side
    /// when it runs within the margin of their edge, two triangle tests each: about three
    /// cells per column. Cells smaller than the margin (1e-5 of the largest coordinate
    /// involved) make it wider, up to the whole grid, each cell once.
    pub fn cast_ray(&self, ray: &Ray, max_t: f32) -> Option<(u32, RayHit)> {
        self.walk_ray(ray, max_t, |_, _| {})
    }

    /// [`HeightField::cast_ray`], calling `on_cell` with each cell `(i, j)` it visits (the
    /// tests count them).
    fn walk_ray(
        &self,
        ray: &Ray,
        max_t: f32,
        mut on_cell: impl FnMut(u32, u32),
    ) -> Option<(u32, RayHit)> {
        if !(max_t >= 0.0 && ray.origin.is_finite() && ray.direction.is_finite()) {
            return None;
        }
        let (o, d) = (ray.origin, ray.direction);
        let d_max = d.abs().max_elem();
        if d_max < TINY_DIRECTION {
            return None;
        }
        let size = scalar::max(
            o.abs().max_elem(),
            scalar::max(
                self.aabb.min.abs().max_elem(),
                self.aabb.max.abs().max_elem(),
            ),
        );
        let m = RAY_TOL * (size + 1.0);
        let slack = m / d_max;
        // Parameters where the ray is inside the grown box: finite, the slab of the
        // largest direction component being at most ~3e4 / 1e-24.
        let (mut s0, mut s1) = (-slack, f32::INFINITY);
        for k in 0..3 {
            let (ok, dk) = (axis(o, k), axis(d, k));
            let (lo, hi) = (axis(self.aabb.min, k) - m, axis(self.aabb.max, k) + m);
            if dk == 0.0 {
                if ok < lo || ok > hi {
                    return None;
                }
                continue;
            }
            let (a, b) = ((lo - ok) / dk, (hi - ok) / dk);
            let (near, far) = if a <= b { (a, b) } else { (b, a) };
            s0 = scalar::max(s0, near);
            s1 = scalar::min(s1, far);
        }
        if !(s0 <= s1 && s0 <= max_t + slack) {
            return None;
        }

        let mut best: Option<(u32, RayHit)> = None;
        let (nx, nz) = (self.cells_x(), self.cells_z());
        if d.x == 0.0 && d.z == 0.0 {
            // Vertical: the cells within the margin of the origin's XZ point.
            let (Some((i0, i1)), Some((j0, j1))) = (
                self.ray_cells(o.x - m, o.x + m, nx),
                self.ray_cells(o.z - m, o.z + m, nz),
            ) else {
                return None;
            };
            for j in j0..=j1 {
                for i in i0..=i1 {
                    on_cell(i, j);
                    self.cast_cell(ray, max_t, i, j, &mut best);
                }
            }
            return best;
        }

        // Walk along the major XZ axis ("columns"), the other being the minor ("rows").
        let x_major = scalar::abs(d.x) >= scalar::abs(d.z);
        let (o_maj, d_maj, n_maj, o_min, d_min, n_min) = if x_major {
            (o.x, d.x, nx, o.z, d.z, nz)
        } else {
            (o.z, d.z, nz, o.x, d.x, nx)
        };
        let (xa, xb) = (o_maj + d_maj * s0, o_maj + d_maj * s1);
        let (c0, c1) = self.ray_cells(scalar::min(xa, xb) - m, scalar::max(xa, xb) + m, n_maj)?;
        for step in 0..=(c1 - c0) {
            let c = if d_maj > 0.0 { c0 + step } else { c1 - step };
            // The parameters where the ray is over column c, grown by the margin.
            let a = (self.coord(c) - m - o_maj) / d_maj;
            let b = (self.coord(c + 1) + m - o_maj) / d_maj;
            let (near, far) = if a <= b { (a, b) } else { (b, a) };
            let (near, far) = (scalar::max(s0, near), scalar::min(s1, far));
            let limit = best.map_or(max_t, |(_, h)| h.t);
            if near > limit + slack {
                break; // this column and every later one start past the nearest hit
            }
            if near > far {
                continue; // (no NaN: finite over nonzero, clamped to the finite [s0, s1])
            }
            let (za, zb) = (o_min + d_min * near, o_min + d_min * far);
            let Some((r0, r1)) =
                self.ray_cells(scalar::min(za, zb) - m, scalar::max(za, zb) + m, n_min)
            else {
                continue;
            };
            for r in r0..=r1 {
                if x_major {
                    on_cell(c, r);
                    self.cast_cell(ray, max_t, c, r, &mut best);
                } else {
                    on_cell(r, c);
                    self.cast_cell(ray, max_t, r, c, &mut best);
                }
            }
        }
        best
    }

    /// [`Triangle::cast_ray`] on cell `(i, j)`'s two triangles, keeping in `best` the
    /// nearest hit so far, ties to the lower triangle index.
    fn cast_cell(&self, ray: &Ray, max_t: f32, i: u32, j: u32, best: &mut Option<(u32, RayHit)>) {
        let first = 2 * (j * self.cells_x() + i);
        for k in 0..2 {
            let Some(hit) = self
                .cell_triangle(i, j, k)
                .and_then(|tri| tri.cast_ray(ray, max_t))
            else {
                continue;
            };
            let t = first + k;
            let better = match *best {
                None => true,
                Some((bt, b)) => hit.t < b.t || (hit.t == b.t && t < bt),
            };
            if better {
                *best = Some((t, hit));
            }
        }
    }

    /// Cells along x: `columns − 1`.
    #[inline]
    fn cells_x(&self) -> u32 {
        self.columns - 1
    }

    /// Cells along z: `rows − 1`.
    #[inline]
    fn cells_z(&self) -> u32 {
        self.rows - 1
    }

    /// Local x (or z) of sample column (or row) `i`: one `f32` product, exact for the
    /// integer and rounded once.
    #[inline]
    fn coord(&self, i: u32) -> f32 {
        i as f32 * self.cell_size
    }

    /// Height of sample `(i, j)`; 0 outside the grid (never for the indices used).
    #[inline]
    fn height(&self, i: u32, j: u32) -> f32 {
        // j · columns + i < columns · rows ≤ 2²⁰ + 3 for the indices used: no overflow.
        let k = u64::from(j) * u64::from(self.columns) + u64::from(i);
        usize::try_from(k)
            .ok()
            .and_then(|k| self.heights.get(k))
            .copied()
            .unwrap_or(0.0)
    }

    /// Heights of cell `(i, j)`'s corners: `[p00, p10, p01, p11]`.
    #[inline]
    fn cell_heights(&self, i: u32, j: u32) -> [f32; 4] {
        [
            self.height(i, j),
            self.height(i + 1, j),
            self.height(i, j + 1),
            self.height(i + 1, j + 1),
        ]
    }

    /// Triangle `k` (0 or 1) of cell `(i, j)`; `None` outside the grid.
    fn cell_triangle(&self, i: u32, j: u32, k: u32) -> Option<Triangle> {
        if i >= self.cells_x() || j >= self.cells_z() || k > 1 {
            return None;
        }
        let [h00, h10, h01, h11] = self.cell_heights(i, j);
        let (x0, x1) = (self.coord(i), self.coord(i + 1));
        let (z0, z1) = (self.coord(j), self.coord(j + 1));
        let p00 = Vec3::new(x0, h00, z0);
        let p11 = Vec3::new(x1, h11, z1);
        let vertices = if k == 0 {
            [p00, p11, Vec3::new(x1, h10, z0)]
        } else {
            [p00, Vec3::new(x0, h01, z1), p11]
        };
        Some(Triangle { vertices })
    }

    /// The cells `lo..=hi` (of `n`) that may meet the coordinate range `[lo, hi]` (either
    /// order of the bounds; exact tests follow): by division, one cell more on each side
    /// for the rounding of the division and of the vertex coordinates (each well under a
    /// cell at [`MAX_HEIGHT_FIELD_CELLS`]). `None` when none can: `hi` below 0 or NaN, `lo`
    /// past the grid's extent or NaN.
    fn candidate_cells(&self, lo: f32, hi: f32, n: u32) -> Option<(u32, u32)> {
        if !(hi >= 0.0 && lo <= self.coord(n)) {
            return None;
        }
        let a = self.floor_cell(lo, n).saturating_sub(1);
        let b = self.floor_cell(hi, n).saturating_add(1).min(n - 1);
        (a <= b).then_some((a, b))
    }

    /// The cells (of `n`) whose range meets `[lo, hi]` (`lo <= hi`, already grown by the
    /// ray margin, which covers the rounding of the division); `None` when the range is
    /// off the grid or NaN.
    fn ray_cells(&self, lo: f32, hi: f32, n: u32) -> Option<(u32, u32)> {
        if !(hi >= 0.0 && lo <= self.coord(n) && lo <= hi) {
            return None;
        }
        Some((self.floor_cell(lo, n), self.floor_cell(hi, n)))
    }

    /// `floor(v / cell_size)` clamped to the cells `0..n` (`n ≥ 1`): 0 for a negative or
    /// NaN `v`, `n − 1` past the end. The `as` conversion of a value in `[0, n)` truncates,
    /// which is the floor; it never sees anything else.
    #[inline]
    fn floor_cell(&self, v: f32, n: u32) -> u32 {
        let q = v / self.cell_size;
        if q.is_nan() || q <= 0.0 {
            0
        } else if q >= n as f32 {
            n - 1
        } else {
            (q as u32).min(n - 1)
        }
    }
}

/// Component `k` (0 x, 1 y, else z).
#[inline]
fn axis(v: Vec3, k: usize) -> f32 {
    match k {
        0 => v.x,
        1 => v.y,
        _ => v.z,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::SplitMix64;
    use std::vec::Vec;

    /// A bumpy `columns × rows` grid: heights in `[-1, 2]` m, a third of them rounded to
    /// 0.5 m so flat patches, shared heights and exactly touching boxes are common.
    fn bumpy(rng: &mut SplitMix64, columns: u32, rows: u32) -> Vec<f32> {
        (0..columns * rows)
            .map(|_| {
                let h = rng.range(-1.0, 2.0);
                if rng.next_u64().is_multiple_of(3) {
                    (h * 2.0) as i32 as f32 * 0.5
                } else {
                    h
                }
            })
            .collect()
    }

    /// The grids the comparisons run on: (heights, columns, rows, cell size).
    fn fields() -> Vec<(Vec<f32>, u32, u32, f32)> {
        let mut rng = SplitMix64::new(41);
        let mut out = Vec::new();
        for (c, r, cs) in [
            (2, 2, 1.0),
            (3, 7, 0.37),
            (33, 17, 1.0),
            (33, 17, 0.25),
            (17, 33, 2.5),
        ] {
            out.push((bumpy(&mut rng, c, r), c, r, cs));
        }
        out
    }

    /// The bounding box of a triangle's three vertices.
    fn tri_box(tri: &Triangle) -> Aabb {
        let [a, b, c] = tri.vertices;
        Aabb::new(a.min(b).min(c), a.max(b).max(c))
    }

    fn brute_query(field: &HeightField, q: &Aabb) -> Vec<u32> {
        (0..field.triangle_count())
            .filter(|&t| tri_box(&field.triangle(t).unwrap()).overlaps(q))
            .collect()
    }

    /// Every edge's neighbour is the one other triangle holding both of its end points
    /// (the same bits), found by a search over every triangle; `None` exactly where no
    /// other triangle holds them (the border).
    #[test]
    fn edge_neighbours_match_a_search_over_every_triangle() {
        for (heights, columns, rows, cell) in fields() {
            let field = HeightField::new(&heights, columns, rows, cell).unwrap();
            let mut border = 0u32;
            for t in 0..field.triangle_count() {
                let [p0, p1, p2] = field.triangle(t).unwrap().vertices;
                for (edge, (u, v)) in [(p0, p1), (p1, p2), (p2, p0)].into_iter().enumerate() {
                    let holders: Vec<u32> = (0..field.triangle_count())
                        .filter(|&o| {
                            let w = field.triangle(o).unwrap().vertices;
                            o != t && w.contains(&u) && w.contains(&v)
                        })
                        .collect();
                    assert!(holders.len() <= 1, "{t}/{edge}: {holders:?}");
                    assert_eq!(field.edge_neighbour(t, edge), holders.first().copied());
                    border += u32::from(holders.is_empty());
                }
            }
            // One edge per cell side on the grid's rim.
            assert_eq!(border, 2 * (columns - 1 + rows - 1));
            assert_eq!(field.edge_neighbour(field.triangle_count(), 0), None);
        }
    }

    fn brute_ray(field: &HeightField, ray: &Ray, max_t: f32) -> Option<(u32, RayHit)> {
        let mut best: Option<(u32, RayHit)> = None;
        for i in 0..field.triangle_count() {
            if let Some(h) = field.triangle(i).unwrap().cast_ray(ray, max_t) {
                if best.is_none_or(|(_, b)| h.t < b.t) {
                    best = Some((i, h));
                }
            }
        }
        best
    }

    /// A random sample coordinate of the grid (exactly a vertex's x or z).
    fn grid_coord(rng: &mut SplitMix64, field: &HeightField, n: u32) -> f32 {
        field.coord((rng.next_u64() % u64::from(n)) as u32)
    }

    #[test]
    fn layout_and_bounds() {
        let heights = [0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 9.0];
        let f = HeightField::new(&heights, 3, 2, 0.5).unwrap();
        assert_eq!(f.triangle_count(), 4);
        assert_eq!((f.columns(), f.rows(), f.cell_size()), (3, 2, 0.5));
        assert_eq!(f.heights(), &heights[..6], "extra entries are not in use");
        assert_eq!(
            f.aabb(),
            Aabb::new(Vec3::ZERO, Vec3::new(1.0, 5.0, 0.5)),
            "9.0 is past columns · rows"
        );
        let v = |x: f32, y: f32, z: f32| Vec3::new(x, y, z);
        // Cell (1, 0): p00 = (0.5, 1, 0), p10 = (1, 2, 0), p01 = (0.5, 4, 0.5),
        // p11 = (1, 5, 0.5).
        assert_eq!(
            f.triangle(2).unwrap().vertices,
            [v(0.5, 1.0, 0.0), v(1.0, 5.0, 0.5), v(1.0, 2.0, 0.0)]
        );
        assert_eq!(
            f.triangle(3).unwrap().vertices,
            [v(0.5, 1.0, 0.0), v(0.5, 4.0, 0.5), v(1.0, 5.0, 0.5)]
        );
        assert_eq!(
            f.triangle(0).unwrap().vertices,
            [v(0.0, 0.0, 0.0), v(0.5, 4.0, 0.5), v(0.5, 1.0, 0.0)]
        );
        assert_eq!(f.triangle(4), None);
        #[cfg(target_pointer_width = "64")]
        assert_eq!(
            core::mem::size_of::<HeightField>(),
            56,
            "as the type's docs say"
        );
        assert_eq!(f.triangle(u32::MAX), None);
        // Negative heights: the box's y range is the heights', not from 0.
        let neg = [-3.0, -2.0, -2.5, -1.5];
        let f = HeightField::new(&neg, 2, 2, 1.0).unwrap();
        assert_eq!(f.aabb().min.y, -3.0);
        assert_eq!(f.aabb().max.y, -1.5);
        // Every triangle index maps to its cell: its vertices' x and z span the cell.
        for (h, c, r, cs) in fields() {
            let f = HeightField::new(&h, c, r, cs).unwrap();
            assert_eq!(f.triangle_count(), 2 * (c - 1) * (r - 1));
            let mut whole = tri_box(&f.triangle(0).unwrap());
            for t in 0..f.triangle_count() {
                let b = tri_box(&f.triangle(t).unwrap());
                let (i, j) = ((t / 2) % (c - 1), (t / 2) / (c - 1));
                assert_eq!((b.min.x, b.max.x), (i as f32 * cs, (i + 1) as f32 * cs));
                assert_eq!((b.min.z, b.max.z), (j as f32 * cs, (j + 1) as f32 * cs));
                whole = whole.union(&b);
            }
            assert_eq!(whole, f.aabb());
        }
    }

    #[test]
    fn triangles_wind_counter_clockwise_from_above() {
        let mut rng = SplitMix64::new(7);
        let mut checked = 0;
        for (h, c, r, cs) in fields() {
            let f = HeightField::new(&h, c, r, cs).unwrap();
            for t in 0..f.triangle_count() {
                let tri = f.triangle(t).unwrap();
                let [a, b, c] = tri.vertices;
                assert!((b - a).cross(c - a).y > 0.0, "triangle {t}");
                assert!(tri.normal().y > 0.0, "triangle {t}");
                checked += 1;
            }
        }
        // Steep fields too: heights up to ±100 m over 1 cm cells.
        let h: Vec<f32> = (0..64).map(|_| rng.range(-100.0, 100.0)).collect();
        let f = HeightField::new(&h, 8, 8, 0.01).unwrap();
        for t in 0..f.triangle_count() {
            assert!(f.triangle(t).unwrap().normal().y > 0.0);
            checked += 1;
        }
        assert_eq!(checked, 2 * (1 + 12 + 512 + 512 + 512) + 98);
        // A flat field: straight up, exactly for power-of-two cells.
        for cs in [1.0, 0.5, 0.25, 2.0, 0.37, 3.3] {
            let flat = [1.5f32; 12];
            let f = HeightField::new(&flat, 4, 3, cs).unwrap();
            for t in 0..f.triangle_count() {
                let n = f.triangle(t).unwrap().normal();
                assert_eq!((n.x, n.z), (0.0, 0.0));
                if [1.0, 0.5, 0.25, 2.0].contains(&cs) {
                    assert_eq!(n, Vec3::Y, "cell {cs}");
                } else {
                    assert!((n.y - 1.0).abs() <= 2.0 * f32::EPSILON, "{n:?}");
                }
            }
        }
    }

    #[test]
    fn query_aabb_matches_brute_force() {
        let mut rng = SplitMix64::new(5);
        let (mut queries, mut empty, mut reported, mut touching) = (0usize, 0usize, 0usize, 0);
        for (h, c, r, cs) in fields() {
            let f = HeightField::new(&h, c, r, cs).unwrap();
            let world = f.aabb();
            let count = if f.triangle_count() > 100 { 3000 } else { 1000 };
            for q in 0..count {
                let mut center = Vec3::new(
                    rng.range(world.min.x - 3.0, world.max.x + 3.0),
                    rng.range(world.min.y - 2.0, world.max.y + 2.0),
                    rng.range(world.min.z - 3.0, world.max.z + 3.0),
                );
                let scale = [0.0, 0.01, 0.3, 1.0, 4.0, 12.0, 1.0e3][q % 7];
                let half = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * scale;
                let mut query = Aabb::from_center_half(center, half);
                match q % 5 {
                    // A face exactly on a grid line or a height: touching counts.
                    1 => {
                        query.min.x = grid_coord(&mut rng, &f, c);
                        query.max.z = grid_coord(&mut rng, &f, r);
                        query.min.z = scalar::min(query.min.z, query.max.z);
                        query.max.x = scalar::max(query.max.x, query.min.x);
                        let k = (rng.next_u64() % h.len() as u64) as usize;
                        query.max.y = h[k];
                        query.min.y = scalar::min(query.min.y, h[k]);
                    }
                    2 => {
                        query.max.x = grid_coord(&mut rng, &f, c);
                        query.min.x = scalar::min(query.min.x, query.max.x);
                        let k = (rng.next_u64() % h.len() as u64) as usize;
                        query.min.y = h[k];
                        query.max.y = scalar::max(query.max.y, h[k]);
                        touching += 1;
                    }
                    // Inverted on one axis (min > max): Aabb::overlaps still answers.
                    3 if q % 2 == 0 => {
                        center.x = query.min.x;
                        query.min.x = query.max.x;
                        query.max.x = center.x;
                    }
                    _ => {}
                }
                let mut got = Vec::new();
                f.query_aabb(&query, |t| got.push(t));
                let want = brute_query(&f, &query);
                assert_eq!(got, want, "query {query:?} on {c} × {r}");
                queries += 1;
                empty += usize::from(got.is_empty());
                reported += got.len();
            }
            // Huge and infinite boxes hold everything; a NaN anywhere overlaps nothing.
            let all: Vec<u32> = (0..f.triangle_count()).collect();
            for big in [1.0e30, f32::INFINITY, MAX_COORDINATE] {
                let q = Aabb::new(Vec3::splat(-big), Vec3::splat(big));
                let mut got = Vec::new();
                f.query_aabb(&q, |t| got.push(t));
                assert_eq!(got, all);
            }
            for k in 0..6 {
                let mut q = Aabb::new(Vec3::splat(-1.0e3), Vec3::splat(1.0e3));
                match k {
                    0 => q.min.x = f32::NAN,
                    1 => q.max.x = f32::NAN,
                    2 => q.min.y = f32::NAN,
                    3 => q.max.y = f32::NAN,
                    4 => q.min.z = f32::NAN,
                    _ => q.max.z = f32::NAN,
                }
                f.query_aabb(&q, |_| panic!("a NaN box overlaps nothing"));
                assert!(brute_query(&f, &q).is_empty());
            }
        }
        assert_eq!(queries, 2 * 1000 + 3 * 3000);
        assert!(empty * 5 > queries, "{empty} of {queries} empty");
        assert!(
            (queries - empty) * 2 > queries,
            "{empty} of {queries} empty"
        );
        assert!(reported > 10 * queries, "{reported} reported");
        assert!(touching > 1000);
    }

    /// A random ray of kind `q % 8` for `f`.
    fn random_ray(rng: &mut SplitMix64, f: &HeightField, q: usize) -> Ray {
        let w = f.aabb();
        let inside = |rng: &mut SplitMix64| {
            Vec3::new(
                rng.range(w.min.x, w.max.x),
                rng.range(w.min.y, w.max.y),
                rng.range(w.min.z, w.max.z),
            )
        };
        let towards = |o: Vec3, target: Vec3| {
            Ray::new(o, target - o).unwrap_or(Ray {
                origin: o,
                direction: -Vec3::Y,
            })
        };
        match q % 8 {
            // Anywhere near the field, any direction.
            0 => Ray {
                origin: Vec3::new(
                    rng.range(w.min.x - 3.0, w.max.x + 3.0),
                    rng.range(w.min.y - 3.0, w.max.y + 3.0),
                    rng.range(w.min.z - 3.0, w.max.z + 3.0),
                ),
                direction: rng.unit_vector(),
            },
            // Straight down (or up) onto a vertex, an edge or anywhere: ties and edges.
            1 => {
                let mut o = inside(rng);
                if rng.next_u64().is_multiple_of(2) {
                    o.x = grid_coord(rng, f, f.columns());
                }
                if rng.next_u64().is_multiple_of(2) {
                    o.z = grid_coord(rng, f, f.rows());
                }
                let up = rng.next_u64().is_multiple_of(4);
                o.y = if up { w.min.y - 1.0 } else { w.max.y + 1.0 };
                Ray {
                    origin: o,
                    direction: if up { Vec3::Y } else { -Vec3::Y },
                }
            }
            // From above towards a point of the field.
            2 => {
                let mut o = inside(rng);
                o.y = w.max.y + rng.range(0.1, 4.0);
                let t = inside(rng);
                towards(o, t)
            }
            // From the side, outside the grid, low and nearly horizontal.
            3 => {
                let side = rng.next_u64() % 4;
                let mut o = inside(rng);
                match side {
                    0 => o.x = w.min.x - rng.range(0.1, 5.0),
                    1 => o.x = w.max.x + rng.range(0.1, 5.0),
                    2 => o.z = w.min.z - rng.range(0.1, 5.0),
                    _ => o.z = w.max.z + rng.range(0.1, 5.0),
                }
                let mut t = inside(rng);
                t.y = o.y + rng.range(-0.3, 0.3);
                towards(o, t)
            }
            // Grazing: nearly horizontal from inside the grid's XZ range.
            4 => {
                let o = inside(rng);
                let a = rng.range(0.0, core::f32::consts::TAU);
                let dy = [0.0, 1.0e-4, -1.0e-3, 0.02][rng.next_u64() as usize % 4];
                Ray::new(o, Vec3::new(scalar::cos(a), dy, scalar::sin(a))).unwrap()
            }
            // Along a grid line (x or z exactly a sample's), slanted.
            5 => {
                let mut o = inside(rng);
                o.y = w.max.y + 0.5;
                o.x = grid_coord(rng, f, f.columns());
                let d = Vec3::new(0.0, -rng.range(0.1, 1.0), rng.range(-1.0, 1.0));
                Ray::new(o, d).unwrap()
            }
            // Diagonal through the cells' corners (along p00–p11 or across it).
            6 => {
                let o = Vec3::new(
                    grid_coord(rng, f, f.columns()),
                    w.max.y + 0.5,
                    grid_coord(rng, f, f.rows()),
                );
                let sx = if rng.next_u64().is_multiple_of(2) {
                    1.0
                } else {
                    -1.0
                };
                let d = Vec3::new(sx, -rng.range(0.05, 1.0), 1.0);
                Ray::new(o, d).unwrap()
            }
            // Far away, towards the field.
            _ => {
                let o = rng.unit_vector() * rng.range(100.0, 5000.0) + w.max;
                let t = inside(rng);
                towards(o, t)
            }
        }
    }

    #[test]
    fn cast_ray_matches_brute_force() {
        let mut rng = SplitMix64::new(17);
        let (mut hits, mut misses, mut ties, mut rays) = (0usize, 0usize, 0usize, 0usize);
        let (mut visited, mut all_cells) = (0usize, 0usize);
        for (h, c, r, cs) in fields() {
            let f = HeightField::new(&h, c, r, cs).unwrap();
            let count = if f.triangle_count() > 100 { 3000 } else { 800 };
            for q in 0..count {
                let mut ray = random_ray(&mut rng, &f, q);
                // Some directions not of unit length (the public fields allow it).
                if q % 11 == 0 {
                    ray.direction *= [0.01, 100.0][q % 2];
                }
                let max_t = [f32::INFINITY, 1.0, 5.0, 30.0, 0.3, 0.0][q % 6];
                let mut cells = Vec::new();
                let got = f.walk_ray(&ray, max_t, |i, j| cells.push((i, j)));
                assert_eq!(got, f.cast_ray(&ray, max_t));
                let want = brute_ray(&f, &ray, max_t);
                assert_eq!(got, want, "ray {ray:?} max_t {max_t} on {c} × {r}");
                // Each cell at most once, all on the grid.
                let n = cells.len();
                cells.sort_unstable();
                cells.dedup();
                assert_eq!(cells.len(), n, "a cell visited twice");
                assert!(cells.iter().all(|&(i, j)| i < c - 1 && j < r - 1));
                visited += n;
                let vertical = ray.direction.x == 0.0 && ray.direction.z == 0.0;
                if q % 8 == 1 && vertical && max_t == f32::INFINITY {
                    // Vertical: one cell, up to four on a grid line or corner.
                    assert!((1..=4).contains(&n), "{n} cells for {ray:?}");
                }
                all_cells += ((c - 1) * (r - 1)) as usize;
                if let (Some((_, g)), Some((_, w))) = (got, want) {
                    assert_eq!(g.t.to_bits(), w.t.to_bits());
                }
                rays += 1;
                if let Some((_, g)) = got {
                    let equal = (0..f.triangle_count())
                        .filter(|&i| {
                            let h = f.triangle(i).unwrap().cast_ray(&ray, max_t);
                            h.is_some_and(|h| h.t == g.t)
                        })
                        .count();
                    ties += usize::from(equal > 1);
                    hits += 1;
                } else {
                    misses += 1;
                }
            }
        }
        assert_eq!(rays, 2 * 800 + 3 * 3000);
        assert!(ties > 200, "{ties} ties");
        assert!(hits * 5 > rays, "{hits} hits, {misses} misses");
        assert!(misses * 4 > rays, "{hits} hits, {misses} misses");
        // The walk visits a small part of what brute force does.
        assert!(visited * 20 < all_cells, "{visited} of {all_cells} cells");
        // Bad rays and limits: nothing.
        let (h, c, r, cs) = &fields()[2];
        let f = HeightField::new(h, *c, *r, *cs).unwrap();
        let down = Ray::new(Vec3::new(3.5, 10.0, 3.5), -Vec3::Y).unwrap();
        assert!(f.cast_ray(&down, 100.0).is_some());
        assert_eq!(f.cast_ray(&down, f32::NAN), None);
        assert_eq!(f.cast_ray(&down, -1.0), None);
        for bad in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
            let r = Ray {
                origin: Vec3::new(bad, 10.0, 3.5),
                direction: -Vec3::Y,
            };
            assert_eq!(f.cast_ray(&r, 100.0), None);
            let r = Ray {
                origin: down.origin,
                direction: Vec3::new(0.0, -1.0, bad),
            };
            assert_eq!(f.cast_ray(&r, 100.0), None);
        }
        for tiny in [0.0, 1.0e-30, f32::MIN_POSITIVE, 1.0e-45] {
            let r = Ray {
                origin: down.origin,
                direction: -Vec3::Y * tiny,
            };
            assert_eq!(f.cast_ray(&r, f32::INFINITY), None);
            assert_eq!(brute_ray(&f, &r, f32::INFINITY), None);
        }
    }

    #[test]
    fn cast_ray_on_a_vertical_ray_finds_the_cell_below() {
        // Above the middle of each cell of a tilted plane: exactly one triangle's hit at
        // the plane's height, on the expected side of the diagonal.
        let (c, r) = (9u32, 6u32);
        let h: Vec<f32> = (0..c * r)
            .map(|k| 0.25 * (k % c) as f32 + 0.5 * (k / c) as f32)
            .collect();
        let f = HeightField::new(&h, c, r, 1.0).unwrap();
        for j in 0..r - 1 {
            for i in 0..c - 1 {
                for (dx, dz, k) in [(0.75, 0.25, 0), (0.25, 0.75, 1)] {
                    let (x, z) = (i as f32 + dx, j as f32 + dz);
                    let ray = Ray::new(Vec3::new(x, 20.0, z), -Vec3::Y).unwrap();
                    let mut cells = Vec::new();
                    let (t, hit) = f.walk_ray(&ray, 100.0, |i, j| cells.push((i, j))).unwrap();
                    assert_eq!(cells, [(i, j)], "one cell");
                    assert_eq!(t, 2 * (j * (c - 1) + i) + k);
                    assert!((hit.point.y - (0.25 * x + 0.5 * z)).abs() < 1e-5);
                    assert!(hit.normal.y > 0.0);
                }
            }
        }
    }

    #[test]
    fn candidate_cells_cover_touching_cells() {
        // A coordinate exactly on sample line i touches cells i − 1 and i, whatever the
        // rounding of the division; a range inside cell i gives at most i − 1..=i + 1.
        let mut rng = SplitMix64::new(29);
        let heights = std::vec![0.0f32; 2 * 4097];
        let mut checked = 0;
        for q in 0..300 {
            let cs = if q < 100 {
                rng.range(super::super::MIN_SIZE, 0.01)
            } else {
                rng.range(0.01, 2.4)
            };
            let f = HeightField::new(&heights, 4097, 2, cs).unwrap();
            let n = f.cells_x();
            for _ in 0..200 {
                let i = (rng.next_u64() % u64::from(n + 1)) as u32;
                let x = f.coord(i);
                let (a, b) = f.candidate_cells(x, x, n).unwrap();
                assert!(a <= i.saturating_sub(1) && b >= i.min(n - 1), "{cs} {i}");
                assert!(b - a <= 3);
                let mid = 0.5 * (x + f.coord(i + 1));
                if i < n {
                    let (a, b) = f.candidate_cells(mid, mid, n).unwrap();
                    assert!(a + 1 >= i && a <= i && b >= i && b <= i + 1, "{cs} {i}");
                }
                checked += 1;
            }
        }
        assert_eq!(checked, 60_000);
        let f = HeightField::new(&heights, 4097, 2, 1.0).unwrap();
        assert_eq!(f.candidate_cells(-0.5, -0.1, 4096), None);
        assert_eq!(f.candidate_cells(4096.5, 5000.0, 4096), None);
        assert_eq!(f.candidate_cells(f32::NAN, 3.0, 4096), None);
        assert_eq!(f.candidate_cells(0.0, f32::NAN, 4096), None);
        assert_eq!(
            f.candidate_cells(f32::NEG_INFINITY, f32::INFINITY, 4096),
            Some((0, 4095))
        );
        assert_eq!(f.candidate_cells(-1e30, 0.0, 4096), Some((0, 1)));
        assert_eq!(f.candidate_cells(4096.0, 1e30, 4096), Some((4094, 4095)));
    }

    #[test]
    fn new_errors_are_exact_and_in_order() {
        let e = |h: &[f32], c: u32, r: u32, cs: f32| HeightField::new(h, c, r, cs).map(|_| ());
        let count = Error::NotPositive(Input::TriangleCount);
        let ok4 = [0.0f32; 4];
        // 1. Too few samples, before anything else (empty heights, NaN cell size).
        for (c, r) in [
            (0, 0),
            (1, 1),
            (1, 5),
            (5, 1),
            (0, 5),
            (5, 0),
            (1, u32::MAX),
        ] {
            assert_eq!(e(&[], c, r, f32::NAN), Err(count), "{c} × {r}");
            assert_eq!(e(&ok4, c, r, 1.0), Err(count), "{c} × {r}");
        }
        // Too many cells: exact integer count, no overflow.
        let many = Error::OutOfRange(Input::TriangleCount);
        let max = MAX_HEIGHT_FIELD_CELLS as u32;
        for (c, r) in [
            (u32::MAX, u32::MAX),
            (u32::MAX, 2),
            (2, u32::MAX),
            (max + 2, 2),
            (1026, 513),
            (1 << 16, 1 << 16),
        ] {
            assert_eq!(e(&[], c, r, f32::NAN), Err(many), "{c} × {r}");
        }
        // 2. Too few heights: columns · rows, before heights and cell size.
        assert_eq!(
            e(&[], max + 1, 2, f32::NAN),
            Err(Error::BufferTooSmall(2 * max + 2))
        );
        assert_eq!(
            e(&[], 1025, 513, 1.0),
            Err(Error::BufferTooSmall(1025 * 513))
        );
        assert_eq!(e(&[f32::NAN; 5], 3, 2, 0.0), Err(Error::BufferTooSmall(6)));
        assert_eq!(e(&[], 2, 2, 1.0), Err(Error::BufferTooSmall(4)));
        // 3. Each height in use, in order; unused entries are not read.
        let point_nf = Error::NonFinite(Input::Point);
        let point_far = Error::OutOfRange(Input::Point);
        for bad in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
            assert_eq!(e(&[0.0, 0.0, 0.0, bad], 2, 2, f32::NAN), Err(point_nf));
            assert_eq!(e(&[0.0, 1e5, 0.0, bad], 2, 2, 1.0), Err(point_far));
            assert_eq!(e(&[bad, 1e5, 0.0, 0.0], 2, 2, 1.0), Err(point_nf));
            assert!(e(&[0.0, 0.0, 0.0, 0.0, bad], 2, 2, 1.0).is_ok());
        }
        for far in [MAX_COORDINATE * 1.0001, -MAX_COORDINATE * 1.0001, 1e30] {
            assert_eq!(e(&[0.0, 0.0, far, 0.0], 2, 2, f32::NAN), Err(point_far));
        }
        let edge = [MAX_COORDINATE, -MAX_COORDINATE, 0.0, 0.0];
        assert!(e(&edge, 2, 2, 1.0).is_ok());
        // 4. Cell size.
        for (cs, want) in [
            (f32::NAN, Error::NonFinite(Input::Distance)),
            (f32::INFINITY, Error::NonFinite(Input::Distance)),
            (f32::NEG_INFINITY, Error::NonFinite(Input::Distance)),
            (0.0, Error::NotPositive(Input::Distance)),
            (-0.0, Error::NotPositive(Input::Distance)),
            (-1.0, Error::NotPositive(Input::Distance)),
            (
                super::super::MIN_SIZE * 0.99,
                Error::OutOfRange(Input::Distance),
            ),
            (
                super::super::MAX_SIZE * 1.01,
                Error::OutOfRange(Input::Distance),
            ),
            (1e-30, Error::OutOfRange(Input::Distance)),
        ] {
            assert_eq!(e(&ok4, 2, 2, cs), Err(want), "cell {cs}");
        }
        assert!(e(&ok4, 2, 2, super::super::MIN_SIZE).is_ok());
        assert!(e(&ok4, 2, 2, super::super::MAX_SIZE).is_ok());
        // 5. Extent: 11 cells of 1 km is too wide, 10 exactly fits (either axis).
        let far = Error::OutOfRange(Input::Distance);
        let z = std::vec![0.0f32; 24];
        assert_eq!(e(&z, 12, 2, 1000.0), Err(far));
        assert_eq!(e(&z, 2, 12, 1000.0), Err(far));
        assert!(e(&z, 11, 2, 1000.0).is_ok());
        assert!(e(&z, 2, 11, 1000.0).is_ok());
        let f = HeightField::new(&z, 11, 2, 1000.0).unwrap();
        assert_eq!(f.aabb().max.x, MAX_COORDINATE);
        // The largest field: 2²⁰ triangles in one strip, last index 2²⁰ − 1.
        let strip = std::vec![0.5f32; 2 * max as usize + 2];
        let f = HeightField::new(&strip, max + 1, 2, 0.01).unwrap();
        assert_eq!(f.triangle_count(), 1 << 20);
        assert!(f.triangle((1 << 20) - 1).is_some());
        assert_eq!(f.triangle(1 << 20), None);
        let mut got = Vec::new();
        // From the last cell's left edge: the last cell and the one touching it there.
        let q = Aabb::new(Vec3::new(f.coord(max - 1), 0.0, 0.0), Vec3::splat(1.0e4));
        f.query_aabb(&q, |t| got.push(t));
        assert_eq!(got, brute_query(&f, &q));
        let last = (1 << 20) - 1;
        assert_eq!(got, [last - 3, last - 2, last - 1, last]);
        let ray = Ray::new(Vec3::new(0.0, 1.0, 0.003), Vec3::new(1.0, -1.0e-4, 0.0)).unwrap();
        assert_eq!(
            f.cast_ray(&ray, f32::INFINITY),
            brute_ray(&f, &ray, f32::INFINITY)
        );
        let (t, hit) = f.cast_ray(&ray, f32::INFINITY).unwrap();
        assert!((hit.point.x - 5000.0).abs() < 0.1, "{hit:?}");
        assert_eq!(t / 2, (hit.point.x / 0.01) as u32, "{hit:?}");
    }

    /// Values that break careless code.
    const SPECIALS: [f32; 10] = [
        f32::NAN,
        f32::INFINITY,
        f32::NEG_INFINITY,
        -0.0,
        1.0e30,
        -1.0e30,
        MAX_COORDINATE,
        1.0e-30,
        f32::MAX,
        f32::MIN_POSITIVE,
    ];

    /// Uniform in `[lo, hi)`, or one time in `one_in` a special value.
    fn pick(rng: &mut SplitMix64, lo: f32, hi: f32, one_in: u64) -> f32 {
        if rng.next_u64().is_multiple_of(one_in) {
            SPECIALS[(rng.next_u64() % SPECIALS.len() as u64) as usize]
        } else {
            rng.range(lo, hi)
        }
    }

    fn pick_vec(rng: &mut SplitMix64, lo: f32, hi: f32) -> Vec3 {
        Vec3::new(
            pick(rng, lo, hi, 8),
            pick(rng, lo, hi, 8),
            pick(rng, lo, hi, 8),
        )
    }

    #[test]
    fn random_garbage_never_panics() {
        let mut rng = SplitMix64::new(23);
        let (mut built, mut unit_rays, mut other_rays) = (0, 0, 0);
        for _ in 0..20_000 {
            let c = (rng.next_u64() % 6) as u32;
            let r = (rng.next_u64() % 6) as u32;
            let n = (rng.next_u64() % 40) as usize;
            let h: Vec<f32> = (0..n).map(|_| pick(&mut rng, -3.0, 3.0, 60)).collect();
            let cs = pick(&mut rng, 0.01, 2.0, 10);
            let Ok(f) = HeightField::new(&h, c, r, cs) else {
                continue;
            };
            built += 1;
            // Boxes with NaN, infinite and huge corners, in order or inverted: the same
            // answer as brute force.
            let (a, b) = (pick_vec(&mut rng, -4.0, 8.0), pick_vec(&mut rng, -4.0, 8.0));
            for q in [Aabb::new(a.min(b), a.max(b)), Aabb::new(a, b)] {
                let mut got = Vec::new();
                f.query_aabb(&q, |t| got.push(t));
                assert_eq!(got, brute_query(&f, &q), "{q:?}");
            }
            // Rays: non-finite ones miss; finite ones, with any origin and a direction
            // unit or not (up to 1e3 long: past that, Triangle::cast_ray's products
            // overflow into spurious hits), give the brute-force answer.
            let ray = Ray {
                origin: pick_vec(&mut rng, -4.0, 8.0),
                direction: pick_vec(&mut rng, -1.0, 1.0),
            };
            let max_t = pick(&mut rng, 0.0, 20.0, 8);
            let got = f.cast_ray(&ray, max_t);
            if !(ray.origin.is_finite() && ray.direction.is_finite()) {
                assert_eq!(got, None);
            } else if ray.direction.abs().max_elem() <= 1.0e3 {
                assert_eq!(got, brute_ray(&f, &ray, max_t), "{ray:?} {max_t}");
                other_rays += 1;
            } else if let Some((t, _)) = got {
                assert!(t < f.triangle_count());
            }
            if let Ok(unit) = Ray::new(ray.origin, ray.direction) {
                let got = f.cast_ray(&unit, max_t);
                assert_eq!(got, brute_ray(&f, &unit, max_t), "{unit:?} {max_t}");
                unit_rays += 1;
            }
            for t in [0, 1, f.triangle_count() - 1] {
                assert!(f.triangle(t).is_some());
            }
            assert_eq!(f.triangle(f.triangle_count()), None);
            assert_eq!(f.triangle(u32::MAX), None);
        }
        assert!(built > 3000, "{built} built");
        assert!(unit_rays > 1000, "{unit_rays} unit rays");
        assert!(other_rays > 1000, "{other_rays} finite rays");
    }
}
