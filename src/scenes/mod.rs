//! The standard scenes of `SCENES.md`, defined once and shared by tests, benchmarks,
//! demos and the side-by-side comparison with other engines. Units are SI, gravity −Y,
//! dt 1/60. "Jitter" comes from [`SplitMix64`] with a fixed seed, so every target builds
//! the same scene.
//!
//! Every scene is first an engine-neutral list of bodies ([`SceneBody`]), produced one at
//! a time by [`Scene::for_each_body`] without allocating; carom's [`Scene::build`] adds
//! that list to a [`World`], and another engine's builder can add the same list to its own
//! world.
//!
//! - [`Scene`]: the world scenes; [`Scene::REFERENCE`] are the ones whose checksums are
//!   golden, run by [`Scene::run`] in a [`ReferenceWorld`].
//! - [`SceneBody`], [`SceneShape`], [`SceneKind`]: the neutral description of one body.
//! - [`narrow`]: the cross-target narrow-phase workload (the golden `narrow` line).
//! - [`queries`]: the query sets of the narrow-phase benchmarks.
//! - [`GoldenLine`]: one line of `tests/golden/checksums.txt`, as every target prints it.

use crate::dynamics::body::Material;
use crate::dynamics::BodyHandle;
use crate::error::{Error, Input};
use crate::math::Vec3;
use crate::rng::SplitMix64;
use crate::shape::{ConvexHull, HeightField, Shape};
use crate::World;

pub mod narrow;
mod neutral;
pub mod queries;
mod terrain;

pub use neutral::{SceneBody, SceneKind, SceneShape};
pub use terrain::{
    TerrainData, TerrainShapes, TERRAIN_CELL, TERRAIN_COLUMNS, TERRAIN_NODES, TERRAIN_SAMPLES,
    TERRAIN_TRIANGLES,
};

/// The world type the reference scenes run in on every target (capacities are part of
/// what a golden checksum means: drop rules depend on them). 1024 contact slots: the
/// `mixed` pile peaks at 536 candidate pairs, so none is dropped (with 512 it dropped
/// pairs from step 104 on, and bodies sank into each other). About 1.1 MB on a 64-bit
/// host, 1.2 MiB of static RAM on a Cortex-M.
pub type ReferenceWorld<'a> = World<'a, 128, 1024, 64>;

/// Hulls the reference scenes use, built by [`make_hulls`] with [`SEED`].
pub const REFERENCE_HULLS: usize = 8;

/// Seed of every scene's jitter.
pub const SEED: u64 = 0x00C0_FFEE_CA20_0001;

/// Points per hull in the `hulls` scene and the narrow-phase query set.
pub const HULL_POINTS: usize = 16;

/// A standard scene.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Scene {
    /// Wall pyramid with a base of 20 boxes (210 boxes), 500 steps.
    Pyramid20,
    /// Wall pyramid with a base of 100 boxes (5050 boxes), 200 steps.
    Pyramid100,
    /// 1000 boxes in a 10×10×10 grid, 300 steps.
    Boxes,
    /// 4096 spheres in a 16×16×16 grid inside four walls, 300 steps.
    Spheres,
    /// 500 convex hulls in a jittered grid, 300 steps.
    Hulls,
    /// A 5 cm sphere at 500 m/s against a 10 cm wall, no gravity, 60 steps.
    Bullet,
    /// A chaotic pile of mixed shapes in a walled box, 1000 steps (determinism).
    Mixed,
    /// Reference scene: small fast spheres fired at thin walls and at each other in a
    /// closed room, continuous collision at work, 1000 steps (determinism).
    Bullets,
    /// Reference scene: a tower of 10 boxes that comes to rest and sleeps, 1000 steps
    /// (determinism).
    Tower,
    /// Jolt Physics' `PerformanceTest` pyramid (`PerformanceTest/PyramidScene.h`): 1240
    /// boxes of 2 m in 15 square layers, 500 steps. See [`jolt_pyramid`].
    JoltPyramid,
    /// 300 mixed bodies (boxes, spheres, capsules, hulls) falling on a bumpy height field
    /// of 10,368 triangles, 300 steps (issue 9's "mesh pile"). Its terrain comes from the
    /// caller: see [`mesh_pile_heights`] and [`Scene::build_on`].
    MeshPile,
    /// Reference scene: 40 mixed bodies (boxes, spheres, capsules, hulls) dropped into a
    /// bowl-shaped height field of 512 triangles, where they slide into a pile, 600 steps
    /// (determinism of the mid phase). Its ground comes from the caller:
    /// [`TerrainShapes::ground`].
    Terrain,
    /// Reference scene: [`Scene::Terrain`] on the same triangles as a [`TriangleMesh`]
    /// with its hierarchy (`crate::shape::TriangleMesh`), 600 steps.
    ///
    /// [`TriangleMesh`]: crate::shape::TriangleMesh
    TerrainMesh,
}

impl Scene {
    /// Every scene: those of SCENES.md in its order, then `jolt_pyramid`, `mesh_pile` and
    /// the two terrain reference scenes.
    pub const ALL: [Scene; 13] = [
        Scene::Pyramid20,
        Scene::Pyramid100,
        Scene::Boxes,
        Scene::Spheres,
        Scene::Hulls,
        Scene::Bullet,
        Scene::Mixed,
        Scene::Bullets,
        Scene::Tower,
        Scene::JoltPyramid,
        Scene::MeshPile,
        Scene::Terrain,
        Scene::TerrainMesh,
    ];

