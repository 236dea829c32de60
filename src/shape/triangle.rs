//! Triangle: three vertices, two-sided, no volume (static bodies only). Vertex ids 0–2,
//! edges by vertex pair, face 0 for the side its normal points to, face 1 for the back.

use super::{Face, FeatureId, Ray, RayHit};
use crate::error::{finite_vec, Error, Input};
use crate::math::{scalar, Aabb, Iso, Vec3};

/// A triangle with vertices counter-clockwise about `normal()`.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Triangle {
    /// The three vertices (local frame, m).
    pub vertices: [Vec3; 3],
}

/// Smallest area (m²) of a usable triangle.
const MIN_AREA: f32 = 1.0e-12;

/// Below this `|cos|` of the angle between a ray and the triangle's normal, the ray is
/// treated as parallel to the triangle (a miss).
const PARALLEL_COS: f32 = 1.0e-7;

/// Relative tolerance of [`Triangle::intersects`]: a signed volume within
/// `TOUCH_TOL · (l + m) · l²` of zero, or a signed area within `TOUCH_TOL · (l + m) · l`,
/// counts as zero, `l` being the largest coordinate difference it was computed from and
/// `m` the largest coordinate of the six vertices (m): some tens of `f32` roundings, so
/// coplanar or touching input rounded to `f32` still reads as touching.
const TOUCH_TOL: f32 = 2.0e-6;

impl Triangle {
    /// A triangle; vertices must be finite, within ±[`crate::MAX_COORDINATE`] and not
    /// collinear.
    pub fn new(a: Vec3, b: Vec3, c: Vec3) -> Result<Triangle, Error> {
        for v in [a, b, c] {
            finite_vec(v, Input::Point)?;
            if v.abs().max_elem() > crate::error::MAX_COORDINATE {
                return Err(Error::OutOfRange(Input::Point));
            }
        }
        let n = (b - a).cross(c - a);
        if 0.5 * n.length() <= MIN_AREA || n.length_squared().is_nan() {
            return Err(Error::NotPositive(Input::Point));
        }
        Ok(Triangle {
            vertices: [a, b, c],
        })
    }

    /// Unit normal, `(b − a) × (c − a)` normalised.
    pub fn normal(&self) -> Vec3 {
        let [a, b, c] = self.vertices;
        (b - a).cross(c - a).normalize_or(Vec3::Y)
    }

    pub(crate) fn core_support(&self, dir: Vec3) -> (Vec3, u32) {
        let mut best = 0;
        let mut best_d = self.vertices[0].dot(dir);
        for i in 1..3 {
            let d = self.vertices[i].dot(dir);
            if d > best_d {
                best = i;
                best_d = d;
            }
        }
        (self.vertices[best], best as u32)
    }

    pub(crate) fn core_vertex(&self, index: u32) -> Vec3 {
        self.vertices[(index as usize).min(2)]
    }

    /// The triangle itself, facing `dir`'s side.
    pub(crate) fn supporting_face(&self, dir: Vec3) -> Face {
        self.supporting_tri(dir).with_capacity()
    }

    /// [`Triangle::supporting_face`] as a three-corner face.
    pub(crate) fn supporting_tri(&self, dir: Vec3) -> Face<3> {
        let n = self.normal();
        let order: [usize; 3] = if n.dot(dir) >= 0.0 {
            [0, 1, 2]
        } else {
            [0, 2, 1]
        };
        let front = order[1] == 1;
        let mut f = Face::new(
            if front { n } else { -n },
            FeatureId::face(if front { 0 } else { 1 }),
        );
        for (k, &i) in order.iter().enumerate() {
            let j = order[(k + 1) % 3];
            let v = self.vertices[i.min(2)];
            f.push(
                v,
                FeatureId::vertex(i as u32),
                FeatureId::edge(i as u32, j as u32),
            );
        }
        f
    }

    pub(crate) fn aabb(&self, pose: &Iso) -> Aabb {
        let p0 = pose.transform_point(self.vertices[0]);
        let mut b = Aabb::new(p0, p0);
        for v in &self.vertices[1..] {
            let p = pose.transform_point(*v);
            b = Aabb::new(b.min.min(p), b.max.max(p));
        }
        b
    }

    pub(crate) fn bounding_radius(&self) -> f32 {
        let mut r = 0.0;
        for v in &self.vertices {
            r = scalar::max(r, v.length());
        }
        r
    }

    /// Two-sided Möller–Trumbore ray cast in the local frame. The ray counts as parallel
    /// when the cosine of its angle to the triangle's normal is below 1e-7 (a test
    /// relative to the triangle's size, so small triangles are not missed); NaN-safe
    /// compares keep an overflowed barycentric from slipping through as a hit.
    pub fn cast_ray(&self, ray: &Ray, max_t: f32) -> Option<RayHit> {
        let [a, b, c] = self.vertices;
        let e1 = b - a;
        let e2 = c - a;
        let p = ray.direction.cross(e2);
        // det = e1 · (d × e2) = −d · (e1 × e2) = −|e1 × e2| cos θ.
        let det = e1.dot(p);
        let parallel = PARALLEL_COS * e1.cross(e2).length();
        if scalar::abs(det) <= parallel || det.is_nan() {
            return None;
        }
        let inv = 1.0 / det;
        let s = ray.origin - a;
        let u = s.dot(p) * inv;
        if !(0.0..=1.0).contains(&u) {
            return None;
        }
        let q = s.cross(e1);
        let v = ray.direction.dot(q) * inv;
        if !(v >= 0.0 && u + v <= 1.0) {
            return None;
        }
        let t = e2.dot(q) * inv;
        if !(t >= 0.0 && t <= max_t) {
            return None;
        }
        let n = self.normal();
        Some(RayHit {
            t,
            point: ray.at(t),
            normal: if n.dot(ray.direction) <= 0.0 { n } else { -n },
        })
    }

