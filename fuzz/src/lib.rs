//! Fuzz input decoding, shared by every target in `fuzz_targets/`: bytes (through
//! `arbitrary`) to shapes, poses and motions. Shapes are built only through carom's public
//! constructors; an input they reject is skipped by the target (rejecting it is the right
//! answer, and the property functions check the doors themselves).
//!
//! Every number is either *tame* or *raw*, as the input chooses:
//! - tame: a small integer times a unit (1/4096 m for coordinates, ...), so shapes land
//!   near each other, faces line up and degenerate clouds (duplicates, coplanar points)
//!   are common: the geometry the narrow phase finds hard;
//! - raw: any `f32` bit pattern (NaN, ±∞, subnormals, 3e38), for the validation paths.
//!
//! Rotations are the identity (axis-aligned contact is the common hard case), a
//! quaternion normalised from arbitrary components, or raw components (often not unit).

use arbitrary::Arbitrary;
use carom::collide::Motion;
use carom::math::{Iso, Quat, Vec3};
use carom::shape::{ConvexHull, Shape};

/// Metres per step of a tame coordinate: ±8 m in 0.24 mm steps.
pub const COORD_UNIT: f32 = 1.0 / 4096.0;
/// Metres per step of a tame size: (0, 8] m.
pub const SIZE_UNIT: f32 = 1.0 / 8192.0;
/// m/s per step of a tame linear velocity: ±512 m/s.
pub const LINEAR_UNIT: f32 = 1.0 / 64.0;
/// rad/s per step of a tame angular velocity: ±32 rad/s.
pub const ANGULAR_UNIT: f32 = 1.0 / 1024.0;
/// Seconds per step of a tame time span: (0, 4] s.
pub const TIME_UNIT: f32 = 1.0 / 16384.0;
/// Metres per step of a tame tolerance or margin: (0, 1] m.
pub const TOLERANCE_UNIT: f32 = 1.0 / 65536.0;

/// A signed number: `Tame(n)` is `n · unit`, `Raw` any bits.
#[derive(Arbitrary, Clone, Copy, Debug)]
pub enum Num {
    /// A small integer, scaled by the caller's unit.
    Tame(i16),
    /// Any `f32`.
    Raw(f32),
}

impl Num {
    /// The value, tame integers scaled by `unit`.
    pub fn value(self, unit: f32) -> f32 {
        match self {
            Num::Tame(n) => f32::from(n) * unit,
            Num::Raw(x) => x,
        }
    }
}

/// A positive number: `Tame(n)` is `(n + 1) · unit`, `Raw` any bits (so zero and negative
/// sizes reach the constructors too).
#[derive(Arbitrary, Clone, Copy, Debug)]
pub enum Len {
    /// A small integer, scaled by the caller's unit.
    Tame(u16),
    /// Any `f32`.
    Raw(f32),
}

impl Len {
    /// The value, tame integers scaled by `unit`.
    pub fn value(self, unit: f32) -> f32 {
        match self {
            Len::Tame(n) => (f32::from(n) + 1.0) * unit,
            Len::Raw(x) => x,
        }
    }
}

/// A vector of [`Num`]s.
pub type Vec3Input = [Num; 3];

/// The vector, tame components scaled by `unit`.
pub fn vec3(v: &Vec3Input, unit: f32) -> Vec3 {
    Vec3::new(v[0].value(unit), v[1].value(unit), v[2].value(unit))
}

/// A rotation.
#[derive(Arbitrary, Clone, Copy, Debug)]
pub enum RotationInput {
    /// No rotation.
    Identity,
    /// `(x, y, z, w)` normalised by `Quat::normalize` (all zero gives the identity).
    Normalised([i16; 4]),
    /// Raw components, used as given (mostly not unit: exercises validation).
    Raw([f32; 4]),
}

impl RotationInput {
    /// The quaternion.
    pub fn quat(&self) -> Quat {
        match *self {
            RotationInput::Identity => Quat::IDENTITY,
            RotationInput::Normalised([x, y, z, w]) => {
                Quat::from_xyzw(f32::from(x), f32::from(y), f32::from(z), f32::from(w)).normalize()
            }
            RotationInput::Raw([x, y, z, w]) => Quat::from_xyzw(x, y, z, w),
        }
    }
}

/// A pose: position (tame unit [`COORD_UNIT`]) and rotation.
#[derive(Arbitrary, Clone, Copy, Debug)]
pub struct PoseInput {
    /// Position.
    pub position: Vec3Input,
    /// Rotation.
    pub rotation: RotationInput,
}

impl PoseInput {
    /// The pose.
    pub fn iso(&self) -> Iso {
        Iso::new(vec3(&self.position, COORD_UNIT), self.rotation.quat())
    }
}

/// A motion over a step: pose, linear velocity ([`LINEAR_UNIT`]) and angular velocity
/// ([`ANGULAR_UNIT`]).
#[derive(Arbitrary, Clone, Copy, Debug)]
pub struct MotionInput {
    /// Pose at time 0.
    pub pose: PoseInput,
    /// Linear velocity.
    pub linear: Vec3Input,
    /// Angular velocity.
    pub angular: Vec3Input,
}

