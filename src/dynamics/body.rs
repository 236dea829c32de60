//! Rigid bodies: description, validated state, and the two integration stages of the
//! step (velocities, then positions).

use crate::config::CombineRule;
use crate::error::{finite_vec, non_negative, positive, Error, Input};
use crate::math::{scalar, Aabb, Iso, Mat3, Quat, Vec3};
use crate::shape::Shape;

/// How a body moves.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum BodyKind {
    /// Moved by forces, gravity and contacts.
    Dynamic,
    /// Never moves; infinite mass.
    Static,
    /// Moves with the velocity the user sets; infinite mass, pushes dynamic bodies.
    Kinematic,
}

/// Surface properties. Two touching bodies combine theirs by the world's rules
/// ([`crate::WorldConfig::friction_combine`] and
/// [`crate::WorldConfig::restitution_combine`]); by default restitution by the larger and
/// each friction coefficient by the geometric mean `√(μa μb)`. Rolling resistance and
/// twist friction always take the larger.
///
/// # Examples
///
/// ```
/// use carom::{BodyDesc, Material, Shape, World};
///
/// # fn main() -> Result<(), carom::Error> {
/// let rubber = Material { restitution: 0.8, static_friction: 1.0, kinetic_friction: 0.8, ..Material::DEFAULT };
/// let ice = Material { restitution: 0.1, static_friction: 0.05, kinetic_friction: 0.02, ..Material::DEFAULT };
/// // What a rubber ball on ice gets: the larger restitution, the geometric mean of frictions.
/// let m = Material::combine(&rubber, &ice);
/// assert_eq!(m.restitution, 0.8);
/// assert!((m.kinetic_friction - (0.8f32 * 0.02).sqrt()).abs() < 1e-6);
///
/// let mut world: World<'static, 4, 8> = World::new();
/// world.add(BodyDesc::dynamic(Shape::sphere(0.1)?).material(rubber))?;
/// // Materials are checked when they enter a world.
/// let bad = Material { restitution: -1.0, ..Material::DEFAULT };
/// assert!(world.add(BodyDesc::dynamic(Shape::sphere(0.1)?).material(bad)).is_err());
/// # Ok(())
/// # }
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "arbitrary", derive(arbitrary::Arbitrary))]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Material {
    /// Coefficient of restitution, 0 (no bounce) to 1 (elastic).
    pub restitution: f32,
    /// Static friction coefficient (≥ 0): the Coulomb cone while a contact sticks.
    pub static_friction: f32,
    /// Kinetic friction coefficient (≥ 0): the cone while a contact slides.
    pub kinetic_friction: f32,
    /// Rolling resistance coefficient (dimensionless, ≥ 0, as a tyre's `c_rr`): a body
    /// rolling on one or two contact points feels a torque of at most
    /// `rolling_resistance · N · r` against its rolling, with `N` the normal force and
    /// `r` its lever arm to the contact. Manifolds of three or more points are flat
    /// patches that do not roll, and skip it.
    pub rolling_resistance: f32,
    /// Twist (torsional) friction coefficient (dimensionless, ≥ 0): a body spinning
    /// about the normal on a single contact point feels a torque of at most
    /// `twist_friction · N · r`. Manifolds of two or more points resist twist through
    /// their points' friction, and skip it.
    pub twist_friction: f32,
}

impl Material {
    /// No bounce, static friction 0.6, kinetic 0.4, rolling resistance 0.01 and twist
    /// friction 0.01 (hard surfaces: a ball at 1 m/s rolls about 7 m).
    pub const DEFAULT: Material = Material {
        restitution: 0.0,
        static_friction: 0.6,
        kinetic_friction: 0.4,
        rolling_resistance: 0.01,
        twist_friction: 0.01,
    };

    /// Largest friction, rolling or twist coefficient accepted.
    pub const MAX_COEFFICIENT: f32 = 100.0;

