//! Checksums and snapshots of the world's dynamic state.
//!
//! # Format (version 5)
//! Little-endian throughout, no pointer-sized values:
//!
//! | bytes | field |
//! | --- | --- |
//! | 8 | magic `b"CAROMSNP"` |
//! | 2 | format version ([`FORMAT_VERSION`]) |
//! | 1 | math backend: 0 libm, 1 micromath |
//! | 1 | reserved, 0 |
//! | 4, 4, 4 | capacities `BODIES`, `CONTACTS`, `EVENTS` |
//! | 4 | payload length in bytes |
//! | 8 | FNV-1a 64 of the payload (integrity check) |
//! | … | payload |
//!
//! The payload holds the configuration (its two combine rules last, as `u32` codes in
//! declaration order: 0 geometric mean, 1 average, 2 min, 3 max, 4 multiply; version 4
//! added them; an unknown code is `Corrupt`), the step counter, every body slot
//! (generation, and for a used slot the whole body: shape, pose, velocities, mass,
//! material, flags, sleep timer, broad-phase box) and the contact cache with its
//! warm-start impulses and reuse state (version 5 added the bodies' rotations at each
//! manifold's build, which the solver's lever arms keep). What a body's description determines (mass, inertia, centre of mass) is
//! derived again on restore, exactly as `World::add` derives it, never read; everything
//! else is bounded, so any snapshot `restore` accepts steps to a finite state. Floats are stored as their bit patterns with `-0.0` canonicalised to `+0.0`.
//! Hull shapes are stored as a fingerprint (FNV-1a 64 of the hull's data); `restore`
//! finds the hull among those the target world's bodies already use (or those passed to
//! [`World::restore_with_hulls`]).
//!
//! # Checksum
//! [`World::checksum`] is FNV-1a 64 over a canonical stream: the step counter; for every
//! live body in slot order its slot, generation, pose, velocities, awake flag and sleep
//! timer; for every contact its bodies, normal, per point the feature id and the
//! accumulated normal impulse, and the patch's friction and twist impulses. Free slots
//! never count.

use super::body::{Body, BodyKind, MassSpec, Material};
use super::contact::{Contact, ContactPoint};
use crate::config::{CombineRule, WorldConfig};
use crate::error::{Error, SnapshotError};
use crate::math::{Aabb, Iso, Quat, Vec3};
use crate::shape::{
    Capsule, Compound, ConvexHull, Cuboid, HalfSpace, HeightField, Shape, Sphere, Triangle,
    TriangleMesh,
};
use crate::World;

/// Snapshot format version; bumped whenever the byte layout changes.
pub const FORMAT_VERSION: u16 = 5;

const MAGIC: [u8; 8] = *b"CAROMSNP";
const HEADER_LEN: usize = 8 + 2 + 1 + 1 + 12 + 4 + 8;

/// 0 for libm, 1 for micromath: snapshots from another backend are refused.
#[cfg(not(feature = "micromath"))]
pub const MATH_BACKEND: u8 = 0;
/// 0 for libm, 1 for micromath: snapshots from another backend are refused.
#[cfg(feature = "micromath")]
pub const MATH_BACKEND: u8 = 1;

/// FNV-1a 64-bit offset basis.
const FNV_OFFSET: u64 = 0xcbf2_9ce4_8422_2325;
const FNV_PRIME: u64 = 0x0000_0100_0000_01b3;

/// Where encoded bytes go: a hash or a buffer.
trait Sink {
    fn put(&mut self, bytes: &[u8]);

    fn u8(&mut self, v: u8) {
        self.put(&[v]);
    }
    fn u16(&mut self, v: u16) {
        self.put(&v.to_le_bytes());
    }
    fn u32(&mut self, v: u32) {
        self.put(&v.to_le_bytes());
    }
    fn u64(&mut self, v: u64) {
        self.put(&v.to_le_bytes());
    }
    fn f32(&mut self, v: f32) {
        self.u32(crate::math::scalar::canonical(v).to_bits());
    }
    fn vec3(&mut self, v: Vec3) {
        self.f32(v.x);
        self.f32(v.y);
        self.f32(v.z);
    }
    fn quat(&mut self, q: Quat) {
        self.f32(q.x);
        self.f32(q.y);
        self.f32(q.z);
        self.f32(q.w);
    }
    fn iso(&mut self, i: &Iso) {
        self.vec3(i.position);
        self.quat(i.rotation);
    }
}

/// FNV-1a 64 over everything put into it.
pub(crate) struct Fnv(pub u64);

impl Fnv {
    pub(crate) fn new() -> Fnv {
        Fnv(FNV_OFFSET)
    }
}

impl Sink for Fnv {
    fn put(&mut self, bytes: &[u8]) {
        for b in bytes {
            self.0 = (self.0 ^ *b as u64).wrapping_mul(FNV_PRIME);
        }
    }
}

/// Counts bytes without storing them.
struct Counter(usize);

impl Sink for Counter {
    fn put(&mut self, bytes: &[u8]) {
        self.0 += bytes.len();
    }
}

/// Writes into a slice; `pos` runs past the end when it is too small.
struct Writer<'b> {
    buf: &'b mut [u8],
    pos: usize,
}

impl Sink for Writer<'_> {
    fn put(&mut self, bytes: &[u8]) {
        let end = self.pos + bytes.len();
        if let Some(dst) = self.buf.get_mut(self.pos..end) {
            dst.copy_from_slice(bytes);
        }
        self.pos = end;
    }
}

/// Reads from a slice; every read past the end is `Truncated`.
struct Reader<'b> {
    buf: &'b [u8],
    pos: usize,
}

type R<T> = Result<T, SnapshotError>;