    /// The point of the filled triangle closest to `p` (all in m, local frame).
    ///
    /// With `a, b, c` the vertices, the plane around the triangle splits into seven
    /// Voronoi regions: three vertex regions, three edge regions and the face
    /// (Ericson, *Real-Time Collision Detection*, 5.1.5). The region of `p` follows from
    /// the dot products `d₁ = ab·ap`, `d₂ = ac·ap`, `d₃ = ab·bp`, `d₄ = ac·bp`,
    /// `d₅ = ab·cp`, `d₆ = ac·cp` and the unnormalised barycentric coordinates of the
    /// projection of `p`, `u = d₃d₆ − d₅d₄`, `v = d₅d₂ − d₁d₆` and `w = d₁d₄ − d₃d₂`
    /// (proportional to the barycentric weights of `a`, `b` and `c`):
    ///
    /// * vertex `a` when `d₁ ≤ 0` and `d₂ ≤ 0` (likewise `b`, `c`), returned exactly;
    /// * edge `ab` when `w ≤ 0`, `d₁ ≥ 0`, `d₃ ≤ 0`: `a + ab · d₁ / (d₁ − d₃)` (likewise
    ///   `ac` and `bc`);
    /// * otherwise the face: `a + ab · v/(u+v+w) + ac · w/(u+v+w)`.
    ///
    /// Plain `f32` arithmetic in a fixed order (no fused multiply-add): the same bits on
    /// every target. Never panics; for a degenerate triangle (only possible through the
    /// public field) it answers with the closest point of its three edges.
    ///
    /// # Example
    ///
    /// ```
    /// use carom::{shape::Triangle, Vec3};
    ///
    /// # fn main() -> Result<(), carom::Error> {
    /// let t = Triangle::new(Vec3::ZERO, Vec3::X, Vec3::Y)?;
    /// // Above the face: straight down onto it.
    /// let q = t.closest_point(Vec3::new(0.25, 0.25, 2.0));
    /// assert!((q - Vec3::new(0.25, 0.25, 0.0)).length() < 1e-6);
    /// // Beyond a vertex: the vertex itself.
    /// assert_eq!(t.closest_point(Vec3::new(3.0, -1.0, 0.5)), Vec3::X);
    /// // Beyond the edge from (1, 0, 0) to (0, 1, 0): its midpoint.
    /// let q = t.closest_point(Vec3::new(1.0, 1.0, 0.0));
    /// assert!((q - Vec3::new(0.5, 0.5, 0.0)).length() < 1e-6);
    /// # Ok(())
    /// # }
    /// ```
    pub fn closest_point(&self, p: Vec3) -> Vec3 {
        let [a, b, c] = self.vertices;
        let ab = b - a;
        let ac = c - a;

        // Vertex a: p behind both edges that leave a.
        let ap = p - a;
        let d1 = ab.dot(ap);
        let d2 = ac.dot(ap);
        if d1 <= 0.0 && d2 <= 0.0 {
            return a;
        }
        // Vertex b.
        let bp = p - b;
        let d3 = ab.dot(bp);
        let d4 = ac.dot(bp);
        if d3 >= 0.0 && d4 <= d3 {
            return b;
        }
        // Edge ab: the barycentric weight of c is not positive and p projects inside ab.
        let w = d1 * d4 - d3 * d2;
        if w <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
            return a + ab * ratio(d1, d1 - d3);
        }
        // Vertex c.
        let cp = p - c;
        let d5 = ab.dot(cp);
        let d6 = ac.dot(cp);
        if d6 >= 0.0 && d5 <= d6 {
            return c;
        }
        // Edge ac: the weight of b is not positive.
        let v = d5 * d2 - d1 * d6;
        if v <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
            return a + ac * ratio(d2, d2 - d6);
        }
        // Edge bc: the weight of a is not positive.
        let u = d3 * d6 - d5 * d4;
        let along_b = d4 - d3;
        let along_c = d5 - d6;
        if u <= 0.0 && along_b >= 0.0 && along_c >= 0.0 {
            return b + (c - b) * ratio(along_b, along_b + along_c);
        }
        // Face: all three weights positive.
        let sum = u + v + w;
        if sum > 0.0 && sum.is_finite() {
            let inv = 1.0 / sum;
            return a + ab * (v * inv) + ac * (w * inv);
        }
        // Only a degenerate (collinear) triangle gets here: its closest edge point.
        let mut best = closest_on_segment(p, a, b);
        for (s, e) in [(b, c), (c, a)] {
            let q = closest_on_segment(p, s, e);
            if (q - p).length_squared() < (best - p).length_squared() {
                best = q;
            }
        }
        best
    }

    /// Whether the two filled triangles share at least one point (touching counts), in
    /// the same frame.
    ///
    /// The orientation-predicate form of the interval test (Guigue and Devillers 2003,
    /// after Möller 1997), with `[a, b, c, d] = (d − a) · ((b − a) × (c − a))`, positive
    /// when `d` lies on the side `(b − a) × (c − a)` points to:
    ///
    /// 1. If the three vertices of one triangle lie strictly on the same side of the
    ///    other's plane, they are apart.
    /// 2. If all three vertices of one triangle lie on the other's plane, both are
    ///    projected onto the coordinate plane the normal is most aligned with, and they
    ///    meet if an edge of one meets an edge of the other or a vertex of one lies in
    ///    the other (2D orientation tests, boundaries included).
    /// 3. Otherwise each plane cuts the other triangle along a segment of the line
    ///    `L` where the planes meet. The vertices are renamed `p₁q₁r₁`, `p₂q₂r₂` (and
    ///    the other triangle's winding swapped if needed) so that `p₁` is alone on the
    ///    positive side of the second plane and `p₂` on the positive side of the first.
    ///    The segments then overlap on `L` exactly when
    ///    `[p₁, q₁, p₂, q₂] ≤ 0` and `[p₁, r₁, p₂, r₂] ≥ 0`.
    ///
    /// Every orientation is exactly zero when two of its points coincide, so triangles
    /// that share a vertex or an edge touch; an orientation within a relative tolerance
    /// of about 2·10⁻⁶ of zero (scaled by the size of the triangles and of their
    /// coordinates) also counts as zero, so coplanar triangles in a tilted plane and
    /// contacts closer than about that much also count as touching.
    ///
    /// The pair is put in a fixed order first, so `a.intersects(&b) == b.intersects(&a)`
    /// bit for bit. Plain `f32` arithmetic in a fixed order (no fused multiply-add),
    /// bounded loops (at most the nine edge pairs), no allocation; never panics (any input, NaN included, gives a
    /// `bool`).
    ///
    /// # Example
    ///
    /// ```
    /// use carom::{shape::Triangle, Vec3};
    ///
    /// # fn main() -> Result<(), carom::Error> {
    /// let floor = Triangle::new(Vec3::ZERO, Vec3::new(2.0, 0.0, 0.0), Vec3::new(0.0, 0.0, -2.0))?;
    /// // A vertical triangle poking through the floor.
    /// let post = Triangle::new(
    ///     Vec3::new(0.5, -1.0, -0.5),
    ///     Vec3::new(0.7, -1.0, -0.5),
    ///     Vec3::new(0.6, 1.0, -0.5),
    /// )?;
    /// assert!(floor.intersects(&post));
    /// // Lifted 2 m: apart.
    /// let up = Vec3::new(0.0, 2.0, 0.0);
    /// let [a, b, c] = post.vertices;
    /// let lifted = Triangle::new(a + up, b + up, c + up)?;
    /// assert!(!floor.intersects(&lifted));
    /// // Sharing only a vertex counts.
    /// let touching = Triangle::new(Vec3::ZERO, Vec3::new(-1.0, 1.0, 0.0), Vec3::new(-1.0, -1.0, 0.0))?;
    /// assert!(floor.intersects(&touching));
    /// # Ok(())
    /// # }
    /// ```
    pub fn intersects(&self, other: &Triangle) -> bool {
        // A fixed order of the pair makes the answer symmetric bit for bit.
        let (t1, t2) = if bits_key(self) <= bits_key(other) {
            (self, other)
        } else {
            (other, self)
        };
        let mut m: f32 = 0.0;
        for v in t1.vertices.iter().chain(t2.vertices.iter()) {
            m = scalar::max(m, v.abs().max_elem());
        }
        let [a1, b1, c1] = t1.vertices;
        let [a2, b2, c2] = t2.vertices;

        // Sides of the first triangle's vertices against the second's plane.
        let s1 = [
            orient3(a2, b2, c2, a1, m),
            orient3(a2, b2, c2, b1, m),
            orient3(a2, b2, c2, c1, m),
        ];
        if one_side(s1) {
            return false;
        }
        let s2 = [
            orient3(a1, b1, c1, a2, m),
            orient3(a1, b1, c1, b2, m),
            orient3(a1, b1, c1, c2, m),
        ];
        if one_side(s2) {
            return false;
        }
        let flat1 = s1 == [0.0; 3];
        let flat2 = s2 == [0.0; 3];
        if flat1 || flat2 {
            // Project along the normal of the plane the other triangle lies in.
            let n = if flat2 {
                (b1 - a1).cross(c1 - a1)
            } else {
                (b2 - a2).cross(c2 - a2)
            };
            return coplanar_overlap(t1.vertices, t2.vertices, n, m);
        }

        // p1 alone on the positive side of the second plane (swapping the second
        // triangle's winding flips the sides).
        let (k1, flip2) = lone_vertex(s1);
        let [p1, mut q1, mut r1] = rotate(t1.vertices, k1);
        let (v2, s2) = if flip2 {
            ([a2, c2, b2], [s2[0], s2[2], s2[1]])
        } else {
            ([a2, b2, c2], s2)
        };
        // p2 alone on the positive side of the first plane.
        let (k2, flip1) = lone_vertex(s2);
        let [p2, q2, r2] = rotate(v2, k2);
        if flip1 {
            core::mem::swap(&mut q1, &mut r1);
        }
        // The first triangle covers [j1, i1] of L (i1 on p1q1, j1 on p1r1), the second
        // [i2, j2] (i2 on p2q2, j2 on p2r2), along (n1 × n2); they overlap when i2 is not
        // past i1 and j1 not past j2.
        orient3(p1, q1, p2, q2, m) <= 0.0 && orient3(p1, r1, p2, r2, m) >= 0.0
    }
}