    /// The reference scenes whose checksums after their steps are kept in
    /// `tests/golden/checksums.txt` and checked on every target.
    /// `terrain` and `terrain_mesh` need their ground: run them with [`Scene::run_on`].
    pub const REFERENCE: [Scene; 5] = [
        Scene::Mixed,
        Scene::Bullets,
        Scene::Tower,
        Scene::Terrain,
        Scene::TerrainMesh,
    ];

    /// The scene's name in SCENES.md.
    pub fn name(self) -> &'static str {
        match self {
            Scene::Pyramid20 => "pyramid20",
            Scene::Pyramid100 => "pyramid100",
            Scene::Boxes => "boxes",
            Scene::Spheres => "spheres",
            Scene::Hulls => "hulls",
            Scene::Bullet => "bullet",
            Scene::Mixed => "mixed",
            Scene::Bullets => "bullets",
            Scene::Tower => "tower",
            Scene::JoltPyramid => "jolt_pyramid",
            Scene::MeshPile => "mesh_pile",
            Scene::Terrain => "terrain",
            Scene::TerrainMesh => "terrain_mesh",
        }
    }

    /// The scene called `name` ([`Scene::name`]), if any.
    pub fn from_name(name: &str) -> Option<Scene> {
        Scene::ALL.into_iter().find(|s| s.name() == name)
    }

    /// Steps the scene is run for.
    pub fn steps(self) -> u32 {
        match self {
            Scene::Pyramid20 | Scene::JoltPyramid => 500,
            Scene::Pyramid100 => 200,
            Scene::Boxes | Scene::Spheres | Scene::Hulls | Scene::MeshPile => 300,
            Scene::Bullet => 60,
            Scene::Terrain | Scene::TerrainMesh => 600,
            Scene::Mixed | Scene::Bullets | Scene::Tower => 1000,
        }
    }

    /// Bodies the scene adds (ground and walls included).
    pub fn body_count(self) -> usize {
        match self {
            Scene::Pyramid20 => 1 + 210,
            Scene::Pyramid100 => 1 + 5050,
            Scene::Boxes => 1 + 1000,
            Scene::Spheres => 5 + 4096,
            Scene::Hulls => 1 + 500,
            Scene::Bullet => 2,
            Scene::Mixed => MIXED_WALLS + MIXED_BODIES,
            Scene::Bullets => 6 + BULLETS,
            Scene::Tower => 11,
            Scene::JoltPyramid => 1 + JOLT_PYRAMID_BOXES,
            Scene::MeshPile => 1 + MESH_PILE_BODIES,
            Scene::Terrain | Scene::TerrainMesh => 1 + TERRAIN_BODIES,
        }
    }

    /// Position in [`Scene::for_each_body`]'s order of the body to watch: the top box of
    /// the pyramids and the tower, the bullet, otherwise the first dynamic body.
    pub fn watched(self) -> usize {
        match self {
            Scene::Pyramid20 => pyramid_top(20),
            Scene::Pyramid100 => pyramid_top(100),
            Scene::Boxes | Scene::Hulls | Scene::Bullet | Scene::MeshPile => 1,
            Scene::Terrain | Scene::TerrainMesh => 1,
            Scene::Spheres | Scene::Mixed => 5,
            Scene::Bullets => 6,
            Scene::Tower => 10,
            Scene::JoltPyramid => JOLT_PYRAMID_BOXES,
        }
    }

    /// Call `f` with each of the scene's [`Scene::body_count`] bodies in order (static
    /// ground and walls first), the engine-neutral definition every builder shares.
    /// `hulls_len` is the number of hulls the caller has (see [`make_hulls`]): hull bodies
    /// cycle through indices below it, and `Hulls` and `Mixed` need at least one (else
    /// `Error::OutOfRange(Input::Config)`, converted into `E`). Stops at the first error
    /// `f` returns.
    pub fn for_each_body<E, F>(self, hulls_len: usize, mut f: F) -> Result<(), E>
    where
        E: From<Error>,
        F: FnMut(&SceneBody) -> Result<(), E>,
    {
        let f: &mut dyn FnMut(&SceneBody) -> Result<(), E> = &mut f;
        match self {
            Scene::Pyramid20 => pyramid_bodies(20, f),
            Scene::Pyramid100 => pyramid_bodies(100, f),
            Scene::Boxes => boxes_bodies(f),
            Scene::Spheres => spheres_bodies(f),
            Scene::Hulls => hull_pile_bodies(hulls_len, f),
            Scene::Bullet => bullet_bodies(f),
            Scene::Mixed => mixed_bodies(hulls_len, f),
            Scene::Bullets => bullets_bodies(f),
            Scene::Tower => tower_bodies(10, f),
            Scene::JoltPyramid => jolt_pyramid_bodies(f),
            Scene::MeshPile => mesh_pile_bodies(hulls_len, f),
            Scene::Terrain | Scene::TerrainMesh => terrain_bodies(hulls_len, f),
        }
    }

    /// Add the scene's bodies ([`Scene::for_each_body`]) to `world`. `hulls` are the
    /// shapes of the hull-using scenes (see [`make_hulls`]; at least one is needed for
    /// `Hulls` and `Mixed`). Returns the body to watch ([`Scene::watched`]: the top box,
    /// the bullet, the first dynamic body).
    pub fn build<'a, const B: usize, const C: usize, const E: usize>(
        self,
        world: &mut World<'a, B, C, E>,
        hulls: &'a [ConvexHull],
    ) -> Result<BodyHandle, Error> {
        self.build_on(world, hulls, None)
    }

    /// [`Scene::build`], with the ground [`SceneShape::Terrain`] stands for (`mesh_pile`,
    /// `terrain` and `terrain_mesh` need it: `None` there is
    /// `Error::OutOfRange(Input::Config)`; the other scenes ignore it). Build it with
    /// [`mesh_pile_field`] or [`TerrainShapes::ground`].
    pub fn build_on<'a, const B: usize, const C: usize, const E: usize>(
        self,
        world: &mut World<'a, B, C, E>,
        hulls: &'a [ConvexHull],
        terrain: Option<Shape<'a>>,
    ) -> Result<BodyHandle, Error> {
        add_bodies(world, hulls, terrain, self.watched(), |f| {
            self.for_each_body(hulls.len(), f)
        })
    }

    /// The configuration the scene runs with: the default (sleep on, as behaviour tests
    /// want), with zero gravity for `bullet`. Timing runs switch sleeping off.
    pub fn config(self) -> crate::WorldConfig {
        match self {
            Scene::Bullet => bullet_config(),
            _ => crate::WorldConfig::DEFAULT,
        }
    }

    /// Build the scene into an empty `world`, configure it, step it [`Scene::steps`]
    /// times and return [`World::checksum`]. The one routine the host tests, the
    /// Cortex-M firmware and the WASM build all run for the golden checksums.
    pub fn run<'a, const B: usize, const C: usize, const E: usize>(
        self,
        world: &mut World<'a, B, C, E>,
        hulls: &'a [ConvexHull],
    ) -> Result<u64, Error> {
        self.run_on(world, hulls, None)
    }

    /// [`Scene::run`] with the ground of [`Scene::build_on`]: the scenes with a terrain
    /// (for the reference ones, [`TerrainShapes::ground`]) run only through here.
    pub fn run_on<'a, const B: usize, const C: usize, const E: usize>(
        self,
        world: &mut World<'a, B, C, E>,
        hulls: &'a [ConvexHull],
        terrain: Option<Shape<'a>>,
    ) -> Result<u64, Error> {
        world.set_config(self.config())?;
        self.build_on(world, hulls, terrain)?;
        for _ in 0..self.steps() {
            world.step();
        }
        Ok(world.checksum())
    }

    /// The golden line of this scene with `checksum` after [`Scene::steps`] steps.
    pub fn line(self, checksum: u64) -> GoldenLine {
        GoldenLine {
            name: self.name(),
            steps: self.steps(),
            checksum,
        }
    }
}