impl<'b> Reader<'b> {
    fn take<const K: usize>(&mut self) -> R<[u8; K]> {
        let s = self
            .buf
            .get(self.pos..self.pos + K)
            .ok_or(SnapshotError::Truncated)?;
        let mut a = [0u8; K];
        a.copy_from_slice(s);
        self.pos += K;
        Ok(a)
    }
    fn u8(&mut self) -> R<u8> {
        Ok(self.take::<1>()?[0])
    }
    fn u16(&mut self) -> R<u16> {
        Ok(u16::from_le_bytes(self.take()?))
    }
    fn u32(&mut self) -> R<u32> {
        Ok(u32::from_le_bytes(self.take()?))
    }
    fn u64(&mut self) -> R<u64> {
        Ok(u64::from_le_bytes(self.take()?))
    }
    fn bool(&mut self) -> R<bool> {
        match self.u8()? {
            0 => Ok(false),
            1 => Ok(true),
            _ => Err(SnapshotError::Corrupt),
        }
    }
    /// A finite float.
    fn f32(&mut self) -> R<f32> {
        let v = f32::from_bits(self.u32()?);
        if v.is_finite() {
            Ok(v)
        } else {
            Err(SnapshotError::Corrupt)
        }
    }
    fn vec3(&mut self) -> R<Vec3> {
        Ok(Vec3::new(self.f32()?, self.f32()?, self.f32()?))
    }
    fn quat(&mut self) -> R<Quat> {
        let q = Quat::from_xyzw(self.f32()?, self.f32()?, self.f32()?, self.f32()?);
        if q.is_unit() {
            Ok(q)
        } else {
            Err(SnapshotError::Corrupt)
        }
    }
    fn iso(&mut self) -> R<Iso> {
        Ok(Iso::new(self.vec3()?, self.quat()?))
    }
}

/// Fingerprint of a hull: FNV-1a 64 over its vertices and face planes.
pub(crate) fn hull_fingerprint(h: &ConvexHull) -> u64 {
    let mut f = Fnv::new();
    for v in h.vertices() {
        f.vec3(*v);
    }
    for i in 0..h.face_count() {
        let (n, d) = h.plane(i);
        f.vec3(n);
        f.f32(d);
    }
    f.0
}

/// Fingerprint of a mesh: FNV-1a 64 over its vertices and index triples.
pub(crate) fn mesh_fingerprint(m: &TriangleMesh<'_>) -> u64 {
    let mut f = Fnv::new();
    f.u32(m.vertices().len() as u32);
    for v in m.vertices() {
        f.vec3(*v);
    }
    for t in m.indices() {
        for i in t {
            f.u32(*i);
        }
    }
    f.0
}

/// Fingerprint of a height field: FNV-1a 64 over its grid size, cell size and heights.
pub(crate) fn field_fingerprint(f: &HeightField<'_>) -> u64 {
    let mut h = Fnv::new();
    h.u32(f.columns());
    h.u32(f.rows());
    h.f32(f.cell_size());
    for &y in f.heights() {
        h.f32(y);
    }
    h.0
}

/// Fingerprint of a compound: FNV-1a 64 over each part's pose and shape as a snapshot
/// stores them (a hull part by its fingerprint).
pub(crate) fn compound_fingerprint(c: &Compound<'_>) -> u64 {
    let mut f = Fnv::new();
    f.u32(c.part_count());
    for p in c.parts() {
        f.iso(&p.pose);
        put_shape(&mut f, &p.shape);
    }
    f.0
}

/// A shape referenced by a fingerprint in snapshots: its tag and fingerprint.
pub(crate) fn shape_reference(shape: &Shape<'_>) -> Option<(u8, u64)> {
    match shape {
        Shape::Hull(h) => Some((TAG_HULL, hull_fingerprint(h))),
        Shape::Mesh(m) => Some((TAG_MESH, mesh_fingerprint(m))),
        Shape::HeightField(f) => Some((TAG_FIELD, field_fingerprint(f))),
        Shape::Compound(c) => Some((TAG_COMPOUND, compound_fingerprint(c))),
        _ => None,
    }
}

/// Shape tags of the referenced shapes.
const TAG_HULL: u8 = 3;
const TAG_MESH: u8 = 6;
const TAG_COMPOUND: u8 = 7;
const TAG_FIELD: u8 = 8;

fn put_shape(s: &mut impl Sink, shape: &Shape<'_>) {
    match shape {
        Shape::Sphere(x) => {
            s.u8(0);
            s.f32(x.radius);
        }
        Shape::Capsule(x) => {
            s.u8(1);
            s.f32(x.half_height);
            s.f32(x.radius);
        }
        Shape::Cuboid(x) => {
            s.u8(2);
            s.vec3(x.half_extents);
        }
        Shape::Hull(h) => {
            s.u8(3);
            s.u64(hull_fingerprint(h));
        }
        Shape::HalfSpace(p) => {
            s.u8(4);
            s.vec3(p.normal);
        }
        Shape::Triangle(t) => {
            s.u8(5);
            for v in t.vertices {
                s.vec3(v);
            }
        }
        Shape::Mesh(m) => {
            s.u8(TAG_MESH);
            s.u64(mesh_fingerprint(m));
        }
        Shape::HeightField(f) => {
            s.u8(TAG_FIELD);
            s.u64(field_fingerprint(f));
        }
        Shape::Compound(c) => {
            s.u8(TAG_COMPOUND);
            s.u64(compound_fingerprint(c));
        }
    }
}

