//! Properties of the world's public doors under arbitrary scenes and call sequences
//! ([`world_ops_properties`]), and of snapshot decoding under arbitrary and mutated
//! buffers ([`snapshot_bytes_properties`], [`snapshot_edit_properties`]).
//!
//! Inputs are plain data with raw `f32`s (NaN, ±∞, huge, negative and subnormal values
//! allowed), so the validation paths run as often as the simulation. Everything runs on
//! [`OpsWorld`], a small fixed world type, with bounded work per call: at most
//! [`MAX_OPS`] operations and [`MAX_STEPS`] steps.
//!
//! The oracle for handles is a model of the body pool kept beside the world
//! ([`PoolModel`]): a new body takes the lowest free slot with that slot's generation, and
//! removing a body bumps its slot's generation (`dynamics/pool.rs`). Whatever the world
//! does (steps, snapshots, restores of its own snapshots), the handles it hands out must
//! follow that model, so a handle once removed never names a body again.

use super::{check, Violation};
use crate::config::WorldConfig;
use crate::dynamics::body::{BodyDesc, BodyKind, MassSpec, Material};
use crate::dynamics::events::{Event, StepReport};
use crate::dynamics::query::QueryFilter;
use crate::dynamics::snapshot::{FORMAT_VERSION, MATH_BACKEND};
use crate::dynamics::BodyHandle;
use crate::error::Error;
use crate::math::{scalar, Iso, Quat, Vec3};
use crate::shape::{ConvexHull, Ray, Shape};
use crate::World;

/// Body capacity of [`OpsWorld`].
pub const OPS_BODIES: usize = 16;
/// Contact capacity of [`OpsWorld`].
pub const OPS_CONTACTS: usize = 64;
/// Event capacity of [`OpsWorld`].
pub const OPS_EVENTS: usize = 32;

/// The world type every property here runs on: small, so a fuzz input stays fast and a
/// full pool is reached often.
pub type OpsWorld<'a> = World<'a, OPS_BODIES, OPS_CONTACTS, OPS_EVENTS>;

/// Operations of one call to [`world_ops_properties`] that are run; later ones are
/// ignored (bounded work per fuzz input).
pub const MAX_OPS: usize = 256;
/// Most steps one [`WorldOp::Step`] takes.
pub const MAX_STEPS_PER_OP: u32 = 8;
/// Most steps one call to [`world_ops_properties`] takes in total.
pub const MAX_STEPS: u32 = 64;
/// Hulls one call can build for [`WorldOp::Add`] (they must outlive the world, so they
/// are built up-front): the `k`-th hull `Add` uses table entry `k % MAX_OP_HULLS`.
pub const MAX_OP_HULLS: usize = 4;
/// Points of a hull in a [`ShapeSpec::Hull`].
pub const MAX_HULL_POINTS: usize = 8;
/// Bytes of the stack buffers snapshots are written to; `tests/world_fuzz.rs` checks that
/// `OpsWorld::max_snapshot_len()` fits.
pub const SNAPSHOT_BUFFER: usize = 32 * 1024;
/// Steps the fixture of the snapshot properties may take before it is snapshotted.
pub const FIXTURE_MAX_STEPS: u32 = 32;
/// Edits of one call to [`snapshot_edit_properties`] that are applied.
pub const MAX_EDITS: usize = 16;
/// Steps a world restored from a fuzzed buffer takes to show that its state is sound.
pub const RESTORED_STEPS: u32 = 4;

/// The working range: the largest magnitude of any accepted input (m, m/s, rad/s, N,
/// N·s, N·m, kg, kg/m³, 1/s, m/s², friction) for which the world must keep its state
/// finite. Beyond it `f32` products such as `m v²`, `r × j` or `|v|²` overflow; only
/// "no panic, errors change nothing, handles follow the model" is checked there.
pub const WORLD_WORKING_RANGE: f32 = 1.0e4;
/// Smallest extent (m) of a dynamic body's shape in the working range.
pub const WORLD_MIN_EXTENT: f32 = 1.0e-2;
/// Smallest mass (kg) of a dynamic body in the working range.
pub const WORLD_MIN_MASS: f32 = 1.0e-3;
/// Largest time step (s) in the working range.
pub const WORLD_MAX_DT: f32 = 1.0;

/// True for a position the API accepts: finite, within ±[`crate::MAX_COORDINATE`].
fn position_ok(v: Vec3) -> bool {
    v.is_finite() && v.abs().max_elem() <= crate::MAX_COORDINATE
}

/// Violations these properties report today that are known, unfixed findings in the
/// engine, each with an ignored regression test in `tests/world_fuzz.rs`. The seeded
/// tests and the fuzz targets count an input that hits one instead of failing, so they
/// keep finding new problems. Empty: every finding so far is fixed (`finding_*` tests).
pub const KNOWN_FINDINGS: [&str; 0] = [];

/// True when `v` is one of the [`KNOWN_FINDINGS`].
pub fn is_known_finding(v: &Violation) -> bool {
    KNOWN_FINDINGS.contains(&v.0)
}

/// How far a hit normal's length may be from 1: a few `f32` roundings of a normalisation.
const NORMAL_SLACK: f32 = 1.0e-3;

/// The snapshot header as documented in `dynamics::snapshot` (the header layout is the same in every version so far), parsed here
/// independently of the decoder: magic (8), version (2), backend (1), reserved (1),
/// capacities (3 × 4), payload length (4), FNV-1a 64 of the payload (8).
const MAGIC: [u8; 8] = *b"CAROMSNP";
const HEADER_LEN: usize = 36;
const RESERVED_AT: usize = 11;
const LEN_AT: usize = 24;
const SUM_AT: usize = 28;

// ------------------------------------------------------------------------------------
// Inputs
// ------------------------------------------------------------------------------------

/// A shape as plain data, built through the public constructors (which may refuse it).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ShapeSpec {
    /// `Shape::sphere(radius)`.
    Sphere {
        /// Radius (m).
        radius: f32,
    },
    /// `Shape::capsule(half_height, radius)`.
    Capsule {
        /// Half the core segment's length (m).
        half_height: f32,
        /// Radius (m).
        radius: f32,
    },
    /// `Shape::cuboid(half_extents)`.
    Cuboid {
        /// Half-extents (m).
        half_extents: Vec3,
    },
    /// `ConvexHull::new(&points[..count])` (`count` clamped to [`MAX_HULL_POINTS`]).
    Hull {
        /// The point cloud (m).
        points: [Vec3; MAX_HULL_POINTS],
        /// How many of `points` are used.
        count: u8,
    },
    /// `Shape::half_space(normal)`.
    HalfSpace {
        /// Plane normal (any length).
        normal: Vec3,
    },
    /// `Shape::triangle(a, b, c)`.
    Triangle {
        /// Corners (m).
        corners: [Vec3; 3],
    },
}

impl ShapeSpec {
    /// The points of a hull spec, `None` for other shapes.
    pub fn hull_points(&self) -> Option<&[Vec3]> {
        match self {
            ShapeSpec::Hull { points, count } => {
                let n = usize::min(*count as usize, MAX_HULL_POINTS);
                points.get(..n)
            }
            _ => None,
        }
    }

    /// The shape of a non-hull spec through its constructor; `None` for a hull spec.
    fn simple(&self) -> Option<Result<Shape<'static>, Error>> {
        Some(match *self {
            ShapeSpec::Sphere { radius } => Shape::sphere(radius),
            ShapeSpec::Capsule {
                half_height,
                radius,
            } => Shape::capsule(half_height, radius),
            ShapeSpec::Cuboid { half_extents } => Shape::cuboid(half_extents),
            ShapeSpec::HalfSpace { normal } => Shape::half_space(normal),
            ShapeSpec::Triangle { corners: [a, b, c] } => Shape::triangle(a, b, c),
            ShapeSpec::Hull { .. } => return None,
        })
    }
}