impl MotionInput {
    /// The motion.
    pub fn motion(&self) -> Motion {
        Motion {
            pose: self.pose.iso(),
            linear: vec3(&self.linear, LINEAR_UNIT),
            angular: vec3(&self.angular, ANGULAR_UNIT),
        }
    }
}

/// A shape of any kind; sizes in [`SIZE_UNIT`], points in [`COORD_UNIT`].
#[derive(Arbitrary, Clone, Debug)]
pub enum ShapeInput {
    /// `Shape::sphere(radius)`.
    Sphere {
        /// Radius.
        radius: Len,
    },
    /// `Shape::capsule(half_height, radius)`.
    Capsule {
        /// Half the core segment's length.
        half_height: Len,
        /// Radius.
        radius: Len,
    },
    /// `Shape::cuboid(half_extents)`.
    Cuboid {
        /// Half-extents.
        half_extents: [Len; 3],
    },
    /// `ConvexHull::new(points)`.
    Hull {
        /// The point cloud (any length; the constructor bounds it).
        points: Vec<Vec3Input>,
    },
    /// `Shape::half_space(normal)`.
    HalfSpace {
        /// Plane normal (any length; the constructor normalises or rejects it).
        normal: Vec3Input,
    },
    /// `Shape::triangle(a, b, c)`.
    Triangle {
        /// Corners.
        corners: [Vec3Input; 3],
    },
}

/// A shape built from a [`ShapeInput`]; hulls are owned here so the shape can borrow them.
pub enum Built {
    /// A shape that owns its data.
    Simple(Shape<'static>),
    /// A hull.
    Hull(Box<ConvexHull>),
}

impl Built {
    /// The shape.
    pub fn shape(&self) -> Shape<'_> {
        match self {
            Built::Simple(s) => *s,
            Built::Hull(h) => Shape::hull(h),
        }
    }
}

/// The points of a cloud, tame coordinates in [`COORD_UNIT`].
pub fn points(cloud: &[Vec3Input]) -> Vec<Vec3> {
    cloud.iter().map(|p| vec3(p, COORD_UNIT)).collect()
}

impl ShapeInput {
    /// Build the shape through the public constructor; `None` when it rejects the input.
    pub fn build(&self) -> Option<Built> {
        let len = |l: &Len| l.value(SIZE_UNIT);
        let shape = match self {
            ShapeInput::Sphere { radius } => Shape::sphere(len(radius)),
            ShapeInput::Capsule {
                half_height,
                radius,
            } => Shape::capsule(len(half_height), len(radius)),
            ShapeInput::Cuboid {
                half_extents: [x, y, z],
            } => Shape::cuboid(Vec3::new(len(x), len(y), len(z))),
            ShapeInput::Hull { points: cloud } => {
                return ConvexHull::new(&points(cloud))
                    .ok()
                    .map(|h| Built::Hull(Box::new(h)));
            }
            ShapeInput::HalfSpace { normal } => Shape::half_space(vec3(normal, COORD_UNIT)),
            ShapeInput::Triangle { corners: [a, b, c] } => Shape::triangle(
                vec3(a, COORD_UNIT),
                vec3(b, COORD_UNIT),
                vec3(c, COORD_UNIT),
            ),
        };
        shape.ok().map(Built::Simple)
    }
}

/// Input of the `narrow_phase` target: two shapes, two poses, a contact margin
/// ([`TOLERANCE_UNIT`]).
#[derive(Arbitrary, Clone, Debug)]
pub struct PairInput {
    /// Shape A.
    pub a: ShapeInput,
    /// Pose of A (world frame).
    pub pose_a: PoseInput,
    /// Shape B.
    pub b: ShapeInput,
    /// Pose of B (world frame).
    pub pose_b: PoseInput,
    /// Speculative margin of `contact`.
    pub margin: Len,
}

/// Input of the `toi` target: two shapes, two motions, the time span ([`TIME_UNIT`]) and
/// tolerance ([`TOLERANCE_UNIT`]).
#[derive(Arbitrary, Clone, Debug)]
pub struct ToiInput {
    /// Shape A.
    pub a: ShapeInput,
    /// Motion of A.
    pub motion_a: MotionInput,
    /// Shape B.
    pub b: ShapeInput,
    /// Motion of B.
    pub motion_b: MotionInput,
    /// End of the time span (s).
    pub t_max: Len,
    /// Distance that counts as touching (m).
    pub tolerance: Len,
}

// ---------------------------------------------------------------------------------------
// World operations (`world` target) and snapshot buffers (`snapshot` target)
// ---------------------------------------------------------------------------------------

use carom::props::{BodySpec, HandleRef, ShapeSpec, SnapshotEdit, WorldOp, MAX_HULL_POINTS};
use carom::{BodyHandle, BodyKind, CombineRule, MassSpec, Material, QueryFilter, WorldConfig};

