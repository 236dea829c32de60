//! The public error type. Every fallible public function returns `Result<_, Error>` and
//! leaves all state unchanged when it returns `Err`.
//!
//! Errors are plain `Copy` values: an [`Error`] says what went wrong, and for input
//! errors which input ([`Input`]); no message is formatted and nothing is allocated. A
//! step never fails: what does not fit in a pool during [`crate::World::step`] is dropped
//! by a documented rule and counted in its [`crate::StepReport`] instead.
//!
//! # Examples
//!
//! ```
//! use carom::{Error, Input, Shape};
//!
//! assert_eq!(Shape::sphere(-1.0), Err(Error::NotPositive(Input::Radius)));
//! assert_eq!(Shape::sphere(f32::NAN), Err(Error::NonFinite(Input::Radius)));
//! assert!(Shape::sphere(0.5).is_ok());
//! ```

/// Which input an [`Error`] is about (carried by [`Error::NonFinite`],
/// [`Error::NotPositive`], [`Error::Negative`], [`Error::OutOfRange`] and
/// [`Error::NotUnit`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum Input {
    /// A sphere or capsule radius ([`crate::Shape::sphere`], [`crate::Shape::capsule`]).
    Radius,
    /// A capsule's half height (half the length of its core segment).
    HalfHeight,
    /// A cuboid's half-extents ([`crate::Shape::cuboid`]).
    HalfExtents,
    /// A point of a hull or triangle ([`crate::ConvexHull::new`],
    /// [`crate::Shape::triangle`]).
    Point,
    /// A plane normal or other direction (a half-space normal, a ray's direction).
    Direction,
    /// A position: a body's, a pose's, a ray's origin (also beyond
    /// ±[`MAX_COORDINATE`]).
    Position,
    /// A rotation quaternion.
    Rotation,
    /// A linear velocity.
    LinearVelocity,
    /// An angular velocity.
    AngularVelocity,
    /// A density.
    Density,
    /// A mass.
    Mass,
    /// A force, torque or impulse (`World::apply_force` and its kin).
    Force,
    /// A distance, margin or tolerance (a query's margin or maximum distance, a
    /// configuration's slop or margins).
    Distance,
    /// A time or time step (`WorldConfig::dt`, [`crate::FixedTimestep`]'s step and frame
    /// times).
    Time,
    /// A material coefficient (restitution or friction).
    Material,
    /// A damping coefficient.
    Damping,
    /// Gravity.
    Gravity,
    /// An iteration or substep count (`WorldConfig::substeps`,
    /// [`crate::FixedTimestep`]'s steps per frame).
    Iterations,
    /// A configuration value not listed above (a [`crate::WorldConfig`] field, a scene
    /// that needs hulls it was not given).
    Config,
    /// A vertex index of a mesh triangle ([`crate::shape::TriangleMesh::build`]): one not
    /// below the number of vertices is [`Error::OutOfRange`].
    Index,
    /// The number of triangles of a mesh ([`crate::shape::TriangleMesh::build`]): none is
    /// [`Error::NotPositive`], more than [`crate::shape::MAX_MESH_TRIANGLES`]
    /// [`Error::OutOfRange`].
    TriangleCount,
    /// A part of a compound ([`crate::shape::Compound::new`]): a shape that cannot be a
    /// part (not a convex solid) is [`Error::OutOfRange`].
    Part,
    /// The number of parts of a compound ([`crate::shape::Compound::new`]): none is
    /// [`Error::NotPositive`], more than [`crate::shape::MAX_COMPOUND_PARTS`]
    /// [`Error::OutOfRange`].
    PartCount,
}

/// Which fixed-capacity pool an [`Error::PoolFull`] is about.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum Pool {
    /// The body pool (`World`'s `BODIES` capacity): [`crate::World::add`] on a world
    /// that already holds `BODIES` bodies.
    Bodies,
    /// The contact pool. Not returned by this version: a full contact pool drops pairs
    /// during a step and counts them in [`crate::StepReport::dropped_contacts`].
    Contacts,
    /// A caller-provided output buffer. Not returned by this version: queries that fill
    /// a slice return how many results fit (a short snapshot buffer is
    /// [`Error::BufferTooSmall`]).
    Output,
}