    /// Check ranges: restitution in `[0, 1]`; friction, rolling and twist coefficients
    /// finite and in `[0, 100]`.
    pub fn validate(&self) -> Result<(), Error> {
        non_negative(self.restitution, Input::Material)?;
        if self.restitution > 1.0 {
            return Err(Error::OutOfRange(Input::Material));
        }
        for c in [
            self.static_friction,
            self.kinetic_friction,
            self.rolling_resistance,
            self.twist_friction,
        ] {
            non_negative(c, Input::Material)?;
            if c > Self::MAX_COEFFICIENT {
                return Err(Error::OutOfRange(Input::Material));
            }
        }
        Ok(())
    }

    /// The material of a contact between `a` and `b` under the default rules
    /// ([`crate::WorldConfig::DEFAULT`]'s): restitution by [`CombineRule::Max`], static
    /// and kinetic friction by [`CombineRule::GeometricMean`]. See
    /// [`Material::combine_with`].
    pub fn combine(a: &Material, b: &Material) -> Material {
        Self::combine_with(a, b, CombineRule::GeometricMean, CombineRule::Max)
    }

    /// The material of a contact between `a` and `b`: static and kinetic friction by
    /// `friction`, restitution by `restitution`, rolling resistance and twist friction
    /// by the larger (whatever the rules). Symmetric in `a` and `b`.
    ///
    /// ```
    /// use carom::{CombineRule, Material};
    ///
    /// let ice = Material { static_friction: 0.0, kinetic_friction: 0.0, ..Material::DEFAULT };
    /// let m = Material::combine_with(&ice, &Material::DEFAULT, CombineRule::Max, CombineRule::Min);
    /// assert_eq!(m.kinetic_friction, Material::DEFAULT.kinetic_friction);
    /// ```
    pub fn combine_with(
        a: &Material,
        b: &Material,
        friction: CombineRule,
        restitution: CombineRule,
    ) -> Material {
        Material {
            restitution: restitution.apply(a.restitution, b.restitution),
            static_friction: friction.apply(a.static_friction, b.static_friction),
            kinetic_friction: friction.apply(a.kinetic_friction, b.kinetic_friction),
            rolling_resistance: scalar::max(a.rolling_resistance, b.rolling_resistance),
            twist_friction: scalar::max(a.twist_friction, b.twist_friction),
        }
    }
}

impl Default for Material {
    fn default() -> Self {
        Material::DEFAULT
    }
}

/// How a dynamic body's mass is given. Either way the resulting mass must be finite and
/// its inverse too: a mass below about 3e-39 kg (1/m overflows `f32`) or an inertia
/// without a finite inverse is refused with `NotPositive(Mass)`.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum MassSpec {
    /// Uniform density (kg/m³); mass and inertia follow from the shape.
    Density(f32),
    /// Total mass (kg); inertia scaled from the shape at uniform density.
    Mass(f32),
}