/// A body description as plain data ([`BodyDesc`] without the borrowed shape).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BodySpec {
    /// Dynamic, static or kinematic.
    pub kind: BodyKind,
    /// The shape.
    pub shape: ShapeSpec,
    /// Position (m).
    pub position: Vec3,
    /// Rotation, raw components (not normalised here).
    pub rotation: Quat,
    /// Linear velocity (m/s).
    pub linear_velocity: Vec3,
    /// Angular velocity (rad/s).
    pub angular_velocity: Vec3,
    /// Mass or density.
    pub mass: MassSpec,
    /// Material.
    pub material: Material,
    /// Linear damping (1/s).
    pub linear_damping: f32,
    /// Angular damping (1/s).
    pub angular_damping: f32,
    /// Collision group bits.
    pub group: u32,
    /// Collision mask bits.
    pub mask: u32,
    /// Sensor flag.
    pub sensor: bool,
    /// Continuous collision flag.
    pub ccd: bool,
    /// User data.
    pub user_data: u64,
}

impl BodySpec {
    /// The description for `shape`.
    fn desc<'a>(&self, shape: Shape<'a>) -> BodyDesc<'a> {
        let base = match self.kind {
            BodyKind::Dynamic => BodyDesc::dynamic(shape),
            BodyKind::Static => BodyDesc::fixed(shape),
            BodyKind::Kinematic => BodyDesc::kinematic(shape),
        };
        let mut d = base
            .position(self.position)
            .rotation(self.rotation)
            .velocity(self.linear_velocity)
            .angular_velocity(self.angular_velocity)
            .material(self.material)
            .damping(self.linear_damping, self.angular_damping)
            .filter(self.group, self.mask)
            .sensor(self.sensor)
            .ccd(self.ccd)
            .user_data(self.user_data);
        d.mass = self.mass;
        d
    }

    /// True when an input the world must refuse is plainly bad: a non-finite number, a
    /// rotation that is not unit, a material out of range, negative damping, a bad mass
    /// for a dynamic body, or a static-only shape on a dynamic body. (A `false` does not
    /// promise success: mass properties may still overflow.)
    fn plainly_bad(&self, shape: &Shape<'_>) -> bool {
        let mass_good = match self.mass {
            MassSpec::Density(x) | MassSpec::Mass(x) => x.is_finite() && x > 0.0,
        };
        let non_negative = |x: f32| x.is_finite() && x >= 0.0;
        let good = position_ok(self.position)
            && self.rotation.is_unit()
            && self.linear_velocity.is_finite()
            && self.angular_velocity.is_finite()
            && !material_bad(&self.material)
            && non_negative(self.linear_damping)
            && non_negative(self.angular_damping)
            && (self.kind != BodyKind::Dynamic || (mass_good && !shape.is_static_only()));
        !good
    }
}

/// Which body an operation addresses.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HandleRef {
    /// The `k`-th handle [`WorldOp::Add`] returned so far, `k` taken modulo their number
    /// (removed bodies included, so stale handles come up often). With none yet, a
    /// handle no world ever gave out.
    Created(u8),
    /// Any handle, usually garbage.
    Raw(BodyHandle),
}

/// One call on the world's public API, with raw values.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum WorldOp {
    /// `World::add`.
    Add(BodySpec),
    /// `World::remove`.
    Remove(HandleRef),
    /// `World::set_pose` with raw position and rotation.
    SetPose(HandleRef, Vec3, Quat),
    /// `World::set_linear_velocity`.
    SetVelocity(HandleRef, Vec3),
    /// `World::set_angular_velocity`.
    SetAngularVelocity(HandleRef, Vec3),
    /// `World::apply_force`.
    ApplyForce(HandleRef, Vec3),
    /// `World::apply_torque`.
    ApplyTorque(HandleRef, Vec3),
    /// `World::apply_impulse_at(handle, impulse, point)`.
    ApplyImpulseAt(HandleRef, Vec3, Vec3),
    /// `World::wake`.
    Wake(HandleRef),
    /// `World::sleep`.
    Sleep(HandleRef),
    /// `World::set_material`.
    SetMaterial(HandleRef, Material),
    /// `World::set_config` with raw values.
    SetConfig(WorldConfig),
    /// `World::step`, `n` times (at most [`MAX_STEPS_PER_OP`], and [`MAX_STEPS`] per run).
    Step(u8),
    /// `World::cast_ray` and `World::cast_ray_all` with a raw ray (not built by
    /// `Ray::new`, so the direction may be anything).
    CastRay {
        /// Ray origin (m).
        origin: Vec3,
        /// Ray direction (raw).
        direction: Vec3,
        /// Largest distance (m).
        max_t: f32,
        /// Query filter.
        filter: QueryFilter,
    },
    /// `World::overlap` with a shape at a raw pose.
    Overlap {
        /// The query shape.
        shape: ShapeSpec,
        /// Position (m).
        position: Vec3,
        /// Rotation, raw components.
        rotation: Quat,
        /// Query filter.
        filter: QueryFilter,
    },
    /// `World::snapshot` then `World::restore` of it into the same world.
    SnapshotRestore,
    /// `World::restore` of a damaged copy of a fresh snapshot: cut to `at` bytes
    /// (`truncate`) or byte `at` XORed with a non-zero mask (the reserved byte, which
    /// readers ignore, is skipped). Both must be refused.
    CorruptRestore {
        /// Byte offset, modulo the snapshot length.
        at: u32,
        /// XOR mask (0 is turned into 1).
        xor: u8,
        /// Truncate instead of flipping.
        truncate: bool,
    },
    /// `World::checksum` and `World::body_checksum`.
    Checksum,
}

// ------------------------------------------------------------------------------------
// The pool model
// ------------------------------------------------------------------------------------

/// The oracle of the body pool: per slot, its generation, whether it is used and, for a
/// static body, the pose it must keep.
#[derive(Clone, Copy, Debug)]
pub struct PoolModel {
    generation: [u32; OPS_BODIES],
    live: [bool; OPS_BODIES],
    fixed_pose: [Option<Iso>; OPS_BODIES],
}

impl Default for PoolModel {
    fn default() -> Self {
        PoolModel {
            generation: [0; OPS_BODIES],
            live: [false; OPS_BODIES],
            fixed_pose: [None; OPS_BODIES],
        }
    }
}

impl PoolModel {
    /// True when `h` names a body.
    pub fn is_live(&self, h: BodyHandle) -> bool {
        let i = h.index as usize;
        self.live.get(i).copied().unwrap_or(false)
            && self.generation.get(i).copied() == Some(h.generation)
    }

    /// Number of bodies.
    pub fn len(&self) -> usize {
        self.live.iter().filter(|l| **l).count()
    }

    /// True when there are no bodies.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The handle the next add must return: the lowest free slot with its generation;
    /// `None` when full.
    pub fn next_handle(&self) -> Option<BodyHandle> {
        let i = self.live.iter().position(|l| !*l)?;
        Some(BodyHandle {
            index: i as u32,
            generation: self.generation.get(i).copied().unwrap_or(0),
        })
    }

    fn added(&mut self, h: BodyHandle, fixed_pose: Option<Iso>) {
        let i = h.index as usize;
        if let (Some(l), Some(p)) = (self.live.get_mut(i), self.fixed_pose.get_mut(i)) {
            *l = true;
            *p = fixed_pose;
        }
    }

    fn removed(&mut self, h: BodyHandle) {
        let i = h.index as usize;
        if let (Some(l), Some(g), Some(p)) = (
            self.live.get_mut(i),
            self.generation.get_mut(i),
            self.fixed_pose.get_mut(i),
        ) {
            *l = false;
            *g = g.wrapping_add(1);
            *p = None;
        }
    }

    fn set_fixed_pose(&mut self, h: BodyHandle, pose: Iso) {
        if let Some(p) = self.fixed_pose.get_mut(h.index as usize) {
            if p.is_some() {
                *p = Some(pose);
            }
        }
    }

