//! The engine-neutral description of a scene: a list of [`SceneBody`]s, produced one at a
//! time by [`super::Scene::for_each_body`], with nothing carom-specific in it, so carom's
//! [`super::Scene::build`] and another engine's builder (the side-by-side comparison in
//! `compare/`) add the same bodies from one definition.

use crate::dynamics::body::{BodyDesc, Material};
use crate::error::{Error, Input};
use crate::math::{Quat, Vec3};
use crate::shape::{ConvexHull, Shape};

/// The collision shape of a [`SceneBody`], in the body's frame (centred on its origin).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SceneShape {
    /// A ball.
    Sphere {
        /// Radius (m).
        radius: f32,
    },
    /// A capsule along the body's local Y axis: a segment from `(0, −half_height, 0)` to
    /// `(0, half_height, 0)` inflated by `radius`.
    Capsule {
        /// Half the length of the core segment (m).
        half_height: f32,
        /// Radius (m).
        radius: f32,
    },
    /// A box.
    Cuboid {
        /// Half-extents along the body's local axes (m).
        half_extents: Vec3,
    },
    /// A convex hull: an index into the hulls slice the scene was asked for (always below
    /// the `hulls_len` given to [`super::Scene::for_each_body`]). Another engine should
    /// build its hull from that hull's [`ConvexHull::vertices`], so both see one polytope.
    Hull(usize),
    /// The scene's ground, supplied by the caller ([`super::Scene::build_on`]): in
    /// `mesh_pile`, the height field of [`super::mesh_pile_heights`] with
    /// [`super::MESH_PILE_COLUMNS`] samples a side, [`super::MESH_PILE_CELL`] apart; in
    /// `terrain` and `terrain_mesh`, [`super::TerrainShapes`]. Its corner is at the
    /// body's position. Another engine builds it from the same heights (as a triangle
    /// mesh of the same triangles: [`crate::shape::HeightField::triangle`]).
    Terrain,
}

/// How a [`SceneBody`] moves.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SceneKind {
    /// Moved by gravity and contacts.
    Dynamic,
    /// Never moves (ground, walls).
    Static,
}

/// One body of a standard scene, engine-neutral. Units are SI.
///
/// The surface fields are per body; a contact combines two bodies' values as carom does:
/// restitution by the larger, each friction coefficient by the geometric mean.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SceneBody {
    /// Collision shape.
    pub shape: SceneShape,
    /// Dynamic or static.
    pub kind: SceneKind,
    /// Position of the body's origin (the shape's centre) in the world (m).
    pub position: Vec3,
    /// Orientation (unit quaternion).
    pub rotation: Quat,
    /// Initial linear velocity (m/s); zero for static bodies.
    pub velocity: Vec3,
    /// Uniform density (kg/m³); mass and inertia follow from the shape. Read for dynamic
    /// bodies only.
    pub density: f32,
    /// Coefficient of restitution, 0 to 1.
    pub restitution: f32,
    /// Static friction coefficient (an engine with a single coefficient uses this one).
    pub static_friction: f32,
    /// Kinetic (sliding) friction coefficient.
    pub kinetic_friction: f32,
    /// Linear damping (1/s); 0 in every scene but `jolt_pyramid`.
    pub linear_damping: f32,
    /// Angular damping (1/s); 0 in every scene but `jolt_pyramid`.
    pub angular_damping: f32,
}

impl SceneBody {
    /// A body of `kind` and `shape` at the origin, unrotated, at rest, with carom's
    /// defaults: density 1000 kg/m³, [`Material::DEFAULT`] (no bounce, static friction
    /// 0.6, kinetic 0.4), no damping.
    pub const fn new(kind: SceneKind, shape: SceneShape) -> SceneBody {
        SceneBody {
            shape,
            kind,
            position: Vec3::ZERO,
            rotation: Quat::IDENTITY,
            velocity: Vec3::ZERO,
            density: 1000.0,
            restitution: Material::DEFAULT.restitution,
            static_friction: Material::DEFAULT.static_friction,
            kinetic_friction: Material::DEFAULT.kinetic_friction,
            linear_damping: 0.0,
            angular_damping: 0.0,
        }
    }

