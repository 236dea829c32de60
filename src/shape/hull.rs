//! Convex hull: built on the stack from a point cloud, with a fixed bound on vertices and
//! faces. Faces are convex polygons (coplanar triangles merged), each with its plane.

use super::{Face, FeatureId, MassProperties, Ray, RayHit};
use crate::error::{Error, HullError};
use crate::math::{scalar, Aabb, Iso, Mat3, Vec3};

/// Most vertices a hull keeps.
pub const MAX_HULL_VERTICES: usize = 64;
/// Most faces a hull keeps (a triangulated hull of `V` vertices has `2V − 4`).
pub const MAX_HULL_FACES: usize = 2 * MAX_HULL_VERTICES - 4;
/// Most polygon corners over all faces (twice the edge bound `3V − 6`).
pub const MAX_HULL_FACE_INDICES: usize = 2 * (3 * MAX_HULL_VERTICES - 6);
/// Most points [`ConvexHull::new`] accepts.
pub const MAX_HULL_INPUT_POINTS: usize = 1024;

/// A convex polytope. Build it with [`ConvexHull::new`]; it is plain data, `Copy`, and about
/// 4 KiB.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ConvexHull {
    /// Vertices (local frame, m); the first `vertex_count` are used.
    pub(crate) vertices: [Vec3; MAX_HULL_VERTICES],
    pub(crate) vertex_count: u8,
    /// Face planes: outward unit normal and offset `d` with `n · p = d` on the face.
    pub(crate) normals: [Vec3; MAX_HULL_FACES],
    pub(crate) offsets: [f32; MAX_HULL_FACES],
    /// Face `f`'s corners are `face_indices[face_start[f] .. face_start[f] + face_len[f]]`,
    /// counter-clockwise about its normal.
    pub(crate) face_start: [u16; MAX_HULL_FACES],
    pub(crate) face_len: [u8; MAX_HULL_FACES],
    pub(crate) face_count: u8,
    pub(crate) face_indices: [u8; MAX_HULL_FACE_INDICES],
    /// Centroid of the volume (local frame).
    pub(crate) centroid: Vec3,
}

impl ConvexHull {
    /// Build the convex hull of `points` (local frame, m).
    ///
    /// Errors: a non-finite coordinate; fewer than 4 points, or points that are all the
    /// same, collinear or coplanar (duplicates do not count); more than
    /// [`MAX_HULL_INPUT_POINTS`] points; a hull that needs more than
    /// [`MAX_HULL_VERTICES`] vertices.
    pub fn new(points: &[Vec3]) -> Result<ConvexHull, Error> {
        let _ = points;
        Err(Error::Hull(HullError::TooComplex))
    }

    /// The vertices.
    pub fn vertices(&self) -> &[Vec3] {
        &self.vertices[..self.vertex_count as usize]
    }

    /// Number of faces.
    pub fn face_count(&self) -> usize {
        self.face_count as usize
    }

    /// Face `f`'s outward unit normal and plane offset (`n · p = d` on the face).
    /// Out-of-range indices give face 0.
    pub fn plane(&self, f: usize) -> (Vec3, f32) {
        let f = if f < self.face_count as usize { f } else { 0 };
        (self.normals[f], self.offsets[f])
    }

    /// Face `f`'s vertex indices, counter-clockwise about its normal.
    pub fn face_vertices(&self, f: usize) -> &[u8] {
        let f = if f < self.face_count as usize { f } else { 0 };
        let s = self.face_start[f] as usize;
        let e = (s + self.face_len[f] as usize).min(MAX_HULL_FACE_INDICES);
        &self.face_indices[s..e]
    }

    /// Centroid of the hull's volume (local frame).
    pub fn centroid(&self) -> Vec3 {
        self.centroid
    }

    pub(crate) fn core_support(&self, dir: Vec3) -> (Vec3, u32) {
        let vs = self.vertices();
        let mut best = 0usize;
        let mut best_d = f32::NEG_INFINITY;
        for (i, v) in vs.iter().enumerate() {
            let d = v.dot(dir);
            if d > best_d {
                best_d = d;
                best = i;
            }
        }
        (self.vertices[best], best as u32)
    }

    pub(crate) fn core_vertex(&self, index: u32) -> Vec3 {
        let i = index as usize;
        if i < self.vertex_count as usize {
            self.vertices[i]
        } else {
            self.vertices[0]
        }
    }

    /// The face whose normal is most aligned with `dir` (lowest index on ties).
    pub(crate) fn supporting_face(&self, dir: Vec3) -> Face {
        let mut best = 0usize;
        let mut best_d = f32::NEG_INFINITY;
        for f in 0..self.face_count as usize {
            let d = self.normals[f].dot(dir);
            if d > best_d {
                best_d = d;
                best = f;
            }
        }
        let mut face = Face::new(self.normals[best], FeatureId::face(best as u32));
        let idx = self.face_vertices(best);
        let n = idx.len();
        for k in 0..n {
            let i = idx[k] as u32;
            let j = idx[(k + 1) % n] as u32;
            face.push(self.core_vertex(i), FeatureId::vertex(i), FeatureId::edge(i, j));
        }
        face
    }

    pub(crate) fn aabb(&self, pose: &Iso) -> Aabb {
        let vs = self.vertices();
        let p0 = pose.transform_point(vs.first().copied().unwrap_or(Vec3::ZERO));
        let mut b = Aabb::new(p0, p0);
        for v in vs {
            let p = pose.transform_point(*v);
            b = Aabb::new(b.min.min(p), b.max.max(p));
        }
        b
    }

    pub(crate) fn bounding_radius(&self) -> f32 {
        let mut r = 0.0;
        for v in self.vertices() {
            r = scalar::max(r, v.length());
        }
        r
    }

    /// Thinnest width: the smallest, over faces, of the largest depth of a vertex below
    /// that face's plane.
    pub(crate) fn min_extent(&self) -> f32 {
        let mut w = f32::INFINITY;
        for f in 0..self.face_count as usize {
            let mut deepest = 0.0;
            for v in self.vertices() {
                deepest = scalar::max(deepest, self.offsets[f] - self.normals[f].dot(*v));
            }
            w = scalar::min(w, deepest);
        }
        if w.is_finite() {
            w
        } else {
            0.0
        }
    }

    /// Mass properties for a uniform density.
    pub fn mass_properties(&self, density: f32) -> MassProperties {
        let _ = density;
        MassProperties {
            mass: 0.0,
            center: self.centroid,
            inertia: Mat3::ZERO,
        }
    }

    /// Ray cast in the local frame.
    pub fn cast_ray(&self, ray: &Ray, max_t: f32) -> Option<RayHit> {
        let _ = (ray, max_t);
        None
    }
}