    /// The live handles in slot order.
    fn handles(&self) -> impl Iterator<Item = BodyHandle> + '_ {
        self.live
            .iter()
            .zip(self.generation.iter())
            .enumerate()
            .filter(|(_, (l, _))| **l)
            .map(|(i, (_, g))| BodyHandle {
                index: i as u32,
                generation: *g,
            })
    }
}

// ------------------------------------------------------------------------------------
// World operations
// ------------------------------------------------------------------------------------

/// Properties of the world's public API under the call sequence `ops` (the first
/// [`MAX_OPS`]), run on an [`OpsWorld`] with the default configuration:
///
/// - nothing panics (the fuzzer and the test harness check that);
/// - after every operation every body's pose, centre of mass and velocities are
///   finite, its rotation is unit length, a sleeping dynamic body has zero velocities,
///   a static body keeps the pose it was given, and the world's bodies are exactly the
///   [`PoolModel`]'s, in slot order;
/// - `add` returns the model's next handle, with the kind, position, material and user
///   data given; plainly bad inputs (non-finite, not unit, out of range, static-only
///   shape on a dynamic body, full pool) and stale handles are refused; valid setters
///   on live handles succeed; a new configuration is taken exactly as given, and one
///   with a non-finite field is refused;
/// - every operation that returns `Err` leaves the world as it was: checksum, body and
///   contact counts, step count, configuration, and the addressed body's motion,
///   material, mass and kind;
/// - a step advances the step count by one and reports consistent counts: contacts,
///   pairs and events within capacity, at most 4 points per contact, awake bodies equal
///   to the awake dynamic bodies, CCD hits at most sweeps, events naming live bodies
///   (hits with finite data at least `hit_event_speed`), and the report kept by
///   `last_report`;
/// - ray casts and overlap queries refuse plainly bad input and accept good input;
///   hits lie within `[0, max_t]` with finite points and unit normals on live bodies;
///   `cast_ray` agrees with the first hit of `cast_ray_all`, whose hits are sorted;
///   overlap reports live bodies in increasing slot order;
/// - a snapshot restored into the same world leaves the checksum, configuration, counts
///   and the snapshot bytes identical, and the restored world continues exactly like an
///   untouched clone (same checksum after a step, same handle for the next body);
/// - a truncated or corrupted snapshot is refused and changes nothing;
/// - the checksum is a pure function of the state (a clone has the same), and
///   `body_checksum` answers for live handles and refuses stale ones.
pub fn world_ops_properties(ops: &[WorldOp]) -> Result<(), Violation> {
    let ops = ops.get(..usize::min(ops.len(), MAX_OPS)).unwrap_or(&[]);
    let hulls = build_op_hulls(ops);
    let mut run = Run {
        world: OpsWorld::new(),
        model: PoolModel::default(),
        created: [BodyHandle {
            index: 0,
            generation: 0,
        }; MAX_OPS],
        created_len: 0,
        hulls: &hulls,
        hull_adds: 0,
        steps: 0,
        in_range: true,
        accepted: false,
    };
    for op in ops {
        run.accepted = false;
        run.apply(op)?;
        if run.accepted && !op_in_range(op) {
            run.in_range = false;
        }
        run.check_state()?;
    }
    Ok(())
}

/// The hulls of the first [`MAX_OP_HULLS`] hull `Add`s, in order (`None` where the
/// constructor refused the cloud).
fn build_op_hulls(ops: &[WorldOp]) -> [Option<ConvexHull>; MAX_OP_HULLS] {
    let mut out = [None; MAX_OP_HULLS];
    let clouds = ops.iter().filter_map(|op| match op {
        WorldOp::Add(spec) => spec.shape.hull_points(),
        _ => None,
    });
    for (slot, cloud) in out.iter_mut().zip(clouds) {
        *slot = ConvexHull::new(cloud).ok();
    }
    out
}

/// The world under test and its oracle.
struct Run<'h> {
    world: OpsWorld<'h>,
    model: PoolModel,
    /// Every handle `add` returned, in order.
    created: [BodyHandle; MAX_OPS],
    created_len: usize,
    hulls: &'h [Option<ConvexHull>; MAX_OP_HULLS],
    /// Hull `Add`s seen so far (selects the hull table entry).
    hull_adds: usize,
    /// Steps taken so far.
    steps: u32,
    /// Every input accepted so far was in the working range.
    in_range: bool,
    /// The current operation's call succeeded.
    accepted: bool,
}

/// What an erroring operation may not change.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Fingerprint {
    checksum: u64,
    bodies: usize,
    contacts: usize,
    step_count: u64,
    config: WorldConfig,
    /// The addressed body: motion checksum, material, mass bits, kind, awake.
    body: Option<(u64, Material, u32, BodyKind, bool)>,
}

fn fingerprint(world: &OpsWorld<'_>, h: Option<BodyHandle>) -> Fingerprint {
    let body = h.and_then(|h| {
        let b = world.body(h).ok()?;
        let sum = world.body_checksum(h).ok()?;
        Some((
            sum,
            b.material(),
            b.mass().to_bits(),
            b.kind(),
            b.is_awake(),
        ))
    });
    Fingerprint {
        checksum: world.checksum(),
        bodies: world.body_count(),
        contacts: world.contact_count(),
        step_count: world.step_count(),
        config: *world.config(),
        body,
    }
}

impl<'h> Run<'h> {
    fn resolve(&self, r: HandleRef) -> BodyHandle {
        match r {
            HandleRef::Raw(h) => h,
            HandleRef::Created(k) => {
                let created = self.created.get(..self.created_len).unwrap_or(&[]);
                match created.len() {
                    0 => BodyHandle {
                        index: u32::MAX,
                        generation: u32::MAX,
                    },
                    n => created.get(k as usize % n).copied().unwrap_or(BodyHandle {
                        index: u32::MAX,
                        generation: u32::MAX,
                    }),
                }
            }
        }
    }

    fn apply(&mut self, op: &WorldOp) -> Result<(), Violation> {
        match *op {
            WorldOp::Add(spec) => self.add(&spec),
            WorldOp::Remove(r) => self.remove(self.resolve(r)),
            WorldOp::SetPose(r, p, q) => self.set_pose(self.resolve(r), p, q),
            WorldOp::SetVelocity(r, v) => {
                let h = self.resolve(r);
                let good = v.is_finite();
                self.setter(h, good, |w| w.set_linear_velocity(h, v))
            }
            WorldOp::SetAngularVelocity(r, v) => {
                let h = self.resolve(r);
                let good = v.is_finite();
                self.setter(h, good, |w| w.set_angular_velocity(h, v))
            }
            WorldOp::ApplyForce(r, f) => {
                let h = self.resolve(r);
                let huge = f.abs().max_elem() > WORLD_WORKING_RANGE;
                self.setter_or_overflow(h, f.is_finite(), huge, |w| w.apply_force(h, f))
            }
            WorldOp::ApplyTorque(r, t) => {
                let h = self.resolve(r);
                let huge = t.abs().max_elem() > WORLD_WORKING_RANGE;
                self.setter_or_overflow(h, t.is_finite(), huge, |w| w.apply_torque(h, t))
            }
            WorldOp::ApplyImpulseAt(r, j, p) => {
                let h = self.resolve(r);
                let good = j.is_finite() && position_ok(p);
                // The velocity change may overflow f32 when the impulse is huge, or when
                // the body is so light that `|j| / m` passes 1e20 m/s: with lever arms
                // up to 2e4 m and shapes of 1 mm or more, below that even the angular
                // change `|r × j| / I` stays under 1e35.
                let mass = self.world.body(h).map_or(f32::INFINITY, |b| b.mass());
                let light = f64::from(j.length()) / f64::from(mass) > 1.0e20;
                let huge = j.abs().max_elem() > WORLD_WORKING_RANGE || light;
                self.setter_or_overflow(h, good, huge, |w| w.apply_impulse_at(h, j, p))
            }
            WorldOp::Wake(r) => {
                let h = self.resolve(r);
                self.setter(h, true, |w| w.wake(h))
            }
            WorldOp::Sleep(r) => {
                let h = self.resolve(r);
                self.setter(h, true, |w| w.sleep(h))
            }
            WorldOp::SetMaterial(r, m) => self.set_material(self.resolve(r), m),
            WorldOp::SetConfig(c) => self.set_config(c),
            WorldOp::Step(n) => self.step(n),
            WorldOp::CastRay {
                origin,
                direction,
                max_t,
                filter,
            } => self.cast_ray(origin, direction, max_t, filter),
            WorldOp::Overlap {
                shape,
                position,
                rotation,
                filter,
            } => self.overlap(&shape, Iso::new(position, rotation), filter),
            WorldOp::SnapshotRestore => self.snapshot_restore(),
            WorldOp::CorruptRestore { at, xor, truncate } => {
                self.corrupt_restore(at, xor, truncate)
            }
            WorldOp::Checksum => self.checksums(),
        }
    }