fn get_shape<'a>(r: &mut Reader<'_>, refs: &ShapeLookup<'_, 'a>) -> R<Shape<'a>> {
    let bad = |_| SnapshotError::Corrupt;
    Ok(match r.u8()? {
        0 => Shape::Sphere(Sphere::new(r.f32()?).map_err(bad)?),
        1 => {
            let (h, rad) = (r.f32()?, r.f32()?);
            Shape::Capsule(Capsule::new(h, rad).map_err(bad)?)
        }
        2 => Shape::Cuboid(Cuboid::new(r.vec3()?).map_err(bad)?),
        TAG_HULL => refs(TAG_HULL, r.u64()?).ok_or(SnapshotError::MissingHull)?,
        tag @ (TAG_MESH | TAG_FIELD | TAG_COMPOUND) => {
            refs(tag, r.u64()?).ok_or(SnapshotError::MissingShape)?
        }
        4 => {
            // Stored already normalised: keep the bits (normalising again may change them).
            let normal = r.vec3()?;
            if crate::math::scalar::abs(normal.length_squared() - 1.0) > 1.0e-3 {
                return Err(SnapshotError::Corrupt);
            }
            Shape::HalfSpace(HalfSpace { normal })
        }
        5 => {
            let (a, b, c) = (r.vec3()?, r.vec3()?, r.vec3()?);
            Shape::Triangle(Triangle::new(a, b, c).map_err(bad)?)
        }
        _ => return Err(SnapshotError::Corrupt),
    })
}

/// The configuration's fields in declaration order: (floats, counts, flag, combine
/// rules as their codes).
fn config_fields(c: &WorldConfig) -> ([f32; 21], [u32; 4], bool, [u32; 2]) {
    (
        c.float_fields(),
        [
            c.substeps,
            c.velocity_iterations,
            c.relax_iterations,
            c.position_iterations,
        ],
        c.sleep_enabled,
        [c.friction_combine.code(), c.restitution_combine.code()],
    )
}

fn put_config(s: &mut impl Sink, c: &WorldConfig) {
    let (floats, counts, flag, rules) = config_fields(c);
    for v in floats {
        s.f32(v);
    }
    for n in counts {
        s.u32(n);
    }
    s.u8(flag as u8);
    for code in rules {
        s.u32(code);
    }
}

/// A combine rule read back from its code; an unknown code is `Corrupt`.
fn get_rule(r: &mut Reader<'_>) -> R<CombineRule> {
    CombineRule::from_code(r.u32()?).ok_or(SnapshotError::Corrupt)
}

/// A configuration read back; it must pass [`WorldConfig::validate`].
fn get_config(r: &mut Reader<'_>) -> R<WorldConfig> {
    let mut f = [0.0f32; 21];
    for v in f.iter_mut() {
        *v = r.f32()?;
    }
    let mut n = [0u32; 4];
    for v in n.iter_mut() {
        *v = r.u32()?;
    }
    let [gx, gy, gz, dt, contact_hertz, contact_damping_ratio, max_push_speed, restitution_threshold, slop, projection_factor, max_projection, speculative_margin, aabb_margin, stick_speed, sleep_linear_speed, sleep_angular_speed, sleep_time, ccd_motion_fraction, hit_event_speed, max_linear_speed, max_angular_speed] =
        f;
    let [substeps, velocity_iterations, relax_iterations, position_iterations] = n;
    let c = WorldConfig {
        gravity: Vec3::new(gx, gy, gz),
        dt,
        substeps,
        velocity_iterations,
        relax_iterations,
        contact_hertz,
        contact_damping_ratio,
        max_push_speed,
        position_iterations,
        restitution_threshold,
        slop,
        projection_factor,
        max_projection,
        speculative_margin,
        aabb_margin,
        stick_speed,
        sleep_linear_speed,
        sleep_angular_speed,
        sleep_time,
        sleep_enabled: r.bool()?,
        ccd_motion_fraction,
        hit_event_speed,
        max_linear_speed,
        max_angular_speed,
        friction_combine: get_rule(r)?,
        restitution_combine: get_rule(r)?,
    };
    c.validate().map_err(|_| SnapshotError::Corrupt)?;
    Ok(c)
}

fn put_material(s: &mut impl Sink, m: &Material) {
    s.f32(m.restitution);
    s.f32(m.static_friction);
    s.f32(m.kinetic_friction);
    s.f32(m.rolling_resistance);
    s.f32(m.twist_friction);
}

fn get_material(r: &mut Reader<'_>) -> R<Material> {
    let m = Material {
        restitution: r.f32()?,
        static_friction: r.f32()?,
        kinetic_friction: r.f32()?,
        rolling_resistance: r.f32()?,
        twist_friction: r.f32()?,
    };
    m.validate().map_err(|_| SnapshotError::Corrupt)?;
    Ok(m)
}

fn put_body(s: &mut impl Sink, b: &Body<'_>) {
    put_shape(s, &b.shape);
    s.u8(match b.kind {
        BodyKind::Dynamic => 0,
        BodyKind::Static => 1,
        BodyKind::Kinematic => 2,
    });
    s.iso(b.pose());
    s.vec3(b.linear_velocity);
    s.vec3(b.angular_velocity);
    s.vec3(b.force);
    s.vec3(b.torque);
    match b.mass {
        MassSpec::Density(d) => {
            s.u8(0);
            s.f32(d);
        }
        MassSpec::Mass(m) => {
            s.u8(1);
            s.f32(m);
        }
    }
    put_material(s, &b.material);
    s.f32(b.linear_damping);
    s.f32(b.angular_damping);
    s.u32(b.group);
    s.u32(b.mask);
    s.u8(b.sensor as u8);
    s.u8(b.ccd as u8);
    s.u8(b.awake as u8);
    s.f32(b.sleep_time);
    s.u64(b.user_data);
    s.iso(&b.pose0);
    s.vec3(b.fat.min);
    s.vec3(b.fat.max);
    s.u8(b.moved as u8);
}