/// One line of `tests/golden/checksums.txt`, as the host test, the Cortex-M firmware and
/// the WASM build print it: `<name> <steps> 0x<checksum as 16 hex digits>`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct GoldenLine {
    /// Scene or workload name ([`Scene::name`], [`narrow::NAME`]).
    pub name: &'static str,
    /// Steps run (for `narrow`: pairs queried).
    pub steps: u32,
    /// [`World::checksum`] after the steps (for `narrow`: the workload hash).
    pub checksum: u64,
}

impl core::fmt::Display for GoldenLine {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(f, "{} {} 0x{:016x}", self.name, self.steps, self.checksum)
    }
}

/// Fill `out` with hulls of [`HULL_POINTS`] random points on the unit sphere each (fixed
/// seed); returns how many were built.
pub fn make_hulls(out: &mut [ConvexHull], seed: u64) -> Result<usize, Error> {
    let mut rng = SplitMix64::new(seed);
    for h in out.iter_mut() {
        let mut pts = [Vec3::ZERO; HULL_POINTS];
        for p in pts.iter_mut() {
            *p = rng.unit_vector();
        }
        // In place: no hull-sized temporary on the stack (a microcontroller's concern).
        h.rebuild(&pts)?;
    }
    Ok(out.len())
}

/// The callback every body generator below feeds.
type Sink<'f, E> = &'f mut dyn FnMut(&SceneBody) -> Result<(), E>;

/// Add the bodies `each` produces to `world`, in order, and return the handle of the one
/// at position `watch` (`Error::OutOfRange(Input::Config)` when there are fewer).
fn add_bodies<'a, const B: usize, const C: usize, const E: usize>(
    world: &mut World<'a, B, C, E>,
    hulls: &'a [ConvexHull],
    terrain: Option<Shape<'a>>,
    watch: usize,
    each: impl FnOnce(Sink<'_, Error>) -> Result<(), Error>,
) -> Result<BodyHandle, Error> {
    let mut n = 0usize;
    let mut watched = None;
    each(&mut |body: &SceneBody| {
        let h = world.add(body.desc_on(hulls, terrain)?)?;
        if n == watch {
            watched = Some(h);
        }
        n += 1;
        Ok(())
    })?;
    watched.ok_or(Error::OutOfRange(Input::Config))
}

/// A cuboid shape.
const fn cuboid(x: f32, y: f32, z: f32) -> SceneShape {
    SceneShape::Cuboid {
        half_extents: Vec3::new(x, y, z),
    }
}

/// A static ground box of half-extents `half`, top face at y = 0.
fn ground(half: Vec3) -> SceneBody {
    SceneBody::fixed(SceneShape::Cuboid { half_extents: half }).at(Vec3::new(0.0, -half.y, 0.0))
}

/// Position of a wall pyramid's top box in its body order (the last one).
const fn pyramid_top(base: usize) -> usize {
    base * (base + 1) / 2
}

