//! Static triangle mesh with a bounding-volume hierarchy (the mid phase's geometry): the
//! caller owns the vertices, the index triples and the node storage; the mesh borrows
//! them. Built once, top-down, by median splits; queried by box overlap and by ray.

use super::{Ray, RayHit, Triangle};
use crate::error::{finite_vec, Error, Input, MAX_COORDINATE};
use crate::math::{scalar, Aabb, Vec3};

/// Most triangles a [`TriangleMesh`] may have (2²⁰ = 1,048,576). Split larger meshes.
/// Keeps every node index (up to `2 · MAX_MESH_TRIANGLES − 1`) in a `u32`, bounds the
/// tree's depth by [`MAX_BVH_DEPTH`] and the build's cost (see [`TriangleMesh::build`]).
pub const MAX_MESH_TRIANGLES: usize = 1 << 20;

/// Deepest tree [`TriangleMesh::build`] can make, in edges from the root to a leaf:
/// `ceil(log2(MAX_MESH_TRIANGLES))` = 20. A mesh of `n` triangles is at most
/// `ceil(log2 n)` deep (`ceil(log2 n) + 1` levels of nodes): each split halves a range,
/// the larger half holding `ceil(len / 2)` triangles.
pub const MAX_BVH_DEPTH: usize = 20;

/// Slots of the traversal stacks. A depth-first walk that pushes the right child, then
/// the left, holds at most one pending sibling per level above the node it is at, plus
/// the two children it just pushed: at most `depth + 1` entries, `MAX_BVH_DEPTH + 1`.
const STACK: usize = MAX_BVH_DEPTH + 1;

/// Marks a leaf in [`BvhNode`]'s first index.
const LEAF: u32 = u32::MAX;

/// The ray cast grows each inner box by this fraction of the largest coordinate (m) of
/// the box and the ray origin, plus as much again in metres, before its slab test, so
/// the rounding of [`Triangle::cast_ray`] (whose hit may lie a few ulps outside the
/// triangle's box) does not make a pruned box hide a hit it would report.
const RAY_BOX_TOL: f32 = 1.0e-5;

/// One node of a [`TriangleMesh`]'s hierarchy: a bounding box (m) and either two child
/// node indices (an inner node) or one triangle index (a leaf). 32 bytes
/// (`core::mem::size_of::<BvhNode>()`): the box's six `f32` and two `u32`.
///
/// Only [`TriangleMesh::build`] fills nodes; give it storage of
/// [`BvhNode::EMPTY`] (or any nodes: all are overwritten).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct BvhNode {
    /// Bounds of every triangle below the node (m).
    aabb: Aabb,
    /// Left child's node index, or [`LEAF`]. During the build, the start of the node's
    /// range of leaves.
    first: u32,
    /// Right child's node index, or the leaf's triangle index. During the build, the end
    /// of the node's range of leaves.
    second: u32,
}

impl BvhNode {
    /// A placeholder to fill node storage with before [`TriangleMesh::build`].
    pub const EMPTY: BvhNode = BvhNode {
        aabb: Aabb::new(Vec3::ZERO, Vec3::ZERO),
        first: LEAF,
        second: 0,
    };

    /// Bounds (m) of the node's triangles (their vertices' bounding box).
    #[inline]
    pub fn aabb(&self) -> Aabb {
        self.aabb
    }

    /// The left and right child's node indices, for an inner node.
    #[inline]
    pub fn children(&self) -> Option<(u32, u32)> {
        if self.first == LEAF {
            None
        } else {
            Some((self.first, self.second))
        }
    }

    /// The triangle index (into the mesh's index triples), for a leaf.
    #[inline]
    pub fn triangle(&self) -> Option<u32> {
        if self.first == LEAF {
            Some(self.second)
        } else {
            None
        }
    }
}

impl Default for BvhNode {
    fn default() -> BvhNode {
        BvhNode::EMPTY
    }
}