/// Largest coordinate (m) a restored body may have. The API accepts positions within
/// ±`MAX_COORDINATE` (10 km) and the step clamps speeds to `max_linear_speed`, so a
/// simulated body passes 1e10 m only after months of falling; squares of such values
/// still fit in `f32`, which a crafted 1e37 would not.
pub const MAX_STATE_MAGNITUDE: f32 = 1.0e10;

/// Largest force or torque (N, N·m) a restored body may carry into its next step.
pub const MAX_STATE_FORCE: f32 = 1.0e30;

/// A body read back. Everything a body's description determines (inverse mass, inertia,
/// centre of mass, the world inertia) is derived again through [`Body::from_desc_anywhere`],
/// exactly as `World::add` derives it, so a snapshot cannot carry a mass or an inertia
/// the API could not produce; the rest is bounded: positions and boxes within
/// [`MAX_STATE_MAGNITUDE`], forces within [`MAX_STATE_FORCE`], finite velocities (the
/// step clamps them to the speed limits before using them), a non-negative sleep timer.
/// Finds a referenced shape by its tag and fingerprint.
type ShapeLookup<'f, 'a> = dyn Fn(u8, u64) -> Option<Shape<'a>> + 'f;

fn get_body<'a>(r: &mut Reader<'_>, refs: &ShapeLookup<'_, 'a>) -> R<Body<'a>> {
    let shape = get_shape(r, refs)?;
    let kind = match r.u8()? {
        0 => BodyKind::Dynamic,
        1 => BodyKind::Static,
        2 => BodyKind::Kinematic,
        _ => return Err(SnapshotError::Corrupt),
    };
    let pose = r.iso()?;
    let linear_velocity = r.vec3()?;
    let angular_velocity = r.vec3()?;
    let force = r.vec3()?;
    let torque = r.vec3()?;
    let mass = match r.u8()? {
        0 => MassSpec::Density(r.f32()?),
        1 => MassSpec::Mass(r.f32()?),
        _ => return Err(SnapshotError::Corrupt),
    };
    let desc = crate::BodyDesc {
        shape,
        kind,
        pose,
        linear_velocity,
        angular_velocity,
        mass,
        material: get_material(r)?,
        linear_damping: r.f32()?,
        angular_damping: r.f32()?,
        group: r.u32()?,
        mask: r.u32()?,
        sensor: r.bool()?,
        ccd: r.bool()?,
        user_data: 0,
    };
    let awake = r.bool()?;
    let sleep_time = r.f32()?;
    let user_data = r.u64()?;
    let pose0 = r.iso()?;
    let fat = Aabb::new(r.vec3()?, r.vec3()?);
    let moved = r.bool()?;
    let mut b = Body::from_desc_anywhere(&crate::BodyDesc { user_data, ..desc })
        .map_err(|_| SnapshotError::Corrupt)?;
    let ok = |c: bool| {
        if c {
            Ok(())
        } else {
            Err(SnapshotError::Corrupt)
        }
    };
    let small = |v: Vec3| v.abs().max_elem() <= MAX_STATE_MAGNITUDE;
    ok(small(pose.position) && small(pose0.position))?;
    // A box holds the body and a step of its motion: allow it twice the position bound.
    let box_small = |v: Vec3| v.abs().max_elem() <= 2.0 * MAX_STATE_MAGNITUDE;
    ok(fat.is_valid() && box_small(fat.min) && box_small(fat.max))?;
    ok(force.abs().max_elem() <= MAX_STATE_FORCE && torque.abs().max_elem() <= MAX_STATE_FORCE)?;
    ok(sleep_time >= 0.0)?;
    // The stored rotation, bit for bit, unless it is off unit length by more than the
    // step's own normalisation leaves (then normalised once: the result is kept next time).
    b.place(Iso::new(pose.position, settle_rotation(pose.rotation)));
    b.update_inertia();
    b.pose0 = Iso::new(pose0.position, settle_rotation(pose0.rotation));
    b.fat = fat;
    b.moved = moved;
    b.relist = true;
    b.sleep_time = sleep_time;
    b.awake = awake && kind != BodyKind::Static;
    if kind == BodyKind::Dynamic {
        b.force = force;
        b.torque = torque;
    }
    Ok(b)
}

/// Largest `| |q|² − 1 |` of a rotation kept as stored; `Quat::normalize` leaves less.
const SETTLED_ROTATION: f32 = 1.0e-6;

/// `q` when it is unit to within [`SETTLED_ROTATION`], else `q` normalised.
fn settle_rotation(q: Quat) -> Quat {
    if crate::math::scalar::abs(q.length_squared() - 1.0) <= SETTLED_ROTATION {
        q
    } else {
        q.normalize()
    }
}

fn put_point(s: &mut impl Sink, p: &ContactPoint) {
    s.u64(p.id);
    s.vec3(p.local_a);
    s.vec3(p.local_b);
    s.f32(p.separation);
    s.f32(p.normal_impulse);
}

/// A contact point read back: finite, anchors within [`MAX_STATE_MAGNITUDE`], a
/// non-negative normal impulse. (The solver bounds what it warm-starts with, so no finite
/// impulse can push a body to a non-finite speed.)
fn get_point(r: &mut Reader<'_>) -> R<ContactPoint> {
    let p = ContactPoint {
        id: r.u64()?,
        local_a: r.vec3()?,
        local_b: r.vec3()?,
        separation: r.f32()?,
        normal_impulse: r.f32()?,
        ..ContactPoint::default()
    };
    let small = |v: Vec3| v.abs().max_elem() <= MAX_STATE_MAGNITUDE;
    let ok = small(p.local_a)
        && small(p.local_b)
        && crate::math::scalar::abs(p.separation) <= MAX_STATE_MAGNITUDE
        && p.normal_impulse >= 0.0;
    if ok {
        Ok(p)
    } else {
        Err(SnapshotError::Corrupt)
    }
}