fn pyramid_bodies<E>(base: u32, f: Sink<'_, E>) -> Result<(), E> {
    let h = 0.5f32;
    f(&ground(Vec3::new(100.0, 1.0, 100.0)))?;
    let cube = SceneBody::dynamic(cuboid(h, h, h));
    for i in 0..base {
        for j in i..base {
            let x = (i + 1) as f32 * h + 2.0 * (j - i) as f32 * h - h * base as f32;
            let y = (2 * i + 1) as f32 * h;
            f(&cube.at(Vec3::new(x, y, 0.0)))?;
        }
    }
    Ok(())
}

/// `pyramid20` / `pyramid100`: a wall pyramid in the XY plane. Box (i, j), row `i`,
/// `i <= j < base`, at x = (i+1)·h + 2(j−i)·h − h·base, y = (2i+1)·h, h = 0.5, on a
/// ground of half-extents (100, 1, 100) with its top at y = 0. Returns the top box.
pub fn pyramid<'a, const B: usize, const C: usize, const E: usize>(
    world: &mut World<'a, B, C, E>,
    base: u32,
) -> Result<BodyHandle, Error> {
    let top = pyramid_top(base as usize);
    add_bodies(world, &[], None, top, |f| pyramid_bodies(base, f))
}

fn boxes_bodies<E>(f: Sink<'_, E>) -> Result<(), E> {
    f(&ground(Vec3::new(50.0, 0.5, 50.0)))?;
    jittered_grid(SceneBody::dynamic(cuboid(0.5, 0.5, 0.5)), 10, f)
}

/// `boxes`: 1000 boxes (half 0.5) in a 10×10×10 grid, spacing 1.2, lowest layer at y = 2,
/// jitter ±0.1 in x and z. Returns the first box.
pub fn boxes<'a, const B: usize, const C: usize, const E: usize>(
    world: &mut World<'a, B, C, E>,
) -> Result<BodyHandle, Error> {
    add_bodies(world, &[], None, Scene::Boxes.watched(), |f| {
        boxes_bodies(f)
    })
}

fn spheres_bodies<E>(f: Sink<'_, E>) -> Result<(), E> {
    f(&ground(Vec3::new(11.0, 0.5, 11.0)))?;
    let wall_x = SceneBody::fixed(cuboid(0.5, 15.0, 11.0));
    let wall_z = SceneBody::fixed(cuboid(11.0, 15.0, 0.5));
    for s in [-1.0f32, 1.0] {
        f(&wall_x.at(Vec3::new(s * 10.5, 15.0, 0.0)))?;
        f(&wall_z.at(Vec3::new(0.0, 15.0, s * 10.5)))?;
    }
    jittered_grid(
        SceneBody::dynamic(SceneShape::Sphere { radius: 0.5 }),
        16,
        f,
    )
}

/// `spheres`: 4096 spheres (r 0.5) in a 16×16×16 grid, x, z = (i − 7.5)·1.2, y = 2 + j·1.2,
/// jitter ±0.1 in x and z, on a ground (11, 0.5, 11) inside four static walls 1 thick and 30
/// tall with inner faces at ±10. Returns the first sphere.
pub fn spheres<'a, const B: usize, const C: usize, const E: usize>(
    world: &mut World<'a, B, C, E>,
) -> Result<BodyHandle, Error> {
    add_bodies(world, &[], None, Scene::Spheres.watched(), |f| {
        spheres_bodies(f)
    })
}

/// `n`×`n`×`n` copies of `body`, spacing 1.2, centred on x = z = 0, lowest layer at
/// y = 2, jitter ±0.1 in x and z (x fastest, then z, then y).
fn jittered_grid<E>(body: SceneBody, n: u32, f: Sink<'_, E>) -> Result<(), E> {
    let centre = (n as f32 - 1.0) * 0.5;
    let mut rng = SplitMix64::new(SEED);
    for y in 0..n {
        for z in 0..n {
            for x in 0..n {
                let p = Vec3::new(
                    (x as f32 - centre) * 1.2 + rng.range(-0.1, 0.1),
                    2.0 + y as f32 * 1.2,
                    (z as f32 - centre) * 1.2 + rng.range(-0.1, 0.1),
                );
                f(&body.at(p))?;
            }
        }
    }
    Ok(())
}

fn hull_pile_bodies<E: From<Error>>(hulls_len: usize, f: Sink<'_, E>) -> Result<(), E> {
    if hulls_len == 0 {
        return Err(Error::OutOfRange(Input::Config).into());
    }
    f(&ground(Vec3::new(50.0, 0.5, 50.0)))?;
    let mut rng = SplitMix64::new(SEED);
    let mut n = 0usize;
    for y in 0..5 {
        for z in 0..10 {
            for x in 0..10 {
                let hull = n % hulls_len;
                n += 1;
                let p = Vec3::new(
                    (x as f32 - 4.5) * 2.5 + rng.range(-0.2, 0.2),
                    2.0 + y as f32 * 2.5,
                    (z as f32 - 4.5) * 2.5 + rng.range(-0.2, 0.2),
                );
                let mut body = SceneBody::dynamic(SceneShape::Hull(hull)).at(p);
                body.rotation = rng.rotation();
                f(&body)?;
            }
        }
    }
    Ok(())
}

/// `hulls`: 500 hulls (cycling through `hulls`) in a 10×5×10 grid, spacing 2.5, lowest
/// layer at y = 2, jitter ±0.2 in x and z, random rotations. Returns the first hull body.
pub fn hull_pile<'a, const B: usize, const C: usize, const E: usize>(
    world: &mut World<'a, B, C, E>,
    hulls: &'a [ConvexHull],
) -> Result<BodyHandle, Error> {
    add_bodies(world, hulls, None, Scene::Hulls.watched(), |f| {
        hull_pile_bodies(hulls.len(), f)
    })
}