/// `num / den` for a ratio of a part to its whole, limited to `[0, 1]`; 0 when the whole
/// is not positive.
fn ratio(num: f32, den: f32) -> f32 {
    if den > 0.0 {
        scalar::clamp(num / den, 0.0, 1.0)
    } else {
        0.0
    }
}

/// The point of segment `ab` closest to `p`.
fn closest_on_segment(p: Vec3, a: Vec3, b: Vec3) -> Vec3 {
    let ab = b - a;
    a + ab * ratio((p - a).dot(ab), ab.length_squared())
}

/// The vertices' bit patterns: a total order on triangles.
fn bits_key(t: &Triangle) -> [u32; 9] {
    let [a, b, c] = t.vertices;
    [
        a.x.to_bits(),
        a.y.to_bits(),
        a.z.to_bits(),
        b.x.to_bits(),
        b.y.to_bits(),
        b.z.to_bits(),
        c.x.to_bits(),
        c.y.to_bits(),
        c.z.to_bits(),
    ]
}

/// `[a, b, c, d] = (d − a) · ((b − a) × (c − a))`, computed as
/// `(d − a) · ((b − d) × (c − d))`: positive when `d` is on the side of the plane `abc`
/// its normal `(b − a) × (c − a)` points to. Exactly zero when two of the points
/// coincide; within `TOUCH_TOL · (l + m) · l²` of zero (`l` the largest coordinate
/// difference used, `m` the largest coordinate of the pair), zero.
fn orient3(a: Vec3, b: Vec3, c: Vec3, d: Vec3, m: f32) -> f32 {
    if a == b || a == c || a == d || b == c || b == d || c == d {
        return 0.0;
    }
    let u = d - a;
    let v = b - d;
    let w = c - d;
    let s = u.dot(v.cross(w));
    let l = scalar::max(
        u.abs().max_elem(),
        scalar::max(v.abs().max_elem(), w.abs().max_elem()),
    );
    if scalar::abs(s) <= TOUCH_TOL * (l + m) * l * l {
        0.0
    } else {
        s
    }
}