fn put_contact(s: &mut impl Sink, c: &Contact) {
    s.u32(c.a);
    if c.sub == 0 {
        s.u32(c.b);
    } else {
        // A part contact or record (mid phase): B's slot flagged, then the part key. A
        // world of convex bodies writes the same bytes as before parts existed.
        s.u32(c.b | SUB_FLAG);
        s.u32(c.sub);
    }
    s.vec3(c.normal);
    s.vec3(c.normal_local);
    s.u8(c.len);
    for p in c.points() {
        put_point(s, p);
    }
    put_material(s, &c.material);
    s.u8(c.sensor as u8);
    s.u8(c.touching as u8);
    s.iso(&c.built_pose);
    s.quat(c.built_rot_a);
    s.quat(c.built_rot_b);
    s.f32(c.built_margin);
    s.vec3(c.friction_impulse);
    s.f32(c.twist_impulse);
    s.u8(c.sticking as u8);
}

/// A unit vector, or zero (a contact that never had points).
fn unit_or_zero(v: Vec3) -> bool {
    v == Vec3::ZERO || crate::math::scalar::abs(v.length_squared() - 1.0) <= 1.0e-3
}

/// Set in a contact's B slot when a part key follows.
const SUB_FLAG: u32 = 1 << 31;

fn get_contact(r: &mut Reader<'_>) -> R<Contact> {
    let (a, b) = (r.u32()?, r.u32()?);
    let (b, sub) = if b & SUB_FLAG != 0 {
        let sub = r.u32()?;
        if sub == 0 {
            return Err(SnapshotError::Corrupt);
        }
        (b & !SUB_FLAG, sub)
    } else {
        (b, 0)
    };
    let normal = r.vec3()?;
    let normal_local = r.vec3()?;
    let len = r.u8()?;
    if len as usize > 4 || a >= b || !unit_or_zero(normal) || !unit_or_zero(normal_local) {
        return Err(SnapshotError::Corrupt);
    }
    let mut points = [ContactPoint::default(); 4];
    for p in points.iter_mut().take(len as usize) {
        *p = get_point(r)?;
    }
    let material = get_material(r)?;
    let sensor = r.bool()?;
    let touching = r.bool()?;
    let built_pose = r.iso()?;
    let built_rot_a = r.quat()?;
    let built_rot_b = r.quat()?;
    let built_margin = r.f32()?;
    let friction_impulse = r.vec3()?;
    let twist_impulse = r.f32()?;
    let sticking = r.bool()?;
    if built_pose.position.abs().max_elem() > MAX_STATE_MAGNITUDE
        || built_margin > MAX_STATE_MAGNITUDE
        || twist_impulse.abs() > MAX_STATE_FORCE
        || friction_impulse.abs().max_elem() > MAX_STATE_FORCE
    {
        return Err(SnapshotError::Corrupt);
    }
    Ok(Contact {
        a,
        b,
        sub,
        normal,
        normal_local,
        len,
        points,
        material,
        sensor,
        touching,
        built_pose,
        built_rot_a,
        built_rot_b,
        built_margin: if built_margin < 0.0 {
            -1.0
        } else {
            built_margin
        },
        hit_due: false,
        new_parts: 0,
        friction_impulse,
        twist_impulse,
        sticking,
        sat_cache: crate::collide::PairCache::default(),
        apart_gap: 0.0,
    })
}