fn bullet_bodies<E>(f: Sink<'_, E>) -> Result<(), E> {
    f(&SceneBody::fixed(cuboid(0.05, 5.0, 5.0)))?;
    let mut ball = SceneBody::dynamic(SceneShape::Sphere { radius: 0.05 })
        .at(Vec3::new(-5.0, 0.0, 0.0))
        .with_material(Material {
            restitution: 0.0,
            static_friction: 0.0,
            kinetic_friction: 0.0,
            ..Material::DEFAULT
        });
    ball.velocity = Vec3::new(500.0, 0.0, 0.0);
    f(&ball)
}

/// `bullet`: no gravity (the caller's config must set it: see [`bullet_config`]); a
/// sphere of radius 0.05 at x = −5 moving at 500 m/s along +x toward a static wall of
/// half-extents (0.05, 5, 5) at the origin. Returns the bullet.
pub fn bullet<'a, const B: usize, const C: usize, const E: usize>(
    world: &mut World<'a, B, C, E>,
) -> Result<BodyHandle, Error> {
    add_bodies(world, &[], None, Scene::Bullet.watched(), |f| {
        bullet_bodies(f)
    })
}

/// The configuration of the `bullet` scene: the default with zero gravity.
pub fn bullet_config() -> crate::WorldConfig {
    crate::WorldConfig {
        gravity: Vec3::ZERO,
        ..crate::WorldConfig::DEFAULT
    }
}

/// Static bodies of the `mixed` scene: ground and four walls.
pub const MIXED_WALLS: usize = 5;
/// Dynamic bodies of the `mixed` scene.
pub const MIXED_BODIES: usize = 120;

fn mixed_bodies<E: From<Error>>(hulls_len: usize, f: Sink<'_, E>) -> Result<(), E> {
    if hulls_len == 0 {
        return Err(Error::OutOfRange(Input::Config).into());
    }
    f(&ground(Vec3::new(5.0, 0.5, 5.0)))?;
    let wall_x = SceneBody::fixed(cuboid(0.5, 3.0, 5.0));
    let wall_z = SceneBody::fixed(cuboid(5.0, 3.0, 0.5));
    for s in [-1.0f32, 1.0] {
        f(&wall_x.at(Vec3::new(s * 4.5, 3.0, 0.0)))?;
        f(&wall_z.at(Vec3::new(0.0, 3.0, s * 4.5)))?;
    }
    let mut rng = SplitMix64::new(SEED ^ 0x5EED);
    for n in 0..MIXED_BODIES {
        let (x, y, z) = (n % 6, n / 24, (n / 6) % 4);
        let s = rng.range(0.6, 1.4);
        let shape = match n % 4 {
            0 => SceneShape::Sphere { radius: 0.3 * s },
            1 => SceneShape::Capsule {
                half_height: 0.25 * s,
                radius: 0.2 * s,
            },
            2 => cuboid(0.3 * s, 0.2 * s, 0.25 * s),
            _ => SceneShape::Hull(n % hulls_len),
        };
        let material = Material {
            restitution: rng.range(0.0, 0.6),
            static_friction: rng.range(0.3, 0.9),
            kinetic_friction: rng.range(0.1, 0.3),
            ..Material::DEFAULT
        };
        let p = Vec3::new(
            (x as f32 - 2.5) * 1.1 + rng.range(-0.1, 0.1),
            1.0 + y as f32 * 1.1,
            (z as f32 - 1.5) * 1.1 + rng.range(-0.1, 0.1),
        );
        let mut body = SceneBody::dynamic(shape).at(p).with_material(material);
        // Draw order: rotation, then the two velocity components.
        body.rotation = rng.rotation();
        body.velocity = Vec3::new(rng.range(-2.0, 2.0), 0.0, rng.range(-2.0, 2.0));
        body.density = if n % 4 == 3 { 200.0 } else { 1000.0 };
        f(&body)?;
    }
    Ok(())
}

/// `mixed`: 120 bodies (spheres, capsules, boxes and hulls in turn) of varied sizes,
/// rotations, friction and restitution, dropped from a 6×5×4 jittered grid into a box of
/// inner half-width 4 with walls 6 tall. Returns the first dynamic body.
pub fn mixed<'a, const B: usize, const C: usize, const E: usize>(
    world: &mut World<'a, B, C, E>,
    hulls: &'a [ConvexHull],
) -> Result<BodyHandle, Error> {
    add_bodies(world, hulls, None, Scene::Mixed.watched(), |f| {
        mixed_bodies(hulls.len(), f)
    })
}

/// The step at which the cross-target snapshot of the `mixed` scene is taken
/// (`tests/golden/mixed_500.snap`).
pub const SNAPSHOT_STEP: u64 = 500;

/// Restore `snapshot` into `world` (hull shapes looked up in `hulls`) and step it until
/// its step counter reaches `scene.steps()`; returns the checksum. The snapshot may come
/// from another target: a match with the golden checksum proves the state crossed intact.
pub fn continue_from_snapshot<'a, const B: usize, const C: usize, const E: usize>(
    scene: Scene,
    world: &mut World<'a, B, C, E>,
    hulls: &'a [ConvexHull],
    snapshot: &[u8],
) -> Result<u64, Error> {
    world.restore_with_hulls(snapshot, hulls)?;
    while world.step_count() < scene.steps() as u64 {
        world.step();
    }
    Ok(world.checksum())
}

/// Bullets fired in the `bullets` scene.
pub const BULLETS: usize = 12;