/// kg/m³ per step of a tame density: (0, 8192] kg/m³.
pub const DENSITY_UNIT: f32 = 1.0 / 8.0;
/// kg per step of a tame mass: (0, 256] kg.
pub const MASS_UNIT: f32 = 1.0 / 256.0;
/// Per step of a tame material coefficient: ±1 for restitution (half of it refused),
/// ±2 for friction.
pub const RESTITUTION_UNIT: f32 = 1.0 / 32768.0;
/// Per step of a tame friction coefficient: ±2.
pub const FRICTION_UNIT: f32 = 1.0 / 16384.0;
/// 1/s per step of a tame damping: ±8 /s (negative refused).
pub const DAMPING_UNIT: f32 = 1.0 / 4096.0;
/// N (or N·s, N·m) per step of a tame force, impulse or torque: ±2048.
pub const FORCE_UNIT: f32 = 1.0 / 16.0;
/// m/s² per step of tame gravity: ±128 m/s².
pub const GRAVITY_UNIT: f32 = 1.0 / 256.0;
/// Per step of a tame small configuration value (slop, margins, factors, sleep
/// thresholds and times): ±8.
pub const CONFIG_UNIT: f32 = 1.0 / 4096.0;
/// m/s or rad/s per step of a tame speed limit or threshold: ±2048.
pub const SPEED_UNIT: f32 = 1.0 / 16.0;
/// Seconds per step of a tame time step: (0, 1] s.
pub const DT_UNIT: f32 = 1.0 / 65536.0;
/// Metres per step of a tame ray length: (0, 32] m.
pub const RAY_UNIT: f32 = 1.0 / 2048.0;

/// A shape for the world: sizes in [`SIZE_UNIT`], points in [`COORD_UNIT`].
#[derive(Arbitrary, Clone, Copy, Debug)]
pub enum WorldShapeInput {
    /// A sphere.
    Sphere {
        /// Radius.
        radius: Len,
    },
    /// A capsule.
    Capsule {
        /// Half the core segment's length.
        half_height: Len,
        /// Radius.
        radius: Len,
    },
    /// A box.
    Cuboid {
        /// Half-extents.
        half_extents: [Len; 3],
    },
    /// A hull from the first `count` points.
    Hull {
        /// The cloud.
        points: [Vec3Input; MAX_HULL_POINTS],
        /// Points used (clamped by carom).
        count: u8,
    },
    /// A half-space.
    HalfSpace {
        /// Plane normal.
        normal: Vec3Input,
    },
    /// A triangle.
    Triangle {
        /// Corners.
        corners: [Vec3Input; 3],
    },
}

impl WorldShapeInput {
    /// The plain-data shape.
    pub fn spec(&self) -> ShapeSpec {
        let len = |l: &Len| l.value(SIZE_UNIT);
        match self {
            WorldShapeInput::Sphere { radius } => ShapeSpec::Sphere {
                radius: len(radius),
            },
            WorldShapeInput::Capsule {
                half_height,
                radius,
            } => ShapeSpec::Capsule {
                half_height: len(half_height),
                radius: len(radius),
            },
            WorldShapeInput::Cuboid {
                half_extents: [x, y, z],
            } => ShapeSpec::Cuboid {
                half_extents: Vec3::new(len(x), len(y), len(z)),
            },
            WorldShapeInput::Hull { points, count } => ShapeSpec::Hull {
                points: points.map(|p| vec3(&p, COORD_UNIT)),
                count: *count,
            },
            WorldShapeInput::HalfSpace { normal } => ShapeSpec::HalfSpace {
                normal: vec3(normal, COORD_UNIT),
            },
            WorldShapeInput::Triangle { corners } => ShapeSpec::Triangle {
                corners: corners.map(|p| vec3(&p, COORD_UNIT)),
            },
        }
    }
}

/// A body kind.
#[derive(Arbitrary, Clone, Copy, Debug)]
pub enum KindInput {
    /// Dynamic.
    Dynamic,
    /// Static.
    Static,
    /// Kinematic.
    Kinematic,
}

/// A mass specification: density in [`DENSITY_UNIT`] or mass in [`MASS_UNIT`].
#[derive(Arbitrary, Clone, Copy, Debug)]
pub enum MassInput {
    /// `MassSpec::Density`.
    Density(Len),
    /// `MassSpec::Mass`.
    Mass(Len),
}

/// A material: restitution in [`RESTITUTION_UNIT`], frictions in [`FRICTION_UNIT`].
#[derive(Arbitrary, Clone, Copy, Debug)]
pub struct MaterialInput {
    /// Restitution.
    pub restitution: Num,
    /// Static friction.
    pub static_friction: Num,
    /// Kinetic friction.
    pub kinetic_friction: Num,
}

impl MaterialInput {
    /// The material.
    pub fn material(&self) -> Material {
        Material {
            restitution: self.restitution.value(RESTITUTION_UNIT),
            static_friction: self.static_friction.value(FRICTION_UNIT),
            kinetic_friction: self.kinetic_friction.value(FRICTION_UNIT),
            ..Material::DEFAULT
        }
    }
}

/// A body description.
#[derive(Arbitrary, Clone, Copy, Debug)]
pub struct BodyInput {
    /// Kind.
    pub kind: KindInput,
    /// Shape.
    pub shape: WorldShapeInput,
    /// Pose.
    pub pose: PoseInput,
    /// Linear velocity ([`LINEAR_UNIT`]).
    pub linear: Vec3Input,
    /// Angular velocity ([`ANGULAR_UNIT`]).
    pub angular: Vec3Input,
    /// Mass or density.
    pub mass: MassInput,
    /// Material.
    pub material: MaterialInput,
    /// Linear and angular damping ([`DAMPING_UNIT`]).
    pub damping: [Num; 2],
    /// Collision group and mask bits: `None` for the defaults (1, all).
    pub filter: Option<(u32, u32)>,
    /// Sensor flag.
    pub sensor: bool,
    /// Continuous collision flag.
    pub ccd: bool,
    /// User data.
    pub user_data: u64,
}

