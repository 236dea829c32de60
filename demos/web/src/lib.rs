//! carom in a web page: a `cdylib` for `wasm32-unknown-unknown` whose plain `extern "C"`
//! functions (no wasm-bindgen) `main.js` calls through `WebAssembly.instantiate`.
//!
//! One world, a `static` [`ReferenceWorld`] (built by the compiler: it never passes
//! through the stack, and no `unsafe`), runs every scene: the reference scenes are built
//! exactly as `demos/wasm` builds them for the golden lines (fresh world, the scene's
//! configuration, [`Scene::build`] with the hulls of [`scenes::make_hulls`] and
//! [`SEED`]), so `carom_load` of `mixed` and 1000 `carom_step`s end on the golden
//! checksum of `tests/golden/checksums.txt`.
//!
//! Every exported function validates its arguments and returns an error code
//! (negative `i32`) instead of panicking: [`OK`], [`E_SCENE`], [`E_HULLS`], [`E_INPUT`],
//! [`E_FULL`], [`E_WORLD`].
//!
//! Drawing data goes through buffers in wasm memory that JS reads after the call:
//! [`carom_bodies`] fills [`BODY_FLOATS`] `f32`s per body, [`carom_hull`] one hull's
//! vertices and faces.
#![deny(unsafe_op_in_unsafe_fn)]

use std::collections::VecDeque;
use std::sync::{Mutex, MutexGuard, OnceLock};

use carom::scenes::{self, ReferenceWorld, Scene, REFERENCE_HULLS, SEED};
use carom::{BodyDesc, BodyHandle, BodyKind, ConvexHull, Error, Material, Shape, Vec3, World};

/// Success.
pub const OK: i32 = 0;
/// No scene with that index.
pub const E_SCENE: i32 = -1;
/// The reference hulls could not be built.
pub const E_HULLS: i32 = -2;
/// An argument is not finite or out of range.
pub const E_INPUT: i32 = -3;
/// The body pool is full and nothing the page added can make room.
pub const E_FULL: i32 = -4;
/// carom refused the call (the scene could not be built).
pub const E_WORLD: i32 = -5;

/// `f32`s per body in the body buffer: shape kind, flags, position (3), rotation
/// quaternion x y z w (4), shape parameters (3), linear velocity (3), hull index.
pub const BODY_FLOATS: usize = 16;

/// Shape kinds in the body buffer.
const KIND_SPHERE: f32 = 0.0;
const KIND_CAPSULE: f32 = 1.0;
const KIND_CUBOID: f32 = 2.0;
const KIND_HULL: f32 = 3.0;
const KIND_HALF_SPACE: f32 = 4.0;
const KIND_TRIANGLE: f32 = 5.0;

/// Flag bits in the body buffer.
const FLAG_STATIC: u32 = 1;
const FLAG_KINEMATIC: u32 = 2;
const FLAG_AWAKE: u32 = 4;
const FLAG_SPAWNED: u32 = 8;

/// Steps one `carom_step` call runs at most.
const MAX_STEPS_PER_CALL: u32 = 100_000;
/// Positions the page may spawn at: within this many metres of the origin.
const MAX_SPAWN_POSITION: f32 = 500.0;
/// Speeds the page may spawn with (m/s).
const MAX_SPAWN_SPEED: f32 = 1000.0;
/// Box half-extents the page may throw (m).
const BOX_HALF: (f32, f32) = (0.05, 2.0);
/// The bullet: a small dense ball, swept by time of impact.
const BULLET_RADIUS: f32 = 0.06;
const BULLET_DENSITY: f32 = 7800.0;

/// The page's scenes, in the order of its picker. All run in the one [`ReferenceWorld`].
#[derive(Clone, Copy, PartialEq, Eq)]
enum PageScene {
    /// A scene of [`carom::scenes`], built by [`Scene::build`] with [`Scene::config`].
    Standard(Scene),
    /// A wall pyramid with a base of 10 boxes ([`scenes::pyramid`]): 56 bodies, so it fits
    /// the reference world (`pyramid20` has 211).
    Pyramid10,
}

