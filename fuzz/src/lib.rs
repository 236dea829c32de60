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