    /// The shape of an `Add`: its own constructor, or the next hull table entry. `None`
    /// when the constructor refused it (then there is nothing to add).
    fn add_shape(&mut self, spec: &ShapeSpec) -> Option<Shape<'h>> {
        if let Some(simple) = spec.simple() {
            return simple.ok();
        }
        let k = self.hull_adds % MAX_OP_HULLS;
        self.hull_adds = self.hull_adds.wrapping_add(1);
        let hulls: &'h [Option<ConvexHull>; MAX_OP_HULLS] = self.hulls;
        hulls.get(k)?.as_ref().map(Shape::hull)
    }

    fn add(&mut self, spec: &BodySpec) -> Result<(), Violation> {
        let Some(shape) = self.add_shape(&spec.shape) else {
            return Ok(());
        };
        let before = fingerprint(&self.world, None);
        let expected = self.model.next_handle();
        let must_fail = spec.plainly_bad(&shape) || expected.is_none();
        match self.world.add(spec.desc(shape)) {
            Err(_) => {
                check(
                    fingerprint(&self.world, None) == before,
                    "add: refused but changed the world",
                )?;
            }
            Ok(h) => {
                check(!must_fail, "add: accepted a plainly bad description")?;
                check(
                    Some(h) == expected,
                    "add: handle is not the pool model's next (lowest free slot, its generation)",
                )?;
                let b = self
                    .world
                    .body(h)
                    .map_err(|_| Violation("add: the new handle is refused"))?;
                check(
                    b.kind() == spec.kind
                        && b.position() == spec.position
                        && b.material() == spec.material
                        && b.user_data() == spec.user_data,
                    "add: body differs from its description",
                )?;
                let fixed = (spec.kind == BodyKind::Static).then(|| b.pose());
                self.accepted = true;
                let sized = matches!(shape, Shape::HalfSpace(_))
                    || shape.bounding_radius() <= WORLD_WORKING_RANGE;
                let solid = spec.kind != BodyKind::Dynamic
                    || (shape.min_extent() >= WORLD_MIN_EXTENT
                        && (WORLD_MIN_MASS..=WORLD_WORKING_RANGE).contains(&b.mass()));
                if !(sized && solid) {
                    self.in_range = false;
                }
                self.model.added(h, fixed);
                if let Some(slot) = self.created.get_mut(self.created_len) {
                    *slot = h;
                    self.created_len += 1;
                }
            }
        }
        Ok(())
    }

    fn remove(&mut self, h: BodyHandle) -> Result<(), Violation> {
        let before = fingerprint(&self.world, None);
        let live = self.model.is_live(h);
        match self.world.remove(h) {
            Ok(()) => {
                check(live, "remove: accepted a stale handle")?;
                self.model.removed(h);
                check(
                    self.world.body(h).err() == Some(Error::StaleHandle),
                    "remove: the removed handle still names a body",
                )?;
            }
            Err(e) => {
                check(!live, "remove: refused a live handle")?;
                check(e == Error::StaleHandle, "remove: stale handle, other error")?;
                check(
                    fingerprint(&self.world, None) == before,
                    "remove: refused but changed the world",
                )?;
            }
        }
        Ok(())
    }

    fn set_pose(&mut self, h: BodyHandle, p: Vec3, q: Quat) -> Result<(), Violation> {
        let good = position_ok(p) && q.is_unit();
        self.setter(h, good, |w| w.set_pose(h, Iso::new(p, q)))?;
        if let Ok(b) = self.world.body(h) {
            if good && b.kind() == BodyKind::Static {
                check(b.position() == p, "set_pose: position not taken as given")?;
                self.model.set_fixed_pose(h, b.pose());
            }
        }
        Ok(())
    }

    fn set_material(&mut self, h: BodyHandle, m: Material) -> Result<(), Violation> {
        let good = !material_bad(&m);
        self.setter(h, good, |w| w.set_material(h, m))?;
        if good && self.model.is_live(h) {
            let taken = self.world.body(h).map(|b| b.material()) == Ok(m);
            check(taken, "set_material: material not taken as given")?;
        }
        Ok(())
    }

    /// A body setter: Ok exactly for a live handle with `good` input; on Err nothing
    /// changed.
    fn setter(
        &mut self,
        h: BodyHandle,
        good: bool,
        f: impl FnOnce(&mut OpsWorld<'h>) -> Result<(), Error>,
    ) -> Result<(), Violation> {
        self.setter_or_overflow(h, good, false, f)
    }

    /// [`Self::setter`] for a value that may also be refused with `OutOfRange` when it is
    /// huge (`may_overflow`): a force or impulse whose result would overflow `f32`.
    fn setter_or_overflow(
        &mut self,
        h: BodyHandle,
        good: bool,
        may_overflow: bool,
        f: impl FnOnce(&mut OpsWorld<'h>) -> Result<(), Error>,
    ) -> Result<(), Violation> {
        let live = self.model.is_live(h);
        let before = fingerprint(&self.world, Some(h));
        match f(&mut self.world) {
            Ok(()) => {
                self.accepted = true;
                check(live && good, "setter: accepted a stale handle or bad value")
            }
            Err(e) => {
                let overflow = may_overflow && matches!(e, Error::OutOfRange(_));
                check(
                    !(live && good) || overflow,
                    "setter: refused a live handle and good value",
                )?;
                check(
                    fingerprint(&self.world, Some(h)) == before,
                    "setter: refused but changed the world",
                )
            }
        }
    }

    fn set_config(&mut self, c: WorldConfig) -> Result<(), Violation> {
        let before = fingerprint(&self.world, None);
        match self.world.set_config(c) {
            Ok(()) => {
                self.accepted = true;
                check(config_finite(&c), "set_config: accepted a non-finite field")?;
                check(
                    config_within_documented_bounds(&c),
                    "set_config: accepted a field outside its documented bounds",
                )?;
                check(
                    *self.world.config() == c,
                    "set_config: config not taken as given",
                )
            }
            Err(_) => check(
                fingerprint(&self.world, None) == before,
                "set_config: refused but changed the world",
            ),
        }
    }

    fn step(&mut self, n: u8) -> Result<(), Violation> {
        let n = u32::min(u32::from(n), MAX_STEPS_PER_OP);
        for _ in 0..n {
            if self.steps >= MAX_STEPS {
                break;
            }
            self.steps += 1;
            let count = self.world.step_count();
            let report = self.world.step();
            check(
                self.world.step_count() == count.wrapping_add(1),
                "step: step count did not advance by one",
            )?;
            check(
                self.world.last_report() == report,
                "step: last_report differs from the returned report",
            )?;
            let model = &self.model;
            check_report(&self.world, &report, &|h| model.is_live(h), self.in_range)?;
            self.check_state()?;
            speeds_within_limits(&self.world)?;
        }
        Ok(())
    }

    fn cast_ray(
        &mut self,
        origin: Vec3,
        direction: Vec3,
        max_t: f32,
        filter: QueryFilter,
    ) -> Result<(), Violation> {
        let ray = Ray { origin, direction };
        let d2 = direction.length_squared();
        let inputs_finite = position_ok(origin) && direction.is_finite() && max_t.is_finite();
        // The documented tolerance on |d|² is 1e-3; 1e-4 is clearly inside, 1e-2 clearly out.
        let clearly_good = inputs_finite && max_t >= 0.0 && scalar::abs(d2 - 1.0) <= 1.0e-4;
        let clearly_bad = !inputs_finite || max_t < 0.0 || scalar::abs(d2 - 1.0) > 1.0e-2;
        let one = self.world.cast_ray(&ray, max_t, filter);
        let mut out = [crate::RayCastHit::default(); 8];
        let all = self.world.cast_ray_all(&ray, max_t, filter, &mut out);
        check(
            one.is_ok() == all.is_ok(),
            "cast_ray: cast_ray and cast_ray_all disagree on the input",
        )?;
        let (Ok(one), Ok(n)) = (one, all) else {
            return check(!clearly_good, "cast_ray: refused a good ray");
        };
        check(!clearly_bad, "cast_ray: accepted a bad ray")?;
        check(n <= out.len(), "cast_ray_all: more hits than room")?;
        let hits = out.get(..n).unwrap_or(&[]);
        // Geometry is checked in the working range only (world and ray); beyond it the
        // casts must still agree with each other and name live bodies.
        let geometric = self.in_range && tame_vec(origin) && tame(max_t);
        for hit in hits.iter().chain(one.iter()) {
            check(
                self.model.is_live(hit.body),
                "cast_ray: hit names no live body",
            )?;
            if !geometric {
                continue;
            }
            check(
                (0.0..=max_t).contains(&hit.t),
                "cast_ray: hit distance outside [0, max_t]",
            )?;
            check(
                hit.point.is_finite() && hit.normal.is_finite(),
                "cast_ray: hit point or normal not finite",
            )?;
            check(
                scalar::abs(hit.normal.length() - 1.0) <= NORMAL_SLACK,
                "cast_ray: hit normal not unit length",
            )?;
        }
        if !geometric {
            return Ok(());
        }
        check(
            hits.windows(2).all(|w| match w {
                [a, b] => a.t <= b.t,
                _ => true,
            }),
            "cast_ray_all: hits not sorted by distance",
        )?;
        match (one, hits.first()) {
            (None, None) => Ok(()),
            (Some(a), Some(b)) => check(
                a.t == b.t && a.body == b.body,
                "cast_ray: differs from the first hit of cast_ray_all",
            ),
            _ => Err(Violation(
                "cast_ray: hit by one of cast_ray, cast_ray_all only",
            )),
        }
    }

    fn overlap(
        &mut self,
        spec: &ShapeSpec,
        pose: Iso,
        filter: QueryFilter,
    ) -> Result<(), Violation> {
        // The query shape only lives for the call, so a hull is built on the spot.
        let hull;
        let shape = match spec.simple() {
            Some(Ok(s)) => s,
            Some(Err(_)) => return Ok(()),
            None => {
                hull = match spec.hull_points().map(ConvexHull::new) {
                    Some(Ok(h)) => h,
                    _ => return Ok(()),
                };
                Shape::hull(&hull)
            }
        };
        let good = position_ok(pose.position) && pose.rotation.is_unit();
        let mut out = [BodyHandle {
            index: u32::MAX,
            generation: u32::MAX,
        }; OPS_BODIES];
        let Ok(n) = self.world.overlap(&shape, &pose, filter, &mut out) else {
            return check(!good, "overlap: refused a good pose");
        };
        check(good, "overlap: accepted a bad pose")?;
        check(n <= out.len(), "overlap: more bodies than room")?;
        let found = out.get(..n).unwrap_or(&[]);
        for h in found {
            check(self.model.is_live(*h), "overlap: names no live body")?;
        }
        check(
            found.windows(2).all(|w| match w {
                [a, b] => a.index < b.index,
                _ => true,
            }),
            "overlap: bodies not in increasing slot order",
        )
    }

    fn snapshot_restore(&mut self) -> Result<(), Violation> {
        let mut buf = [0u8; SNAPSHOT_BUFFER];
        let before = fingerprint(&self.world, None);
        let n = self
            .world
            .snapshot(&mut buf)
            .map_err(|_| Violation("snapshot: refused a buffer of max_snapshot_len"))?;
        check(
            n == self.world.snapshot_len(),
            "snapshot: wrote other than snapshot_len bytes",
        )?;
        let hash = fnv1a(buf.get(..n).unwrap_or(&[]));
        let twin = self.world.clone();
        self.world
            .restore(buf.get(..n).unwrap_or(&[]))
            .map_err(|_| Violation("restore: refused the world's own snapshot"))?;
        check(
            fingerprint(&self.world, None) == before,
            "restore: own snapshot changed checksum, counts or config",
        )?;
        let n2 = self
            .world
            .snapshot(&mut buf)
            .map_err(|_| Violation("snapshot: refused after restore"))?;
        check(
            n2 == n && fnv1a(buf.get(..n2).unwrap_or(&[])) == hash,
            "restore: snapshot after restore differs from the one restored",
        )?;
        self.continues_like(twin)
    }

    /// The restored world continues like `twin`, the clone taken before the snapshot:
    /// the same checksum after a step, the same handles for new bodies in every free slot.
    fn continues_like(&self, twin: OpsWorld<'h>) -> Result<(), Violation> {
        let mut a = self.world.clone();
        let mut b = twin;
        a.step();
        b.step();
        check(
            a.checksum() == b.checksum(),
            "restore: the restored world steps differently from its clone",
        )?;
        let probe = Shape::sphere(0.25).map_err(|_| Violation("sphere(0.25) refused"))?;
        let desc = BodyDesc::dynamic(probe).position(Vec3::new(0.0, 100.0, 0.0));
        // Fill every free slot: each must get the same handle in both.
        for _ in 0..OPS_BODIES {
            let (ha, hb) = (a.add(desc).ok(), b.add(desc).ok());
            check(
                ha == hb,
                "restore: the next body gets another handle than in the clone (lost generations)",
            )?;
            if ha.is_none() {
                break;
            }
        }
        Ok(())
    }

    fn corrupt_restore(&mut self, at: u32, xor: u8, truncate: bool) -> Result<(), Violation> {
        let mut buf = [0u8; SNAPSHOT_BUFFER];
        let Ok(n) = self.world.snapshot(&mut buf) else {
            return Err(Violation("snapshot: refused a buffer of max_snapshot_len"));
        };
        let before = fingerprint(&self.world, None);
        let before_hash = fnv1a(buf.get(..n).unwrap_or(&[]));
        let at = at as usize % usize::max(n, 1);
        let len = if truncate {
            at
        } else {
            // Readers ignore the reserved byte; flip its neighbour instead.
            let at = if at == RESERVED_AT { at + 1 } else { at };
            if let Some(b) = buf.get_mut(at) {
                *b ^= if xor == 0 { 1 } else { xor };
            }
            n
        };
        let result = self.world.restore(buf.get(..len).unwrap_or(&[]));
        check(result.is_err(), "restore: accepted a damaged snapshot")?;
        check(
            fingerprint(&self.world, None) == before,
            "restore: refused but changed the world",
        )?;
        let n2 = self
            .world
            .snapshot(&mut buf)
            .map_err(|_| Violation("snapshot: refused after a refused restore"))?;
        check(
            n2 == n && fnv1a(buf.get(..n2).unwrap_or(&[])) == before_hash,
            "restore: refused but the snapshot bytes changed",
        )
    }

    fn checksums(&self) -> Result<(), Violation> {
        check(
            self.world.clone().checksum() == self.world.checksum(),
            "checksum: a clone has another checksum",
        )?;
        for h in self.model.handles() {
            check(
                self.world.body_checksum(h).is_ok(),
                "body_checksum: refused a live handle",
            )?;
            let stale = BodyHandle {
                index: h.index,
                generation: h.generation.wrapping_add(1),
            };
            check(
                self.world.body_checksum(stale) == Err(Error::StaleHandle),
                "body_checksum: accepted a stale handle",
            )?;
        }
        Ok(())
    }

    /// The state invariants, after every operation.
    fn check_state(&self) -> Result<(), Violation> {
        check(
            self.world.body_count() == self.model.len(),
            "state: body count differs from the pool model",
        )?;
        check(
            self.world.handles().eq(self.model.handles()),
            "state: handles differ from the pool model's",
        )?;
        check(
            self.world.contact_count() <= OPS_CONTACTS,
            "state: more contacts than capacity",
        )?;
        for h in self.model.handles() {
            let b = self
                .world
                .body(h)
                .map_err(|_| Violation("state: a live handle is refused"))?;
            if self.in_range {
                body_sound(&b)?;
            }
            if b.kind() == BodyKind::Dynamic && !b.is_awake() {
                check(
                    b.linear_velocity() == Vec3::ZERO && b.angular_velocity() == Vec3::ZERO,
                    "state: a sleeping dynamic body moves",
                )?;
            }
            if let Some(Some(pose)) = self.model.fixed_pose.get(h.index as usize) {
                check(b.pose() == *pose, "state: a static body moved")?;
            }
        }
        Ok(())
    }
}

/// The step report against the world it describes: counts within capacity, awake
/// bodies counted exactly, events on live bodies with finite data.
fn check_report(
    world: &OpsWorld<'_>,
    report: &StepReport,
    live: &dyn Fn(BodyHandle) -> bool,
    in_range: bool,
) -> Result<(), Violation> {
    check(
        report.contacts as usize <= OPS_CONTACTS && report.pairs as usize <= OPS_CONTACTS,
        "report: more contacts or pairs than capacity",
    )?;
    check(
        u64::from(report.points) <= 4 * u64::from(report.contacts),
        "report: more than 4 points per contact",
    )?;
    check(
        report.ccd_hits <= report.ccd_sweeps,
        "report: more CCD hits than sweeps",
    )?;
    let awake = world
        .handles()
        .filter_map(|h| world.body(h).ok())
        .filter(|b| b.kind() == BodyKind::Dynamic && b.is_awake())
        .count();
    check(
        report.awake_bodies as usize == awake,
        "report: awake_bodies is not the number of awake dynamic bodies",
    )?;
    let events = world.events();
    check(
        events.len() <= OPS_EVENTS,
        "report: more events than capacity",
    )?;
    check(
        report.dropped_events == 0 || events.len() == OPS_EVENTS,
        "report: events dropped while the queue had room",
    )?;
    let min_hit_speed = world.config().hit_event_speed;
    for e in events {
        let (a, b) = match *e {
            Event::ContactBegin { a, b } | Event::ContactEnd { a, b } => (a, b),
            Event::SensorEnter { sensor, other } | Event::SensorLeave { sensor, other } => {
                (sensor, other)
            }
            Event::Hit {
                a,
                b,
                point,
                normal,
                speed,
            } => {
                check(
                    !in_range || (point.is_finite() && normal.is_finite() && speed.is_finite()),
                    "event: hit with non-finite data",
                )?;
                check(
                    !in_range || speed >= min_hit_speed,
                    "event: hit slower than hit_event_speed",
                )?;
                (a, b)
            }
        };
        check(
            live(a) && live(b) && a != b,
            "event: names a dead body or the same body twice",
        )?;
    }
    Ok(())
}

/// After a step every dynamic body moves within the configured speed limits (to the
/// rounding of one scaling): the limits hold at every stage of the step, so the contact
/// solve cannot fling a body faster than the integration allows.
fn speeds_within_limits(world: &OpsWorld<'_>) -> Result<(), Violation> {
    let cfg = world.config();
    let within = |v: Vec3, max: f32| v.length() <= max * (1.0 + 1.0e-5);
    for h in world.handles() {
        let Ok(b) = world.body(h) else { continue };
        if b.kind() == BodyKind::Dynamic {
            check(
                within(b.linear_velocity(), cfg.max_linear_speed)
                    && within(b.angular_velocity(), cfg.max_angular_speed),
                "step: a dynamic body is faster than the speed limits",
            )?;
        }
    }
    Ok(())
}

/// A body's state is usable: finite pose, centre of mass and velocities, unit rotation.
fn body_sound(b: &crate::BodyRef<'_, '_>) -> Result<(), Violation> {
    check(
        b.position().is_finite() && b.center_of_mass().is_finite(),
        "state: position not finite",
    )?;
    check(b.rotation().is_unit(), "state: rotation not unit length")?;
    check(
        b.linear_velocity().is_finite() && b.angular_velocity().is_finite(),
        "state: velocity not finite",
    )
}

/// A material the world must refuse: restitution outside `[0, 1]`, a friction, rolling
/// or twist coefficient outside `[0, 100]`, or anything non-finite.
fn material_bad(m: &Material) -> bool {
    let coefficient = |c: f32| (0.0..=Material::MAX_COEFFICIENT).contains(&c);
    !((0.0..=1.0).contains(&m.restitution)
        && coefficient(m.static_friction)
        && coefficient(m.kinetic_friction)
        && coefficient(m.rolling_resistance)
        && coefficient(m.twist_friction))
}

/// `|x| <=` [`WORLD_WORKING_RANGE`] (false for NaN).
fn tame(x: f32) -> bool {
    scalar::abs(x) <= WORLD_WORKING_RANGE
}

fn tame_vec(v: Vec3) -> bool {
    tame(v.x) && tame(v.y) && tame(v.z)
}

/// The numbers of `op` are in the working range (the sizes and mass of an added body
/// are checked on the body the world built).
fn op_in_range(op: &WorldOp) -> bool {
    match *op {
        WorldOp::Add(ref b) => {
            let mass = match b.mass {
                MassSpec::Density(x) | MassSpec::Mass(x) => x,
            };
            tame_vec(b.position)
                && tame_vec(b.linear_velocity)
                && tame_vec(b.angular_velocity)
                && (b.kind != BodyKind::Dynamic || tame(mass))
                && tame(b.material.static_friction)
                && tame(b.material.kinetic_friction)
                && tame(b.linear_damping)
                && tame(b.angular_damping)
        }
        WorldOp::SetPose(_, p, _) => tame_vec(p),
        WorldOp::SetVelocity(_, v)
        | WorldOp::SetAngularVelocity(_, v)
        | WorldOp::ApplyForce(_, v)
        | WorldOp::ApplyTorque(_, v) => tame_vec(v),
        WorldOp::ApplyImpulseAt(_, j, p) => tame_vec(j) && tame_vec(p),
        WorldOp::SetMaterial(_, m) => tame(m.static_friction) && tame(m.kinetic_friction),
        WorldOp::SetConfig(ref c) => config_in_range(c),
        _ => true,
    }
}

/// Every float field of `c` is in the working range and `dt <=` [`WORLD_MAX_DT`].
fn config_in_range(c: &WorldConfig) -> bool {
    c.dt <= WORLD_MAX_DT && c.float_fields().iter().all(|x| tame(*x))
}

/// True when every float field of `c` is finite.
fn config_finite(c: &WorldConfig) -> bool {
    c.float_fields().iter().all(|x| x.is_finite())
}

/// The documented bounds of `WorldConfig` (its field docs), restated here independently
/// of `WorldConfig::validate`: what an accepted configuration must satisfy.
fn config_within_documented_bounds(c: &WorldConfig) -> bool {
    let r = |x: f32, lo: f32, hi: f32| x.is_finite() && (lo..=hi).contains(&x);
    let g = c.gravity;
    [g.x, g.y, g.z].iter().all(|x| r(*x, -1000.0, 1000.0))
        && r(c.dt, 1.0e-5, 1.0)
        && (1..=64).contains(&c.substeps)
        && (1..=64).contains(&c.velocity_iterations)
        && (1..=64).contains(&c.relax_iterations)
        && (0..=64).contains(&c.position_iterations)
        && r(c.contact_hertz, 0.1, 1000.0)
        && r(c.contact_damping_ratio, 0.0, 1000.0)
        && r(c.max_push_speed, 0.0, 100.0)
        && r(c.restitution_threshold, 0.0, 1000.0)
        && r(c.slop, 0.0, 0.1)
        && r(c.projection_factor, 0.0, 1.0)
        && r(c.max_projection, 0.0, 10.0)
        && r(c.speculative_margin, 0.0, 10.0)
        && r(c.aabb_margin, 0.0, 10.0)
        && r(c.stick_speed, 0.0, 100.0)
        && r(c.sleep_linear_speed, 0.0, 100.0)
        && r(c.sleep_angular_speed, 0.0, 100.0)
        && r(c.sleep_time, 0.0, 1.0e6)
        && r(c.ccd_motion_fraction, 1.0e-3, 100.0)
        && r(c.hit_event_speed, 0.0, 1.0e4)
        && r(c.max_linear_speed, 1.0e-3, 1.0e4)
        && r(c.max_angular_speed, 1.0e-3, 1.0e4)
}

/// FNV-1a 64 (Fowler, Noll, Vo), the hash of the snapshot header, written here
/// independently of the decoder.
pub fn fnv1a(bytes: &[u8]) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for b in bytes {
        h = (h ^ u64::from(*b)).wrapping_mul(0x0000_0100_0000_01b3);
    }
    h
}