/// A static triangle mesh: caller-owned vertices (m) and index triples, and a binary
/// bounding-volume hierarchy with one triangle per leaf, built into caller-provided
/// node storage. Pure geometry, in the mesh's local frame: not a [`crate::Shape`] yet.
///
/// # Memory
///
/// A mesh of `n` triangles needs [`TriangleMesh::nodes_needed`]`(n)` = `2n − 1` nodes of
/// `core::mem::size_of::<BvhNode>()` = 32 bytes: 64 bytes per triangle (less 32 for the
/// whole mesh). The caller's data adds 12 bytes per triangle (`[u32; 3]`) and 12 per
/// vertex (`Vec3`; a grid of shared vertices has about half as many vertices as
/// triangles). The mesh itself is three slice references; its queries use a stack of
/// [`MAX_BVH_DEPTH`]` + 1` `u32`.
///
/// # Layout
///
/// Node 0 is the root. For `n >= 2`, nodes `0..n − 1` are the inner nodes in
/// breadth-first order and nodes `n − 1..2n − 1` the leaves, in the order of the build's
/// final triangle permutation; a single triangle is a single leaf.
///
/// # Example
///
/// ```
/// use carom::shape::{BvhNode, TriangleMesh};
/// use carom::{Aabb, Ray, Vec3};
///
/// # fn main() -> Result<(), carom::Error> {
/// // A 2 m × 2 m floor at y = 0 in two triangles, normals up.
/// let vertices = [
///     Vec3::new(-1.0, 0.0, -1.0),
///     Vec3::new(1.0, 0.0, -1.0),
///     Vec3::new(1.0, 0.0, 1.0),
///     Vec3::new(-1.0, 0.0, 1.0),
/// ];
/// let indices = [[0, 2, 1], [0, 3, 2]];
/// let mut nodes = [BvhNode::EMPTY; TriangleMesh::nodes_needed(2)];
/// let mesh = TriangleMesh::build(&vertices, &indices, &mut nodes)?;
/// assert_eq!(mesh.triangle_count(), 2);
///
/// // Triangles whose bounding boxes overlap a box, depth-first, left child first.
/// let mut found = [false; 2];
/// mesh.query_aabb(&Aabb::new(Vec3::splat(-0.1), Vec3::splat(0.1)), |t| {
///     found[t as usize] = true
/// });
/// assert_eq!(found, [true, true]);
/// let mut above = 0;
/// mesh.query_aabb(&Aabb::new(Vec3::new(-1.0, 1.0, -1.0), Vec3::ONE), |_| above += 1);
/// assert_eq!(above, 0);
///
/// // The nearest hit along a ray, and which triangle it is.
/// let down = Ray::new(Vec3::new(0.5, 3.0, 0.25), -Vec3::Y)?;
/// let (t, hit) = mesh.cast_ray(&down, 100.0).expect("the ray meets the floor");
/// assert_eq!(t, 0);
/// assert!((hit.t - 3.0).abs() < 1e-6);
/// assert!(mesh.cast_ray(&down, 2.0).is_none()); // too short
/// # Ok(())
/// # }
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TriangleMesh<'a> {
    vertices: &'a [Vec3],
    indices: &'a [[u32; 3]],
    nodes: &'a [BvhNode],
}

impl<'a> TriangleMesh<'a> {
    /// Nodes a mesh of `triangles` triangles needs: `2 · triangles − 1` (a binary tree
    /// with one triangle per leaf); 0 for no triangles (which [`TriangleMesh::build`]
    /// refuses). Saturates instead of overflowing.
    pub const fn nodes_needed(triangles: usize) -> usize {
        triangles.saturating_mul(2).saturating_sub(1)
    }

    /// Check a mesh and build its hierarchy into `nodes` (its first
    /// [`TriangleMesh::nodes_needed`]`(indices.len())` entries; the rest are untouched).
    /// Each `indices` entry names a triangle's three vertices in `vertices`,
    /// counter-clockwise about its normal (as [`Triangle::new`]); a triangle's index is its
    /// position in `indices`.
    ///
    /// # Errors
    ///
    /// Checked in this order; on error nothing was written to `nodes`:
    ///
    /// 1. no triangles: [`Error::NotPositive`]`(`[`Input::TriangleCount`]`)`; more than
    ///    [`MAX_MESH_TRIANGLES`]: [`Error::OutOfRange`]`(`[`Input::TriangleCount`]`)`;
    /// 2. `nodes` shorter than `nodes_needed(indices.len())`:
    ///    [`Error::BufferTooSmall`]`(nodes_needed)`;
    /// 3. any vertex, used or not, non-finite: [`Error::NonFinite`]`(`[`Input::Point`]`)`,
    ///    or with a coordinate beyond ±[`MAX_COORDINATE`]:
    ///    [`Error::OutOfRange`]`(`[`Input::Point`]`)`;
    /// 4. then each triangle in order: an index not below `vertices.len()`:
    ///    [`Error::OutOfRange`]`(`[`Input::Index`]`)`; (nearly) no area, repeated indices
    ///    included: [`Triangle::new`]'s error, [`Error::NotPositive`]`(`[`Input::Point`]`)`.
    ///
    /// # Build
    ///
    /// Top-down over ranges of triangles, breadth-first, with no recursion and no stack:
    /// each inner node's range is sorted by triangle centroid along the longest axis of
    /// the range's centroid bounds (x before y before z on equal extents), ties by
    /// triangle index, and split at its middle (the left half holds `len / 2`, rounded
    /// down). Centroids are compared as `(a + b) + c`, three times the centroid, summed
    /// in that order; bounds are minima and maxima. No fused multiply-add, no sum whose
    /// order can vary: the same input gives the same nodes, bit for bit, on every target,
    /// whatever `nodes` held before. Each level sorts every range with the crate's
    /// heapsort: `O(n log² n)` comparisons in all.
    pub fn build(
        vertices: &'a [Vec3],
        indices: &'a [[u32; 3]],
        nodes: &'a mut [BvhNode],
    ) -> Result<TriangleMesh<'a>, Error> {
        let n = indices.len();
        if n == 0 {
            return Err(Error::NotPositive(Input::TriangleCount));
        }
        if n > MAX_MESH_TRIANGLES {
            return Err(Error::OutOfRange(Input::TriangleCount));
        }
        let needed = TriangleMesh::nodes_needed(n);
        if nodes.len() < needed {
            return Err(Error::BufferTooSmall(needed as u32));
        }
        for &v in vertices {
            finite_vec(v, Input::Point)?;
            if v.abs().max_elem() > MAX_COORDINATE {
                return Err(Error::OutOfRange(Input::Point));
            }
        }
        for tri in indices {
            let [a, b, c] = corners(vertices, tri).ok_or(Error::OutOfRange(Input::Index))?;
            Triangle::new(a, b, c)?;
        }