fn bullets_bodies<E>(f: Sink<'_, E>) -> Result<(), E> {
    let t = 0.05; // half thickness
    let slab_y = SceneBody::fixed(cuboid(3.0 + 2.0 * t, t, 3.0 + 2.0 * t));
    let slab_x = SceneBody::fixed(cuboid(t, 3.0, 3.0));
    let slab_z = SceneBody::fixed(cuboid(3.0, 3.0, t));
    for s in [-1.0f32, 1.0] {
        f(&slab_y.at(Vec3::new(0.0, 3.0 + s * (3.0 + t), 0.0)))?;
        f(&slab_x.at(Vec3::new(s * (3.0 + t), 3.0, 0.0)))?;
        f(&slab_z.at(Vec3::new(0.0, 3.0, s * (3.0 + t))))?;
    }
    let ball = SceneBody::dynamic(SceneShape::Sphere { radius: 0.05 }).with_material(Material {
        restitution: 0.5,
        static_friction: 0.5,
        kinetic_friction: 0.3,
        ..Material::DEFAULT
    });
    let mut rng = SplitMix64::new(SEED ^ 0xB011E7);
    for n in 0..BULLETS {
        let (p, v) = if n + 2 >= BULLETS {
            let s = if n + 2 == BULLETS { -1.0 } else { 1.0 };
            (
                Vec3::new(s * 2.0, 1.0, 0.5),
                Vec3::new(-s * 300.0, 0.0, 0.0),
            )
        } else {
            let dir = rng.unit_vector();
            (
                Vec3::new(
                    rng.range(-1.0, 1.0),
                    3.0 + rng.range(-1.0, 1.0),
                    rng.range(-1.0, 1.0),
                ),
                dir * rng.range(150.0, 400.0),
            )
        };
        let mut body = ball.at(p);
        body.velocity = v;
        f(&body)?;
    }
    Ok(())
}

/// `bullets`: a closed room (floor, ceiling and four walls 0.1 m thick, inner half-width
/// 3 m) and [`BULLETS`] spheres of radius 0.05 fired from the centre at 150 to 400 m/s in
/// seeded directions, the last two straight at each other. Returns the first bullet.
pub fn bullets<'a, const B: usize, const C: usize, const E: usize>(
    world: &mut World<'a, B, C, E>,
) -> Result<BodyHandle, Error> {
    add_bodies(world, &[], None, Scene::Bullets.watched(), |f| {
        bullets_bodies(f)
    })
}

fn tower_bodies<E>(height: u32, f: Sink<'_, E>) -> Result<(), E> {
    f(&ground(Vec3::new(10.0, 0.5, 10.0)))?;
    let cube = SceneBody::dynamic(cuboid(0.5, 0.5, 0.5));
    for i in 0..height {
        let y = 0.5 + i as f32 * 1.01;
        f(&cube.at(Vec3::new(0.0, y, 0.0)))?;
    }
    Ok(())
}

/// `tower`: `height` boxes of half-extent 0.5 stacked on a ground box (top at y = 0),
/// 1 cm apart so they settle. Returns the top box.
pub fn tower<'a, const B: usize, const C: usize, const E: usize>(
    world: &mut World<'a, B, C, E>,
    height: u32,
) -> Result<BodyHandle, Error> {
    add_bodies(world, &[], None, height as usize, |f| {
        tower_bodies(height, f)
    })
}

/// Layers of the `jolt_pyramid` scene.
pub const JOLT_PYRAMID_LAYERS: u32 = 15;
/// Boxes of the `jolt_pyramid` scene: 15² + 14² + … + 1² = 1240.
pub const JOLT_PYRAMID_BOXES: usize = 1240;
/// Height (m) each `jolt_pyramid` box falls before it lands on the layer below: layers
/// start 2.5 m apart and the boxes are 2 m tall.
pub const JOLT_PYRAMID_GAP: f32 = 0.5;
/// Jolt's default friction (`BodyCreationSettings::mFriction`), on every body of
/// `jolt_pyramid` (static and kinetic alike).
pub const JOLT_FRICTION: f32 = 0.2;
/// Jolt's default linear and angular damping (1/s, `BodyCreationSettings`), on every
/// dynamic body of `jolt_pyramid`.
pub const JOLT_DAMPING: f32 = 0.05;

fn jolt_pyramid_bodies<E>(f: Sink<'_, E>) -> Result<(), E> {
    let jolt = Material {
        restitution: 0.0,
        static_friction: JOLT_FRICTION,
        kinetic_friction: JOLT_FRICTION,
        ..Material::DEFAULT
    };
    f(&ground(Vec3::new(50.0, 1.0, 50.0)).with_material(jolt))?;
    let size = 2.0f32;
    let half = 0.5 * size;
    let n = JOLT_PYRAMID_LAYERS as i32;
    let mut cube = SceneBody::dynamic(cuboid(half, half, half)).with_material(jolt);
    cube.linear_damping = JOLT_DAMPING;
    cube.angular_damping = JOLT_DAMPING;
    for i in 0..n {
        let offset = if i % 2 == 1 { half } else { 0.0 };
        let y = 1.0 + (size + JOLT_PYRAMID_GAP) * i as f32;
        for j in i / 2..n - (i + 1) / 2 {
            for k in i / 2..n - (i + 1) / 2 {
                let x = -(n as f32) + size * j as f32 + offset;
                let z = -(n as f32) + size * k as f32 + offset;
                f(&cube.at(Vec3::new(x, y, z)))?;
            }
        }
    }
    Ok(())
}