// ------------------------------------------------------------------------------------
// Snapshot decoding
// ------------------------------------------------------------------------------------

/// The hull of the snapshot fixture: a slanted octahedron (6 points, 8 faces).
pub fn fixture_hull() -> Result<ConvexHull, Error> {
    ConvexHull::new(&[
        Vec3::new(0.4, 0.0, 0.0),
        Vec3::new(-0.4, 0.0, 0.0),
        Vec3::new(0.0, 0.5, 0.0),
        Vec3::new(0.0, -0.3, 0.1),
        Vec3::new(0.0, 0.0, 0.4),
        Vec3::new(0.1, 0.0, -0.4),
    ])
}

/// The world the snapshot properties write and decode: a ground box, a half-space below
/// it, a ramp triangle, then resting or falling sphere, box, capsule and hull (the
/// `hull` given), a sensor, and a moving kinematic body: every shape and body kind, and
/// contacts with warm-start impulses after a step or two.
pub fn snapshot_fixture(hull: &ConvexHull) -> Result<OpsWorld<'_>, Error> {
    let mut w = OpsWorld::new();
    let at = |x: f32, y: f32, z: f32| Vec3::new(x, y, z);
    w.add(BodyDesc::fixed(Shape::cuboid(at(6.0, 0.5, 6.0))?).position(at(0.0, -0.5, 0.0)))?;
    w.add(BodyDesc::fixed(Shape::half_space(Vec3::Y)?).position(at(0.0, -2.0, 0.0)))?;
    w.add(BodyDesc::fixed(Shape::triangle(
        at(3.0, 0.0, -1.0),
        at(5.0, 1.0, -1.0),
        at(3.0, 0.0, 1.0),
    )?))?;
    w.add(BodyDesc::dynamic(Shape::sphere(0.3)?).position(at(-2.0, 0.29, 0.0)))?;
    w.add(
        BodyDesc::dynamic(Shape::cuboid(at(0.3, 0.2, 0.25))?)
            .position(at(0.0, 0.5, 0.0))
            .rotation(Quat::from_axis_angle(Vec3::Z, 0.3))
            .material(Material {
                restitution: 0.4,
                static_friction: 0.8,
                kinetic_friction: 0.5,
                ..Material::DEFAULT
            }),
    )?;
    w.add(
        BodyDesc::dynamic(Shape::capsule(0.3, 0.15)?)
            .position(at(2.0, 0.2, 0.0))
            .rotation(Quat::from_axis_angle(Vec3::X, 1.5))
            .mass(2.0),
    )?;
    w.add(
        BodyDesc::dynamic(Shape::hull(hull))
            .position(at(-1.0, 0.35, 1.5))
            .velocity(at(1.0, -2.0, 0.0))
            .angular_velocity(at(0.0, 3.0, 0.0)),
    )?;
    w.add(
        BodyDesc::fixed(Shape::sphere(1.0)?)
            .position(at(0.0, 0.5, 0.0))
            .sensor(true),
    )?;
    w.add(
        BodyDesc::kinematic(Shape::cuboid(at(0.5, 0.1, 0.5))?)
            .position(at(-3.0, 0.1, -3.0))
            .velocity(at(0.5, 0.0, 0.0)),
    )?;
    Ok(w)
}