        let (nodes, _) = nodes.split_at_mut(needed);
        // Leaves in triangle order: the permutation the splits sort lives in them.
        let leaf0 = n - 1;
        for (i, tri) in indices.iter().enumerate() {
            let [a, b, c] = corners(vertices, tri).unwrap_or([Vec3::ZERO; 3]);
            if let Some(slot) = nodes.get_mut(leaf0 + i) {
                *slot = BvhNode {
                    aabb: Aabb::new(a.min(b).min(c), a.max(b).max(c)),
                    first: LEAF,
                    second: i as u32,
                };
            }
        }
        if n >= 2 {
            build_inner(vertices, indices, nodes, n);
        }
        let nodes: &'a [BvhNode] = nodes;
        Ok(TriangleMesh {
            vertices,
            indices,
            nodes,
        })
    }

    /// Number of triangles (at most [`MAX_MESH_TRIANGLES`]).
    #[inline]
    pub fn triangle_count(&self) -> u32 {
        self.indices.len() as u32
    }

    /// The vertices (m) the mesh was built from.
    #[inline]
    pub fn vertices(&self) -> &'a [Vec3] {
        self.vertices
    }

    /// The index triples the mesh was built from, one per triangle.
    #[inline]
    pub fn indices(&self) -> &'a [[u32; 3]] {
        self.indices
    }

    /// The hierarchy: [`TriangleMesh::nodes_needed`]`(triangle_count)` nodes, root first
    /// (see the layout in the type's docs).
    #[inline]
    pub fn nodes(&self) -> &'a [BvhNode] {
        self.nodes
    }

    /// Bounds of the whole mesh (m): the root's box.
    pub fn aabb(&self) -> Aabb {
        self.nodes.first().map_or(Aabb::default(), |r| r.aabb)
    }

    /// Triangle `i` (vertices in m, in its index triple's order); `None` past the last.
    pub fn triangle(&self, i: u32) -> Option<Triangle> {
        let tri = self.indices.get(i as usize)?;
        let vertices = corners(self.vertices, tri)?;
        Some(Triangle { vertices })
    }

    /// Call `f` with the index of every triangle whose bounding box (of its vertices)
    /// overlaps or touches `aabb` (m, [`Aabb::overlaps`]), each once, in depth-first order,
    /// left child first: a fixed order for a given mesh. A box with a NaN overlaps
    /// nothing.
    ///
    /// The walk's stack holds [`MAX_BVH_DEPTH`]` + 1` entries, which a tree from
    /// [`TriangleMesh::build`] cannot exceed (see [`MAX_BVH_DEPTH`]); were it ever full,
    /// the walk would stop early rather than panic.
    pub fn query_aabb(&self, aabb: &Aabb, mut f: impl FnMut(u32)) {
        self.walk(|node| {
            if !node.aabb.overlaps(aabb) {
                return false;
            }
            if node.children().is_none() {
                f(node.second);
            }
            true
        });
    }

    /// The nearest point where `ray` meets a triangle within `max_t` metres, and that
    /// triangle's index: the smallest `t` [`Triangle::cast_ray`] reports over all
    /// triangles (two-sided), ties to the lowest triangle index. `None` for a miss, a
    /// negative or NaN `max_t`, or a ray with a non-finite origin or direction.
    ///
    /// Inner nodes are pruned by a slab test against their box grown by a small
    /// tolerance (1e-5 of the largest coordinate involved, plus 10 µm) and against the
    /// nearest hit so far (ties are still visited), so the answer equals the brute-force
    /// one over every triangle; the walk's stack is bounded as in
    /// [`TriangleMesh::query_aabb`].
    pub fn cast_ray(&self, ray: &Ray, max_t: f32) -> Option<(u32, RayHit)> {
        if !(max_t >= 0.0 && ray.origin.is_finite() && ray.direction.is_finite()) {
            return None;
        }
        let origin_size = ray.origin.abs().max_elem();
        let mut best: Option<(u32, RayHit)> = None;
        self.walk(|node| {
            let limit = best.map_or(max_t, |(_, h)| h.t);
            if node.children().is_some() {
                return ray_meets_box(ray, &node.aabb, origin_size, limit);
            }
            if let Some(hit) = self
                .triangle(node.second)
                .and_then(|t| t.cast_ray(ray, max_t))
            {
                let better = match best {
                    None => true,
                    Some((i, b)) => hit.t < b.t || (hit.t == b.t && node.second < i),
                };
                if better {
                    best = Some((node.second, hit));
                }
            }
            false
        });
        best
    }

    /// The tree walk both queries share: depth-first from the root, left child first,
    /// calling `visit` on every node reached; an inner node's children are reached when
    /// `visit` returns true. The stack holds [`MAX_BVH_DEPTH`]` + 1` entries, which a tree
    /// from [`TriangleMesh::build`] cannot exceed; were it ever full, the walk would stop
    /// early rather than panic. Each node is pushed at most once (a tree), so the loop
    /// needs at most `nodes.len()` pops.
    fn walk(&self, mut visit: impl FnMut(&BvhNode) -> bool) {
        let mut stack = [0u32; STACK];
        let mut len = 1;
        for _ in 0..self.nodes.len() {
            if len == 0 {
                return;
            }
            len -= 1;
            let Some(node) = stack.get(len).and_then(|&i| self.nodes.get(i as usize)) else {
                continue;
            };
            if !visit(node) {
                continue;
            }
            if let Some((left, right)) = node.children() {
                if !push2(&mut stack, &mut len, right, left) {
                    return;
                }
            }
        }
    }
}