/// Everything needed to add a body. Build with [`BodyDesc::dynamic`], [`BodyDesc::fixed`]
/// or [`BodyDesc::kinematic`] and chain setters; [`crate::World::add`] validates it.
///
/// # Examples
///
/// ```
/// use carom::{BodyDesc, BodyKind, Quat, Shape, Vec3, World};
///
/// # fn main() -> Result<(), carom::Error> {
/// let mut world: World<'static, 8, 16> = World::new();
/// // A static ground, and a spinning box thrown at it.
/// world.add(
///     BodyDesc::fixed(Shape::cuboid(Vec3::new(10.0, 0.5, 10.0))?)
///         .position(Vec3::new(0.0, -0.5, 0.0)),
/// )?;
/// let cube = world.add(
///     BodyDesc::dynamic(Shape::cuboid(Vec3::splat(0.25))?)
///         .position(Vec3::new(0.0, 2.0, 0.0))
///         .rotation(Quat::from_axis_angle(Vec3::Y, 0.3))
///         .velocity(Vec3::new(1.0, 0.0, 0.0))
///         .angular_velocity(Vec3::new(0.0, 0.0, 2.0))
///         .density(500.0) // kg/m³: 62.5 kg for this box
///         .user_data(42),
/// )?;
/// let body = world.body(cube)?;
/// assert_eq!(body.kind(), BodyKind::Dynamic);
/// assert!((body.mass() - 62.5).abs() < 1e-3);
/// assert_eq!(body.user_data(), 42);
/// # Ok(())
/// # }
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BodyDesc<'a> {
    /// Collision shape (in the body's frame).
    pub shape: Shape<'a>,
    /// Dynamic, static or kinematic.
    pub kind: BodyKind,
    /// Pose of the body's frame in the world.
    pub pose: Iso,
    /// Linear velocity of the centre of mass (m/s).
    pub linear_velocity: Vec3,
    /// Angular velocity (rad/s, world frame).
    pub angular_velocity: Vec3,
    /// Mass or density (dynamic bodies only). Default density 1000 kg/m³ (water).
    pub mass: MassSpec,
    /// Surface material.
    pub material: Material,
    /// Linear damping (1/s): velocity is scaled by `1 / (1 + dt · c)` each step.
    pub linear_damping: f32,
    /// Angular damping (1/s), as linear damping.
    pub angular_damping: f32,
    /// Collision group bits: this body is in these groups.
    pub group: u32,
    /// Collision mask bits: this body collides with bodies in these groups. A pair
    /// collides when `a.group & b.mask != 0 && b.group & a.mask != 0`.
    pub mask: u32,
    /// A sensor reports enter/leave events and never pushes.
    pub sensor: bool,
    /// Sweep this body with time of impact when it moves fast (continuous collision).
    pub ccd: bool,
    /// Free for the user; carom never reads it.
    pub user_data: u64,
}