impl BodyInput {
    /// The plain-data description.
    pub fn spec(&self) -> BodySpec {
        let (group, mask) = self.filter.unwrap_or((1, u32::MAX));
        BodySpec {
            kind: match self.kind {
                KindInput::Dynamic => BodyKind::Dynamic,
                KindInput::Static => BodyKind::Static,
                KindInput::Kinematic => BodyKind::Kinematic,
            },
            shape: self.shape.spec(),
            position: vec3(&self.pose.position, COORD_UNIT),
            rotation: self.pose.rotation.quat(),
            linear_velocity: vec3(&self.linear, LINEAR_UNIT),
            angular_velocity: vec3(&self.angular, ANGULAR_UNIT),
            mass: match self.mass {
                MassInput::Density(d) => MassSpec::Density(d.value(DENSITY_UNIT)),
                MassInput::Mass(m) => MassSpec::Mass(m.value(MASS_UNIT)),
            },
            material: self.material.material(),
            linear_damping: self.damping[0].value(DAMPING_UNIT),
            angular_damping: self.damping[1].value(DAMPING_UNIT),
            group,
            mask,
            sensor: self.sensor,
            ccd: self.ccd,
            user_data: self.user_data,
        }
    }
}

/// A handle: one `add` returned, or anything.
#[derive(Arbitrary, Clone, Copy, Debug)]
pub enum HandleInput {
    /// The `k`-th created handle (modulo their number).
    Created(u8),
    /// A handle near the real ones: a small slot and generation.
    Near {
        /// Slot.
        index: u8,
        /// Generation.
        generation: u8,
    },
    /// Any bits.
    Raw {
        /// Slot.
        index: u32,
        /// Generation.
        generation: u32,
    },
}

impl HandleInput {
    /// The handle reference.
    pub fn handle(&self) -> HandleRef {
        match *self {
            HandleInput::Created(k) => HandleRef::Created(k),
            HandleInput::Near { index, generation } => HandleRef::Raw(BodyHandle {
                index: u32::from(index % 20),
                generation: u32::from(generation % 4),
            }),
            HandleInput::Raw { index, generation } => {
                HandleRef::Raw(BodyHandle { index, generation })
            }
        }
    }
}

/// One change to the default configuration.
#[derive(Arbitrary, Clone, Copy, Debug)]
pub enum ConfigEdit {
    /// Gravity ([`GRAVITY_UNIT`]).
    Gravity(Vec3Input),
    /// Time step ([`DT_UNIT`]).
    Dt(Len),
    /// Sub-steps.
    Substeps(u8),
    /// Velocity iterations.
    VelocityIterations(u16),
    /// Position iterations.
    PositionIterations(u16),
    /// Restitution threshold ([`SPEED_UNIT`]).
    RestitutionThreshold(Num),
    /// Slop ([`CONFIG_UNIT`]).
    Slop(Num),
    /// Projection factor ([`CONFIG_UNIT`]).
    ProjectionFactor(Num),
    /// Largest projection ([`CONFIG_UNIT`]).
    MaxProjection(Num),
    /// Speculative margin ([`CONFIG_UNIT`]).
    SpeculativeMargin(Num),
    /// Stick speed ([`CONFIG_UNIT`]).
    StickSpeed(Num),
    /// Sleep speeds, linear and angular ([`CONFIG_UNIT`]).
    SleepSpeeds(Num, Num),
    /// Sleep time ([`CONFIG_UNIT`]).
    SleepTime(Num),
    /// Sleep on or off.
    SleepEnabled(bool),
    /// CCD motion fraction ([`CONFIG_UNIT`]).
    CcdMotionFraction(Num),
    /// Hit event speed ([`SPEED_UNIT`]).
    HitEventSpeed(Num),
    /// Speed limits, linear and angular ([`SPEED_UNIT`]).
    SpeedLimits(Num, Num),
    /// Friction and restitution combine rules, each code modulo the five rules.
    CombineRules(u8, u8),
}

/// The combine rule of `code` (modulo the five rules, in declaration order).
fn combine_rule(code: u8) -> CombineRule {
    CombineRule::ALL
        .get(usize::from(code) % CombineRule::ALL.len())
        .copied()
        .unwrap_or(CombineRule::GeometricMean)
}