/// `jolt_pyramid`: the pyramid of Jolt Physics' `PerformanceTest` (its
/// `PerformanceTest/PyramidScene.h`, scene "Pyramid"), the same bodies in the same order.
///
/// What Jolt's scene does, as read from its source:
/// - ground: a static box of half-extents (50, 1, 50) at (0, −1, 0), top face at y = 0;
/// - boxes: cubes of size 2 m (half-extent 1, convex radius 0 in Jolt), in
///   [`JOLT_PYRAMID_LAYERS`] = 15 layers; layer `i` (0 at the bottom) holds
///   (15 − i) × (15 − i) boxes, j and k from ⌊i/2⌋ to 15 − ⌈i/2⌉ − 1, at
///   x = −15 + 2j + o, y = 1 + 2.5 i, z = −15 + 2k + o, with o = 1 on odd layers (each
///   box straddles four below) and 0 on even ones: 1240 boxes (j outer, k inner);
/// - boxes in a layer touch side by side; layers start [`JOLT_PYRAMID_GAP`] = 0.5 m
///   apart, so every layer falls 0.5 m onto the one below and the top box comes to rest
///   about 14 × 0.5 = 7 m below its start;
/// - material: Jolt's defaults, friction [`JOLT_FRICTION`] = 0.2 (geometric mean, as
///   carom combines), restitution 0, density 1000 kg/m³, linear and angular damping
///   [`JOLT_DAMPING`] = 0.05 1/s;
/// - Jolt's performance test steps it 500 times (its default `-i`) at dt 1/60 with one
///   collision step per update, with sleeping disallowed on every box.
///
/// Returns the top box.
pub fn jolt_pyramid<'a, const B: usize, const C: usize, const E: usize>(
    world: &mut World<'a, B, C, E>,
) -> Result<BodyHandle, Error> {
    add_bodies(world, &[], None, Scene::JoltPyramid.watched(), |f| {
        jolt_pyramid_bodies(f)
    })
}

/// Samples per side of the `mesh_pile` terrain: 72 × 72 cells, 10,368 triangles.
pub const MESH_PILE_COLUMNS: u32 = 73;

/// Cell size of the `mesh_pile` terrain (m): 36 m a side.
pub const MESH_PILE_CELL: f32 = 0.5;

/// Heights of the `mesh_pile` terrain.
pub const MESH_PILE_SAMPLES: usize = (MESH_PILE_COLUMNS * MESH_PILE_COLUMNS) as usize;

/// Dynamic bodies of `mesh_pile`.
pub const MESH_PILE_BODIES: usize = 300;

/// `|2 frac(x) − 1|` for `x ≥ 0`: a triangle wave of period 1 between 0 and 1, by
/// integer truncation (the same bits everywhere).
pub(crate) fn triangle_wave(x: f32) -> f32 {
    let frac = x - (x as u32) as f32;
    let t = 2.0 * frac - 1.0;
    if t < 0.0 {
        -t
    } else {
        t
    }
}

/// The `mesh_pile` terrain's heights (m), row-major as [`HeightField`] reads them, into
/// `out` (its first [`MESH_PILE_SAMPLES`]; fewer if it is shorter): two crossed ridges
/// of triangle waves, 1.2 m at their highest, with a finer ripple. Plain `+ − × /` and
/// integer truncation, no trigonometry: the same bits on every target and backend.
pub fn mesh_pile_heights(out: &mut [f32]) {
    let n = MESH_PILE_COLUMNS;
    for (k, h) in out.iter_mut().enumerate().take(MESH_PILE_SAMPLES) {
        let (i, j) = (k as u32 % n, k as u32 / n);
        let (x, z) = (i as f32, j as f32);
        *h = 1.2 * triangle_wave(x / 24.0) * triangle_wave(z / 18.0)
            + 0.15 * triangle_wave((x + 2.0 * z) / 7.0);
    }
}

/// The `mesh_pile` terrain over `heights` (from [`mesh_pile_heights`]), for
/// [`Scene::build_on`].
pub fn mesh_pile_field(heights: &[f32]) -> Result<HeightField<'_>, Error> {
    HeightField::new(
        heights,
        MESH_PILE_COLUMNS,
        MESH_PILE_COLUMNS,
        MESH_PILE_CELL,
    )
}

/// `mesh_pile`: the terrain (its corner at `(−18, 0, −18)`, centred on the origin), then
/// 300 bodies in a 10 × 10 × 3 grid 2 m apart, 3 m above the terrain's top and 1.5 m
/// between layers: boxes, spheres, capsules and hulls in turn, of varied sizes, turned
/// and moving sideways at random (seeded). Needs a hull (`hulls_len ≥ 1`).
fn mesh_pile_bodies<E: From<Error>>(hulls_len: usize, f: Sink<'_, E>) -> Result<(), E> {
    if hulls_len == 0 {
        return Err(Error::OutOfRange(Input::Config).into());
    }
    let half = (MESH_PILE_COLUMNS - 1) as f32 * MESH_PILE_CELL * 0.5;
    f(&SceneBody::fixed(SceneShape::Terrain).at(Vec3::new(-half, 0.0, -half)))?;
    let mut rng = SplitMix64::new(SEED ^ 0x3E54);
    for n in 0..MESH_PILE_BODIES {
        let (x, z, y) = (n % 10, (n / 10) % 10, n / 100);
        let centre = Vec3::new(
            (x as f32 - 4.5) * 2.0,
            4.5 + y as f32 * 1.5,
            (z as f32 - 4.5) * 2.0,
        );
        f(&mixed_body(n, hulls_len, centre, &mut rng))?;
    }
    Ok(())
}