/// Why a convex hull could not be built ([`crate::ConvexHull::new`], carried by
/// [`Error::Hull`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum HullError {
    /// Fewer than 4 points were given (clouds of duplicates report what they reduce
    /// to: `Coincident`, `Collinear` or `Coplanar`).
    TooFewPoints,
    /// All points are (nearly) the same point.
    Coincident,
    /// All points lie (nearly) on one line.
    Collinear,
    /// All points lie (nearly) in one plane.
    Coplanar,
    /// More input points than [`crate::shape::MAX_HULL_INPUT_POINTS`].
    TooManyPoints,
    /// The hull needs more vertices or faces than its fixed bound, even after the
    /// documented reduction.
    TooComplex,
}

/// Everything that can go wrong at carom's public doors. Whatever the variant, the call
/// changed nothing, with one documented exception: [`ConvexHull::rebuild`] leaves its slot
/// as [`ConvexHull::UNIT_TETRAHEDRON`], a valid hull, never a partly written one.
///
/// [`ConvexHull::rebuild`]: crate::ConvexHull::rebuild
/// [`ConvexHull::UNIT_TETRAHEDRON`]: crate::ConvexHull::UNIT_TETRAHEDRON
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum Error {
    /// The input holds a NaN or an infinity: a shape size, a point, a pose, a velocity,
    /// a force, a material or configuration value, a frame time, a query's margin.
    NonFinite(Input),
    /// The input must be strictly positive and is zero or negative: a size (radius,
    /// half-extents), a mass or density, `dt`, a substep count, a frame's maximum steps.
    NotPositive(Input),
    /// The input is negative where zero or more is required: a restitution or friction
    /// coefficient, a damping, a margin, the frame time given to
    /// [`crate::FixedTimestep::advance`].
    Negative(Input),
    /// The input is outside its documented range: a size outside
    /// [`MIN_SIZE`, `MAX_SIZE`](crate::shape::MIN_SIZE), a coordinate beyond
    /// ±[`MAX_COORDINATE`], a configuration value beyond its bound (see
    /// [`crate::WorldConfig`]), a triangle with (nearly) no area.
    OutOfRange(Input),
    /// A rotation quaternion is not of unit length (normalise it with
    /// [`crate::Quat::normalize`]), or a direction that must be unit is not.
    NotUnit(Input),
    /// A convex hull could not be built from the points given to
    /// [`crate::ConvexHull::new`]; the [`HullError`] says why.
    Hull(HullError),
    /// The shape has no volume, so no mass can be derived from a density: mass
    /// properties of a half-space or a triangle ([`crate::Shape::mass_properties`]).
    NoVolume,
    /// The shape may only be used by a static body (half-space planes, triangles):
    /// [`crate::World::add`] with a dynamic or kinematic body of such a shape.
    StaticOnly,
    /// A handle refers to a removed body (or was never valid for this world): any
    /// [`crate::World`] method taking a [`crate::BodyHandle`] after
    /// [`crate::World::remove`] (slots are reused with a new generation, so an old handle
    /// never reaches a new body).
    StaleHandle,
    /// A fixed-capacity pool is full; nothing was changed. The [`Pool`] says which:
    /// today only [`Pool::Bodies`], from [`crate::World::add`].
    PoolFull(Pool),
    /// A caller-provided buffer is too small; the value is the length needed:
    /// [`crate::World::snapshot`] into a buffer shorter than
    /// [`crate::World::snapshot_len`] (bytes), [`crate::shape::TriangleMesh::build`] into
    /// node storage shorter than [`crate::shape::TriangleMesh::nodes_needed`] (nodes).
    BufferTooSmall(u32),
    /// A query that takes one convex shape ([`crate::collide::contact`],
    /// [`crate::collide::distance`], [`crate::collide::penetration`],
    /// [`crate::collide::separation`], [`crate::collide::time_of_impact`] and their kin)
    /// was given a triangle mesh, a height field or a compound: query their parts instead.
    NotConvex,
    /// A snapshot is truncated, corrupt or from an incompatible build:
    /// [`crate::World::restore`] and [`crate::World::restore_with_hulls`]; the
    /// [`SnapshotError`] says why, and the world is unchanged.
    Snapshot(SnapshotError),
}

