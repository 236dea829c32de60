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
/// Pure geometry, in the field's local frame: not a [`crate::Shape`] yet.
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
#[derive(Clone, Copy, Debug)]
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
        self.cell_triangle(cell % nx, cell / nx, t % 2)
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
    pub fn cast_ray(&self, ray: &Ray, max_t: f32) -> Option<(u32, RayHit)> {
        if !(max_t >= 0.0 && ray.origin.is_finite() && ray.direction.is_finite()) {
            return None;
        }
        let (o, d) = (ray.origin, ray.direction);
        let d_max = d.abs().max_elem();
        if !(d_max >= TINY_DIRECTION) {
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
        let Some((c0, c1)) =
            self.ray_cells(scalar::min(xa, xb) - m, scalar::max(xa, xb) + m, n_maj)
        else {
            return None;
        };
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
            if !(near <= far) {
                continue;
            }
            let (za, zb) = (o_min + d_min * near, o_min + d_min * far);
            let Some((r0, r1)) =
                self.ray_cells(scalar::min(za, zb) - m, scalar::max(za, zb) + m, n_min)
            else {
                continue;
            };
            for r in r0..=r1 {
                if x_major {
                    self.cast_cell(ray, max_t, c, r, &mut best);
                } else {
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
        if !(q > 0.0) {
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
