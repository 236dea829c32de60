//! The standard scenes of `SCENES.md`, defined once and shared by tests, benchmarks and
//! demos. Units are SI, gravity −Y, dt 1/60. "Jitter" comes from [`SplitMix64`] with a
//! fixed seed, so every target builds the same scene.
//!
//! - [`Scene`]: the world scenes; [`Scene::REFERENCE`] are the ones whose checksums are
//!   golden, run by [`Scene::run`] in a [`ReferenceWorld`].
//! - [`narrow`]: the cross-target narrow-phase workload (the golden `narrow` line).
//! - [`queries`]: the query sets of the narrow-phase benchmarks.
//! - [`GoldenLine`]: one line of `tests/golden/checksums.txt`, as every target prints it.

use crate::dynamics::body::{BodyDesc, Material};
use crate::dynamics::BodyHandle;
use crate::error::Error;
use crate::math::Vec3;
use crate::rng::SplitMix64;
use crate::shape::{ConvexHull, Shape};
use crate::World;

pub mod narrow;
pub mod queries;

/// The world type the reference scenes run in on every target (capacities are part of
/// what a golden checksum means: drop rules depend on them).
pub type ReferenceWorld<'a> = World<'a, 128, 512, 64>;

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
}

impl Scene {
    /// Every scene, in the order of SCENES.md.
    pub const ALL: [Scene; 9] = [
        Scene::Pyramid20,
        Scene::Pyramid100,
        Scene::Boxes,
        Scene::Spheres,
        Scene::Hulls,
        Scene::Bullet,
        Scene::Mixed,
        Scene::Bullets,
        Scene::Tower,
    ];

    /// The reference scenes whose checksums after their steps are kept in
    /// `tests/golden/checksums.txt` and checked on every target.
    pub const REFERENCE: [Scene; 3] = [Scene::Mixed, Scene::Bullets, Scene::Tower];

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
        }
    }

    /// Steps the scene is run for.
    pub fn steps(self) -> u32 {
        match self {
            Scene::Pyramid20 => 500,
            Scene::Pyramid100 => 200,
            Scene::Boxes | Scene::Spheres | Scene::Hulls => 300,
            Scene::Bullet => 60,
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
        }
    }

    /// Add the scene's bodies to `world`. `hulls` are the shapes of the hull-using scenes
    /// (see [`make_hulls`]; at least one is needed for `Hulls` and `Mixed`). Returns the
    /// body to watch (the top box, the bullet, the first dynamic body).
    pub fn build<'a, const B: usize, const C: usize, const E: usize>(
        self,
        world: &mut World<'a, B, C, E>,
        hulls: &'a [ConvexHull],
    ) -> Result<BodyHandle, Error> {
        match self {
            Scene::Pyramid20 => pyramid(world, 20),
            Scene::Pyramid100 => pyramid(world, 100),
            Scene::Boxes => boxes(world),
            Scene::Spheres => spheres(world),
            Scene::Hulls => hull_pile(world, hulls),
            Scene::Bullet => bullet(world),
            Scene::Mixed => mixed(world, hulls),
            Scene::Bullets => bullets(world),
            Scene::Tower => tower(world, 10),
        }
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
        world.set_config(self.config())?;
        self.build(world, hulls)?;
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
        *h = ConvexHull::new(&pts)?;
    }
    Ok(out.len())
}

fn ground<'a, const B: usize, const C: usize, const E: usize>(
    world: &mut World<'a, B, C, E>,
    half: Vec3,
) -> Result<BodyHandle, Error> {
    // Top face at y = 0.
    world.add(BodyDesc::fixed(Shape::cuboid(half)?).position(Vec3::new(0.0, -half.y, 0.0)))
}

/// `pyramid20` / `pyramid100`: a wall pyramid in the XY plane. Box (i, j), row `i`,
/// `i <= j < base`, at x = (i+1)·h + 2(j−i)·h − h·base, y = (2i+1)·h, h = 0.5.
/// Returns the top box.
pub fn pyramid<'a, const B: usize, const C: usize, const E: usize>(
    world: &mut World<'a, B, C, E>,
    base: u32,
) -> Result<BodyHandle, Error> {
    let h = 0.5f32;
    ground(world, Vec3::new(100.0, 1.0, 100.0))?;
    let cube = Shape::cuboid(Vec3::splat(h))?;
    let mut top = None;
    for i in 0..base {
        for j in i..base {
            let x = (i + 1) as f32 * h + 2.0 * (j - i) as f32 * h - h * base as f32;
            let y = (2 * i + 1) as f32 * h;
            top = Some(world.add(BodyDesc::dynamic(cube).position(Vec3::new(x, y, 0.0)))?);
        }
    }
    top.ok_or(Error::OutOfRange(crate::Input::Config))
}