impl<'a, const BODIES: usize, const CONTACTS: usize, const EVENTS: usize>
    World<'a, BODIES, CONTACTS, EVENTS>
{
    /// A 64-bit checksum of the canonical dynamic state (see the module docs of
    /// `dynamics::snapshot`): equal on two peers exactly when their simulations agree.
    pub fn checksum(&self) -> u64 {
        let mut f = Fnv::new();
        f.u64(self.step_count);
        for (i, b) in self.bodies.iter() {
            f.u32(i as u32);
            f.u32(self.bodies.generation(i));
            hash_body_motion(&mut f, b);
        }
        for c in self.contacts.iter() {
            f.u32(c.a);
            f.u32(c.b);
            f.vec3(c.normal);
            f.u8(c.len);
            for p in c.points.iter().take(c.len as usize) {
                f.u64(p.id);
                f.f32(p.normal_impulse);
            }
            f.vec3(c.friction_impulse);
            f.f32(c.twist_impulse);
        }
        f.0
    }

    /// The checksum of one body's motion state (pose, velocities, sleep), to find the first
    /// body two peers disagree on.
    pub fn body_checksum(&self, h: crate::BodyHandle) -> Result<u64, Error> {
        let b = self.bodies.get(h).ok_or(Error::StaleHandle)?;
        let mut f = Fnv::new();
        hash_body_motion(&mut f, b);
        Ok(f.0)
    }

    fn put_payload(&self, s: &mut impl Sink) {
        put_config(s, &self.config);
        s.u64(self.step_count);
        s.u32(self.bodies.touched() as u32);
        for i in 0..self.bodies.touched() {
            s.u32(self.bodies.generation(i));
            match self.bodies.at(i) {
                Some(b) => {
                    s.u8(1);
                    put_body(s, b);
                }
                None => s.u8(0),
            }
        }
        s.u32(self.contacts.len() as u32);
        for c in self.contacts.iter() {
            put_contact(s, c);
        }
    }

    /// Bytes [`World::snapshot`] needs for the current state.
    pub fn snapshot_len(&self) -> usize {
        let mut c = Counter(0);
        self.put_payload(&mut c);
        HEADER_LEN + c.0
    }

    /// The most bytes a snapshot of this world type can need (every slot used by the
    /// largest shape record, the contact pool full): size a static buffer with it.
    pub fn max_snapshot_len() -> usize {
        let mut body = Counter(0);
        if let Ok(tri) = Shape::triangle(Vec3::ZERO, Vec3::X, Vec3::Y) {
            if let Ok(b) = Body::from_desc(&crate::BodyDesc::fixed(tri)) {
                put_body(&mut body, &b);
            }
        }
        let mut contact = Counter(0);
        put_contact(
            &mut contact,
            &Contact {
                len: 4,
                ..Contact::default()
            },
        );
        let mut config = Counter(0);
        put_config(&mut config, &WorldConfig::DEFAULT);
        HEADER_LEN
            + config.0
            + 8 // step counter
            + 4 + BODIES * (4 + 1 + body.0) // slots: generation, used flag, body
            + 4 + CONTACTS * contact.0
    }

    /// Write the dynamic state into `buf`; returns the bytes written. Fails with
    /// `BufferTooSmall(needed)` (nothing meaningful written) when `buf` is too short.
    ///
    /// # Examples
    ///
    /// ```
    /// use carom::{BodyDesc, Shape, Vec3, World};
    ///
    /// # fn main() -> Result<(), carom::Error> {
    /// type W = World<'static, 4, 8>;
    /// let mut world = W::new();
    /// world.add(BodyDesc::dynamic(Shape::sphere(0.5)?).position(Vec3::new(0.0, 5.0, 0.0)))?;
    /// world.step();
    ///
    /// // Save, run ahead, roll back: the world continues bit-identically.
    /// let mut buf = vec![0u8; W::max_snapshot_len()];
    /// let n = world.snapshot(&mut buf)?;
    /// let saved = world.checksum();
    /// for _ in 0..10 {
    ///     world.step();
    /// }
    /// world.restore(&buf[..n])?;
    /// assert_eq!(world.checksum(), saved);
    ///
    /// // A snapshot restores only into the same world type and build.
    /// let mut other: World<'static, 8, 8> = World::new();
    /// assert!(other.restore(&buf[..n]).is_err());
    /// # Ok(())
    /// # }
    /// ```
    pub fn snapshot(&self, buf: &mut [u8]) -> Result<usize, Error> {
        let needed = self.snapshot_len();
        if buf.len() < needed {
            return Err(Error::BufferTooSmall(needed as u32));
        }
        let (head, body) = buf.split_at_mut(HEADER_LEN);
        let mut w = Writer { buf: body, pos: 0 };
        self.put_payload(&mut w);
        let payload_len = w.pos;
        let mut f = Fnv::new();
        f.put(body.get(..payload_len).unwrap_or(&[]));
        let mut hw = Writer { buf: head, pos: 0 };
        write_header::<BODIES, CONTACTS, EVENTS>(&mut hw, payload_len as u32, f.0);
        Ok(HEADER_LEN + payload_len)
    }

    /// Replace the dynamic state with a snapshot's. Hull shapes are looked up among the
    /// hulls this world's bodies use now. On any error the world is unchanged.
    pub fn restore(&mut self, buf: &[u8]) -> Result<(), Error> {
        self.restore_with_hulls(buf, &[])
    }

    /// [`World::restore`], also looking hull shapes up in `hulls`.
    pub fn restore_with_hulls(&mut self, buf: &[u8], hulls: &'a [ConvexHull]) -> Result<(), Error> {
        let payload = check_header::<BODIES, CONTACTS, EVENTS>(buf).map_err(Error::Snapshot)?;
        // The shapes the world already references, plus the caller's hulls.
        let current = self.clone_shape_refs();
        let lookup = |tag: u8, fp: u64| -> Option<Shape<'a>> {
            let known = current.iter().flatten().copied();
            let given = hulls.iter().map(Shape::Hull);
            known
                .chain(given)
                .find(|s| shape_reference(s) == Some((tag, fp)))
        };
        // Pass 1: validate everything without touching the world.
        self.read_payload(payload, &lookup, false)
            .map_err(Error::Snapshot)?;
        // Pass 2: the same reads, now applied. Cannot fail after pass 1.
        self.read_payload(payload, &lookup, true)
            .map_err(Error::Snapshot)?;
        self.events.clear();
        self.pairs.clear();
        self.quiet = false;
        Ok(())
    }

    /// Up to 64 distinct referenced shapes (hulls, meshes, compounds) of the bodies
    /// (enough for restore lookups).
    fn clone_shape_refs(&self) -> [Option<Shape<'a>>; 64] {
        let mut out: [Option<Shape<'a>>; 64] = [None; 64];
        let mut n = 0;
        let same = |x: &Shape<'a>, y: &Shape<'a>| match (x, y) {
            (Shape::Hull(p), Shape::Hull(q)) => core::ptr::eq(*p, *q),
            (Shape::Mesh(p), Shape::Mesh(q)) => core::ptr::eq(*p, *q),
            (Shape::HeightField(p), Shape::HeightField(q)) => core::ptr::eq(*p, *q),
            (Shape::Compound(p), Shape::Compound(q)) => core::ptr::eq(*p, *q),
            _ => false,
        };
        for (_, b) in self.bodies.iter() {
            if matches!(
                b.shape,
                Shape::Hull(_) | Shape::Mesh(_) | Shape::HeightField(_) | Shape::Compound(_)
            ) && !out.iter().flatten().any(|x| same(x, &b.shape))
            {
                if let Some(slot) = out.get_mut(n) {
                    *slot = Some(b.shape);
                    n += 1;
                }
            }
        }
        out
    }

    fn read_payload(&mut self, payload: &[u8], refs: &ShapeLookup<'_, 'a>, apply: bool) -> R<()> {
        let mut r = Reader {
            buf: payload,
            pos: 0,
        };
        let config = get_config(&mut r)?;
        let step_count = r.u64()?;
        let high = r.u32()? as usize;
        if high > BODIES {
            return Err(SnapshotError::Corrupt);
        }
        let mut live = [false; BODIES];
        // Bodies with parts (mesh, compound): their pairs are records and part contacts.
        let mut composite = [false; BODIES];
        if apply {
            self.bodies.reset();
            self.config = config;
            self.step_count = step_count;
        }
        for (i, (is_live, parts)) in live
            .iter_mut()
            .zip(composite.iter_mut())
            .enumerate()
            .take(high)
        {
            let generation = r.u32()?;
            let body = if r.bool()? {
                *is_live = true;
                let body = get_body(&mut r, refs)?;
                *parts = !body.shape.is_convex();
                Some(body)
            } else {
                None
            };
            if apply {
                self.bodies.set_slot(i, generation, body);
            }
        }
        if apply {
            // The broad-phase tree is derived: the next step builds it again.
            self.broad.invalidate();
        }
        let n_contacts = r.u32()? as usize;
        if n_contacts > CONTACTS {
            return Err(SnapshotError::Capacity);
        }
        if apply {
            self.contacts.clear();
        }
        let mut last_key = None;
        // A pair with parts whose record has not come yet.
        let mut open_pair: Option<u64> = None;
        for _ in 0..n_contacts {
            let c = get_contact(&mut r)?;
            let alive = |s: u32| live.get(s as usize).copied().unwrap_or(false);
            let parts = |s: u32| composite.get(s as usize).copied().unwrap_or(false);
            if !alive(c.a) || !alive(c.b) || last_key.is_some_and(|k| k >= c.full_key()) {
                return Err(SnapshotError::Corrupt);
            }
            // Convex pairs have one contact with key 0; a pair with parts has part
            // contacts (without points past its shapes' parts) and then its record.
            let with_parts = parts(c.a) || parts(c.b);
            let open_other = open_pair.is_some_and(|k| k != c.key());
            if (c.sub == 0) == with_parts || open_other || (c.is_record() && c.len != 0) {
                return Err(SnapshotError::Corrupt);
            }
            open_pair = if c.is_record() {
                None
            } else {
                with_parts.then_some(c.key())
            };
            last_key = Some(c.full_key());
            if apply && self.contacts.push(c).is_err() {
                return Err(SnapshotError::Capacity);
            }
        }
        if r.pos != payload.len() || open_pair.is_some() {
            return Err(SnapshotError::Corrupt);
        }
        Ok(())
    }
}