const SCENES: [PageScene; 4] = [
    PageScene::Standard(Scene::Mixed),
    PageScene::Standard(Scene::Bullets),
    PageScene::Standard(Scene::Tower),
    PageScene::Pyramid10,
];

impl PageScene {
    fn name(self) -> &'static str {
        match self {
            PageScene::Standard(s) => s.name(),
            PageScene::Pyramid10 => "pyramid10",
        }
    }

    /// Steps of its golden line (reference scenes) or a sensible run length.
    fn steps(self) -> u32 {
        match self {
            PageScene::Standard(s) => s.steps(),
            PageScene::Pyramid10 => 500,
        }
    }
}

/// The world every scene runs in: the golden checksums' world type.
static WORLD: Mutex<ReferenceWorld<'static>> = Mutex::new(World::new());

/// The reference hulls, built once.
static HULLS: OnceLock<Result<Vec<ConvexHull>, Error>> = OnceLock::new();

/// What the page added and the buffers it reads.
struct State {
    scene: usize,
    /// Bodies thrown or fired since the last load, oldest first: removed when the pool is
    /// full to make room.
    spawned: VecDeque<BodyHandle>,
    bodies: Vec<f32>,
    hull: Vec<f32>,
}

static STATE: Mutex<State> = Mutex::new(State {
    scene: 0,
    spawned: VecDeque::new(),
    bodies: Vec::new(),
    hull: Vec::new(),
});

/// A poisoned lock only means a call trapped while holding it; the data is still whole.
fn lock<T>(m: &Mutex<T>) -> MutexGuard<'_, T> {
    m.lock().unwrap_or_else(|e| e.into_inner())
}

fn hulls() -> Result<&'static [ConvexHull], Error> {
    let built = HULLS.get_or_init(|| {
        let mut hulls = vec![ConvexHull::UNIT_TETRAHEDRON; REFERENCE_HULLS];
        scenes::make_hulls(&mut hulls, SEED)?;
        Ok(hulls)
    });
    match built {
        Ok(h) => Ok(h.as_slice()),
        Err(e) => Err(*e),
    }
}

/// Number of scenes in the picker.
#[no_mangle]
pub extern "C" fn carom_scene_count() -> u32 {
    SCENES.len() as u32
}

/// Address of scene `i`'s name (ASCII, [`carom_scene_name_len`] bytes); 0 if there is
/// no such scene.
#[no_mangle]
pub extern "C" fn carom_scene_name_ptr(i: u32) -> *const u8 {
    SCENES
        .get(i as usize)
        .map_or(core::ptr::null(), |s| s.name().as_ptr())
}

/// Length of scene `i`'s name in bytes; 0 if there is no such scene.
#[no_mangle]
pub extern "C" fn carom_scene_name_len(i: u32) -> u32 {
    SCENES.get(i as usize).map_or(0, |s| s.name().len() as u32)
}

/// The steps of scene `i`'s golden line (`mixed`, `bullets`, `tower`: 1000) or its usual
/// run length; 0 if there is no such scene.
#[no_mangle]
pub extern "C" fn carom_scene_steps(i: u32) -> u32 {
    SCENES.get(i as usize).map_or(0, |s| s.steps())
}

/// Empty the world and build scene `i` into it at step 0. Returns [`OK`], [`E_SCENE`],
/// [`E_HULLS`] or [`E_WORLD`] (the world is then empty).
#[no_mangle]
pub extern "C" fn carom_load(i: u32) -> i32 {
    let Some(&scene) = SCENES.get(i as usize) else {
        return E_SCENE;
    };
    let hulls = match hulls() {
        Ok(h) => h,
        Err(_) => return E_HULLS,
    };
    let mut state = lock(&STATE);
    let mut world = lock(&WORLD);
    state.scene = i as usize;
    state.spawned.clear();
    // As demos/wasm and the host test: a fresh world, the scene's config, its bodies.
    *world = ReferenceWorld::new();
    let built = match scene {
        PageScene::Standard(s) => world
            .set_config(s.config())
            .and_then(|()| s.build(&mut world, hulls)),
        PageScene::Pyramid10 => scenes::pyramid(&mut world, 10),
    };
    match built {
        Ok(_) => OK,
        Err(_) => {
            *world = ReferenceWorld::new();
            E_WORLD
        }
    }
}