/// The default configuration with `edits` applied in order.
pub fn config(edits: &[ConfigEdit]) -> WorldConfig {
    let mut c = WorldConfig::DEFAULT;
    for e in edits {
        match *e {
            ConfigEdit::Gravity(g) => c.gravity = vec3(&g, GRAVITY_UNIT),
            ConfigEdit::Dt(dt) => c.dt = dt.value(DT_UNIT),
            ConfigEdit::Substeps(n) => c.substeps = u32::from(n),
            ConfigEdit::VelocityIterations(n) => c.velocity_iterations = u32::from(n),
            ConfigEdit::PositionIterations(n) => c.position_iterations = u32::from(n),
            ConfigEdit::RestitutionThreshold(x) => c.restitution_threshold = x.value(SPEED_UNIT),
            ConfigEdit::Slop(x) => c.slop = x.value(CONFIG_UNIT),
            ConfigEdit::ProjectionFactor(x) => c.projection_factor = x.value(CONFIG_UNIT),
            ConfigEdit::MaxProjection(x) => c.max_projection = x.value(CONFIG_UNIT),
            ConfigEdit::SpeculativeMargin(x) => c.speculative_margin = x.value(CONFIG_UNIT),
            ConfigEdit::StickSpeed(x) => c.stick_speed = x.value(CONFIG_UNIT),
            ConfigEdit::SleepSpeeds(l, a) => {
                c.sleep_linear_speed = l.value(CONFIG_UNIT);
                c.sleep_angular_speed = a.value(CONFIG_UNIT);
            }
            ConfigEdit::SleepTime(x) => c.sleep_time = x.value(CONFIG_UNIT),
            ConfigEdit::SleepEnabled(on) => c.sleep_enabled = on,
            ConfigEdit::CcdMotionFraction(x) => c.ccd_motion_fraction = x.value(CONFIG_UNIT),
            ConfigEdit::HitEventSpeed(x) => c.hit_event_speed = x.value(SPEED_UNIT),
            ConfigEdit::SpeedLimits(l, a) => {
                c.max_linear_speed = l.value(SPEED_UNIT);
                c.max_angular_speed = a.value(SPEED_UNIT);
            }
            ConfigEdit::CombineRules(f, r) => {
                c.friction_combine = combine_rule(f);
                c.restitution_combine = combine_rule(r);
            }
        }
    }
    c
}

/// A query filter: `None` sees everything.
pub type FilterInput = Option<(u32, u32, bool)>;

fn filter(f: &FilterInput) -> QueryFilter {
    match *f {
        None => QueryFilter::ALL,
        Some((group, mask, include_sensors)) => QueryFilter {
            group,
            mask,
            include_sensors,
        },
    }
}

/// One call on the world (see `carom::props::WorldOp`).
#[derive(Arbitrary, Clone, Debug)]
pub enum OpInput {
    /// Add a body.
    Add(BodyInput),
    /// Remove a body.
    Remove(HandleInput),
    /// Teleport (position [`COORD_UNIT`]).
    SetPose(HandleInput, PoseInput),
    /// Set the linear velocity ([`LINEAR_UNIT`]).
    SetVelocity(HandleInput, Vec3Input),
    /// Set the angular velocity ([`ANGULAR_UNIT`]).
    SetAngularVelocity(HandleInput, Vec3Input),
    /// Add a force ([`FORCE_UNIT`]).
    ApplyForce(HandleInput, Vec3Input),
    /// Add a torque ([`FORCE_UNIT`]).
    ApplyTorque(HandleInput, Vec3Input),
    /// Apply an impulse ([`FORCE_UNIT`]) at a point ([`COORD_UNIT`]).
    ApplyImpulseAt(HandleInput, Vec3Input, Vec3Input),
    /// Wake a body.
    Wake(HandleInput),
    /// Put a body to sleep.
    Sleep(HandleInput),
    /// Change a material.
    SetMaterial(HandleInput, MaterialInput),
    /// Replace the configuration with the default plus edits.
    SetConfig(Vec<ConfigEdit>),
    /// Step `n` times.
    Step(u8),
    /// Cast a ray: origin ([`COORD_UNIT`]), raw direction ([`COORD_UNIT`]; `None` for
    /// the unit direction along it), length ([`RAY_UNIT`]).
    CastRay {
        /// Origin.
        origin: Vec3Input,
        /// Direction.
        direction: Vec3Input,
        /// Use the direction as given (usually not unit) instead of normalising it.
        raw_direction: bool,
        /// Length.
        max_t: Num,
        /// Filter.
        filter: FilterInput,
    },
    /// Overlap query.
    Overlap {
        /// Shape.
        shape: WorldShapeInput,
        /// Pose.
        pose: PoseInput,
        /// Filter.
        filter: FilterInput,
    },
    /// Snapshot and restore.
    SnapshotRestore,
    /// Restore a damaged snapshot.
    CorruptRestore {
        /// Offset.
        at: u32,
        /// XOR mask.
        xor: u8,
        /// Truncate instead.
        truncate: bool,
    },
    /// Checksums.
    Checksum,
}