/// One change to a snapshot buffer, for [`snapshot_edit_properties`]. Offsets are taken
/// modulo the current length.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SnapshotEdit {
    /// XOR one byte.
    Xor {
        /// Offset.
        at: u32,
        /// Mask.
        mask: u8,
    },
    /// Overwrite 4 bytes with a little-endian word (e.g. the bits of NaN, −1.0, 1e30
    /// over a float field, or a huge count over a length field).
    Word {
        /// Offset of the first byte.
        at: u32,
        /// The word.
        bits: u32,
    },
    /// Cut the buffer to `len` bytes (modulo the current length plus one).
    Truncate {
        /// New length.
        len: u32,
    },
    /// Remove one byte (the rest moves down).
    Delete {
        /// Offset.
        at: u32,
    },
    /// Insert one byte (the rest moves up; the last byte falls off a full buffer).
    Insert {
        /// Offset.
        at: u32,
        /// The byte.
        byte: u8,
    },
}

/// Properties of `World::restore(buf)` on the [`snapshot_fixture`] after `steps` steps
/// (modulo [`FIXTURE_MAX_STEPS`] + 1), for any bytes: see [`restore_properties`].
pub fn snapshot_bytes_properties(buf: &[u8], steps: u8) -> Result<(), Violation> {
    let hull = fixture_hull().map_err(|_| Violation("fixture: hull refused"))?;
    let mut world =
        snapshot_fixture(&hull).map_err(|_| Violation("fixture: a body was refused"))?;
    for _ in 0..u32::from(steps) % (FIXTURE_MAX_STEPS + 1) {
        world.step();
    }
    restore_properties(&mut world, buf)
}

