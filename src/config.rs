//! Every tunable of the world, with its unit, default, bounds and reason.
//!
//! The defaults suit bodies from about 5 cm to 10 m moving up to a few hundred metres per
//! second, in SI units with gravity along −Y (see the README, "Units and conventions").
//! Every field has a closed range that [`WorldConfig::validate`] enforces (the error names
//! the first field out of range); the ranges keep every product the step forms inside
//! `f32`, so no accepted configuration can make a world's state non-finite.

use crate::dynamics::body::Material;
use crate::error::{Error, Input};
use crate::math::{scalar, Vec3};
use crate::shape::Shape;

/// Allowed penetration (m) that the solver and projection leave in place, so resting
/// contacts stay touching instead of flickering. Box2D uses 0.005 m.
pub const LINEAR_SLOP: f32 = 0.005;

/// Extra margin (m) a full narrow phase keeps beyond the one the step asks for, so a
/// manifold can be reused while its pair drifts by up to this much (see
/// `dynamics::contact`, "Manifold reuse"). One slop; pairs with a convex hull take
/// [`HULL_REUSE_SLACK`], a box on a mesh triangle [`TRIANGLE_REUSE_SLACK`], two spheres
/// none (see [`reuse_slack`]).
pub const REUSE_SLACK: f32 = LINEAR_SLOP;

/// [`REUSE_SLACK`] of a pair with a convex hull (m): six slops, 3 cm.
///
/// The slack trades rebuilds for speculative points: a larger one lets a manifold live
/// longer, and keeps points up to `margin + slack` apart, which the solver then carries.
/// A hull's manifold costs about ten times a box pair's (the hull–hull separating axis
/// test measures edge pairs), so hull pairs take a long window. In the `hulls` scene
/// (300 steps, instructions against one slop): two slops −6 %, four −11 %; against four,
/// six −5.8 % (4 % more points summed over the steps), eight −7.7 % (10 % more points).
/// Six keeps most of eight's gain with less than half its extra points (and a reused
/// point lags a rolling or sliding hull by at most 3 cm); the box and sphere scenes keep
/// one slop, where even two cost more than they save (`spheres` +1.1 %).
pub const HULL_REUSE_SLACK: f32 = 6.0 * LINEAR_SLOP;

/// [`REUSE_SLACK`] of a box on a mesh or height-field triangle (m): four slops.
///
/// A box on terrain is a group of triangle parts that is rebuilt whole (every part's
/// separating axis test, clipping, internal-edge correction and patch merge) as soon as
/// the box drifts past the slack, and a sliding or settling box does so nearly every
/// step with one slop: in `mesh_pile` (300 steps) four slops for box–triangle parts cut
/// the instructions by 4.7 %; eight saved nothing more while the summed points grew by
/// 10 %. Spheres and capsules on triangles keep one slop: their parts cost little to
/// build (four slops for them as well saved nothing more there), and a reused point on a
/// rolling ball lags behind the ball's lowest point.
pub const TRIANGLE_REUSE_SLACK: f32 = 4.0 * LINEAR_SLOP;

/// The reuse slack (m) of a pair of shapes: 0 for two spheres (measured afresh every step
/// in closed form, never reused: see `dynamics::contact`, "Sphere pairs"),
/// [`HULL_REUSE_SLACK`] when either is a [`Shape::Hull`], [`TRIANGLE_REUSE_SLACK`] for a
/// [`Shape::Cuboid`] and a [`Shape::Triangle`], else [`REUSE_SLACK`]. A mesh,
/// height-field or compound body's pairs are formed part by part, so it is the part's
/// shape that counts there (a mesh's parts are triangles).
///
/// ```
/// use carom::config::{reuse_slack, HULL_REUSE_SLACK, REUSE_SLACK, TRIANGLE_REUSE_SLACK};
/// use carom::{ConvexHull, Shape, Vec3};
///
/// let hull = ConvexHull::new(&[Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z]).unwrap();
/// let ball = Shape::sphere(0.5).unwrap();
/// let cube = Shape::cuboid(Vec3::splat(0.5)).unwrap();
/// let tri = Shape::triangle(Vec3::ZERO, Vec3::X, Vec3::Z).unwrap();
/// assert_eq!(reuse_slack(&ball, &ball), 0.0);
/// assert_eq!(reuse_slack(&ball, &cube), REUSE_SLACK);
/// assert_eq!(reuse_slack(&ball, &Shape::Hull(&hull)), HULL_REUSE_SLACK);
/// assert_eq!(reuse_slack(&tri, &Shape::Hull(&hull)), HULL_REUSE_SLACK);
/// assert_eq!(reuse_slack(&tri, &cube), TRIANGLE_REUSE_SLACK);
/// assert_eq!(reuse_slack(&ball, &tri), REUSE_SLACK);
/// ```
#[inline]
pub fn reuse_slack(a: &Shape<'_>, b: &Shape<'_>) -> f32 {
    match (a, b) {
        (Shape::Sphere(_), Shape::Sphere(_)) => 0.0,
        (Shape::Hull(_), _) | (_, Shape::Hull(_)) => HULL_REUSE_SLACK,
        (Shape::Triangle(_), Shape::Cuboid(_)) | (Shape::Cuboid(_), Shape::Triangle(_)) => {
            TRIANGLE_REUSE_SLACK
        }
        _ => REUSE_SLACK,
    }
}