impl OpInput {
    /// The plain-data operation.
    pub fn op(&self) -> WorldOp {
        match self {
            OpInput::Add(b) => WorldOp::Add(b.spec()),
            OpInput::Remove(h) => WorldOp::Remove(h.handle()),
            OpInput::SetPose(h, p) => {
                WorldOp::SetPose(h.handle(), vec3(&p.position, COORD_UNIT), p.rotation.quat())
            }
            OpInput::SetVelocity(h, v) => WorldOp::SetVelocity(h.handle(), vec3(v, LINEAR_UNIT)),
            OpInput::SetAngularVelocity(h, v) => {
                WorldOp::SetAngularVelocity(h.handle(), vec3(v, ANGULAR_UNIT))
            }
            OpInput::ApplyForce(h, f) => WorldOp::ApplyForce(h.handle(), vec3(f, FORCE_UNIT)),
            OpInput::ApplyTorque(h, t) => WorldOp::ApplyTorque(h.handle(), vec3(t, FORCE_UNIT)),
            OpInput::ApplyImpulseAt(h, j, p) => {
                WorldOp::ApplyImpulseAt(h.handle(), vec3(j, FORCE_UNIT), vec3(p, COORD_UNIT))
            }
            OpInput::Wake(h) => WorldOp::Wake(h.handle()),
            OpInput::Sleep(h) => WorldOp::Sleep(h.handle()),
            OpInput::SetMaterial(h, m) => WorldOp::SetMaterial(h.handle(), m.material()),
            OpInput::SetConfig(edits) => WorldOp::SetConfig(config(edits)),
            OpInput::Step(n) => WorldOp::Step(*n),
            OpInput::CastRay {
                origin,
                direction,
                raw_direction,
                max_t,
                filter: f,
            } => {
                let d = vec3(direction, COORD_UNIT);
                WorldOp::CastRay {
                    origin: vec3(origin, COORD_UNIT),
                    direction: if *raw_direction {
                        d
                    } else {
                        d.normalize_or(Vec3::Y)
                    },
                    max_t: max_t.value(RAY_UNIT),
                    filter: filter(f),
                }
            }
            OpInput::Overlap {
                shape,
                pose,
                filter: f,
            } => WorldOp::Overlap {
                shape: shape.spec(),
                position: vec3(&pose.position, COORD_UNIT),
                rotation: pose.rotation.quat(),
                filter: filter(f),
            },
            OpInput::SnapshotRestore => WorldOp::SnapshotRestore,
            OpInput::CorruptRestore { at, xor, truncate } => WorldOp::CorruptRestore {
                at: *at,
                xor: *xor,
                truncate: *truncate,
            },
            OpInput::Checksum => WorldOp::Checksum,
        }
    }
}

/// The operations of a `world` input.
pub fn world_ops(ops: &[OpInput]) -> Vec<WorldOp> {
    ops.iter().map(OpInput::op).collect()
}

/// Float bit patterns worth writing over a snapshot field.
pub const SPECIAL_FLOATS: [f32; 12] = [
    f32::NAN,
    f32::INFINITY,
    f32::NEG_INFINITY,
    0.0,
    -0.0,
    -1.0,
    2.0,
    1.0e-3,
    1.0e30,
    -3.4e38,
    1.0e-40,
    f32::MIN_POSITIVE,
];

/// One edit of a real snapshot (see `carom::props::SnapshotEdit`).
#[derive(Arbitrary, Clone, Copy, Debug)]
pub enum EditInput {
    /// XOR a byte.
    Xor {
        /// Offset.
        at: u32,
        /// Mask.
        mask: u8,
    },
    /// Write 4 bytes.
    Word {
        /// Offset.
        at: u32,
        /// Bits.
        bits: u32,
    },
    /// Write one of [`SPECIAL_FLOATS`].
    Special {
        /// Offset.
        at: u32,
        /// Which (modulo the table).
        which: u8,
    },
    /// Truncate.
    Truncate {
        /// New length.
        len: u32,
    },
    /// Remove a byte.
    Delete {
        /// Offset.
        at: u32,
    },
    /// Insert a byte.
    Insert {
        /// Offset.
        at: u32,
        /// Byte.
        byte: u8,
    },
}

impl EditInput {
    /// The edit.
    pub fn edit(&self) -> SnapshotEdit {
        match *self {
            EditInput::Xor { at, mask } => SnapshotEdit::Xor { at, mask },
            EditInput::Word { at, bits } => SnapshotEdit::Word { at, bits },
            EditInput::Special { at, which } => SnapshotEdit::Word {
                at,
                bits: SPECIAL_FLOATS[which as usize % SPECIAL_FLOATS.len()].to_bits(),
            },
            EditInput::Truncate { len } => SnapshotEdit::Truncate { len },
            EditInput::Delete { at } => SnapshotEdit::Delete { at },
            EditInput::Insert { at, byte } => SnapshotEdit::Insert { at, byte },
        }
    }
}

/// Input of the `snapshot` target.
#[derive(Arbitrary, Clone, Debug)]
pub enum SnapshotInput {
    /// Arbitrary bytes restored into the fixture after `steps` steps.
    Bytes {
        /// Fixture steps.
        steps: u8,
        /// The buffer.
        bytes: Vec<u8>,
    },
    /// A real snapshot of the fixture after `steps` steps, edited; `reseal` recomputes the
    /// header's payload hash so the field checks are reached.
    Edited {
        /// Fixture steps.
        steps: u8,
        /// The edits.
        edits: Vec<EditInput>,
        /// Recompute the payload hash.
        reseal: bool,
    },
}

// ---------------------------------------------------------------------------------------
// The `mesh` target: meshes and height fields built from raw input, their queries against
// brute force, and a small world of bodies (convex and compound) falling on them.