/// `boxes`: 1000 boxes (half 0.5) in a 10×10×10 grid, spacing 1.2, lowest layer at y = 2,
/// jitter ±0.1 in x and z. Returns the first box.
pub fn boxes<'a, const B: usize, const C: usize, const E: usize>(
    world: &mut World<'a, B, C, E>,
) -> Result<BodyHandle, Error> {
    ground(world, Vec3::new(50.0, 0.5, 50.0))?;
    jittered_grid(world, Shape::cuboid(Vec3::splat(0.5))?, 10)
}

/// `spheres`: 4096 spheres (r 0.5) in a 16×16×16 grid, x, z = (i − 7.5)·1.2, y = 2 + j·1.2,
/// jitter ±0.1 in x and z, on a ground (11, 0.5, 11) inside four static walls 1 thick and 30
/// tall with inner faces at ±10. Returns the first sphere.
pub fn spheres<'a, const B: usize, const C: usize, const E: usize>(
    world: &mut World<'a, B, C, E>,
) -> Result<BodyHandle, Error> {
    ground(world, Vec3::new(11.0, 0.5, 11.0))?;
    let wall_x = Shape::cuboid(Vec3::new(0.5, 15.0, 11.0))?;
    let wall_z = Shape::cuboid(Vec3::new(11.0, 15.0, 0.5))?;
    for s in [-1.0f32, 1.0] {
        world.add(BodyDesc::fixed(wall_x).position(Vec3::new(s * 10.5, 15.0, 0.0)))?;
        world.add(BodyDesc::fixed(wall_z).position(Vec3::new(0.0, 15.0, s * 10.5)))?;
    }
    jittered_grid(world, Shape::sphere(0.5)?, 16)
}

/// `n`×`n`×`n` dynamic copies of `shape`, spacing 1.2, centred on x = z = 0, lowest layer
/// at y = 2, jitter ±0.1 in x and z (x fastest, then z, then y). Returns the first body.
fn jittered_grid<'a, const B: usize, const C: usize, const E: usize>(
    world: &mut World<'a, B, C, E>,
    shape: Shape<'a>,
    n: u32,
) -> Result<BodyHandle, Error> {
    let centre = (n as f32 - 1.0) * 0.5;
    let mut rng = SplitMix64::new(SEED);
    let mut first = None;
    for y in 0..n {
        for z in 0..n {
            for x in 0..n {
                let p = Vec3::new(
                    (x as f32 - centre) * 1.2 + rng.range(-0.1, 0.1),
                    2.0 + y as f32 * 1.2,
                    (z as f32 - centre) * 1.2 + rng.range(-0.1, 0.1),
                );
                let hnd = world.add(BodyDesc::dynamic(shape).position(p))?;
                first.get_or_insert(hnd);
            }
        }
    }
    first.ok_or(Error::OutOfRange(crate::Input::Config))
}

/// `hulls`: 500 hulls (cycling through `hulls`) in a 10×5×10 grid, spacing 2.5, lowest
/// layer at y = 2, jitter ±0.2 in x and z, random rotations. Returns the first hull body.
pub fn hull_pile<'a, const B: usize, const C: usize, const E: usize>(
    world: &mut World<'a, B, C, E>,
    hulls: &'a [ConvexHull],
) -> Result<BodyHandle, Error> {
    if hulls.is_empty() {
        return Err(Error::OutOfRange(crate::Input::Config));
    }
    ground(world, Vec3::new(50.0, 0.5, 50.0))?;
    let mut rng = SplitMix64::new(SEED);
    let mut first = None;
    let mut n = 0usize;
    for y in 0..5 {
        for z in 0..10 {
            for x in 0..10 {
                let hull = &hulls[n % hulls.len()];
                n += 1;
                let p = Vec3::new(
                    (x as f32 - 4.5) * 2.5 + rng.range(-0.2, 0.2),
                    2.0 + y as f32 * 2.5,
                    (z as f32 - 4.5) * 2.5 + rng.range(-0.2, 0.2),
                );
                let hnd = world.add(
                    BodyDesc::dynamic(Shape::hull(hull))
                        .position(p)
                        .rotation(rng.rotation()),
                )?;
                first.get_or_insert(hnd);
            }
        }
    }
    first.ok_or(Error::OutOfRange(crate::Input::Config))
}