/// How a contact combines a coefficient of its two bodies' materials into one: the
/// choice PhysX, Unity, Godot, Jolt and rapier offer. [`WorldConfig::friction_combine`]
/// picks it for the friction coefficients, [`WorldConfig::restitution_combine`] for
/// restitution.
///
/// Every rule is symmetric and plain IEEE single-precision arithmetic (the same bits on
/// every target). The two means, `Min` and `Max` stay between `a` and `b` (to the last
/// bit with libm; the `micromath` square root is within 1 ulp); `Multiply` stays in
/// `[0, 1]` for two coefficients in `[0, 1]` and is capped at 100. So two materials'
/// coefficients in `[0, 100]` ([`Material::MAX_COEFFICIENT`]) combine into one in
/// `[0, 100]`, and two restitutions into one in `[0, 1]`.
///
/// # Examples
///
/// ```
/// use carom::CombineRule;
///
/// assert_eq!(CombineRule::GeometricMean.apply(0.0, 0.9), 0.0);
/// assert_eq!(CombineRule::Average.apply(0.0, 0.9), 0.45);
/// assert_eq!(CombineRule::Min.apply(0.2, 0.9), 0.2);
/// assert_eq!(CombineRule::Max.apply(0.2, 0.9), 0.9);
/// assert_eq!(CombineRule::Multiply.apply(0.5, 0.5), 0.25);
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "arbitrary", derive(arbitrary::Arbitrary))]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum CombineRule {
    /// `√(a · b)`: zero when either is zero (one frictionless body makes every contact
    /// it touches frictionless). The default for friction (Box2D's, Jolt's).
    GeometricMean,
    /// `(a + b) / 2`, computed as `(a + b) · 0.5` (PhysX's and Unity's default).
    Average,
    /// The smaller, `min(a, b)`.
    Min,
    /// The larger, `max(a, b)`. The default for restitution.
    Max,
    /// The product `a · b`, capped at [`Material::MAX_COEFFICIENT`]: `min(a · b, 100)`.
    Multiply,
}

impl CombineRule {
    /// Every rule, in declaration order (the order of their snapshot codes).
    pub const ALL: [CombineRule; 5] = [
        CombineRule::GeometricMean,
        CombineRule::Average,
        CombineRule::Min,
        CombineRule::Max,
        CombineRule::Multiply,
    ];

    /// The rule's code in a snapshot: its declaration index.
    pub(crate) fn code(self) -> u32 {
        match self {
            CombineRule::GeometricMean => 0,
            CombineRule::Average => 1,
            CombineRule::Min => 2,
            CombineRule::Max => 3,
            CombineRule::Multiply => 4,
        }
    }

    /// The rule of a snapshot code; `None` for an unknown code.
    pub(crate) fn from_code(code: u32) -> Option<CombineRule> {
        let index = usize::try_from(code).ok()?;
        CombineRule::ALL.get(index).copied()
    }

    /// Combine the coefficients `a` and `b` (finite, non-negative: a material's) by the
    /// formula on the variant.
    #[inline]
    pub fn apply(self, a: f32, b: f32) -> f32 {
        match self {
            CombineRule::GeometricMean => scalar::sqrt(a * b),
            CombineRule::Average => (a + b) * 0.5,
            CombineRule::Min => scalar::min(a, b),
            CombineRule::Max => scalar::max(a, b),
            CombineRule::Multiply => scalar::min(a * b, Material::MAX_COEFFICIENT),
        }
    }
}