use carom::shape::{BvhNode, Compound, CompoundPart, HeightField, Ray, TriangleMesh};
use carom::{Aabb, BodyDesc, World};

/// The level geometry of a `mesh` input.
#[derive(Arbitrary, Clone, Debug)]
pub enum GroundInput {
    /// A triangle mesh: vertices ([`COORD_UNIT`]) and index triples (any values).
    Mesh {
        /// Vertices.
        vertices: Vec<Vec3Input>,
        /// Index triples.
        triangles: Vec<[u8; 3]>,
    },
    /// A height field: `columns × rows` samples ([`COORD_UNIT`]), a cell size
    /// ([`SIZE_UNIT`]).
    Field {
        /// Samples along x.
        columns: u8,
        /// Samples along z.
        rows: u8,
        /// Heights, row-major (short input reads as a too-short buffer).
        heights: Vec<Num>,
        /// Cell size.
        cell: Len,
    },
}

/// A body falling on the ground: one convex shape, or a compound of up to four.
#[derive(Arbitrary, Clone, Debug)]
pub struct FallingInput {
    /// The parts (one: a plain convex body).
    pub parts: Vec<(PoseInput, ShapeInput)>,
    /// Its pose.
    pub pose: PoseInput,
    /// Its velocity ([`LINEAR_UNIT`]).
    pub velocity: Vec3Input,
    /// Continuous collision on.
    pub ccd: bool,
}

/// Input of the `mesh` target.
#[derive(Arbitrary, Clone, Debug)]
pub struct MeshInput {
    /// The ground.
    pub ground: GroundInput,
    /// Boxes ([`COORD_UNIT`], corners in any order) for the box query.
    pub boxes: Vec<(Vec3Input, Vec3Input)>,
    /// Rays: origin ([`COORD_UNIT`]), direction (any), length ([`SIZE_UNIT`]).
    pub rays: Vec<(Vec3Input, Vec3Input, Len)>,
    /// Bodies falling on it.
    pub bodies: Vec<FallingInput>,
    /// Steps to take (at most 60).
    pub steps: u8,
}

/// Triangle lookups shared by meshes and height fields.
trait Soup {
    fn count(&self) -> u32;
    fn tri(&self, i: u32) -> Option<carom::shape::Triangle>;
    fn boxed(&self, aabb: &Aabb, f: &mut dyn FnMut(u32));
    fn ray(&self, ray: &Ray, max_t: f32) -> Option<(u32, carom::shape::RayHit)>;
}