/// Load the current scene again.
#[no_mangle]
pub extern "C" fn carom_reset() -> i32 {
    let scene = lock(&STATE).scene;
    carom_load(scene as u32)
}

/// The index of the scene last loaded.
#[no_mangle]
pub extern "C" fn carom_scene() -> u32 {
    lock(&STATE).scene as u32
}

/// Advance the world by `n` fixed steps (at most 100 000 per call); returns the steps
/// taken.
#[no_mangle]
pub extern "C" fn carom_step(n: u32) -> u32 {
    let n = n.min(MAX_STEPS_PER_CALL);
    let mut world = lock(&WORLD);
    for _ in 0..n {
        world.step();
    }
    n
}

/// Steps taken since the scene was loaded (exact as an `f64` up to 2^53).
#[no_mangle]
pub extern "C" fn carom_step_count() -> f64 {
    lock(&WORLD).step_count() as f64
}

/// High 32 bits of `World::checksum`.
#[no_mangle]
pub extern "C" fn carom_checksum_hi() -> u32 {
    (lock(&WORLD).checksum() >> 32) as u32
}

/// Low 32 bits of `World::checksum`.
#[no_mangle]
pub extern "C" fn carom_checksum_lo() -> u32 {
    lock(&WORLD).checksum() as u32
}

/// Number of bodies.
#[no_mangle]
pub extern "C" fn carom_body_count() -> u32 {
    lock(&WORLD).body_count() as u32
}

/// Bodies awake after the last step.
#[no_mangle]
pub extern "C" fn carom_awake_count() -> u32 {
    lock(&WORLD).last_report().awake_bodies
}

/// Contacts with at least one point after the last step.
#[no_mangle]
pub extern "C" fn carom_contact_count() -> u32 {
    lock(&WORLD).contact_count() as u32
}

/// Validate a spawn position and velocity.
fn spawn_input(p: Vec3, v: Vec3) -> Option<(Vec3, Vec3)> {
    let ok = |x: f32, limit: f32| x.is_finite() && x.abs() <= limit;
    let p_ok = [p.x, p.y, p.z].iter().all(|&x| ok(x, MAX_SPAWN_POSITION));
    let v_ok = [v.x, v.y, v.z].iter().all(|&x| ok(x, MAX_SPAWN_SPEED));
    (p_ok && v_ok).then_some((p, v))
}

/// Add `desc`; when the pool is full, remove the oldest body the page added and retry.
fn spawn(desc: BodyDesc<'static>) -> i32 {
    let mut state = lock(&STATE);
    let mut world = lock(&WORLD);
    loop {
        match world.add(desc) {
            Ok(h) => {
                state.spawned.push_back(h);
                return OK;
            }
            Err(Error::PoolFull(_)) => match state.spawned.pop_front() {
                // A handle the world no longer knows is just dropped.
                Some(old) => {
                    let _ = world.remove(old);
                }
                None => return E_FULL,
            },
            Err(_) => return E_INPUT,
        }
    }
}

/// Throw a box of half-extent `half` (m, 0.05 to 2) from `(px, py, pz)` at `(vx, vy,
/// vz)` m/s, spinning. Positions within 500 m of the origin, speeds up to 1000 m/s per
/// axis. When the world is full the oldest thrown body goes. Returns [`OK`],
/// [`E_INPUT`] or [`E_FULL`].
#[no_mangle]
pub extern "C" fn carom_throw_box(
    px: f32,
    py: f32,
    pz: f32,
    vx: f32,
    vy: f32,
    vz: f32,
    half: f32,
) -> i32 {
    let Some((p, v)) = spawn_input(Vec3::new(px, py, pz), Vec3::new(vx, vy, vz)) else {
        return E_INPUT;
    };
    if !(half.is_finite() && (BOX_HALF.0..=BOX_HALF.1).contains(&half)) {
        return E_INPUT;
    }
    let Ok(shape) = Shape::cuboid(Vec3::splat(half)) else {
        return E_INPUT;
    };
    spawn(
        BodyDesc::dynamic(shape)
            .position(p)
            .velocity(v)
            .angular_velocity(Vec3::new(2.0, 3.0, 1.0))
            .material(Material {
                restitution: 0.2,
                ..Material::DEFAULT
            }),
    )
}