/// A stage of the step, for [`StepTrace`] and [`World::step_observed`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stage {
    /// 1–3: movement bounds, enlarged boxes and new candidate pairs.
    BroadPhase = 0,
    /// 4–6: manifolds and the contact cache.
    NarrowPhase = 1,
    /// 7: the soft step (velocities, contacts, positions, restitution).
    Solve = 2,
    /// 8: continuous collision.
    Continuous = 3,
    /// 9: projection.
    Projection = 4,
    /// 10: sleep.
    Sleep = 5,
}

impl Stage {
    /// Number of stages traced.
    pub const COUNT: usize = 6;
    /// All stages, in step order.
    pub const ALL: [Stage; Stage::COUNT] = [
        Stage::BroadPhase,
        Stage::NarrowPhase,
        Stage::Solve,
        Stage::Continuous,
        Stage::Projection,
        Stage::Sleep,
    ];
}

/// Digests of the world state after each stage of one step (folded over sub-steps),
/// filled by [`World::step_traced`]. The first stage whose digest differs between two
/// peers is where they diverged; [`World::body_checksum`] then names the body.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct StepTrace {
    /// One digest per [`Stage`], indexed by `stage as usize`.
    pub digests: [u64; Stage::COUNT],
}

impl StepTrace {
    /// The first stage whose digest differs from `other`'s, if any.
    pub fn first_difference(&self, other: &StepTrace) -> Option<Stage> {
        Stage::ALL
            .iter()
            .copied()
            .find(|s| self.digests.get(*s as usize) != other.digests.get(*s as usize))
    }
}

/// What hears of a step's stages as they end: the digests of [`World::step_traced`] and
/// the callback of [`World::step_observed`] (neither, for [`World::step`]).
pub(crate) struct Hooks<'t> {
    pub trace: Option<&'t mut StepTrace>,
    pub on_stage: Option<&'t mut dyn FnMut(Stage)>,
}

impl Hooks<'_> {
    /// No digest, no callback.
    pub const NONE: Hooks<'static> = Hooks {
        trace: None,
        on_stage: None,
    };
}

impl<'a, const BODIES: usize, const CONTACTS: usize, const EVENTS: usize>
    World<'a, BODIES, CONTACTS, EVENTS>
{
    /// `stage` has ended: fold the state into the trace, if tracing, then tell the
    /// callback, if any.
    pub(crate) fn stage_done(&self, hooks: &mut Hooks<'_>, stage: Stage) {
        self.trace(hooks.trace.as_deref_mut(), stage);
        if let Some(f) = hooks.on_stage.as_deref_mut() {
            f(stage);
        }
    }

    /// Fold the state after `stage` into `trace`, if tracing.
    fn trace(&self, trace: Option<&mut StepTrace>, stage: Stage) {
        let Some(t) = trace else {
            return;
        };
        let mut f = Fnv::new();
        f.u64(t.digests.get(stage as usize).copied().unwrap_or(0));
        f.u64(self.checksum());
        if stage == Stage::BroadPhase {
            for (a, b) in self.pairs.iter() {
                f.u32(*a);
                f.u32(*b);
            }
        }
        if let Some(d) = t.digests.get_mut(stage as usize) {
            *d = f.0;
        }
    }
}