/// Settings of a [`crate::World`]. Build with [`WorldConfig::DEFAULT`] and change fields.
///
/// The solver is a *soft step* (Catto, "Solver2D", 2024; Box2D v3): each step is cut
/// into `substeps` sub-steps; each sub-step integrates velocities, applies the
/// accumulated impulses again (warm start), runs `velocity_iterations` soft iterations
/// with a bounded push-out, integrates positions and runs `relax_iterations` iterations
/// without push-out. Contacts are springs of `contact_hertz` with damping ratio
/// `contact_damping_ratio`: stiff enough to hold stacks, soft enough never to explode.
///
/// # Examples
///
/// ```
/// use carom::{Vec3, World, WorldConfig};
///
/// # fn main() -> Result<(), carom::Error> {
/// // The Moon, stepped at 120 Hz, with sleeping off.
/// let config = WorldConfig {
///     gravity: Vec3::new(0.0, -1.62, 0.0),
///     dt: 1.0 / 120.0,
///     sleep_enabled: false,
///     ..WorldConfig::DEFAULT
/// };
/// let world: World<'static, 8, 16> = World::with_config(config)?; // validated
/// assert_eq!(world.config().dt, 1.0 / 120.0);
///
/// // An invalid field is refused, naming it.
/// let bad = WorldConfig { substeps: 0, ..WorldConfig::DEFAULT };
/// assert!(World::<'static, 8, 16>::with_config(bad).is_err());
/// # Ok(())
/// # }
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct WorldConfig {
    /// Gravity (m/s²). Default `(0, −9.81, 0)`; each component within ±1000.
    pub gravity: Vec3,
    /// Fixed time step (s). Default 1/60; 1e-5 to 1.
    pub dt: f32,
    /// Sub-steps per step, each of `dt / substeps`. Default 4 (Box2D v3's); 1 to 64.
    pub substeps: u32,
    /// Soft (biased) contact iterations per sub-step. Default 1 (Box2D v3's); 1 to 64.
    pub velocity_iterations: u32,
    /// Relax iterations per sub-step: the normal rows without push-out (removing the
    /// velocity the push-out added), friction, rolling and twist. Default 1; 1 to 64.
    pub relax_iterations: u32,
    /// Contact stiffness (Hz) of dynamic–dynamic contacts; contacts with a static or
    /// kinematic body use twice this. Capped at a quarter of the sub-step rate inside the
    /// step. Default 45 Hz (Box2D v3 uses 30 Hz: a soft contact sags by `load / (m ω²)`,
    /// and at 30 Hz a tower of 20 unit boxes sags 10 cm and buckles; at 45 Hz it sags
    /// 5 cm and stands, and `pyramid100` sinks 0.3 m instead of 0.67 m; 60 Hz, the cap at
    /// 4 sub-steps, rings unless a second soft iteration is paid for); 0.1 to 1000.
    pub contact_hertz: f32,
    /// Contact damping ratio (dimensionless). Default 10 (over-damped: no bounce from the
    /// spring; Box2D v3's and rapier's value); 0 to 1000.
    pub contact_damping_ratio: f32,
    /// Largest speed (m/s) at which the soft contact pushes overlapping bodies apart.
    /// Default 1 m/s (a third of Box2D v3's `contactPushMaxVelocity`: one relax pass per
    /// sub-step cannot take the push back out of a column of deep contacts, and in the
    /// `boxes` pile 3 m/s launched boxes 7 m above where they landed); 0 to 100.
    pub max_push_speed: f32,
    /// Projection passes per step over the contacts still deeper than `4 · slop` after
    /// the solve. Default 1; 0 to 64.
    pub position_iterations: u32,
    /// Closing speed (m/s) above which restitution applies; slower impacts are
    /// inelastic so resting contacts do not bounce. Default 1.0 m/s (Box2D's value);
    /// 0 to 1000.
    pub restitution_threshold: f32,
    /// Penetration (m) left alone by the solver's push-out and by projection. Default
    /// [`LINEAR_SLOP`]; 0 to 0.1.
    pub slop: f32,
    /// Fraction of the remaining penetration projection removes per pass, 0 to 1.
    /// Default 0.2 (Catto's Baumgarte-like factor: fast enough, no overshoot).
    pub projection_factor: f32,
    /// Largest distance (m) projection moves one body in one step, all its contacts
    /// together. Default 0.01 m (0.6 m/s at 60 Hz, below the solver's push-out):
    /// projection moves poses past friction, so a larger budget lets piles creep apart
    /// (the `boxes` pile lost a quarter of its height in 10 s at 0.05 m); 0 to 10.
    pub max_projection: f32,
    /// Speculative margin (m): contact points this far apart (plus the distance the pair
    /// closes in one step) are kept, so the solver stops bodies before they touch.
    /// Default 0.01 m (2 × slop). With continuous collision on (each body's default) the
    /// margin also grows by what the pair can close in the step, so this fixed part
    /// only covers what the step itself adds (gravity: 2.7 mm at 60 Hz). Box2D v3 and
    /// Jolt keep 0.02 m and rapier 2 mm; 0.02 m kept 5 to 10 % more points in the piles,
    /// and one slop lets a Newton's cradle's touching balls lose their points; 0 to 10.
    pub speculative_margin: f32,
    /// Margin (m) by which the broad phase enlarges a moving body's box, so a body that
    /// moves a little keeps its box and its candidate pairs (no search). Default 0.05 m
    /// (half Box2D's 2D `aabbMargin`: in 3D a box has more neighbours within the margin,
    /// and every such pair holds a contact slot: the `boxes` pile peaked at 8773 pairs with
    /// 0.1 m, 5228 with 0.05 m, for the same ~1700 touching contacts); 0 to 10.
    pub aabb_margin: f32,
    /// Relative tangential speed (m/s) below which a contact sticks (static friction).
    /// Default 0.01 m/s; 0 to 100.
    pub stick_speed: f32,
    /// Linear speed (m/s) below which a body may fall asleep. Default 0.05 m/s; 0 to 100.
    pub sleep_linear_speed: f32,
    /// Angular speed (rad/s) below which a body may fall asleep. Default 0.05 rad/s;
    /// 0 to 100.
    pub sleep_angular_speed: f32,
    /// Time (s) an island must stay slow before it sleeps. Default 0.5 s; 0 to 1e6.
    pub sleep_time: f32,
    /// Whether bodies may sleep at all. Default true; benchmarks switch it off.
    pub sleep_enabled: bool,
    /// Fraction of a body's smallest extent it may move in one step before continuous
    /// collision sweeps it. Default 0.25; 1e-3 to 100.
    pub ccd_motion_fraction: f32,
    /// Closing speed (m/s) above which a contact reports a hit event. Default 1.0 m/s;
    /// 0 to 1e4.
    pub hit_event_speed: f32,
    /// Largest linear speed (m/s) a body may reach; faster is clamped. Default 1000 m/s;
    /// 1e-3 to 1e4.
    pub max_linear_speed: f32,
    /// Largest angular speed (rad/s) a body may reach. Default 100 rad/s; 1e-3 to 1e4.
    pub max_angular_speed: f32,
    /// How a contact combines its bodies' static and kinetic friction coefficients.
    /// Default [`CombineRule::GeometricMean`] `√(μa μb)`; any rule. Rolling resistance
    /// and twist friction always take the larger (see [`Material::combine_with`]).
    pub friction_combine: CombineRule,
    /// How a contact combines its bodies' restitutions. Default [`CombineRule::Max`]
    /// (a bouncy ball bounces on any floor); any rule.
    pub restitution_combine: CombineRule,
}