/// Dynamic body `n` of a mixed drop (`mesh_pile`, `terrain`): a box, a sphere, a capsule
/// or a hull in turn (hull `n % hulls_len`, `hulls_len ≥ 1`), scaled by 0.7–1.3, within
/// ±0.3 m of `centre` in x and z, turned and moving sideways at random (from `rng`).
fn mixed_body(n: usize, hulls_len: usize, centre: Vec3, rng: &mut SplitMix64) -> SceneBody {
    let s = rng.range(0.7, 1.3);
    let shape = match n % 4 {
        0 => cuboid(0.4 * s, 0.3 * s, 0.35 * s),
        1 => SceneShape::Sphere { radius: 0.35 * s },
        2 => SceneShape::Capsule {
            half_height: 0.3 * s,
            radius: 0.25 * s,
        },
        _ => SceneShape::Hull(n.checked_rem(hulls_len).unwrap_or(0)),
    };
    let p = Vec3::new(
        centre.x + rng.range(-0.3, 0.3),
        centre.y,
        centre.z + rng.range(-0.3, 0.3),
    );
    let mut body = SceneBody::dynamic(shape).at(p);
    body.rotation = rng.rotation();
    body.velocity = Vec3::new(rng.range(-1.0, 1.0), 0.0, rng.range(-1.0, 1.0));
    body
}

/// Dynamic bodies of `terrain` and `terrain_mesh`.
pub const TERRAIN_BODIES: usize = 40;

/// `terrain` / `terrain_mesh`: the ground ([`TerrainShapes`], its corner at
/// `(−8, 0, −8)`, centred on the origin), then 40 mixed bodies ([`mixed_body`]) in a
/// 4 × 5 × 2 grid 1.6 m apart, 4 m up and 1.5 m between layers, over the bowl's middle.
/// Needs a hull (`hulls_len ≥ 1`).
fn terrain_bodies<E: From<Error>>(hulls_len: usize, f: Sink<'_, E>) -> Result<(), E> {
    if hulls_len == 0 {
        return Err(Error::OutOfRange(Input::Config).into());
    }
    let half = (TERRAIN_COLUMNS - 1) as f32 * TERRAIN_CELL * 0.5;
    f(&SceneBody::fixed(SceneShape::Terrain).at(Vec3::new(-half, 0.0, -half)))?;
    let mut rng = SplitMix64::new(SEED ^ 0x7E22);
    for n in 0..TERRAIN_BODIES {
        let (x, z, y) = (n % 4, (n / 4) % 5, n / 20);
        let centre = Vec3::new(
            (x as f32 - 1.5) * 1.6,
            4.0 + y as f32 * 1.5,
            (z as f32 - 2.0) * 1.6,
        );
        f(&mixed_body(n, hulls_len, centre, &mut rng))?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_scene_lists_its_body_count_and_watches_a_dynamic_body() {
        for scene in Scene::ALL {
            let mut n = 0usize;
            let mut watched = None;
            let r: Result<(), Error> = scene.for_each_body(3, |b| {
                if n == scene.watched() {
                    watched = Some(*b);
                }
                n += 1;
                Ok(())
            });
            assert_eq!(r, Ok(()), "{scene:?}");
            assert_eq!(n, scene.body_count(), "{scene:?}");
            assert_eq!(
                watched.map(|b| b.kind),
                Some(SceneKind::Dynamic),
                "{scene:?}"
            );
            assert_eq!(Scene::from_name(scene.name()), Some(scene));
        }
        assert_eq!(Scene::from_name("nope"), None);
    }

    #[test]
    fn hull_scenes_need_a_hull_and_stay_below_the_count_given() {
        for scene in [
            Scene::Hulls,
            Scene::Mixed,
            Scene::MeshPile,
            Scene::Terrain,
            Scene::TerrainMesh,
        ] {
            let r: Result<(), Error> = scene.for_each_body(0, |_| Ok(()));
            assert_eq!(r, Err(Error::OutOfRange(Input::Config)));
            let r: Result<(), Error> = scene.for_each_body(3, |b| match b.shape {
                SceneShape::Hull(i) if i >= 3 => Err(Error::OutOfRange(Input::Point)),
                _ => Ok(()),
            });
            assert_eq!(r, Ok(()));
        }
    }

    #[test]
    fn the_jolt_pyramid_has_jolts_layers_and_top() {
        let mut per_layer = [0usize; JOLT_PYRAMID_LAYERS as usize];
        let mut last = None;
        let r: Result<(), Error> = Scene::JoltPyramid.for_each_body(0, |b| {
            if b.kind == SceneKind::Dynamic {
                let layer = ((b.position.y - 1.0) / 2.5) as usize;
                if let Some(c) = per_layer.get_mut(layer) {
                    *c += 1;
                }
                last = Some(b.position);
            }
            Ok(())
        });
        assert_eq!(r, Ok(()));
        for (i, c) in per_layer.iter().enumerate() {
            assert_eq!(*c, (15 - i) * (15 - i));
        }
        assert_eq!(last, Some(Vec3::new(-1.0, 36.0, -1.0)));
    }

    #[test]
    fn a_stopping_callback_stops_the_list() {
        let mut n = 0;
        let r = Scene::Spheres.for_each_body(0, |_| {
            n += 1;
            if n == 3 {
                Err(Error::OutOfRange(Input::Radius))
            } else {
                Ok(())
            }
        });
        assert_eq!(r, Err(Error::OutOfRange(Input::Radius)));
        assert_eq!(n, 3);
    }
}