/// A point of the projection plane.
#[derive(Clone, Copy, PartialEq)]
struct P2 {
    x: f32,
    y: f32,
}

/// `(a − c) × (b − c)`, positive when `abc` turns counter-clockwise. Exactly zero when
/// two of the points coincide; within `TOUCH_TOL · (l + m) · l` of zero, zero.
fn orient2(a: P2, b: P2, c: P2, m: f32) -> f32 {
    if a == b || a == c || b == c {
        return 0.0;
    }
    let (ux, uy) = (a.x - c.x, a.y - c.y);
    let (vx, vy) = (b.x - c.x, b.y - c.y);
    let s = ux * vy - uy * vx;
    let l = scalar::max(
        scalar::max(scalar::abs(ux), scalar::abs(uy)),
        scalar::max(scalar::abs(vx), scalar::abs(vy)),
    );
    if scalar::abs(s) <= TOUCH_TOL * (l + m) * l {
        0.0
    } else {
        s
    }
}

/// All three strictly positive or all three strictly negative.
fn one_side(s: [f32; 3]) -> bool {
    (s[0] > 0.0 && s[1] > 0.0 && s[2] > 0.0) || (s[0] < 0.0 && s[1] < 0.0 && s[2] < 0.0)
}

/// `[v[k], v[k + 1], v[k + 2]]`, indices mod 3.
fn rotate<T: Copy>(v: [T; 3], k: usize) -> [T; 3] {
    let [a, b, c] = v;
    match k {
        0 => [a, b, c],
        1 => [b, c, a],
        _ => [c, a, b],
    }
}

/// The rotation `k` that puts first a vertex alone on its side of a plane (the other two
/// on the other side or on the plane, and the first off it or the other two off it),
/// and whether the sides must be swapped to make its side the positive one. Signs not
/// all equal and not all zero always have one; anything else (NaN) gets `(0, false)`.
fn lone_vertex(s: [f32; 3]) -> (usize, bool) {
    for k in 0..3 {
        let [p, q, r] = rotate(s, k);
        if (p > 0.0 && q <= 0.0 && r <= 0.0) || (p >= 0.0 && q < 0.0 && r < 0.0) {
            return (k, false);
        }
        if (p < 0.0 && q >= 0.0 && r >= 0.0) || (p <= 0.0 && q > 0.0 && r > 0.0) {
            return (k, true);
        }
    }
    (0, false)
}

/// Whether closed segments `ab` and `cd` of a plane meet.
fn segments_meet(a: P2, b: P2, c: P2, d: P2, m: f32) -> bool {
    let o1 = orient2(a, b, c, m);
    let o2 = orient2(a, b, d, m);
    let o3 = orient2(c, d, a, m);
    let o4 = orient2(c, d, b, m);
    if (o1 == 0.0 && o2 == 0.0) || (o3 == 0.0 && o4 == 0.0) {
        // On one line: compare the intervals along the axis they spread most on.
        let spread_x = scalar::abs(b.x - a.x) + scalar::abs(d.x - c.x);
        let spread_y = scalar::abs(b.y - a.y) + scalar::abs(d.y - c.y);
        let (a, b, c, d) = if spread_x >= spread_y {
            (a.x, b.x, c.x, d.x)
        } else {
            (a.y, b.y, c.y, d.y)
        };
        let lo = scalar::max(scalar::min(a, b), scalar::min(c, d));
        let hi = scalar::min(scalar::max(a, b), scalar::max(c, d));
        return lo <= hi;
    }
    let apart_cd = (o1 > 0.0 && o2 > 0.0) || (o1 < 0.0 && o2 < 0.0);
    let apart_ab = (o3 > 0.0 && o4 > 0.0) || (o3 < 0.0 && o4 < 0.0);
    !apart_cd && !apart_ab
}

/// Whether `p` lies in the closed triangle `t` (either winding).
fn in_triangle(p: P2, t: [P2; 3], m: f32) -> bool {
    let [a, b, c] = t;
    let s = [
        orient2(a, b, p, m),
        orient2(b, c, p, m),
        orient2(c, a, p, m),
    ];
    !(s.iter().any(|&x| x > 0.0) && s.iter().any(|&x| x < 0.0))
}