impl<'a> BodyDesc<'a> {
    fn with_kind(shape: Shape<'a>, kind: BodyKind) -> BodyDesc<'a> {
        BodyDesc {
            shape,
            kind,
            pose: Iso::IDENTITY,
            linear_velocity: Vec3::ZERO,
            angular_velocity: Vec3::ZERO,
            mass: MassSpec::Density(1000.0),
            material: Material::DEFAULT,
            linear_damping: 0.0,
            angular_damping: 0.0,
            group: 1,
            mask: u32::MAX,
            sensor: false,
            ccd: true,
            user_data: 0,
        }
    }

    /// A dynamic body.
    pub fn dynamic(shape: Shape<'a>) -> BodyDesc<'a> {
        Self::with_kind(shape, BodyKind::Dynamic)
    }

    /// A static body (`static` is a keyword).
    pub fn fixed(shape: Shape<'a>) -> BodyDesc<'a> {
        Self::with_kind(shape, BodyKind::Static)
    }

    /// A kinematic body.
    pub fn kinematic(shape: Shape<'a>) -> BodyDesc<'a> {
        Self::with_kind(shape, BodyKind::Kinematic)
    }

    /// Set the position (m).
    pub fn position(mut self, p: Vec3) -> Self {
        self.pose.position = p;
        self
    }

    /// Set the rotation (unit quaternion).
    pub fn rotation(mut self, q: Quat) -> Self {
        self.pose.rotation = q;
        self
    }

    /// Set the linear velocity (m/s).
    pub fn velocity(mut self, v: Vec3) -> Self {
        self.linear_velocity = v;
        self
    }

    /// Set the angular velocity (rad/s).
    pub fn angular_velocity(mut self, w: Vec3) -> Self {
        self.angular_velocity = w;
        self
    }

    /// Set a uniform density (kg/m³).
    pub fn density(mut self, d: f32) -> Self {
        self.mass = MassSpec::Density(d);
        self
    }

    /// Set the total mass (kg).
    pub fn mass(mut self, m: f32) -> Self {
        self.mass = MassSpec::Mass(m);
        self
    }

    /// Set the material.
    pub fn material(mut self, m: Material) -> Self {
        self.material = m;
        self
    }

    /// Set linear and angular damping (1/s).
    pub fn damping(mut self, linear: f32, angular: f32) -> Self {
        self.linear_damping = linear;
        self.angular_damping = angular;
        self
    }

    /// Set collision group and mask bits.
    pub fn filter(mut self, group: u32, mask: u32) -> Self {
        self.group = group;
        self.mask = mask;
        self
    }

    /// Make the body a sensor (or not).
    pub fn sensor(mut self, on: bool) -> Self {
        self.sensor = on;
        self
    }

    /// Switch continuous collision on or off (default on).
    pub fn ccd(mut self, on: bool) -> Self {
        self.ccd = on;
        self
    }

    /// Set user data.
    pub fn user_data(mut self, d: u64) -> Self {
        self.user_data = d;
        self
    }
}

/// A body's state inside the world.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Body<'a> {
    pub shape: Shape<'a>,
    /// `shape.bounding_radius()` (m), formed once: a body's shape never changes, and the
    /// contact update, continuous collision and the broad phase read it for every pair or
    /// body in every step (a cuboid's is a square root, a hull's a load through its
    /// reference).
    pub bounding_radius: f32,
    /// How far (m) the core of the shape reaches from the centre of mass, at most: the
    /// core's reach from the origin ([`Body::core_reach`]) plus the centre of mass's L1
    /// distance from it. Formed once, as `bounding_radius` (the shape and the centre of
    /// mass never change): every pair's closing bound reads it in every step.
    pub turn_reach: f32,
    /// `|ω| turn_reach` (m/s): the fastest the body's turn moves a point of its core
    /// (the spin's share of a pair's closing bound, `contact::closing_bound`). Formed for
    /// every body at the start of the narrow phase ([`Body::refresh_spin_reach`]), once
    /// per body instead of once per pair (two square roots per pair fewer; the same
    /// product, so the same bits). Derived, not state: a snapshot neither holds nor needs
    /// it.
    pub spin_reach: f32,
    pub kind: BodyKind,
    /// Pose of the body frame (the shape's frame) in the world: read through
    /// [`Body::pose`], changed only through [`Body::place`] (which keeps `center_world`).
    pose: Iso,
    /// `Mat3::from_quat(pose.rotation)`, kept with the pose (every write goes through
    /// [`Body::place`]): the solver's gather and the shape's box read it every step.
    rot: Mat3,
    /// Centre of mass in the body frame.
    pub center_local: Vec3,
    /// Centre of mass in the world (m), `pose.transform_point(center_local)`: kept by
    /// [`Body::place`], which every change of `pose` goes through.
    center_world: Vec3,
    /// Velocity of the centre of mass (m/s).
    pub linear_velocity: Vec3,
    /// Angular velocity (rad/s, world).
    pub angular_velocity: Vec3,
    /// Force (N) and torque (N·m) accumulated for the next step, then cleared.
    pub force: Vec3,
    pub torque: Vec3,
    /// Inverse mass (1/kg); 0 for static and kinematic bodies.
    pub inv_mass: f32,
    /// How the mass was given: inverse mass, inertia and centre of mass are derived from
    /// it and the shape (also when a snapshot is restored).
    pub mass: MassSpec,
    /// Inverse inertia about the centre of mass, body axes.
    pub inv_inertia_local: Mat3,
    /// `R I⁻¹ Rᵀ`, refreshed whenever the rotation changes.
    pub inv_inertia_world: Mat3,
    pub material: Material,
    pub linear_damping: f32,
    pub angular_damping: f32,
    pub group: u32,
    pub mask: u32,
    pub sensor: bool,
    pub ccd: bool,
    pub awake: bool,
    /// Seconds the body has been slow enough to sleep.
    pub sleep_time: f32,
    pub user_data: u64,
    /// Pose at the start of the current step (for continuous collision).
    pub pose0: Iso,
    /// The broad phase's enlarged box (world, m): it holds the body's movement bounds
    /// over the step; a body whose movement leaves it gets a new one and looks for new
    /// candidate pairs. Static bodies have their exact box.
    pub fat: Aabb,
    /// Set when `fat` was replaced (or the body was added or teleported): the broad phase
    /// looks for the body's new pairs and clears it.
    pub moved: bool,
    /// Set while the part lists of the body's pairs with meshes and compounds may have
    /// changed since the mid phase last formed them (`mid_phase`, "Lists kept"): the
    /// broad phase sets it with every `moved` it clears, and a new or restored body
    /// starts with it; stage 4 clears it once it has placed every list whole. Derived
    /// state: not in snapshots.
    pub relist: bool,
    /// A box (world, m) around the shape at `pose` for the narrow phase's test of empty
    /// pairs ([`Body::refresh_bounds`]), formed each step: by the broad phase for the
    /// bodies whose movement bounds it forms (awake, not static), at the start of the
    /// narrow phase for the others. Derived, not state: a snapshot neither holds nor
    /// needs it.
    pub bounds: Aabb,
}

/// A shape built from its public fields must satisfy what its constructor checks: the
/// constructor is run again on the fields (`World::add` and snapshot restore both come
/// through here). A half-space's normal must already be unit length (to 1e-3 in `|n|²`).
pub(crate) fn check_shape(shape: &Shape<'_>) -> Result<(), Error> {
    use crate::shape::{Capsule, Cuboid, HalfSpace, Sphere, Triangle};
    match shape {
        Shape::Sphere(s) => Sphere::new(s.radius).map(|_| ()),
        Shape::Capsule(c) => Capsule::new(c.half_height, c.radius).map(|_| ()),
        Shape::Cuboid(c) => Cuboid::new(c.half_extents).map(|_| ()),
        Shape::HalfSpace(h) => {
            HalfSpace::new(h.normal)?;
            if scalar::abs(h.normal.length_squared() - 1.0) > 1.0e-3 {
                return Err(Error::NotUnit(Input::Direction));
            }
            Ok(())
        }
        Shape::Triangle(t) => {
            let [a, b, c] = t.vertices;
            Triangle::new(a, b, c).map(|_| ())
        }
        // Hulls can only come from `ConvexHull::new`, which validated them.
        Shape::Hull(_) => Ok(()),
        // Meshes and compounds have private fields: their constructors checked them.
        Shape::Mesh(_) | Shape::HeightField(_) | Shape::Compound(_) => Ok(()),
    }
}

impl<'a> Body<'a> {
    /// Validate a description and derive mass properties.
    pub fn from_desc(d: &BodyDesc<'a>) -> Result<Body<'a>, Error> {
        crate::error::position(d.pose.position)?;
        Self::from_desc_anywhere(d)
    }

    /// [`Body::from_desc`] without the position range check (snapshot restore, whose
    /// bodies may have travelled beyond it). The position must still be finite.
    pub fn from_desc_anywhere(d: &BodyDesc<'a>) -> Result<Body<'a>, Error> {
        finite_vec(d.pose.position, Input::Position)?;
        check_shape(&d.shape)?;
        if !d.pose.rotation.is_finite() {
            return Err(Error::NonFinite(Input::Rotation));
        }
        if !d.pose.rotation.is_unit() {
            return Err(Error::NotUnit(Input::Rotation));
        }
        finite_vec(d.linear_velocity, Input::LinearVelocity)?;
        finite_vec(d.angular_velocity, Input::AngularVelocity)?;
        d.material.validate()?;
        non_negative(d.linear_damping, Input::Damping)?;
        non_negative(d.angular_damping, Input::Damping)?;
        let (inv_mass, inv_inertia_local, center_local) = match d.kind {
            BodyKind::Dynamic => {
                if d.shape.is_static_only() {
                    return Err(Error::StaticOnly);
                }
                let props = match d.mass {
                    MassSpec::Density(rho) => {
                        d.shape.mass_properties(positive(rho, Input::Density)?)?
                    }
                    MassSpec::Mass(m) => {
                        let m = positive(m, Input::Mass)?;
                        let unit = d.shape.mass_properties(1.0)?;
                        let k = m / unit.mass;
                        crate::shape::MassProperties {
                            mass: m,
                            center: unit.center,
                            inertia: unit.inertia.scale(k),
                        }
                    }
                };
                let inv_i = props
                    .inertia
                    .inverse()
                    .filter(|m| m.is_finite())
                    .ok_or(Error::NotPositive(Input::Mass))?;
                // A mass so small that 1/m overflows f32 (below about 3e-39 kg, a
                // subnormal density) is no mass a solver can use: refused like zero.
                let inv_mass = 1.0 / props.mass;
                if !(props.mass > 0.0 && props.mass.is_finite() && inv_mass.is_finite()) {
                    return Err(Error::NotPositive(Input::Mass));
                }
                (inv_mass, inv_i, props.center)
            }
            BodyKind::Static | BodyKind::Kinematic => (0.0, Mat3::ZERO, Vec3::ZERO),
        };
        let rotation = d.pose.rotation.normalize();
        let pose = Iso::new(d.pose.position, rotation);
        let still = d.kind == BodyKind::Static;
        let bounding_radius = d.shape.bounding_radius();
        let c = center_local.abs();
        let mut b = Body {
            shape: d.shape,
            bounding_radius,
            turn_reach: crate::shape::core_reach_within(bounding_radius, d.shape.radius())
                + ((c.x + c.y) + c.z),
            kind: d.kind,
            pose,
            rot: Mat3::from_quat(pose.rotation),
            center_local,
            center_world: pose.transform_point(center_local),
            linear_velocity: if still { Vec3::ZERO } else { d.linear_velocity },
            angular_velocity: if still {
                Vec3::ZERO
            } else {
                d.angular_velocity
            },
            force: Vec3::ZERO,
            torque: Vec3::ZERO,
            inv_mass,
            // Only a dynamic body's mass means anything; the others keep a canonical 0.
            mass: if d.kind == BodyKind::Dynamic {
                d.mass
            } else {
                MassSpec::Density(0.0)
            },
            inv_inertia_local,
            inv_inertia_world: Mat3::ZERO,
            material: d.material,
            linear_damping: d.linear_damping,
            angular_damping: d.angular_damping,
            group: d.group,
            mask: d.mask,
            sensor: d.sensor,
            ccd: d.ccd,
            awake: !still,
            sleep_time: 0.0,
            user_data: d.user_data,
            pose0: pose,
            fat: d.shape.aabb(&pose),
            moved: true,
            relist: true,
            bounds: d.shape.aabb(&pose),
            spin_reach: 0.0,
        };
        b.update_inertia();
        b.refresh_bounds();
        b.refresh_spin_reach();
        Ok(b)
    }

    /// Form [`Body::bounds`] at the current pose: the shape's exact box when it costs a
    /// few products (sphere, capsule, cuboid, triangle), else the box of its bounding
    /// sphere about the body's origin (a hull's exact box is a pass over its vertices).
    pub fn refresh_bounds(&mut self) {
        self.bounds = if self.exact_bounds() {
            self.shape.aabb_turned(&self.pose, &self.rot)
        } else {
            self.sphere_bounds()
        };
    }

    /// Form [`Body::spin_reach`] from the angular velocity now.
    #[inline]
    pub fn refresh_spin_reach(&mut self) {
        self.spin_reach = self.angular_velocity.length() * self.turn_reach;
    }

    /// [`Body::refresh_bounds`] given the shape's exact box at the current pose (the
    /// broad phase forms it anyway).
    pub fn refresh_bounds_from(&mut self, exact: Aabb) {
        self.bounds = if self.exact_bounds() {
            exact
        } else {
            self.sphere_bounds()
        };
    }

    /// True when [`Body::bounds`] is the shape's exact box.
    #[inline]
    fn exact_bounds(&self) -> bool {
        matches!(
            self.shape,
            Shape::Sphere(_) | Shape::Capsule(_) | Shape::Cuboid(_) | Shape::Triangle(_)
        )
    }

    /// The box of the shape's bounding sphere about the body's origin.
    #[inline]
    fn sphere_bounds(&self) -> Aabb {
        Aabb::from_center_half(self.pose.position, Vec3::splat(self.bounding_radius))
    }

    /// True for a dynamic body.
    #[inline]
    pub fn is_dynamic(&self) -> bool {
        self.kind == BodyKind::Dynamic
    }

    /// [`Shape::core_reach`] from the kept bounding radius (a cuboid's is a square root).
    #[inline]
    pub fn core_reach(&self) -> f32 {
        crate::shape::core_reach_within(self.bounding_radius, self.shape.radius())
    }

    /// Centre of mass in the world (m).
    #[inline]
    pub fn world_center(&self) -> Vec3 {
        self.center_world
    }

    /// Pose of the body frame (the shape's frame) in the world.
    #[inline(always)]
    pub fn pose(&self) -> &Iso {
        &self.pose
    }

    /// The pose's rotation as a matrix, `Mat3::from_quat(pose().rotation)`.
    #[inline(always)]
    pub fn rotation_matrix(&self) -> &Mat3 {
        &self.rot
    }

    /// Put the body frame at `pose`, its centre of mass with it.
    #[inline]
    pub fn place(&mut self, pose: Iso) {
        self.place_turned(pose, &Mat3::from_quat(pose.rotation));
    }

    /// [`Body::place`] given `r = Mat3::from_quat(pose.rotation)`.
    #[inline]
    fn place_turned(&mut self, pose: Iso, r: &Mat3) {
        self.pose = pose;
        self.rot = *r;
        self.center_world = pose.transform_point(self.center_local);
    }

    /// Refresh `R I⁻¹ Rᵀ` after the rotation changed.
    #[inline]
    pub fn update_inertia(&mut self) {
        let r = self.rot;
        self.update_inertia_turned(&r);
    }

    /// [`Body::update_inertia`] given `r`, the pose's rotation as a matrix.
    #[inline]
    fn update_inertia_turned(&mut self, r: &Mat3) {
        if self.is_dynamic() {
            self.inv_inertia_world = self.inv_inertia_local.rotated(r);
        }
    }

    /// Velocity of the world point `p` (m/s): `v + ω × (p − c)`.
    #[inline]
    pub fn velocity_at(&self, p: Vec3) -> Vec3 {
        self.linear_velocity + self.angular_velocity.cross(p - self.world_center())
    }

    /// Apply an impulse `j` (N·s) at the world point `p`.
    #[inline]
    pub fn apply_impulse_at(&mut self, j: Vec3, p: Vec3) {
        if self.is_dynamic() {
            let r = p - self.world_center();
            self.linear_velocity += j * self.inv_mass;
            self.angular_velocity += self.inv_inertia_world.mul_vec(r.cross(j));
        }
    }

    /// Move the body so its centre of mass is at `c` with rotation `q` (projection, CCD).
    pub fn set_center_pose(&mut self, c: Vec3, q: Quat) {
        self.place(Iso::new(c - q.rotate(self.center_local), q));
        self.update_inertia();
    }

    /// [`Body::set_center_pose`] given `r = Mat3::from_quat(q)` (the solver keeps it).
    pub fn set_center_pose_turned(&mut self, c: Vec3, q: Quat, r: &Mat3) {
        self.place_turned(Iso::new(c - q.rotate(self.center_local), q), r);
        self.update_inertia_turned(r);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shape::ConvexHull;

    /// Every body's kept rotation matrix is `Mat3::from_quat` of its rotation, bit for
    /// bit: at creation, after steps of the solver (which hands its own matrix over),
    /// after `set_center_pose` (what projection and continuous collision move bodies
    /// with), after a teleport and after a snapshot is restored.
    #[test]
    fn the_kept_rotation_matrix_is_the_rotations_to_the_bit() {
        use crate::{World, WorldConfig};
        fn check(world: &World<'_, 64, 512, 64>, when: &str) -> usize {
            let mut n = 0;
            for (_, b) in world.bodies.iter() {
                let want = Mat3::from_quat(b.pose().rotation);
                let got = b.rotation_matrix();
                for (g, w) in [(got.x, want.x), (got.y, want.y), (got.z, want.z)] {
                    assert!(
                        g.x.to_bits() == w.x.to_bits()
                            && g.y.to_bits() == w.y.to_bits()
                            && g.z.to_bits() == w.z.to_bits(),
                        "{when}: {got:?} against {want:?}"
                    );
                }
                n += 1;
            }
            n
        }
        let cube = Shape::cuboid(Vec3::new(0.5, 0.3, 0.4)).unwrap();
        let ball = Shape::sphere(0.3).unwrap();
        let mut world: std::boxed::Box<World<'_, 64, 512, 64>> =
            std::boxed::Box::new(World::with_config(WorldConfig::DEFAULT).unwrap());
        let ground = Shape::cuboid(Vec3::new(20.0, 0.5, 20.0)).unwrap();
        world
            .add(BodyDesc::fixed(ground).position(Vec3::new(0.0, -0.5, 0.0)))
            .unwrap();
        let mut rng = crate::rng::SplitMix64::new(17);
        let mut handles = std::vec::Vec::new();
        for i in 0..24 {
            let shape = if i % 3 == 0 { ball } else { cube };
            let desc = BodyDesc::dynamic(shape)
                .position(Vec3::new(
                    rng.range(-2.0, 2.0),
                    0.4 + 0.5 * i as f32,
                    rng.range(-2.0, 2.0),
                ))
                .rotation(rng.rotation())
                .angular_velocity(rng.unit_vector() * rng.range(0.0, 8.0))
                .ccd(i % 5 == 0);
            handles.push(world.add(desc).unwrap());
        }
        assert_eq!(check(&world, "created"), 25);
        for _ in 0..90 {
            world.step();
        }
        check(&world, "after 90 steps");
        for (_, b) in world.bodies.iter_mut() {
            let c = b.world_center() + Vec3::new(0.0, 0.01, 0.0);
            b.set_center_pose(c, rng.rotation());
        }
        check(&world, "after set_center_pose");
        let moved = handles[3];
        world
            .set_pose(moved, Iso::new(Vec3::new(0.0, 3.0, 0.0), rng.rotation()))
            .unwrap();
        check(&world, "after a teleport");
        let mut buf = std::vec![0u8; world.snapshot_len()];
        world.snapshot(&mut buf).unwrap();
        for _ in 0..30 {
            world.step();
        }
        world.restore(&buf).unwrap();
        check(&world, "after a restore");
    }

    #[test]
    fn a_body_keeps_its_shapes_bounding_radius_to_the_bit() {
        let points = [
            Vec3::new(0.3, -0.2, 0.1),
            Vec3::new(-0.4, 0.5, 0.2),
            Vec3::new(0.1, 0.2, -0.6),
            Vec3::new(0.2, 0.7, 0.5),
            Vec3::new(-0.3, -0.4, -0.2),
        ];
        let hull = ConvexHull::new(&points).unwrap();
        let shapes = [
            Shape::sphere(0.7).unwrap(),
            Shape::capsule(0.9, 0.2).unwrap(),
            Shape::cuboid(Vec3::new(0.5, 0.25, 1.5)).unwrap(),
            Shape::triangle(Vec3::ZERO, Vec3::X, Vec3::new(0.0, 2.0, 1.0)).unwrap(),
            Shape::half_space(Vec3::Y).unwrap(),
            Shape::hull(&hull),
        ];
        let mut built = 0;
        for shape in shapes {
            // A half-space or triangle cannot be dynamic: those descriptions are refused.
            for desc in [BodyDesc::dynamic(shape), BodyDesc::fixed(shape)] {
                let Ok(body) = Body::from_desc(&desc.position(Vec3::new(1.0, 2.0, 3.0))) else {
                    continue;
                };
                built += 1;
                assert_eq!(
                    body.bounding_radius.to_bits(),
                    shape.bounding_radius().to_bits(),
                    "{shape:?}"
                );
            }
        }
        assert!(built >= 10, "{built} bodies built");
    }
}