/// [`Soup`] for a type with the mesh query methods (`TriangleMesh`, `HeightField`).
macro_rules! soup {
    ($t:ty) => {
        impl Soup for $t {
            fn count(&self) -> u32 {
                self.triangle_count()
            }
            fn tri(&self, i: u32) -> Option<carom::shape::Triangle> {
                self.triangle(i)
            }
            fn boxed(&self, aabb: &Aabb, f: &mut dyn FnMut(u32)) {
                self.query_aabb(aabb, f)
            }
            fn ray(&self, ray: &Ray, max_t: f32) -> Option<(u32, carom::shape::RayHit)> {
                self.cast_ray(ray, max_t)
            }
        }
    };
}
soup!(TriangleMesh<'_>);
soup!(HeightField<'_>);

/// Box queries against every triangle's box, ray casts against every triangle (nearest,
/// lowest index on ties): the same triangles and the same bits.
fn soup_queries(soup: &dyn Soup, input: &MeshInput) -> Result<(), String> {
    for (a, b) in input.boxes.iter().take(4) {
        let (a, b) = (vec3(a, COORD_UNIT), vec3(b, COORD_UNIT));
        let aabb = Aabb::new(a.min(b), a.max(b));
        let mut got = Vec::new();
        soup.boxed(&aabb, &mut |i| got.push(i));
        got.sort_unstable();
        let mut want = Vec::new();
        for i in 0..soup.count() {
            let Some(t) = soup.tri(i) else {
                return Err(format!("triangle {i} missing"));
            };
            let [p, q, r] = t.vertices;
            if Aabb::new(p.min(q).min(r), p.max(q).max(r)).overlaps(&aabb) {
                want.push(i);
            }
        }
        if got != want {
            return Err(format!("box {aabb:?}: {got:?} vs brute force {want:?}"));
        }
    }
    for (o, d, len) in input.rays.iter().take(4) {
        let Ok(ray) = Ray::new(vec3(o, COORD_UNIT), vec3(d, 1.0)) else {
            continue;
        };
        let max_t = len.value(SIZE_UNIT);
        if !(max_t.is_finite() && max_t >= 0.0) {
            continue;
        }
        let got = soup.ray(&ray, max_t);
        let mut want: Option<(u32, f32)> = None;
        for i in 0..soup.count() {
            let Some(t) = soup.tri(i) else { continue };
            let shape = Shape::Triangle(t);
            if let Ok(Some(h)) = shape.cast_ray(&Iso::IDENTITY, &ray, max_t) {
                if want.is_none_or(|(_, w)| h.t < w) {
                    want = Some((i, h.t));
                }
            }
        }
        let got = got.map(|(i, h)| (i, h.t));
        if got.map(|(i, t)| (i, t.to_bits())) != want.map(|(i, t)| (i, t.to_bits())) {
            return Err(format!(
                "ray {ray:?} to {max_t}: {got:?} vs brute force {want:?}"
            ));
        }
    }
    Ok(())
}

/// The `mesh` target's property: the ground builds or is refused without a panic; its
/// queries agree with brute force; bodies (convex or compound, CCD on or off) fall on it
/// for up to 60 steps with a finite state; a snapshot taken halfway restores into a world
/// with the same ground and replays the same checksums.
pub fn mesh_case(input: &MeshInput) -> Result<(), String> {
    match &input.ground {
        GroundInput::Mesh {
            vertices,
            triangles,
        } => {
            let v = points(vertices);
            let t: Vec<[u32; 3]> = triangles.iter().map(|t| t.map(u32::from)).collect();
            let mut nodes = vec![BvhNode::EMPTY; TriangleMesh::nodes_needed(t.len())];
            let Ok(mesh) = TriangleMesh::build(&v, &t, &mut nodes) else {
                return Ok(());
            };
            soup_queries(&mesh, input)?;
            falling(Shape::Mesh(&mesh), input)
        }
        GroundInput::Field {
            columns,
            rows,
            heights,
            cell,
        } => {
            let h: Vec<f32> = heights.iter().map(|n| n.value(COORD_UNIT)).collect();
            let cell = cell.value(SIZE_UNIT);
            let Ok(field) = HeightField::new(&h, u32::from(*columns), u32::from(*rows), cell)
            else {
                return Ok(());
            };
            soup_queries(&field, input)?;
            falling(Shape::HeightField(&field), input)
        }
    }
}

type MeshWorld<'a> = World<'a, 8, 512, 64>;

/// The ground and the bodies of `input` (shapes built by the caller) into `w`.
fn populate<'a>(
    w: &mut MeshWorld<'a>,
    ground: Shape<'a>,
    shapes: &[Option<Shape<'a>>],
    input: &MeshInput,
) -> Result<(), String> {
    w.add(BodyDesc::fixed(ground))
        .map_err(|e| format!("ground refused: {e:?}"))?;
    for (b, shape) in input.bodies.iter().zip(shapes) {
        let Some(shape) = shape else { continue };
        let desc = BodyDesc::dynamic(*shape)
            .position(b.pose.iso().position)
            .rotation(b.pose.iso().rotation)
            .velocity(vec3(&b.velocity, LINEAR_UNIT))
            .ccd(b.ccd);
        // Refusals (static-only shapes, bad values) are fine; nothing may panic.
        let _ = w.add(desc);
    }
    Ok(())
}

/// Bodies falling on `ground` (see [`mesh_case`]).
fn falling(ground: Shape<'_>, input: &MeshInput) -> Result<(), String> {
    // Everything the bodies borrow, built first.
    let mut built: Vec<Vec<(Iso, Built)>> = Vec::new();
    for b in input.bodies.iter().take(4) {
        let parts: Vec<(Iso, Built)> = b
            .parts
            .iter()
            .take(4)
            .filter_map(|(pose, s)| s.build().map(|x| (pose.iso(), x)))
            .collect();
        built.push(parts);
    }
    let pieces: Vec<Vec<CompoundPart<'_>>> = built
        .iter()
        .map(|parts| {
            parts
                .iter()
                .map(|(pose, b)| CompoundPart::new(*pose, b.shape()))
                .collect()
        })
        .collect();
    let compounds: Vec<Option<Compound<'_>>> = pieces
        .iter()
        .map(|p| {
            if p.len() > 1 {
                Compound::new(p).ok()
            } else {
                None
            }
        })
        .collect();
    let shapes: Vec<Option<Shape<'_>>> = (0..input.bodies.len().min(4))
        .map(|i| match (compounds.get(i), pieces.get(i)) {
            (Some(Some(c)), _) => Some(Shape::Compound(c)),
            (_, Some(p)) => p.first().map(|x| x.shape),
            _ => None,
        })
        .collect();
    let mut w: Box<MeshWorld<'_>> = Box::default();
    populate(&mut w, ground, &shapes, input)?;
    let steps = usize::from(input.steps.min(60));
    let half = steps / 2;
    for _ in 0..half {
        w.step();
    }
    let mut buf = vec![0u8; MeshWorld::max_snapshot_len()];
    let n = w
        .snapshot(&mut buf)
        .map_err(|e| format!("snapshot: {e:?}"))?;
    let mut replay = Vec::new();
    for _ in half..steps {
        w.step();
        replay.push(w.checksum());
    }
    for h in w.handles() {
        let Ok(b) = w.body(h) else { continue };
        if !(b.position().is_finite() && b.linear_velocity().is_finite()) {
            return Err(format!("body {h:?} went non-finite: {:?}", b.position()));
        }
    }
    let mut again: Box<MeshWorld<'_>> = Box::default();
    populate(&mut again, ground, &shapes, input)?;
    again
        .restore(buf.get(..n).unwrap_or(&[]))
        .map_err(|e| format!("restore: {e:?}"))?;
    for (k, want) in replay.into_iter().enumerate() {
        again.step();
        if again.checksum() != want {
            return Err(format!("replay differs {} steps after the snapshot", k + 1));
        }
    }
    Ok(())
}