/// Properties of `World::restore` on a real snapshot damaged by `edits`: the
/// [`snapshot_fixture`] steps `steps` times (modulo [`FIXTURE_MAX_STEPS`] + 1) and is
/// snapshotted; the first [`MAX_EDITS`] edits are applied; with `reseal` the header's
/// payload hash is recomputed so the decoder's field checks are reached. The buffer is
/// restored into the same world one step later (so a restore visibly changes it):
///
/// - an unchanged buffer is accepted and gives back the snapshotted checksum;
/// - anything else: see [`restore_properties`].
pub fn snapshot_edit_properties(
    steps: u8,
    edits: &[SnapshotEdit],
    reseal: bool,
) -> Result<(), Violation> {
    let hull = fixture_hull().map_err(|_| Violation("fixture: hull refused"))?;
    let mut world =
        snapshot_fixture(&hull).map_err(|_| Violation("fixture: a body was refused"))?;
    for _ in 0..u32::from(steps) % (FIXTURE_MAX_STEPS + 1) {
        world.step();
    }
    let mut buf = [0u8; SNAPSHOT_BUFFER];
    let n = world
        .snapshot(&mut buf)
        .map_err(|_| Violation("snapshot: refused a buffer of max_snapshot_len"))?;
    let original_hash = fnv1a(buf.get(..n).unwrap_or(&[]));
    let original_sum = world.checksum();
    let mut len = n;
    for edit in edits.iter().take(MAX_EDITS) {
        len = apply_edit(&mut buf, len, *edit);
    }
    if reseal {
        reseal_header(&mut buf, len);
    }
    let bytes = buf.get(..len).unwrap_or(&[]);
    let unchanged = len == n && fnv1a(bytes) == original_hash;
    world.step();
    if unchanged {
        let mut probe = world.clone();
        check(
            probe.restore(bytes).is_ok() && probe.checksum() == original_sum,
            "restore: an unchanged snapshot was refused or restored another state",
        )?;
    }
    restore_properties(&mut world, bytes)
}