impl WorldConfig {
    /// The float fields in declaration order (snapshots write them in this order; the
    /// property functions bound them together).
    pub(crate) fn float_fields(&self) -> [f32; 21] {
        [
            self.gravity.x,
            self.gravity.y,
            self.gravity.z,
            self.dt,
            self.contact_hertz,
            self.contact_damping_ratio,
            self.max_push_speed,
            self.restitution_threshold,
            self.slop,
            self.projection_factor,
            self.max_projection,
            self.speculative_margin,
            self.aabb_margin,
            self.stick_speed,
            self.sleep_linear_speed,
            self.sleep_angular_speed,
            self.sleep_time,
            self.ccd_motion_fraction,
            self.hit_event_speed,
            self.max_linear_speed,
            self.max_angular_speed,
        ]
    }

    /// The defaults listed on each field.
    pub const DEFAULT: WorldConfig = WorldConfig {
        gravity: Vec3::new(0.0, -9.81, 0.0),
        dt: 1.0 / 60.0,
        substeps: 4,
        velocity_iterations: 1,
        relax_iterations: 1,
        contact_hertz: 45.0,
        contact_damping_ratio: 10.0,
        max_push_speed: 1.0,
        position_iterations: 1,
        restitution_threshold: 1.0,
        slop: LINEAR_SLOP,
        projection_factor: 0.2,
        max_projection: 0.01,
        speculative_margin: 2.0 * LINEAR_SLOP,
        aabb_margin: 0.05,
        stick_speed: 0.01,
        sleep_linear_speed: 0.05,
        sleep_angular_speed: 0.05,
        sleep_time: 0.5,
        sleep_enabled: true,
        ccd_motion_fraction: 0.25,
        hit_event_speed: 1.0,
        max_linear_speed: 1000.0,
        max_angular_speed: 100.0,
        friction_combine: CombineRule::GeometricMean,
        restitution_combine: CombineRule::Max,
    };