/// Fire a bullet: a 6 cm steel ball swept by continuous collision, from `(px, py, pz)`
/// at `(vx, vy, vz)` m/s (limits as [`carom_throw_box`]).
#[no_mangle]
pub extern "C" fn carom_fire_bullet(px: f32, py: f32, pz: f32, vx: f32, vy: f32, vz: f32) -> i32 {
    let Some((p, v)) = spawn_input(Vec3::new(px, py, pz), Vec3::new(vx, vy, vz)) else {
        return E_INPUT;
    };
    let Ok(shape) = Shape::sphere(BULLET_RADIUS) else {
        return E_INPUT;
    };
    spawn(
        BodyDesc::dynamic(shape)
            .position(p)
            .velocity(v)
            .density(BULLET_DENSITY)
            .ccd(true),
    )
}

/// Write [`BODY_FLOATS`] `f32`s per body into the body buffer (read it at
/// [`carom_bodies_ptr`]); returns the number of bodies written. Per body: shape kind
/// (0 sphere, 1 capsule, 2 cuboid, 3 hull, 4 half-space, 5 triangle), flags (1 static,
/// 2 kinematic, 4 awake, 8 added by the page), position x y z, rotation x y z w, shape
/// parameters (sphere: radius; capsule: half-height, radius; cuboid: half-extents;
/// half-space: normal; hull: its bounding box's half-extents), linear velocity x y z,
/// hull index (the hull of [`carom_hull`], -1 if none).
#[no_mangle]
pub extern "C" fn carom_bodies() -> u32 {
    let hulls = hulls().unwrap_or(&[]);
    let mut state = lock(&STATE);
    let world = lock(&WORLD);
    let State {
        bodies, spawned, ..
    } = &mut *state;
    bodies.clear();
    let mut n = 0u32;
    for h in world.handles() {
        let Ok(b) = world.body(h) else { continue };
        let (kind, params, hull_index) = match b.shape() {
            Shape::Sphere(s) => (KIND_SPHERE, [s.radius, 0.0, 0.0], -1.0),
            Shape::Capsule(c) => (KIND_CAPSULE, [c.half_height, c.radius, 0.0], -1.0),
            Shape::Cuboid(c) => (KIND_CUBOID, c.half_extents.to_array(), -1.0),
            Shape::Hull(hull) => {
                let index = hulls
                    .iter()
                    .position(|x| core::ptr::eq(x, hull))
                    .map_or(-1.0, |i| i as f32);
                let bounds = b.shape().local_aabb();
                let half = (bounds.max - bounds.min) * 0.5;
                (KIND_HULL, half.to_array(), index)
            }
            Shape::HalfSpace(s) => (KIND_HALF_SPACE, s.normal.to_array(), -1.0),
            Shape::Triangle(_) => (KIND_TRIANGLE, [0.0; 3], -1.0),
            // The page's scenes have none of these; drawn as their bounds' half-extents.
            _ => {
                let bounds = b.shape().local_aabb();
                let half = (bounds.max - bounds.min) * 0.5;
                (KIND_HULL, half.to_array(), -1.0)
            }
        };
        let mut flags = match b.kind() {
            BodyKind::Static => FLAG_STATIC,
            BodyKind::Kinematic => FLAG_KINEMATIC,
            BodyKind::Dynamic => 0,
        };
        if b.is_awake() {
            flags |= FLAG_AWAKE;
        }
        if spawned.contains(&h) {
            flags |= FLAG_SPAWNED;
        }
        let p = b.position();
        let q = b.rotation();
        let v = b.linear_velocity();
        let record: [f32; BODY_FLOATS] = [
            kind,
            flags as f32,
            p.x,
            p.y,
            p.z,
            q.x,
            q.y,
            q.z,
            q.w,
            params[0],
            params[1],
            params[2],
            v.x,
            v.y,
            v.z,
            hull_index,
        ];
        bodies.extend_from_slice(&record);
        n += 1;
    }
    n
}