/// `bullet`: no gravity (the caller's config must set it: see [`bullet_config`]); a
/// sphere of radius 0.05 at x = −5 moving at 500 m/s along +x toward a static wall of
/// half-extents (0.05, 5, 5) at the origin. Returns the bullet.
pub fn bullet<'a, const B: usize, const C: usize, const E: usize>(
    world: &mut World<'a, B, C, E>,
) -> Result<BodyHandle, Error> {
    world.add(BodyDesc::fixed(Shape::cuboid(Vec3::new(0.05, 5.0, 5.0))?))?;
    world.add(
        BodyDesc::dynamic(Shape::sphere(0.05)?)
            .position(Vec3::new(-5.0, 0.0, 0.0))
            .velocity(Vec3::new(500.0, 0.0, 0.0))
            .material(Material {
                restitution: 0.0,
                static_friction: 0.0,
                kinetic_friction: 0.0,
                ..Material::DEFAULT
            }),
    )
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

/// `mixed`: 120 bodies (spheres, capsules, boxes and hulls in turn) of varied sizes,
/// rotations, friction and restitution, dropped from a 6×5×4 jittered grid into a box of
/// inner half-width 4 with walls 6 tall. Returns the first dynamic body.
pub fn mixed<'a, const B: usize, const C: usize, const E: usize>(
    world: &mut World<'a, B, C, E>,
    hulls: &'a [ConvexHull],
) -> Result<BodyHandle, Error> {
    if hulls.is_empty() {
        return Err(Error::OutOfRange(crate::Input::Config));
    }
    ground(world, Vec3::new(5.0, 0.5, 5.0))?;
    let wall_x = Shape::cuboid(Vec3::new(0.5, 3.0, 5.0))?;
    let wall_z = Shape::cuboid(Vec3::new(5.0, 3.0, 0.5))?;
    for s in [-1.0f32, 1.0] {
        world.add(BodyDesc::fixed(wall_x).position(Vec3::new(s * 4.5, 3.0, 0.0)))?;
        world.add(BodyDesc::fixed(wall_z).position(Vec3::new(0.0, 3.0, s * 4.5)))?;
    }
    let mut rng = SplitMix64::new(SEED ^ 0x5EED);
    let mut first = None;
    for n in 0..MIXED_BODIES {
        let (x, y, z) = (n % 6, n / 24, (n / 6) % 4);
        let s = rng.range(0.6, 1.4);
        let shape = match n % 4 {
            0 => Shape::sphere(0.3 * s)?,
            1 => Shape::capsule(0.25 * s, 0.2 * s)?,
            2 => Shape::cuboid(Vec3::new(0.3 * s, 0.2 * s, 0.25 * s))?,
            _ => Shape::hull(&hulls[n % hulls.len()]),
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
        let hnd = world.add(
            BodyDesc::dynamic(shape)
                .position(p)
                .rotation(rng.rotation())
                .velocity(Vec3::new(rng.range(-2.0, 2.0), 0.0, rng.range(-2.0, 2.0)))
                .material(material)
                .density(if n % 4 == 3 { 200.0 } else { 1000.0 }),
        )?;
        first.get_or_insert(hnd);
    }
    first.ok_or(Error::OutOfRange(crate::Input::Config))
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

/// `bullets`: a closed room (floor, ceiling and four walls 0.1 m thick, inner half-width
/// 3 m) and [`BULLETS`] spheres of radius 0.05 fired from the centre at 150 to 400 m/s in
/// seeded directions, the last two straight at each other. Returns the first bullet.
pub fn bullets<'a, const B: usize, const C: usize, const E: usize>(
    world: &mut World<'a, B, C, E>,
) -> Result<BodyHandle, Error> {
    let t = 0.05; // half thickness
    let slab_y = Shape::cuboid(Vec3::new(3.0 + 2.0 * t, t, 3.0 + 2.0 * t))?;
    let slab_x = Shape::cuboid(Vec3::new(t, 3.0, 3.0))?;
    let slab_z = Shape::cuboid(Vec3::new(3.0, 3.0, t))?;
    for s in [-1.0f32, 1.0] {
        world.add(BodyDesc::fixed(slab_y).position(Vec3::new(0.0, 3.0 + s * (3.0 + t), 0.0)))?;
        world.add(BodyDesc::fixed(slab_x).position(Vec3::new(s * (3.0 + t), 3.0, 0.0)))?;
        world.add(BodyDesc::fixed(slab_z).position(Vec3::new(0.0, 3.0, s * (3.0 + t))))?;
    }
    let ball = Shape::sphere(0.05)?;
    let mut rng = SplitMix64::new(SEED ^ 0xB011E7);
    let mut first = None;
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
        let hnd = world.add(BodyDesc::dynamic(ball).position(p).velocity(v).material(
            Material {
                restitution: 0.5,
                static_friction: 0.5,
                kinetic_friction: 0.3,
                ..Material::DEFAULT
            },
        ))?;
        first.get_or_insert(hnd);
    }
    first.ok_or(Error::OutOfRange(crate::Input::Config))
}

/// `tower`: `height` boxes of half-extent 0.5 stacked on a ground box (top at y = 0),
/// 1 cm apart so they settle. Returns the top box.
pub fn tower<'a, const B: usize, const C: usize, const E: usize>(
    world: &mut World<'a, B, C, E>,
    height: u32,
) -> Result<BodyHandle, Error> {
    ground(world, Vec3::new(10.0, 0.5, 10.0))?;
    let cube = Shape::cuboid(Vec3::splat(0.5))?;
    let mut top = None;
    for i in 0..height {
        let y = 0.5 + i as f32 * 1.01;
        top = Some(world.add(BodyDesc::dynamic(cube).position(Vec3::new(0.0, y, 0.0)))?);
    }
    top.ok_or(Error::OutOfRange(crate::Input::Config))
}
