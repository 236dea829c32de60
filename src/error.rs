//! The public error type. Every fallible public function returns `Result<_, Error>` and
//! leaves all state unchanged when it returns `Err`.

/// Which input an [`Error`] is about.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum Input {
    /// A sphere or capsule radius.
    Radius,
    /// A capsule's half height (half the length of its core segment).
    HalfHeight,
    /// A cuboid's half-extents.
    HalfExtents,
    /// A point of a hull or triangle.
    Point,
    /// A plane normal or other direction.
    Direction,
    /// A position.
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
    /// A force or impulse.
    Force,
    /// A distance, margin or tolerance.
    Distance,
    /// A time or time step.
    Time,
    /// A material coefficient (restitution or friction).
    Material,
    /// A damping coefficient.
    Damping,
    /// Gravity.
    Gravity,
    /// An iteration or substep count.
    Iterations,
    /// A configuration value not listed above.
    Config,
}

/// Which fixed-capacity pool an [`Error::PoolFull`] is about.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum Pool {
    /// The body pool (`World`'s `BODIES` capacity).
    Bodies,
    /// The contact pool.
    Contacts,
    /// A caller-provided output buffer.
    Output,
}

/// Why a convex hull could not be built.
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

/// Everything that can go wrong at carom's public doors.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum Error {
    /// The input holds a NaN or an infinity.
    NonFinite(Input),
    /// The input must be strictly positive (a size, mass, density, time step).
    NotPositive(Input),
    /// The input is negative where zero or more is required.
    Negative(Input),
    /// The input is outside its documented range.
    OutOfRange(Input),
    /// A rotation quaternion is not of unit length.
    NotUnit(Input),
    /// A convex hull could not be built.
    Hull(HullError),
    /// The shape has no volume, so no mass can be derived from a density.
    NoVolume,
    /// The shape may only be used by a static body (half-space planes, triangles).
    StaticOnly,
    /// A handle refers to a removed body (or was never valid for this world).
    StaleHandle,
    /// A fixed-capacity pool is full; nothing was changed.
    PoolFull(Pool),
    /// A caller-provided buffer is too small; the value is the length needed.
    BufferTooSmall(u32),
    /// A snapshot is truncated, corrupt or from an incompatible build.
    Snapshot(SnapshotError),
}

/// Why a snapshot was refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum SnapshotError {
    /// Shorter than its header says.
    Truncated,
    /// Does not start with carom's magic bytes.
    BadMagic,
    /// Written by another format version.
    Version,
    /// Written by a world with other capacities.
    Capacity,
    /// Written by a build with another math backend (libm vs micromath).
    MathBackend,
    /// The integrity check does not match the contents.
    Checksum,
    /// The contents decode to an invalid state.
    Corrupt,
    /// A body's hull shape was not found among the hulls given to restore.
    MissingHull,
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
            Error::BufferTooSmall(n) => write!(f, "buffer too small, {n} bytes needed"),
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
