//! Cuboid (box) centred on the local origin. Vertex `i` has coordinate `k` positive when
//! bit `k` of `i` is set. Faces: 0 −X, 1 +X, 2 −Y, 3 +Y, 4 −Z, 5 +Z.

use super::{Face, FeatureId, MassProperties, Ray, RayHit};
use crate::error::{finite_vec, Error, Input};
use crate::math::{scalar, Mat3, Vec3};

/// The corners of face `2 axis + positive` (vertex indices), counter-clockwise about its
/// outward normal: with `u = axis + 1`, `w = axis + 2` (mod 3), the corners in `(u, w)`
/// signs `(−, −), (+, −), (+, +), (−, +)` for a positive face, reversed for a negative one.
const FACE_CORNERS: [[u8; 4]; 6] = face_corners();

const fn face_corners() -> [[u8; 4]; 6] {
    let mut out = [[0u8; 4]; 6];
    let mut f = 0;
    while f < 6 {
        let axis = f / 2;
        let positive = f % 2 == 1;
        let (u, w) = ((axis + 1) % 3, (axis + 2) % 3);
        let signs = [(false, false), (true, false), (true, true), (false, true)];
        let mut k = 0;
        while k < 4 {
            let (su, sw) = if positive { signs[k] } else { signs[3 - k] };
            let mut id = 0u8;
            if positive {
                id |= 1 << axis;
            }
            if su {
                id |= 1 << u;
            }
            if sw {
                id |= 1 << w;
            }
            out[f][k] = id;
            k += 1;
        }
        f += 1;
    }
    out
}

/// The vertex ids of each face's corners, in [`FACE_CORNERS`] order.
/// The corners of [`FACE_CORNERS`] as signs: corner `i` is `h ⊙ (±1, ±1, ±1)` (bit `k` of
/// `i` set: `+1` on axis `k`), so a face is four exact products instead of twelve selects.
const FACE_SIGNS: [[Vec3; 4]; 6] = face_signs();

const fn face_signs() -> [[Vec3; 4]; 6] {
    let mut out = [[Vec3::ZERO; 4]; 6];
    let mut f = 0;
    while f < 6 {
        let mut k = 0;
        while k < 4 {
            let id = FACE_CORNERS[f][k];
            out[f][k] = Vec3::new(corner_sign(id, 1), corner_sign(id, 2), corner_sign(id, 4));
            k += 1;
        }
        f += 1;
    }
    out
}

/// `+1` when corner `id` has `bit` set, else `−1`.
const fn corner_sign(id: u8, bit: u8) -> f32 {
    if id & bit != 0 {
        1.0
    } else {
        -1.0
    }
}

const FACE_VERTEX_IDS: [[FeatureId; 4]; 6] = face_ids(false);

/// The ids of each face's edges, from corner `k` to corner `k + 1` (wrapping).
const FACE_EDGE_IDS: [[FeatureId; 4]; 6] = face_ids(true);

const fn face_ids(edges: bool) -> [[FeatureId; 4]; 6] {
    let mut out = [[FeatureId(0); 4]; 6];
    let mut f = 0;
    while f < 6 {
        let mut k = 0;
        while k < 4 {
            let (id, next) = (
                FACE_CORNERS[f][k] as u32,
                FACE_CORNERS[f][(k + 1) % 4] as u32,
            );
            out[f][k] = if edges {
                FeatureId::edge(id, next)
            } else {
                FeatureId::vertex(id)
            };
            k += 1;
        }
        f += 1;
    }
    out
}

/// A box with half-extents along local X, Y and Z.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Cuboid {
    /// Half-extents (m), each finite and positive.
    pub half_extents: Vec3,
}

impl Cuboid {
    /// A box; every half-extent must be finite and positive.
    pub fn new(half_extents: Vec3) -> Result<Cuboid, Error> {
        finite_vec(half_extents, Input::HalfExtents)?;
        for h in half_extents.to_array() {
            super::size(h, Input::HalfExtents)?;
        }
        Ok(Cuboid { half_extents })
    }

    pub(crate) fn core_support(&self, dir: Vec3) -> (Vec3, u32) {
        let h = self.half_extents;
        let mut i = 0;
        let x = if dir.x >= 0.0 {
            i |= 1;
            h.x
        } else {
            -h.x
        };
        let y = if dir.y >= 0.0 {
            i |= 2;
            h.y
        } else {
            -h.y
        };
        let z = if dir.z >= 0.0 {
            i |= 4;
            h.z
        } else {
            -h.z
        };
        (Vec3::new(x, y, z), i)
    }