/// Address of the body buffer [`carom_bodies`] filled (valid until the next call into
/// this module).
#[no_mangle]
pub extern "C" fn carom_bodies_ptr() -> *const f32 {
    lock(&STATE).bodies.as_ptr()
}

/// Number of reference hulls ([`carom_hull`] takes 0 to this minus one).
#[no_mangle]
pub extern "C" fn carom_hull_count() -> u32 {
    hulls().map_or(0, |h| h.len() as u32)
}

/// Write hull `i` into the hull buffer (read it at [`carom_hull_ptr`]) and return its
/// length in `f32`s (0 if there is no such hull): vertex count V, face count F, V
/// vertices (x y z, local frame), then per face its vertex count and vertex indices
/// (counter-clockwise about its outward normal).
#[no_mangle]
pub extern "C" fn carom_hull(i: u32) -> u32 {
    let Some(hull) = hulls().ok().and_then(|h| h.get(i as usize)) else {
        return 0;
    };
    let mut state = lock(&STATE);
    let out = &mut state.hull;
    out.clear();
    let vertices = hull.vertices();
    out.push(vertices.len() as f32);
    out.push(hull.face_count() as f32);
    for v in vertices {
        out.extend_from_slice(&v.to_array());
    }
    for f in 0..hull.face_count() {
        let face = hull.face_vertices(f);
        out.push(face.len() as f32);
        out.extend(face.iter().map(|&k| f32::from(k)));
    }
    out.len() as u32
}

/// Address of the hull buffer [`carom_hull`] filled (valid until the next call).
#[no_mangle]
pub extern "C" fn carom_hull_ptr() -> *const f32 {
    lock(&STATE).hull.as_ptr()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// One test: the functions share the one world.
    #[test]
    fn the_page_api() {
        reference_scenes_match_the_golden_file();
        bad_inputs_are_refused();
    }

    /// The page's way (load, then step) gives the golden checksums.
    fn reference_scenes_match_the_golden_file() {
        let golden = include_str!("../../../tests/golden/checksums.txt");
        for (i, scene) in SCENES.iter().enumerate() {
            let Some(line) = golden
                .lines()
                .find(|l| l.split(' ').next() == Some(scene.name()))
            else {
                continue;
            };
            assert_eq!(carom_load(i as u32), OK);
            carom_step(scene.steps());
            let sum = (u64::from(carom_checksum_hi()) << 32) | u64::from(carom_checksum_lo());
            let mine = format!("{} {} 0x{sum:016x}", scene.name(), scene.steps());
            assert_eq!(mine, line);
        }
    }

    fn bad_inputs_are_refused() {
        assert_eq!(carom_load(99), E_SCENE);
        assert_eq!(carom_load(2), OK);
        assert_eq!(
            carom_throw_box(f32::NAN, 0.0, 0.0, 0.0, 0.0, 0.0, 0.5),
            E_INPUT
        );
        assert_eq!(carom_throw_box(0.0, 5.0, 0.0, 0.0, 0.0, 0.0, 0.0), E_INPUT);
        assert_eq!(carom_fire_bullet(0.0, 5.0, 0.0, 1e9, 0.0, 0.0), E_INPUT);
        assert!(carom_scene_name_ptr(99).is_null());
        assert_eq!(carom_hull(99), 0);
        // Throwing into a full world recycles the oldest thrown body.
        for _ in 0..300 {
            assert_eq!(carom_throw_box(0.0, 5.0, 0.0, 0.0, 0.0, 0.0, 0.3), OK);
        }
        assert_eq!(carom_body_count(), 128);
        assert_eq!(carom_step(3), 3);
        assert_eq!(carom_bodies(), 128);
    }
}