/// Apply one edit to `buf[..len]`; returns the new length.
fn apply_edit(buf: &mut [u8; SNAPSHOT_BUFFER], len: usize, edit: SnapshotEdit) -> usize {
    let wrap = |at: u32, n: usize| at as usize % usize::max(n, 1);
    match edit {
        SnapshotEdit::Xor { at, mask } => {
            if let Some(b) = buf.get_mut(wrap(at, len)) {
                *b ^= mask;
            }
            len
        }
        SnapshotEdit::Word { at, bits } => {
            let at = wrap(at, len);
            let end = usize::min(at + 4, len);
            if let Some(dst) = buf.get_mut(at..end) {
                for (d, s) in dst.iter_mut().zip(bits.to_le_bytes()) {
                    *d = s;
                }
            }
            len
        }
        SnapshotEdit::Truncate { len: to } => to as usize % (len + 1),
        SnapshotEdit::Delete { at } => {
            if len == 0 {
                return 0;
            }
            let at = wrap(at, len);
            if let Some(tail) = buf.get_mut(at..len) {
                tail.rotate_left(1);
            }
            len - 1
        }
        SnapshotEdit::Insert { at, byte } => {
            let at = wrap(at, len + 1);
            let new_len = usize::min(len + 1, SNAPSHOT_BUFFER);
            if let Some(tail) = buf.get_mut(at..new_len) {
                tail.rotate_right(1);
                if let Some(first) = tail.first_mut() {
                    *first = byte;
                }
            }
            new_len
        }
    }
}

/// Rewrite the header's payload hash for the payload length the header states, when
/// the buffer holds that much.
fn reseal_header(buf: &mut [u8; SNAPSHOT_BUFFER], len: usize) {
    let Some(payload_len) = read_u32(buf.get(..len).unwrap_or(&[]), LEN_AT) else {
        return;
    };
    let end = HEADER_LEN.saturating_add(payload_len as usize);
    if end > len {
        return;
    }
    let sum = fnv1a(buf.get(HEADER_LEN..end).unwrap_or(&[]));
    if let Some(dst) = buf.get_mut(SUM_AT..SUM_AT + 8) {
        dst.copy_from_slice(&sum.to_le_bytes());
    }
}

fn read_u32(buf: &[u8], at: usize) -> Option<u32> {
    let b = buf.get(at..at + 4)?;
    let mut a = [0u8; 4];
    a.copy_from_slice(b);
    Some(u32::from_le_bytes(a))
}

/// True when `buf` starts with the header a version-1 writer of an [`OpsWorld`] on this
/// build writes, and holds the payload it announces with a matching hash. The reserved
/// byte is not checked: readers ignore it.
fn header_valid(buf: &[u8]) -> bool {
    let word = |at: usize| read_u32(buf, at);
    let Some(len) = word(LEN_AT) else {
        return false;
    };
    let end = HEADER_LEN.saturating_add(len as usize);
    let (Some(payload), Some(sum)) = (buf.get(HEADER_LEN..end), buf.get(SUM_AT..SUM_AT + 8)) else {
        return false;
    };
    buf.get(..8) == Some(&MAGIC[..])
        && buf.get(8..10) == Some(&FORMAT_VERSION.to_le_bytes()[..])
        && buf.get(10) == Some(&MATH_BACKEND)
        && word(12) == Some(OPS_BODIES as u32)
        && word(16) == Some(OPS_CONTACTS as u32)
        && word(20) == Some(OPS_EVENTS as u32)
        && sum == fnv1a(payload).to_le_bytes()
}

/// Properties of `world.restore(buf)` for any bytes:
///
/// - it never panics;
/// - refused: the world is unchanged (checksum, counts, step count, configuration and
///   its whole snapshot);
/// - accepted: the buffer has a valid header (checked by an independent parser: magic,
///   version, math backend, capacities, payload hash); every body is sound (finite
///   pose and velocities, unit rotation) and the configuration validates; the state is
///   a fixpoint (its snapshot restores into a clone with the same checksum and the same
///   snapshot bytes); and [`RESTORED_STEPS`] steps keep it sound with consistent
///   reports.
pub fn restore_properties(world: &mut OpsWorld<'_>, buf: &[u8]) -> Result<(), Violation> {
    let mut scratch = [0u8; SNAPSHOT_BUFFER];
    let before = fingerprint(world, None);
    let before_hash = snapshot_hash(world, &mut scratch)?;
    if world.restore(buf).is_err() {
        check(
            fingerprint(world, None) == before,
            "restore: refused but changed the world",
        )?;
        return check(
            snapshot_hash(world, &mut scratch)? == before_hash,
            "restore: refused but the snapshot bytes changed",
        );
    }
    check(
        header_valid(buf),
        "restore: accepted a buffer with a bad header",
    )?;
    check(
        world.config().validate().is_ok(),
        "restore: accepted an invalid configuration",
    )?;
    restored_sound(world)
        .map_err(|_| Violation("restore: accepted a body with a non-finite or non-unit state"))?;
    let hash = snapshot_hash(world, &mut scratch)?;
    let n = world.snapshot_len();
    let mut copy = world.clone();
    copy.restore(scratch.get(..n).unwrap_or(&[]))
        .map_err(|_| Violation("restore: refused the snapshot of a restored world"))?;
    check(
        copy.checksum() == world.checksum(),
        "restore: the restored state's snapshot restores to another checksum",
    )?;
    check(
        snapshot_hash(&copy, &mut scratch)? == hash,
        "restore: snapshot after restore differs from the one restored",
    )?;
    let in_range = restored_in_range(world);
    for _ in 0..RESTORED_STEPS {
        let report = world.step();
        let w: &OpsWorld<'_> = world;
        check_report(w, &report, &|h| w.body(h).is_ok(), in_range).map_err(|_| {
            Violation("restore: an accepted state steps to an inconsistent report or events")
        })?;
        if in_range {
            restored_sound(world).map_err(|_| {
                Violation(
                    "restore: an accepted state in the working range went non-finite when stepped",
                )
            })?;
        }
    }
    Ok(())
}

/// What can be seen of `world` through the public API is in the working range: the
/// configuration, every position, velocity and shape size, and every dynamic body's
/// mass and smallest extent.
fn restored_in_range(world: &OpsWorld<'_>) -> bool {
    config_in_range(world.config())
        && world.handles().all(|h| {
            let Ok(b) = world.body(h) else {
                return false;
            };
            let shape = b.shape();
            let sized = matches!(shape, Shape::HalfSpace(_))
                || shape.bounding_radius() <= WORLD_WORKING_RANGE;
            let solid = b.kind() != BodyKind::Dynamic
                || (shape.min_extent() >= WORLD_MIN_EXTENT
                    && (WORLD_MIN_MASS..=WORLD_WORKING_RANGE).contains(&b.mass()));
            sized
                && solid
                && tame_vec(b.position())
                && tame_vec(b.linear_velocity())
                && tame_vec(b.angular_velocity())
        })
}

/// Every body of `world` is sound and the counts are within capacity.
fn restored_sound(world: &OpsWorld<'_>) -> Result<(), Violation> {
    check(
        world.body_count() <= OPS_BODIES && world.contact_count() <= OPS_CONTACTS,
        "restore: counts beyond capacity",
    )?;
    for h in world.handles() {
        let b = world
            .body(h)
            .map_err(|_| Violation("state: a handle from handles() is refused"))?;
        body_sound(&b)?;
    }
    Ok(())
}

/// FNV-1a of the world's snapshot, written into `scratch`.
fn snapshot_hash(
    world: &OpsWorld<'_>,
    scratch: &mut [u8; SNAPSHOT_BUFFER],
) -> Result<u64, Violation> {
    let n = world
        .snapshot(scratch)
        .map_err(|_| Violation("snapshot: refused a buffer of max_snapshot_len"))?;
    Ok(fnv1a(scratch.get(..n).unwrap_or(&[])))
}