    pub(crate) fn core_vertex(&self, index: u32) -> Vec3 {
        let h = self.half_extents;
        Vec3::new(
            if index & 1 != 0 { h.x } else { -h.x },
            if index & 2 != 0 { h.y } else { -h.y },
            if index & 4 != 0 { h.z } else { -h.z },
        )
    }

    /// The face whose normal is most aligned with `dir` (ties: X before Y before Z).
    pub(crate) fn supporting_face(&self, dir: Vec3) -> Face {
        self.supporting_quad(dir).with_capacity()
    }

    /// [`Cuboid::supporting_face`] as a four-corner face.
    pub(crate) fn supporting_quad(&self, dir: Vec3) -> Face<4> {
        let a = dir.abs();
        let axis = if a.x >= a.y && a.x >= a.z {
            0
        } else if a.y >= a.z {
            1
        } else {
            2
        };
        let positive = dir[axis] >= 0.0;
        self.quad(axis, positive)
    }

    /// Face on `axis` (0, 1, 2) on the positive or negative side, counter-clockwise about
    /// its outward normal; corners from [`FACE_CORNERS`] (by [`FACE_SIGNS`]).
    pub(crate) fn quad(&self, axis: usize, positive: bool) -> Face<4> {
        let axis = axis.min(2);
        let s = if positive { 1.0 } else { -1.0 };
        let mut normal = Vec3::ZERO;
        set(&mut normal, axis, s);
        let face_index = (2 * axis + positive as usize).min(5);
        // `h · ±1` is exact: the corners `core_vertex` gives, to the bit.
        let h = self.half_extents;
        Face {
            normal,
            id: FeatureId::face(face_index as u32),
            len: 4,
            vertices: FACE_SIGNS[face_index].map(|s| h.mul_elem(s)),
            vertex_ids: FACE_VERTEX_IDS[face_index],
            edge_ids: FACE_EDGE_IDS[face_index],
        }
    }

    /// `m = 8 hx hy hz ρ`, `Ixx = m (hy² + hz²) / 3` and so on.
    pub fn mass_properties(&self, density: f32) -> MassProperties {
        let h = self.half_extents;
        let mass = density * 8.0 * h.x * h.y * h.z;
        let k = mass / 3.0;
        MassProperties {
            mass,
            center: Vec3::ZERO,
            inertia: Mat3::from_diagonal(Vec3::new(
                k * (h.y * h.y + h.z * h.z),
                k * (h.x * h.x + h.z * h.z),
                k * (h.x * h.x + h.y * h.y),
            )),
        }
    }

    /// Ray cast in the local frame by the slab method.
    pub fn cast_ray(&self, ray: &Ray, max_t: f32) -> Option<RayHit> {
        let h = self.half_extents;
        let mut t_enter = 0.0f32;
        let mut t_exit = max_t;
        let mut enter_axis: Option<(usize, f32)> = None;
        for k in 0..3 {
            let o = ray.origin[k];
            let d = ray.direction[k];
            if scalar::abs(d) < 1.0e-12 {
                if o < -h[k] || o > h[k] {
                    return None;
                }
                continue;
            }
            let inv = 1.0 / d;
            let mut t0 = (-h[k] - o) * inv;
            let mut t1 = (h[k] - o) * inv;
            let mut s = -1.0;
            if t0 > t1 {
                core::mem::swap(&mut t0, &mut t1);
                s = 1.0;
            }
            if t0 > t_enter {
                t_enter = t0;
                enter_axis = Some((k, s));
            }
            t_exit = scalar::min(t_exit, t1);
            if t_enter > t_exit {
                return None;
            }
        }
        let normal = match enter_axis {
            Some((k, s)) => {
                let mut n = Vec3::ZERO;
                set(&mut n, k, s);
                n
            }
            None => -ray.direction, // origin inside
        };
        Some(RayHit {
            t: t_enter,
            point: ray.at(t_enter),
            normal,
        })
    }
}

fn set(v: &mut Vec3, k: usize, value: f32) {
    match k {
        0 => v.x = value,
        1 => v.y = value,
        _ => v.z = value,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn faces_are_counter_clockwise_and_on_their_plane() {
        let b = Cuboid::new(Vec3::new(1.0, 2.0, 3.0)).unwrap();
        for axis in 0..3 {
            for positive in [false, true] {
                let f = b.quad(axis, positive);
                assert_eq!(f.len, 4);
                let p = f.points();
                let n = (p[1] - p[0]).cross(p[2] - p[1]).normalize_or(Vec3::ZERO);
                assert!((n - f.normal).length() < 1e-6, "{axis} {positive}");
                for v in p {
                    assert!((v.dot(f.normal) - b.half_extents[axis]).abs() < 1e-6);
                }
            }
        }
    }
}