/// Why a snapshot was refused by [`crate::World::restore`] (carried by
/// [`Error::Snapshot`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum SnapshotError {
    /// Shorter than its header says.
    Truncated,
    /// Does not start with carom's magic bytes.
    BadMagic,
    /// Written by another format version.
    Version,
    /// Written by a world with other capacities (`BODIES`, `CONTACTS`, `EVENTS`).
    Capacity,
    /// Written by a build with another math backend (libm vs micromath).
    MathBackend,
    /// The integrity check does not match the contents.
    Checksum,
    /// The contents decode to an invalid state.
    Corrupt,
    /// A body's hull shape was not found among the hulls given to restore
    /// (plain [`crate::World::restore`] looks among the hulls its bodies use now).
    MissingHull,
    /// A body's mesh, height field or compound was not found among the shapes the world's
    /// bodies use now (restore into a world that holds the same level geometry and
    /// compounds).
    MissingShape,
}

impl core::fmt::Display for Error {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Error::NonFinite(i) => write!(f, "{i:?} is not finite"),
            Error::NotPositive(i) => write!(f, "{i:?} must be positive"),
            Error::Negative(i) => write!(f, "{i:?} must not be negative"),
            Error::OutOfRange(i) => write!(f, "{i:?} is out of range"),
            Error::NotUnit(i) => write!(f, "{i:?} is not a unit quaternion"),
            Error::Hull(h) => write!(f, "convex hull: {h:?}"),
            Error::NoVolume => write!(f, "the shape has no volume"),
            Error::StaticOnly => write!(f, "the shape is for static bodies only"),
            Error::StaleHandle => write!(f, "stale body handle"),
            Error::PoolFull(p) => write!(f, "{p:?} pool is full"),
            Error::BufferTooSmall(n) => write!(f, "buffer too small, {n} elements needed"),
            Error::NotConvex => write!(f, "a shape with parts where one convex shape is needed"),
            Error::Snapshot(s) => write!(f, "snapshot refused: {s:?}"),
        }
    }
}

impl core::error::Error for Error {}

/// Check that a scalar is finite and strictly positive.
pub(crate) fn positive(x: f32, what: Input) -> Result<f32, Error> {
    if !x.is_finite() {
        Err(Error::NonFinite(what))
    } else if x > 0.0 {
        Ok(x)
    } else {
        Err(Error::NotPositive(what))
    }
}

/// Check that a scalar is finite and not negative.
pub(crate) fn non_negative(x: f32, what: Input) -> Result<f32, Error> {
    if !x.is_finite() {
        Err(Error::NonFinite(what))
    } else if x >= 0.0 {
        Ok(x)
    } else {
        Err(Error::Negative(what))
    }
}

/// Largest coordinate (m) a position given at the API may have. `f32` keeps about 1 mm
/// of resolution at 10 km; further out the tolerances (slop, margins) stop making sense.
pub const MAX_COORDINATE: f32 = 1.0e4;

/// Check a position: finite, and every coordinate within ±[`MAX_COORDINATE`].
pub(crate) fn position(v: crate::math::Vec3) -> Result<crate::math::Vec3, Error> {
    finite_vec(v, Input::Position)?;
    if v.abs().max_elem() <= MAX_COORDINATE {
        Ok(v)
    } else {
        Err(Error::OutOfRange(Input::Position))
    }
}

/// Check that a vector is finite.
pub(crate) fn finite_vec(v: crate::math::Vec3, what: Input) -> Result<crate::math::Vec3, Error> {
    if v.is_finite() {
        Ok(v)
    } else {
        Err(Error::NonFinite(what))
    }
}