    /// Check every field against its documented range; the error names the first bad
    /// one (`NonFinite` for NaN or infinity, `OutOfRange` otherwise). The combine rules
    /// (`friction_combine`, `restitution_combine`) have no range: every rule is valid.
    pub fn validate(&self) -> Result<(), Error> {
        let g = self.gravity;
        for v in [g.x, g.y, g.z] {
            within(v, -1000.0, 1000.0, Input::Gravity)?;
        }
        within(self.dt, 1.0e-5, 1.0, Input::Time)?;
        count(self.substeps, 1, 64)?;
        count(self.velocity_iterations, 1, 64)?;
        count(self.relax_iterations, 1, 64)?;
        within(self.contact_hertz, 0.1, 1000.0, Input::Config)?;
        within(self.contact_damping_ratio, 0.0, 1000.0, Input::Config)?;
        within(self.max_push_speed, 0.0, 100.0, Input::Config)?;
        count(self.position_iterations, 0, 64)?;
        within(self.restitution_threshold, 0.0, 1000.0, Input::Config)?;
        within(self.slop, 0.0, 0.1, Input::Distance)?;
        within(self.projection_factor, 0.0, 1.0, Input::Config)?;
        within(self.max_projection, 0.0, 10.0, Input::Distance)?;
        within(self.speculative_margin, 0.0, 10.0, Input::Distance)?;
        within(self.aabb_margin, 0.0, 10.0, Input::Distance)?;
        within(self.stick_speed, 0.0, 100.0, Input::Config)?;
        within(self.sleep_linear_speed, 0.0, 100.0, Input::Config)?;
        within(self.sleep_angular_speed, 0.0, 100.0, Input::Config)?;
        within(self.sleep_time, 0.0, 1.0e6, Input::Time)?;
        within(self.ccd_motion_fraction, 1.0e-3, 100.0, Input::Config)?;
        within(self.hit_event_speed, 0.0, 1.0e4, Input::Config)?;
        within(self.max_linear_speed, 1.0e-3, 1.0e4, Input::Config)?;
        within(self.max_angular_speed, 1.0e-3, 1.0e4, Input::Config)?;
        Ok(())
    }

    /// The material of a contact between bodies of materials `a` and `b` under this
    /// configuration's combine rules.
    pub(crate) fn combine_materials(&self, a: &Material, b: &Material) -> Material {
        Material::combine_with(a, b, self.friction_combine, self.restitution_combine)
    }

    /// The sub-step `h = dt / substeps` (s).
    #[inline]
    pub fn substep(&self) -> f32 {
        self.dt / self.substeps as f32
    }
}

/// `v` is finite and in `[lo, hi]`.
fn within(v: f32, lo: f32, hi: f32, what: Input) -> Result<f32, Error> {
    if !v.is_finite() {
        return Err(Error::NonFinite(what));
    }
    if v < lo || v > hi {
        return Err(Error::OutOfRange(what));
    }
    Ok(v)
}

/// An iteration count in `[lo, hi]`.
fn count(n: u32, lo: u32, hi: u32) -> Result<u32, Error> {
    if n < lo || n > hi {
        return Err(Error::OutOfRange(Input::Iterations));
    }
    Ok(n)
}

impl Default for WorldConfig {
    fn default() -> Self {
        WorldConfig::DEFAULT
    }
}