/// Whether two triangles of one plane (normal `n`, any length) overlap: projected
/// along `n`'s largest component, an edge of one meets an edge of the other or a vertex
/// of one lies in the other.
fn coplanar_overlap(t1: [Vec3; 3], t2: [Vec3; 3], n: Vec3, m: f32) -> bool {
    let an = n.abs();
    let drop = if an.x >= an.y && an.x >= an.z {
        0
    } else if an.y >= an.z {
        1
    } else {
        2
    };
    let project = |v: Vec3| match drop {
        0 => P2 { x: v.y, y: v.z },
        1 => P2 { x: v.z, y: v.x },
        _ => P2 { x: v.x, y: v.y },
    };
    let [a1, b1, c1] = t1.map(project);
    let [a2, b2, c2] = t2.map(project);
    for (p, q) in [(a1, b1), (b1, c1), (c1, a1)] {
        for (r, s) in [(a2, b2), (b2, c2), (c2, a2)] {
            if segments_meet(p, q, r, s, m) {
                return true;
            }
        }
    }
    in_triangle(a1, [a2, b2, c2], m) || in_triangle(a2, [a1, b1, c1], m)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::SplitMix64;

    type D3 = [f64; 3];

    fn d3(v: Vec3) -> D3 {
        [v.x as f64, v.y as f64, v.z as f64]
    }
    fn sub(a: D3, b: D3) -> D3 {
        [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
    }
    fn add(a: D3, b: D3) -> D3 {
        [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
    }
    fn scale(a: D3, s: f64) -> D3 {
        [a[0] * s, a[1] * s, a[2] * s]
    }
    fn dot(a: D3, b: D3) -> f64 {
        a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
    }
    fn cross(a: D3, b: D3) -> D3 {
        [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ]
    }
    fn dist(a: D3, b: D3) -> f64 {
        dot(sub(a, b), sub(a, b)).sqrt()
    }
    fn tri64(t: &Triangle) -> [D3; 3] {
        t.vertices.map(d3)
    }
    fn edges(t: [D3; 3]) -> [(D3, D3); 3] {
        [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])]
    }

    /// Barycentric coordinates of the projection of `p` onto the triangle's plane, and
    /// the distance of `p` from that plane (f64).
    fn barycentric(t: [D3; 3], p: D3) -> ([f64; 3], f64) {
        let n = cross(sub(t[1], t[0]), sub(t[2], t[0]));
        let nn = dot(n, n);
        let wa = dot(cross(sub(t[2], t[1]), sub(p, t[1])), n) / nn;
        let wb = dot(cross(sub(t[0], t[2]), sub(p, t[2])), n) / nn;
        let wc = dot(cross(sub(t[1], t[0]), sub(p, t[0])), n) / nn;
        ([wa, wb, wc], dot(sub(p, t[0]), n).abs() / nn.sqrt())
    }

    fn closest_on_segment64(p: D3, a: D3, b: D3) -> D3 {
        let ab = sub(b, a);
        let t = (dot(sub(p, a), ab) / dot(ab, ab)).clamp(0.0, 1.0);
        add(a, scale(ab, t))
    }

    /// Distance from `p` to the filled triangle: the plane if the foot is inside,
    /// otherwise the nearest edge (f64, independent of the code under test).
    fn point_triangle_dist(p: D3, t: [D3; 3]) -> f64 {
        let (w, h) = barycentric(t, p);
        if w.iter().all(|&x| x >= 0.0) {
            return h;
        }
        edges(t)
            .iter()
            .map(|&(a, b)| dist(p, closest_on_segment64(p, a, b)))
            .fold(f64::INFINITY, f64::min)
    }

    /// Distance between segments: the interior pair of the lines' closest points when
    /// both lie inside, otherwise an endpoint is involved.
    fn segment_segment_dist(p1: D3, q1: D3, p2: D3, q2: D3) -> f64 {
        let mut best = f64::INFINITY;
        for (p, a, b) in [(p1, p2, q2), (q1, p2, q2), (p2, p1, q1), (q2, p1, q1)] {
            best = best.min(dist(p, closest_on_segment64(p, a, b)));
        }
        let d1 = sub(q1, p1);
        let d2 = sub(q2, p2);
        let r = sub(p1, p2);
        let (a, e, b) = (dot(d1, d1), dot(d2, d2), dot(d1, d2));
        let (c, f) = (dot(d1, r), dot(d2, r));
        let den = a * e - b * b;
        if den > 1e-12 * a * e {
            let s = (b * f - c * e) / den;
            let t = (a * f - b * c) / den;
            if (0.0..=1.0).contains(&s) && (0.0..=1.0).contains(&t) {
                best = best.min(dist(add(p1, scale(d1, s)), add(p2, scale(d2, t))));
            }
        }
        best
    }

    /// Smallest vertex–face and edge–edge distance (the distance between the triangles
    /// when no edge of one crosses the other).
    fn feature_distance(a: [D3; 3], b: [D3; 3]) -> f64 {
        let mut best = f64::INFINITY;
        for v in a {
            best = best.min(point_triangle_dist(v, b));
        }
        for v in b {
            best = best.min(point_triangle_dist(v, a));
        }
        for (p, q) in edges(a) {
            for (r, s) in edges(b) {
                best = best.min(segment_segment_dist(p, q, r, s));
            }
        }
        best
    }

    /// Whether an edge of `a` crosses the filled `b`: endpoints at least `margin` on
    /// either side of `b`'s plane and the crossing at least `margin` inside every edge.
    fn edge_pierces(a: [D3; 3], b: [D3; 3], margin: f64) -> bool {
        let n = cross(sub(b[1], b[0]), sub(b[2], b[0]));
        let n = scale(n, 1.0 / dot(n, n).sqrt());
        edges(a).iter().any(|&(p, q)| {
            let dp = dot(sub(p, b[0]), n);
            let dq = dot(sub(q, b[0]), n);
            if !((dp >= margin && dq <= -margin) || (dp <= -margin && dq >= margin)) {
                return false;
            }
            let x = add(p, scale(sub(q, p), dp / (dp - dq)));
            edges(b).iter().all(|&(u, v)| {
                let e = sub(v, u);
                dot(cross(e, sub(x, u)), n) / dot(e, e).sqrt() >= margin
            })
        })
    }

    /// Brute-force answer for a pair: `Some` when clear by at least 1e-4 m.
    fn oracle(a: &Triangle, b: &Triangle) -> Option<bool> {
        let (a, b) = (tri64(a), tri64(b));
        if edge_pierces(a, b, 1e-4) || edge_pierces(b, a, 1e-4) {
            return Some(true);
        }
        let any_pierce = edge_pierces(a, b, -1e-9) || edge_pierces(b, a, -1e-9);
        if !any_pierce && feature_distance(a, b) >= 1e-4 {
            return Some(false);
        }
        None
    }

    fn v(x: f32, y: f32, z: f32) -> Vec3 {
        Vec3::new(x, y, z)
    }

    fn tri(a: Vec3, b: Vec3, c: Vec3) -> Triangle {
        Triangle::new(a, b, c).unwrap()
    }

    fn random_point(r: &mut SplitMix64, half: f32) -> Vec3 {
        v(
            r.range(-half, half),
            r.range(-half, half),
            r.range(-half, half),
        )
    }

    #[test]
    fn closest_point_matches_dense_sampling() {
        let mut r = SplitMix64::new(0x7419);
        const GRID: usize = 200;
        const EDGE_STEPS: usize = 2000;
        let mut compared = 0u64;
        let (mut in_face, mut on_edge_or_vertex) = (0, 0);
        for case in 0..2500 {
            let t = loop {
                let (a, b, c) = (
                    random_point(&mut r, 1.0),
                    random_point(&mut r, 1.0),
                    random_point(&mut r, 1.0),
                );
                if let Ok(t) = Triangle::new(a, b, c) {
                    break t;
                }
            };
            let p = if case % 2 == 0 {
                random_point(&mut r, 2.0)
            } else {
                // Near the face: a point of the triangle moved off its plane.
                let [a, b, c] = t.vertices;
                let (u, w) = (r.next_f32(), r.next_f32());
                let (u, w) = if u + w > 1.0 {
                    (1.0 - u, 1.0 - w)
                } else {
                    (u, w)
                };
                a + (b - a) * u
                    + (c - a) * w
                    + t.normal() * r.range(-1.0, 1.0)
                    + random_point(&mut r, 0.1)
            };
            let q = t.closest_point(p);
            let t64 = tri64(&t);
            let (w, h) = barycentric(t64, d3(q));
            assert!(
                w.iter().all(|&x| x >= -1e-5),
                "case {case}: off the face {w:?}"
            );
            assert!(h < 1e-5, "case {case}: {h} off the plane");
            if w.iter().all(|&x| x > 1e-4) {
                in_face += 1;
            } else {
                on_edge_or_vertex += 1;
            }
            let (p64, got) = (d3(p), dist(d3(p), d3(q)));
            let mut best = f64::INFINITY;
            for i in 0..=GRID {
                for j in 0..=GRID - i {
                    let (u, s) = (i as f64 / GRID as f64, j as f64 / GRID as f64);
                    let x = add(
                        t64[0],
                        add(scale(sub(t64[1], t64[0]), u), scale(sub(t64[2], t64[0]), s)),
                    );
                    best = best.min(dist(p64, x));
                    compared += 1;
                }
            }
            for (a, b) in edges(t64) {
                for k in 0..=EDGE_STEPS {
                    let x = add(a, scale(sub(b, a), k as f64 / EDGE_STEPS as f64));
                    best = best.min(dist(p64, x));
                    compared += 1;
                }
            }
            assert!(
                best >= got - 1e-5,
                "case {case}: a sample is {best}, the answer {got}"
            );
            // The sampling is dense enough to have caught a wrong answer.
            assert!(best - got < 0.02, "case {case}: {got} vs {best}");
            // And the answer agrees with projection-or-nearest-edge in f64.
            let want = point_triangle_dist(p64, t64);
            assert!((got - want).abs() < 1e-5, "case {case}: {got} vs {want}");
        }
        std::println!(
            "closest_point: {in_face} in the face, {on_edge_or_vertex} on an edge or vertex, \
             {compared} samples"
        );
        assert!(
            in_face > 500 && on_edge_or_vertex > 500,
            "{in_face} {on_edge_or_vertex}"
        );
        assert!(compared > 10_000_000);
    }

    #[test]
    fn closest_point_exact_cases() {
        let t = tri(v(0.0, 0.0, 0.0), v(2.0, 0.0, 0.0), v(0.0, 2.0, 0.0));
        // Above (and below) the interior: straight down.
        for z in [3.0, -0.5] {
            let q = t.closest_point(v(0.5, 0.25, z));
            assert!((q - v(0.5, 0.25, 0.0)).length() < 1e-6, "{q:?}");
        }
        // Beyond each vertex: the vertex, bit for bit.
        assert_eq!(t.closest_point(v(-1.0, -1.0, 1.0)), t.vertices[0]);
        assert_eq!(t.closest_point(v(3.0, -0.5, -2.0)), t.vertices[1]);
        assert_eq!(t.closest_point(v(-0.5, 3.0, 0.0)), t.vertices[2]);
        // Beyond an edge: onto it.
        let q = t.closest_point(v(1.0, -3.0, 1.0));
        assert!((q - v(1.0, 0.0, 0.0)).length() < 1e-6, "{q:?}");
        let q = t.closest_point(v(2.0, 2.0, 0.0));
        assert!((q - v(1.0, 1.0, 0.0)).length() < 1e-6, "{q:?}");
        // A point of the triangle is its own closest point.
        for p in [v(0.5, 0.5, 0.0), v(1.0, 0.0, 0.0), v(0.0, 2.0, 0.0)] {
            assert!((t.closest_point(p) - p).length() < 1e-6);
        }
    }

    /// Random pairs of triangles about their centres, the centres in a box a little
    /// smaller than the triangles (so about half the pairs meet).
    fn random_pair(r: &mut SplitMix64) -> (Triangle, Triangle) {
        let mut one = || loop {
            let c = random_point(r, 0.33);
            let u = r.unit_vector();
            let w = u.cross(r.unit_vector()).normalize_or(u.any_perpendicular());
            let x = u.cross(w);
            let start = r.range(0.0, core::f32::consts::TAU);
            let mut p = [Vec3::ZERO; 3];
            for (i, q) in p.iter_mut().enumerate() {
                let ang = start + i as f32 * 2.1 + r.range(-0.6, 0.6);
                *q = c + (w * ang.cos() + x * ang.sin()) * r.range(0.3, 1.0);
            }
            if let Ok(t) = Triangle::new(p[0], p[1], p[2]) {
                if (p[1] - p[0]).cross(p[2] - p[0]).length() > 0.02 {
                    return t;
                }
            }
        };
        (one(), one())
    }

    #[test]
    fn intersects_matches_brute_force() {
        let mut r = SplitMix64::new(0x1917);
        let (mut yes, mut no, mut skipped) = (0, 0, 0);
        for case in 0..20_000 {
            let (a, b) = random_pair(&mut r);
            let got = a.intersects(&b);
            assert_eq!(got, b.intersects(&a), "case {case}: not symmetric");
            match oracle(&a, &b) {
                Some(want) => {
                    assert_eq!(got, want, "case {case}: {a:?} {b:?}");
                    if want {
                        yes += 1;
                    } else {
                        no += 1;
                    }
                }
                None => skipped += 1,
            }
        }
        std::println!("intersects oracle: {yes} intersecting, {no} apart, {skipped} skipped");
        assert!(yes >= 5000 && no >= 5000, "{yes} {no}");
        assert!(skipped < 200, "{skipped}");
    }

    /// Triangles of one plane: `z = 0` exactly (exact zeros), or a tilted plane whose
    /// `f32` rounding leaves the vertices only nearly coplanar (the tolerance's job).
    #[test]
    fn coplanar_pairs_match_2d_oracle() {
        let mut r = SplitMix64::new(0xc0);
        for tilted in [false, true] {
            let (mut yes, mut no, mut skipped) = (0, 0, 0);
            for case in 0..8000 {
                let rot = r.rotation();
                let shift = random_point(&mut r, 3.0);
                let mut flat = || loop {
                    let c = v(r.range(-0.5, 0.5), r.range(-0.5, 0.5), 0.0);
                    let mut p = [Vec3::ZERO; 3];
                    for x in &mut p {
                        let ang = r.range(0.0, core::f32::consts::TAU);
                        let len = r.range(0.2, 1.0);
                        *x = c + v(len * ang.cos(), len * ang.sin(), 0.0);
                    }
                    if let Ok(t) = Triangle::new(p[0], p[1], p[2]) {
                        if t.normal().z.abs() > 0.5
                            && (p[1] - p[0]).cross(p[2] - p[0]).length() > 0.02
                        {
                            return t;
                        }
                    }
                };
                let (a, b) = (flat(), flat());
                // The oracle works on the exact plane z = 0.
                let want = oracle_2d(&a, &b);
                let place = |t: &Triangle| {
                    if tilted {
                        let [p, q, s] = t.vertices.map(|x| rot.rotate(x) + shift);
                        Triangle::new(p, q, s).unwrap()
                    } else {
                        *t
                    }
                };
                let (a, b) = (place(&a), place(&b));
                let got = a.intersects(&b);
                assert_eq!(got, b.intersects(&a), "case {case}: not symmetric");
                match want {
                    Some(w) => {
                        assert_eq!(got, w, "tilted {tilted} case {case}: {a:?} {b:?}");
                        if w {
                            yes += 1;
                        } else {
                            no += 1;
                        }
                    }
                    None => skipped += 1,
                }
            }
            std::println!(
                "coplanar (tilted {tilted}): {yes} overlap, {no} apart, {skipped} skipped"
            );
            assert!(yes >= 1500 && no >= 1500, "{yes} {no}");
        }
    }

    /// Coplanar oracle in `z = 0`: clearly overlapping when a vertex is 1e-4 m inside
    /// the other or two edges properly cross by 1e-4 m; clearly apart when the smallest
    /// vertex–face / edge–edge distance is at least 1e-4 m.
    fn oracle_2d(a: &Triangle, b: &Triangle) -> Option<bool> {
        let (a, b) = (tri64(a), tri64(b));
        let side = |u: D3, w: D3, x: D3| {
            let e = sub(w, u);
            (e[0] * (x[1] - u[1]) - e[1] * (x[0] - u[0])) / (e[0] * e[0] + e[1] * e[1]).sqrt()
        };
        let inside = |x: D3, t: [D3; 3]| {
            let s = edges(t).map(|(u, w)| side(u, w, x));
            s.iter().all(|&d| d >= 1e-4) || s.iter().all(|&d| d <= -1e-4)
        };
        let crossing = |p: D3, q: D3, r: D3, s: D3| {
            let (s1, s2) = (side(p, q, r), side(p, q, s));
            let (s3, s4) = (side(r, s, p), side(r, s, q));
            s1 * s2 < 0.0
                && s3 * s4 < 0.0
                && s1.abs().min(s2.abs()) >= 1e-4
                && s3.abs().min(s4.abs()) >= 1e-4
        };
        let cross_any = edges(a)
            .iter()
            .any(|&(p, q)| edges(b).iter().any(|&(r, s)| crossing(p, q, r, s)));
        if cross_any || a.iter().any(|&x| inside(x, b)) || b.iter().any(|&x| inside(x, a)) {
            return Some(true);
        }
        if feature_distance(a, b) >= 1e-4 {
            return Some(false);
        }
        None
    }

    #[test]
    fn intersects_special_cases() {
        let t = tri(v(0.0, 0.0, 0.0), v(1.0, 0.0, 0.0), v(0.0, 1.0, 0.0));
        let check = |a: &Triangle, b: &Triangle, want: bool, what: &str| {
            assert_eq!(a.intersects(b), want, "{what}");
            assert_eq!(b.intersects(a), want, "{what} (swapped)");
            // Winding and vertex order do not matter.
            let [p, q, r] = b.vertices;
            for o in [[q, r, p], [r, p, q], [p, r, q], [r, q, p]] {
                let b2 = tri(o[0], o[1], o[2]);
                assert_eq!(a.intersects(&b2), want, "{what} (reordered)");
            }
        };
        check(&t, &t, true, "itself");
        // Coplanar, overlapping (partly, and one inside the other).
        check(
            &t,
            &tri(v(0.2, 0.2, 0.0), v(1.5, 0.2, 0.0), v(0.2, 1.5, 0.0)),
            true,
            "coplanar overlap",
        );
        check(
            &t,
            &tri(v(0.1, 0.1, 0.0), v(0.3, 0.1, 0.0), v(0.1, 0.3, 0.0)),
            true,
            "coplanar inside",
        );
        check(
            &t,
            &tri(v(-1.0, -1.0, 0.0), v(3.0, -1.0, 0.0), v(-1.0, 3.0, 0.0)),
            true,
            "coplanar around",
        );
        // Coplanar, apart (across the hypotenuse, and just beyond a vertex).
        check(
            &t,
            &tri(v(0.6, 0.6, 0.0), v(1.5, 0.6, 0.0), v(0.6, 1.5, 0.0)),
            false,
            "coplanar apart",
        );
        check(
            &t,
            &tri(v(1.01, 0.0, 0.0), v(2.0, 0.0, 0.0), v(1.5, 1.0, 0.0)),
            false,
            "coplanar gap",
        );
        // Coplanar, touching along part of an edge, and at one vertex.
        check(
            &t,
            &tri(v(0.5, 0.0, 0.0), v(2.0, 0.0, 0.0), v(1.0, -1.0, 0.0)),
            true,
            "coplanar edge contact",
        );
        check(
            &t,
            &tri(v(1.0, 0.0, 0.0), v(2.0, 0.0, 0.0), v(2.0, 1.0, 0.0)),
            true,
            "coplanar vertex contact",
        );
        // A shared edge: coplanar and folded.
        check(
            &t,
            &tri(v(1.0, 0.0, 0.0), v(0.0, 0.0, 0.0), v(0.5, -1.0, 0.0)),
            true,
            "shared edge flat",
        );
        check(
            &t,
            &tri(v(1.0, 0.0, 0.0), v(0.0, 0.0, 0.0), v(0.3, -0.7, 0.9)),
            true,
            "shared edge folded",
        );
        check(
            &t,
            &tri(v(1.0, 0.0, 0.0), v(0.0, 1.0, 0.0), v(0.9, 0.8, -0.4)),
            true,
            "shared hypotenuse",
        );
        // A shared vertex only, out of plane.
        check(
            &t,
            &tri(v(0.0, 1.0, 0.0), v(-1.0, 2.0, 1.0), v(0.5, 2.0, 1.0)),
            true,
            "shared vertex",
        );
        check(
            &t,
            &tri(v(0.0, 0.0, 0.0), v(-1.0, -0.5, 0.7), v(-0.4, -1.0, -0.6)),
            true,
            "shared vertex, crossing plane",
        );
        // A vertex touching the face, and an edge lying on it.
        check(
            &t,
            &tri(v(0.2, 0.2, 0.0), v(0.5, 0.5, 1.0), v(0.0, 0.5, 1.0)),
            true,
            "vertex on face",
        );
        check(
            &t,
            &tri(v(0.2, 0.2, 0.0), v(0.4, 0.2, 0.0), v(0.3, 0.5, 1.0)),
            true,
            "edge on face",
        );
        // Piercing through the middle, and through an edge.
        check(
            &t,
            &tri(v(0.2, 0.2, -1.0), v(0.3, 0.2, 1.0), v(0.2, 0.3, 1.0)),
            true,
            "pierce",
        );
        check(
            &t,
            &tri(v(0.5, -0.5, -1.0), v(0.5, 0.5, 1.0), v(0.5, 0.5, -1.0)),
            true,
            "through edge",
        );
        // Parallel planes, offset.
        for dz in [1e-3, 0.5, -2.0] {
            let [a, b, c] = t.vertices.map(|x| x + v(0.1, 0.1, dz));
            check(&t, &tri(a, b, c), false, "parallel offset");
        }
        // Crossing the plane beside the triangle.
        check(
            &t,
            &tri(v(2.0, 2.0, -1.0), v(3.0, 2.0, 1.0), v(2.0, 3.0, 1.0)),
            false,
            "beside",
        );
        // The line of the planes meets both, but the segments miss each other.
        check(
            &t,
            &tri(v(0.8, 0.8, -1.0), v(0.8, 0.8, 1.0), v(2.0, 0.8, 0.0)),
            false,
            "segments miss",
        );
    }

    /// Off-axis contacts with bit-identical shared vertices (as in a mesh) always
    /// touch; a copy moved 1 cm along the normal never does.
    #[test]
    fn random_shared_features_touch_and_offsets_do_not() {
        let mut r = SplitMix64::new(0x5eed);
        for case in 0..3000 {
            let (a, b) = random_pair(&mut r);
            let [p, q, s] = a.vertices;
            let [x, y, _] = b.vertices;
            // A shared edge (either direction) and a shared vertex.
            for (u, w, z) in [(q, p, x), (p, q, x), (p, x, y)] {
                if let Ok(c) = Triangle::new(u, w, z) {
                    assert!(a.intersects(&c), "case {case}: {a:?} {c:?}");
                    assert!(c.intersects(&a), "case {case}: {c:?} {a:?}");
                }
            }
            let off = a.normal() * 0.01;
            let lifted = tri(p + off, q + off, s + off);
            assert!(!a.intersects(&lifted), "case {case}: {a:?}");
        }
    }

    #[test]
    fn odd_inputs_do_not_panic() {
        // Only reachable through the public field.
        let collinear = Triangle {
            vertices: [v(0.0, 0.0, 0.0), v(1.0, 0.0, 0.0), v(2.0, 0.0, 0.0)],
        };
        let q = collinear.closest_point(v(1.5, 1.0, 0.0));
        assert!((q - v(1.5, 0.0, 0.0)).length() < 1e-6, "{q:?}");
        let point = Triangle {
            vertices: [v(1.0, 1.0, 1.0); 3],
        };
        assert_eq!(point.closest_point(Vec3::ZERO), v(1.0, 1.0, 1.0));
        let nan = Triangle {
            vertices: [
                v(f32::NAN, 0.0, 0.0),
                v(1.0, 0.0, 0.0),
                v(0.0, f32::INFINITY, 0.0),
            ],
        };
        let t = tri(v(0.0, 0.0, 0.0), v(1.0, 0.0, 0.0), v(0.0, 1.0, 0.0));
        for a in [collinear, point, nan, t] {
            for b in [collinear, point, nan, t] {
                assert_eq!(a.intersects(&b), b.intersects(&a));
            }
            let _ = a.closest_point(v(f32::NAN, 1.0, 2.0));
        }
        assert!(collinear.intersects(&t));
    }
}