/// The three vertices of an index triple; `None` if an index is out of range.
fn corners(vertices: &[Vec3], tri: &[u32; 3]) -> Option<[Vec3; 3]> {
    let [a, b, c] = *tri;
    Some([
        *vertices.get(a as usize)?,
        *vertices.get(b as usize)?,
        *vertices.get(c as usize)?,
    ])
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

/// Three times triangle `t`'s centroid, `(a + b) + c`; zero for an invalid index (never
/// after validation).
fn centroid3(vertices: &[Vec3], indices: &[[u32; 3]], t: u32) -> Vec3 {
    match indices
        .get(t as usize)
        .and_then(|tri| corners(vertices, tri))
    {
        Some([a, b, c]) => (a + b) + c,
        None => Vec3::ZERO,
    }
}

/// Build the inner nodes `0..n − 1` over the leaves `n − 1..2n − 1` (already written, in
/// triangle order), `n >= 2`. Breadth-first: node `i`'s leaf range sits in its own
/// fields until it is processed; its inner children take the next free indices, which
/// are always past `i`. A full binary tree of `n` leaves has exactly `n − 1` inner nodes.
fn build_inner(vertices: &[Vec3], indices: &[[u32; 3]], nodes: &mut [BvhNode], n: usize) {
    let leaf0 = n - 1;
    if let Some(root) = nodes.get_mut(0) {
        root.first = 0;
        root.second = n as u32;
    }
    let mut next = 1usize;
    for i in 0..leaf0 {
        let Some(&BvhNode { first, second, .. }) = nodes.get(i) else {
            return;
        };
        let (lo, hi) = (first as usize, second as usize);
        let Some(leaves) = nodes.get_mut(leaf0 + lo..leaf0 + hi) else {
            return;
        };
        let Some(head) = leaves.first() else {
            return;
        };
        // Box of the range, and bounds of its centroids.
        let mut aabb = head.aabb;
        let c0 = centroid3(vertices, indices, head.second);
        let (mut cmin, mut cmax) = (c0, c0);
        for leaf in leaves.iter() {
            aabb = aabb.union(&leaf.aabb);
            let c = centroid3(vertices, indices, leaf.second);
            cmin = cmin.min(c);
            cmax = cmax.max(c);
        }
        let ext = cmax - cmin;
        let k = if ext.x >= ext.y && ext.x >= ext.z {
            0
        } else if ext.y >= ext.z {
            1
        } else {
            2
        };
        crate::sort::sort_unstable_by(leaves, |p, q| {
            let cp = axis(centroid3(vertices, indices, p.second), k);
            let cq = axis(centroid3(vertices, indices, q.second), k);
            cp < cq || (cp == cq && p.second < q.second)
        });
        let mid = lo + (hi - lo) / 2;
        let mut child = |l: usize, h: usize| -> u32 {
            if h - l == 1 {
                (leaf0 + l) as u32
            } else {
                let c = next;
                next += 1;
                if let Some(slot) = nodes.get_mut(c) {
                    *slot = BvhNode {
                        aabb: Aabb::default(),
                        first: l as u32,
                        second: h as u32,
                    };
                }
                c as u32
            }
        };
        let left = child(lo, mid);
        let right = child(mid, hi);
        if let Some(slot) = nodes.get_mut(i) {
            *slot = BvhNode {
                aabb,
                first: left,
                second: right,
            };
        }
    }
}

/// Push `a` then `b`; false (nothing pushed) if both do not fit.
#[inline]
fn push2(stack: &mut [u32; STACK], len: &mut usize, a: u32, b: u32) -> bool {
    if *len + 2 > STACK {
        return false;
    }
    if let Some(s) = stack.get_mut(*len) {
        *s = a;
    }
    if let Some(s) = stack.get_mut(*len + 1) {
        *s = b;
    }
    *len += 2;
    true
}

/// Slab test: does `ray` (finite) pass through `aabb`, grown by the ray tolerance, at
/// some `t` in `[0, limit]`?
fn ray_meets_box(ray: &Ray, aabb: &Aabb, origin_size: f32, limit: f32) -> bool {
    let size = scalar::max(
        origin_size,
        scalar::max(aabb.min.abs().max_elem(), aabb.max.abs().max_elem()),
    );
    let margin = RAY_BOX_TOL * (size + 1.0);
    let (mut t0, mut t1) = (0.0f32, limit);
    for k in 0..3 {
        let o = axis(ray.origin, k);
        let d = axis(ray.direction, k);
        let lo = axis(aabb.min, k) - margin;
        let hi = axis(aabb.max, k) + margin;
        if d == 0.0 {
            if o < lo || o > hi {
                return false;
            }
            continue;
        }
        let a = (lo - o) / d;
        let b = (hi - o) / d;
        let (near, far) = if a <= b { (a, b) } else { (b, a) };
        t0 = scalar::max(t0, near);
        t1 = scalar::min(t1, far);
        if t0 > t1 {
            return false;
        }
    }
    true
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Iso;
    use crate::rng::SplitMix64;
    use std::vec::Vec;

    /// A jittered `cells × cells` height field over x, z in `[0, cells]` m, heights in
    /// `[0, 2]` m, two triangles per cell (normals up).
    fn height_field(rng: &mut SplitMix64, cells: u32) -> (Vec<Vec3>, Vec<[u32; 3]>) {
        let side = cells + 1;
        let mut v = Vec::new();
        for z in 0..side {
            for x in 0..side {
                v.push(Vec3::new(
                    x as f32 + rng.range(-0.3, 0.3),
                    rng.range(0.0, 2.0),
                    z as f32 + rng.range(-0.3, 0.3),
                ));
            }
        }
        let mut ix = Vec::new();
        for z in 0..cells {
            for x in 0..cells {
                let i = z * side + x;
                ix.push([i, i + side, i + 1]);
                ix.push([i + 1, i + side, i + side + 1]);
            }
        }
        (v, ix)
    }

    /// `n` random triangles in a 10 m cube, edges 0.05 to 2 m.
    fn soup(rng: &mut SplitMix64, n: usize) -> (Vec<Vec3>, Vec<[u32; 3]>) {
        let mut v = Vec::new();
        let mut ix = Vec::new();
        while ix.len() < n {
            let a = Vec3::new(
                rng.range(-5.0, 5.0),
                rng.range(-5.0, 5.0),
                rng.range(-5.0, 5.0),
            );
            let s = rng.range(0.05, 2.0);
            let b = a + rng.unit_vector() * s;
            let c = a + rng.unit_vector() * s;
            if Triangle::new(a, b, c).is_ok() {
                let k = v.len() as u32;
                v.extend([a, b, c]);
                ix.push([k, k + 1, k + 2]);
            }
        }
        (v, ix)
    }

    fn build(v: &[Vec3], ix: &[[u32; 3]]) -> Vec<BvhNode> {
        let mut nodes = std::vec![BvhNode::EMPTY; TriangleMesh::nodes_needed(ix.len())];
        TriangleMesh::build(v, ix, &mut nodes).expect("valid mesh");
        nodes
    }

    fn node_bits(nodes: &[BvhNode]) -> Vec<u32> {
        let mut out = Vec::new();
        for n in nodes {
            let b = n.aabb;
            for x in [b.min.x, b.min.y, b.min.z, b.max.x, b.max.y, b.max.z] {
                out.push(x.to_bits());
            }
            out.push(n.first);
            out.push(n.second);
        }
        out
    }

    /// Deepest leaf (edges from the root), and a check that every triangle sits in
    /// exactly one leaf and every child box lies inside its parent's.
    fn depth_and_shape(mesh: &TriangleMesh) -> usize {
        let nodes = mesh.nodes();
        let mut seen = std::vec![0u32; mesh.triangle_count() as usize];
        let mut visits = 0;
        let mut deepest = 0;
        let mut stack = std::vec![(0u32, 0usize)];
        while let Some((i, d)) = stack.pop() {
            visits += 1;
            assert!(visits <= nodes.len(), "cycle");
            let node = nodes[i as usize];
            deepest = deepest.max(d);
            match node.children() {
                Some((l, r)) => {
                    for c in [l, r] {
                        assert!(node.aabb().contains(&nodes[c as usize].aabb()));
                        stack.push((c, d + 1));
                    }
                }
                None => {
                    let t = node.triangle().unwrap();
                    seen[t as usize] += 1;
                    let tri = mesh.triangle(t).unwrap();
                    assert_eq!(node.aabb(), tri.aabb(&Iso::IDENTITY));
                }
            }
        }
        assert_eq!(visits, nodes.len());
        assert!(seen.iter().all(|&s| s == 1));
        deepest
    }

    fn ceil_log2(n: usize) -> usize {
        (usize::BITS - (n - 1).leading_zeros()) as usize
    }

    fn meshes() -> Vec<(Vec<Vec3>, Vec<[u32; 3]>)> {
        let mut rng = SplitMix64::new(91);
        let mut out = std::vec![height_field(&mut rng, 32), soup(&mut rng, 500)];
        for n in [1, 2, 3, 5, 17] {
            out.push(soup(&mut rng, n));
        }
        out
    }

    #[test]
    fn node_is_32_bytes() {
        assert_eq!(core::mem::size_of::<BvhNode>(), 32);
        assert_eq!(TriangleMesh::nodes_needed(0), 0);
        assert_eq!(TriangleMesh::nodes_needed(1), 1);
        assert_eq!(TriangleMesh::nodes_needed(1000), 1999);
        assert_eq!(TriangleMesh::nodes_needed(usize::MAX), usize::MAX - 1);
        assert_eq!(ceil_log2(MAX_MESH_TRIANGLES), MAX_BVH_DEPTH);
    }

    #[test]
    fn query_aabb_matches_brute_force() {
        let mut rng = SplitMix64::new(5);
        let mut reported_total = 0usize;
        let mut empty_queries = 0usize;
        let mut queries = 0usize;
        for (v, ix) in meshes() {
            let mut nodes = std::vec![BvhNode::EMPTY; TriangleMesh::nodes_needed(ix.len())];
            let mesh = TriangleMesh::build(&v, &ix, &mut nodes).unwrap();
            assert!(depth_and_shape(&mesh) <= ceil_log2(ix.len()));
            let boxes: Vec<Aabb> = (0..ix.len())
                .map(|i| mesh.triangle(i as u32).unwrap().aabb(&Iso::IDENTITY))
                .collect();
            let world = mesh.aabb();
            let count = if ix.len() > 100 { 3000 } else { 300 };
            for q in 0..count {
                let c = Vec3::new(
                    rng.range(world.min.x - 2.0, world.max.x + 2.0),
                    rng.range(world.min.y - 2.0, world.max.y + 2.0),
                    rng.range(world.min.z - 2.0, world.max.z + 2.0),
                );
                // Sizes from a point to a quarter of the world and more.
                let scale = [0.0, 0.01, 0.3, 1.0, 4.0, 12.0][q % 6];
                let h = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * scale;
                let query = Aabb::from_center_half(c, h);
                let mut got = Vec::new();
                mesh.query_aabb(&query, |t| got.push(t));
                let want: Vec<u32> = (0..ix.len() as u32)
                    .filter(|&t| boxes[t as usize].overlaps(&query))
                    .collect();
                let mut order = Vec::new();
                reference_order(mesh.nodes(), 0, &query, &mut order);
                assert_eq!(got, order, "not depth-first, left first");
                let mut sorted = got.clone();
                sorted.sort_unstable();
                sorted.dedup();
                assert_eq!(sorted.len(), got.len(), "an index reported twice");
                assert_eq!(sorted, want, "query {query:?}");
                // The same query reports the same order.
                let mut again = Vec::new();
                mesh.query_aabb(&query, |t| again.push(t));
                assert_eq!(again, got);
                reported_total += got.len();
                empty_queries += usize::from(got.is_empty());
                queries += 1;
            }
        }
        // Both empty and well-filled answers are common.
        assert!(
            empty_queries * 10 > queries,
            "{empty_queries} of {queries} empty"
        );
        assert!(reported_total > 10 * queries, "{reported_total} reported");
    }

    /// Leaves overlapping `q` below node `i`, recursively, left child first.
    fn reference_order(nodes: &[BvhNode], i: u32, q: &Aabb, out: &mut Vec<u32>) {
        let node = nodes[i as usize];
        if !node.aabb().overlaps(q) {
            return;
        }
        match node.children() {
            Some((l, r)) => {
                reference_order(nodes, l, q, out);
                reference_order(nodes, r, q, out);
            }
            None => out.push(node.triangle().unwrap()),
        }
    }

    fn brute_ray(mesh: &TriangleMesh, ray: &Ray, max_t: f32) -> Option<(u32, RayHit)> {
        let mut best: Option<(u32, RayHit)> = None;
        for i in 0..mesh.triangle_count() {
            if let Some(h) = mesh.triangle(i).unwrap().cast_ray(ray, max_t) {
                if best.is_none_or(|(_, b)| h.t < b.t) {
                    best = Some((i, h));
                }
            }
        }
        best
    }

    #[test]
    fn cast_ray_matches_brute_force() {
        let mut rng = SplitMix64::new(17);
        let (mut hits, mut misses, mut ties) = (0usize, 0usize, 0usize);
        for (v, ix) in meshes() {
            let mut nodes = std::vec![BvhNode::EMPTY; TriangleMesh::nodes_needed(ix.len())];
            let mesh = TriangleMesh::build(&v, &ix, &mut nodes).unwrap();
            let world = mesh.aabb();
            let count = if ix.len() > 100 { 3000 } else { 300 };
            for q in 0..count {
                let ray = match q % 3 {
                    // Anywhere near the mesh, any direction.
                    0 => Ray {
                        origin: Vec3::new(
                            rng.range(world.min.x - 3.0, world.max.x + 3.0),
                            rng.range(world.min.y - 3.0, world.max.y + 3.0),
                            rng.range(world.min.z - 3.0, world.max.z + 3.0),
                        ),
                        direction: rng.unit_vector(),
                    },
                    // Straight down onto a vertex (shared by up to six triangles).
                    1 => {
                        let p = v[(rng.next_u64() % v.len() as u64) as usize];
                        Ray {
                            origin: p + Vec3::new(0.0, rng.range(0.5, 5.0), 0.0),
                            direction: -Vec3::Y,
                        }
                    }
                    // From above the mesh towards a random point of it.
                    _ => {
                        let o = Vec3::new(
                            rng.range(world.min.x, world.max.x),
                            world.max.y + rng.range(0.1, 4.0),
                            rng.range(world.min.z, world.max.z),
                        );
                        let target = Vec3::new(
                            rng.range(world.min.x, world.max.x),
                            rng.range(world.min.y, world.max.y),
                            rng.range(world.min.z, world.max.z),
                        );
                        Ray::new(o, target - o).unwrap_or(Ray {
                            origin: o,
                            direction: -Vec3::Y,
                        })
                    }
                };
                let max_t = [f32::INFINITY, 1.0, 5.0, 30.0][q % 4];
                let got = mesh.cast_ray(&ray, max_t);
                let want = brute_ray(&mesh, &ray, max_t);
                assert_eq!(got, want, "ray {ray:?} max_t {max_t}");
                if let (Some((_, g)), Some((_, w))) = (got, want) {
                    assert_eq!(g.t.to_bits(), w.t.to_bits());
                }
                if let Some((_, g)) = got {
                    let equal = (0..mesh.triangle_count())
                        .filter(|&i| {
                            let h = mesh.triangle(i).unwrap().cast_ray(&ray, max_t);
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
        // Hits shared by several triangles at the same distance (373 of 3,059).
        assert!(ties > 100, "{ties} ties");
        assert!(hits * 4 > hits + misses, "{hits} hits, {misses} misses");
        assert!(misses * 4 > hits + misses, "{hits} hits, {misses} misses");
        // Bad rays and limits: nothing, no panic.
        let (v, ix) = soup(&mut rng, 50);
        let nodes = build(&v, &ix);
        let mesh = TriangleMesh {
            vertices: &v,
            indices: &ix,
            nodes: &nodes,
        };
        let ok = Ray::new(Vec3::new(0.0, 0.0, -20.0), Vec3::Z).unwrap();
        assert_eq!(mesh.cast_ray(&ok, f32::NAN), None);
        assert_eq!(mesh.cast_ray(&ok, -1.0), None);
        for bad in [f32::NAN, f32::INFINITY] {
            let r = Ray {
                origin: Vec3::new(bad, 0.0, 0.0),
                direction: Vec3::Z,
            };
            assert_eq!(mesh.cast_ray(&r, 100.0), None);
            let r = Ray {
                origin: Vec3::ZERO,
                direction: Vec3::new(0.0, bad, 1.0),
            };
            assert_eq!(mesh.cast_ray(&r, 100.0), None);
        }
    }

    #[test]
    fn build_is_deterministic_bit_for_bit() {
        for (v, ix) in meshes() {
            let a = build(&v, &ix);
            // Storage that held another mesh's nodes gives the same result.
            let mut b = std::vec![BvhNode::EMPTY; a.len() + 3];
            for (k, n) in b.iter_mut().enumerate() {
                n.first = k as u32 * 7;
                n.second = u32::MAX - k as u32;
                n.aabb = Aabb::new(Vec3::splat(k as f32), Vec3::splat(-1.0));
            }
            let tail = b[a.len()..].to_vec();
            TriangleMesh::build(&v, &ix, &mut b).unwrap();
            assert_eq!(node_bits(&a), node_bits(&b[..a.len()]));
            assert_eq!(
                node_bits(&tail),
                node_bits(&b[a.len()..]),
                "past the end touched"
            );
            // Inner nodes first, then leaves (for two triangles or more).
            let n = ix.len();
            assert!(a[..n - 1].iter().all(|x| x.children().is_some()));
            assert!(a[n - 1..].iter().all(|x| x.triangle().is_some()));
        }
        // A fixed checksum of a height field's nodes (no sqrt in its making, so the same
        // under both math backends).
        let mut rng = SplitMix64::new(3);
        let (v, ix) = height_field(&mut rng, 8);
        let bits = node_bits(&build(&v, &ix));
        let sum = bits.iter().fold(0u64, |h, &x| {
            (h ^ u64::from(x)).wrapping_mul(0x0000_0100_0000_01b3)
        });
        let again = node_bits(&build(&v, &ix));
        assert_eq!(bits, again);
        // Pinned: it changes only when the build's rule does (or a target breaks it).
        assert_eq!(sum, 0x0914_d3c4_5d50_c5a6);
    }

    #[test]
    fn build_errors_are_exact_and_write_nothing() {
        let sentinel = BvhNode {
            aabb: Aabb::new(Vec3::splat(7.0), Vec3::splat(9.0)),
            first: 11,
            second: 13,
        };
        let good = [Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z];
        let check = |v: &[Vec3], ix: &[[u32; 3]], storage: usize, want: Error| {
            let mut nodes = std::vec![sentinel; storage];
            let got = TriangleMesh::build(v, ix, &mut nodes).map(|_| ());
            assert_eq!(got, Err(want), "{v:?} {ix:?}");
            assert!(nodes.iter().all(|n| *n == sentinel), "written on error");
        };
        let tri = [[0u32, 1, 2]];
        check(&good, &[], 10, Error::NotPositive(Input::TriangleCount));
        check(&[], &[], 0, Error::NotPositive(Input::TriangleCount));
        check(&good, &[[0, 1, 4]], 1, Error::OutOfRange(Input::Index));
        check(
            &good,
            &[[0, 1, u32::MAX]],
            1,
            Error::OutOfRange(Input::Index),
        );
        check(&good, &[[u32::MAX; 3]], 1, Error::OutOfRange(Input::Index));
        check(&[], &tri, 1, Error::OutOfRange(Input::Index));
        for bad in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
            let v = [Vec3::ZERO, Vec3::X, Vec3::new(0.0, bad, 0.0)];
            check(&v, &tri, 1, Error::NonFinite(Input::Point));
            // Unused vertices are checked too.
            let v = [Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::new(bad, 0.0, 0.0)];
            check(&v, &tri, 1, Error::NonFinite(Input::Point));
        }
        let far = Vec3::new(0.0, 0.0, MAX_COORDINATE * 1.0001);
        check(
            &[Vec3::ZERO, Vec3::X, far],
            &tri,
            1,
            Error::OutOfRange(Input::Point),
        );
        let edge = Vec3::new(0.0, 0.0, -MAX_COORDINATE);
        let mut nodes = [BvhNode::EMPTY];
        assert!(TriangleMesh::build(&[Vec3::ZERO, Vec3::X, edge], &tri, &mut nodes).is_ok());
        // Degenerate: exactly Triangle::new's error.
        let line = [Vec3::ZERO, Vec3::X, Vec3::X * 2.0];
        let want = Triangle::new(line[0], line[1], line[2]).unwrap_err();
        assert_eq!(want, Error::NotPositive(Input::Point));
        check(&line, &tri, 1, want);
        check(&good, &[[0, 1, 2], [0, 0, 1]], 3, want);
        let tiny = [Vec3::ZERO, Vec3::X * 1e-7, Vec3::Y * 1e-7];
        check(
            &tiny,
            &tri,
            1,
            Triangle::new(tiny[0], tiny[1], tiny[2]).unwrap_err(),
        );
        // Storage: 2n − 1 nodes.
        let two = [[0, 1, 2], [0, 1, 3]];
        check(&good, &two, 2, Error::BufferTooSmall(3));
        check(&good, &two, 0, Error::BufferTooSmall(3));
        check(&good, &tri, 0, Error::BufferTooSmall(1));
        // Storage comes before vertex checks; counts before storage.
        check(&[Vec3::splat(f32::NAN)], &tri, 0, Error::BufferTooSmall(1));
        let many = std::vec![[0u32; 3]; MAX_MESH_TRIANGLES + 1];
        check(&good, &many, 0, Error::OutOfRange(Input::TriangleCount));
    }

    #[test]
    fn random_garbage_never_panics() {
        let mut rng = SplitMix64::new(23);
        let specials = [f32::NAN, f32::INFINITY, -0.0, 1e30, MAX_COORDINATE, 1e-30];
        let mut built = 0;
        for _ in 0..10_000 {
            let nv = (rng.next_u64() % 8) as usize;
            let v: Vec<Vec3> = (0..nv)
                .map(|_| {
                    let mut c = [0.0f32; 3];
                    for x in &mut c {
                        *x = if rng.next_u64().is_multiple_of(100) {
                            specials[(rng.next_u64() % 6) as usize]
                        } else {
                            rng.range(-3.0, 3.0)
                        };
                    }
                    Vec3::new(c[0], c[1], c[2])
                })
                .collect();
            let nt = (rng.next_u64() % 6) as usize;
            let ix: Vec<[u32; 3]> = (0..nt)
                .map(|_| {
                    let mut t = [0u32; 3];
                    for x in &mut t {
                        *x = match rng.next_u64() % 40 {
                            0 => u32::MAX,
                            1 => nv as u32,
                            _ => (rng.next_u64() % (nv.max(1) as u64)) as u32,
                        };
                    }
                    t
                })
                .collect();
            let storage = match rng.next_u64() % 4 {
                0 => (rng.next_u64() % 12) as usize,
                _ => TriangleMesh::nodes_needed(nt),
            };
            let mut nodes = std::vec![BvhNode::EMPTY; storage];
            if let Ok(mesh) = TriangleMesh::build(&v, &ix, &mut nodes) {
                built += 1;
                assert!(depth_and_shape(&mesh) <= ceil_log2(nt));
                let q = Aabb::new(Vec3::splat(rng.range(-4.0, 0.0)), Vec3::splat(f32::NAN));
                mesh.query_aabb(&q, |_| panic!("a NaN box overlaps nothing"));
                let r = Ray {
                    origin: Vec3::new(rng.range(-4.0, 4.0), 5.0, 0.0),
                    direction: rng.unit_vector(),
                };
                assert_eq!(mesh.cast_ray(&r, 50.0), brute_ray(&mesh, &r, 50.0));
                assert_eq!(mesh.triangle(nt as u32), None);
                assert_eq!(mesh.triangle(u32::MAX), None);
            }
        }
        assert!(built > 500, "{built} built");
    }

    #[test]
    fn depth_bound_holds_for_coincident_centroids() {
        // 1,000 nested triangles around the origin, all with centroid sum exactly zero:
        // (−s + 2s) − s = 0 and (−s − s) + 2s = 0 in f32.
        let mut v = Vec::new();
        let mut ix = Vec::new();
        for k in 0..1000u32 {
            let s = 1.0e-3 * (k + 1) as f32;
            v.extend([
                Vec3::new(-s, -s, 0.0),
                Vec3::new(2.0 * s, -s, 0.0),
                Vec3::new(-s, 2.0 * s, 0.0),
            ]);
            ix.push([3 * k, 3 * k + 1, 3 * k + 2]);
        }
        for k in 0..1000u32 {
            assert_eq!(centroid3(&v, &ix, k), Vec3::ZERO);
        }
        // And 1,000 copies of one tiny triangle.
        let same_v = [Vec3::ZERO, Vec3::X * 1e-3, Vec3::Y * 1e-3];
        let same_ix = std::vec![[0u32, 1, 2]; 1000];
        for (v, ix) in [(&v[..], &ix[..]), (&same_v[..], &same_ix[..])] {
            let mut nodes = std::vec![BvhNode::EMPTY; TriangleMesh::nodes_needed(ix.len())];
            let mesh = TriangleMesh::build(v, ix, &mut nodes).unwrap();
            let depth = depth_and_shape(&mesh);
            assert_eq!(depth, ceil_log2(1000)); // 10: balanced despite the ties
            let mut all = Vec::new();
            mesh.query_aabb(&Aabb::new(Vec3::splat(-1e-4), Vec3::splat(1e-4)), |t| {
                all.push(t)
            });
            all.sort_unstable();
            assert_eq!(all, (0..1000).collect::<Vec<u32>>());
            // Ties by index: the leaves come in triangle order.
            let leaves: Vec<u32> = mesh.nodes()[999..]
                .iter()
                .map(|n| n.triangle().unwrap())
                .collect();
            assert_eq!(leaves, (0..1000).collect::<Vec<u32>>());
            // A ray through all 1,000 (from both sides): the brute-force answer; for the
            // copies, all at the same distance, the lowest index.
            for dir in [-1.0f32, 1.0] {
                let ray = Ray::new(Vec3::new(1e-4, 2e-4, -5.0 * dir), Vec3::Z * dir).unwrap();
                let hit = mesh.cast_ray(&ray, 10.0);
                assert_eq!(hit, brute_ray(&mesh, &ray, 10.0));
                assert!(hit.is_some());
                if v.len() == 3 {
                    assert_eq!(hit.map(|(i, h)| (i, h.t)), Some((0, 5.0)));
                }
            }
        }
    }
}