/// The motion state of a body, hashed.
fn hash_body_motion(f: &mut Fnv, b: &Body<'_>) {
    f.iso(b.pose());
    f.vec3(b.linear_velocity);
    f.vec3(b.angular_velocity);
    f.u8(b.awake as u8);
    f.f32(b.sleep_time);
}

/// Check the header; returns the payload.
fn check_header<const B: usize, const C: usize, const E: usize>(buf: &[u8]) -> R<&[u8]> {
    let mut r = Reader { buf, pos: 0 };
    if r.take::<8>()? != MAGIC {
        return Err(SnapshotError::BadMagic);
    }
    if r.u16()? != FORMAT_VERSION {
        return Err(SnapshotError::Version);
    }
    if r.u8()? != MATH_BACKEND {
        return Err(SnapshotError::MathBackend);
    }
    let _reserved = r.u8()?;
    if r.u32()? as usize != B || r.u32()? as usize != C || r.u32()? as usize != E {
        return Err(SnapshotError::Capacity);
    }
    let len = r.u32()? as usize;
    let sum = r.u64()?;
    let end = HEADER_LEN
        .checked_add(len)
        .ok_or(SnapshotError::Truncated)?;
    let payload = buf.get(HEADER_LEN..end).ok_or(SnapshotError::Truncated)?;
    let mut f = Fnv::new();
    f.put(payload);
    if f.0 != sum {
        return Err(SnapshotError::Checksum);
    }
    Ok(payload)
}

/// `serde` support for the same state as [`World::snapshot`]: a `World` serialises as the
/// snapshot's bytes (a sequence of `u8`, streamed: nothing is allocated), and
/// [`RestoreSeed`] deserialises such bytes into an existing world through
/// [`World::restore_with_hulls`], with the same checks and errors.
#[cfg(feature = "serde")]
mod serde_support {
    use super::{write_header, Fnv, Sink, HEADER_LEN};
    use crate::shape::ConvexHull;
    use crate::World;
    use serde::de::{DeserializeSeed, Error as _, SeqAccess, Visitor};
    use serde::ser::{SerializeSeq, Serializer};

    /// Feeds bytes to a `SerializeSeq`, keeping the first error.
    struct SeqSink<S: SerializeSeq> {
        seq: S,
        err: Option<S::Error>,
    }

    impl<S: SerializeSeq> Sink for SeqSink<S> {
        fn put(&mut self, bytes: &[u8]) {
            for b in bytes {
                if self.err.is_none() {
                    if let Err(e) = self.seq.serialize_element(b) {
                        self.err = Some(e);
                    }
                }
            }
        }
    }

    impl<const B: usize, const C: usize, const E: usize> serde::Serialize for World<'_, B, C, E> {
        fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
            let len = self.snapshot_len();
            let mut hash = Fnv::new();
            self.put_payload(&mut hash);
            let seq = serializer.serialize_seq(Some(len))?;
            let mut sink = SeqSink { seq, err: None };
            write_header::<B, C, E>(&mut sink, (len - HEADER_LEN) as u32, hash.0);
            self.put_payload(&mut sink);
            match sink.err {
                Some(e) => Err(e),
                None => sink.seq.end(),
            }
        }
    }

    /// Deserialises snapshot bytes into `world`. Formats that hand out byte slices restore
    /// straight from them; sequences are first gathered into `scratch` (size it with
    /// [`World::max_snapshot_len`]).
    pub struct RestoreSeed<'w, 'a, const B: usize, const C: usize, const E: usize> {
        /// The world to restore into (unchanged on error).
        pub world: &'w mut World<'a, B, C, E>,
        /// Hulls to look hull shapes up in, besides those the world already uses.
        pub hulls: &'a [ConvexHull],
        /// Room for the bytes when the format yields them one by one.
        pub scratch: &'w mut [u8],
    }

    impl<'de, const B: usize, const C: usize, const E: usize> DeserializeSeed<'de>
        for RestoreSeed<'_, '_, B, C, E>
    {
        type Value = ();

        fn deserialize<D: serde::Deserializer<'de>>(self, d: D) -> Result<(), D::Error> {
            d.deserialize_bytes(self)
        }
    }

    impl<'de, const B: usize, const C: usize, const E: usize> Visitor<'de>
        for RestoreSeed<'_, '_, B, C, E>
    {
        type Value = ();

        fn expecting(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
            f.write_str("carom snapshot bytes")
        }

        fn visit_bytes<Er: serde::de::Error>(self, v: &[u8]) -> Result<(), Er> {
            self.world
                .restore_with_hulls(v, self.hulls)
                .map_err(Er::custom)
        }

        fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<(), A::Error> {
            let mut n = 0usize;
            while let Some(b) = seq.next_element::<u8>()? {
                let slot = self
                    .scratch
                    .get_mut(n)
                    .ok_or_else(|| A::Error::custom("snapshot larger than the scratch buffer"))?;
                *slot = b;
                n += 1;
            }
            let bytes = self.scratch.get(..n).unwrap_or(&[]);
            self.world
                .restore_with_hulls(bytes, self.hulls)
                .map_err(A::Error::custom)
        }
    }
}

#[cfg(feature = "serde")]
pub use serde_support::RestoreSeed;

/// Write the snapshot header for a payload of `len` bytes hashing to `hash`.
fn write_header<const B: usize, const C: usize, const E: usize>(
    s: &mut impl Sink,
    len: u32,
    hash: u64,
) {
    s.put(&MAGIC);
    s.u16(FORMAT_VERSION);
    s.u8(MATH_BACKEND);
    s.u8(0);
    s.u32(B as u32);
    s.u32(C as u32);
    s.u32(E as u32);
    s.u32(len);
    s.u64(hash);
}