    /// A dynamic body (see [`SceneBody::new`] for the defaults).
    pub const fn dynamic(shape: SceneShape) -> SceneBody {
        SceneBody::new(SceneKind::Dynamic, shape)
    }

    /// A static body (see [`SceneBody::new`] for the defaults).
    pub const fn fixed(shape: SceneShape) -> SceneBody {
        SceneBody::new(SceneKind::Static, shape)
    }

    /// The same body at `position`.
    pub const fn at(mut self, position: Vec3) -> SceneBody {
        self.position = position;
        self
    }

    /// The surface as a carom [`Material`].
    pub const fn material(&self) -> Material {
        Material {
            restitution: self.restitution,
            static_friction: self.static_friction,
            kinetic_friction: self.kinetic_friction,
            ..Material::DEFAULT
        }
    }

    /// The same body with the surface of `m`.
    pub const fn with_material(mut self, m: Material) -> SceneBody {
        self.restitution = m.restitution;
        self.static_friction = m.static_friction;
        self.kinetic_friction = m.kinetic_friction;
        self
    }

    /// The carom shape; `hulls` resolves [`SceneShape::Hull`] (an index past its end is
    /// `Error::OutOfRange(Input::Config)`), and [`SceneShape::Terrain`] needs
    /// [`SceneBody::shape_on`] (here it is `Error::OutOfRange(Input::Config)`).
    pub fn shape<'a>(&self, hulls: &'a [ConvexHull]) -> Result<Shape<'a>, Error> {
        self.shape_on(hulls, None)
    }

    /// [`SceneBody::shape`], with `terrain` for [`SceneShape::Terrain`] (`None`:
    /// `Error::OutOfRange(Input::Config)`).
    pub fn shape_on<'a>(
        &self,
        hulls: &'a [ConvexHull],
        terrain: Option<Shape<'a>>,
    ) -> Result<Shape<'a>, Error> {
        match self.shape {
            SceneShape::Terrain => terrain.ok_or(Error::OutOfRange(Input::Config)),
            SceneShape::Sphere { radius } => Shape::sphere(radius),
            SceneShape::Capsule {
                half_height,
                radius,
            } => Shape::capsule(half_height, radius),
            SceneShape::Cuboid { half_extents } => Shape::cuboid(half_extents),
            SceneShape::Hull(i) => hulls
                .get(i)
                .map(Shape::hull)
                .ok_or(Error::OutOfRange(Input::Config)),
        }
    }

    /// The carom [`BodyDesc`] of this body (shape resolved as [`SceneBody::shape`]); every
    /// field not described here keeps [`BodyDesc`]'s default. [`crate::World::add`]
    /// validates it.
    pub fn desc<'a>(&self, hulls: &'a [ConvexHull]) -> Result<BodyDesc<'a>, Error> {
        self.desc_on(hulls, None)
    }

    /// [`SceneBody::desc`], with `terrain` for [`SceneShape::Terrain`].
    pub fn desc_on<'a>(
        &self,
        hulls: &'a [ConvexHull],
        terrain: Option<Shape<'a>>,
    ) -> Result<BodyDesc<'a>, Error> {
        let shape = self.shape_on(hulls, terrain)?;
        let desc = match self.kind {
            SceneKind::Dynamic => BodyDesc::dynamic(shape),
            SceneKind::Static => BodyDesc::fixed(shape),
        };
        Ok(desc
            .position(self.position)
            .rotation(self.rotation)
            .velocity(self.velocity)
            .density(self.density)
            .material(self.material())
            .damping(self.linear_damping, self.angular_damping))
    }
}
