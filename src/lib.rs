//! # carom
//!
//! A `no_std`, allocation-free, deterministic 3D rigid-body collision engine with a fixed
//! time step.
//!
//! **The principle:** the same inputs give bit-identical results on every target, in
//! bounded memory and bounded time, and no input makes it panic.
//!
//! ```
//! use carom::{BodyDesc, Shape, Vec3, World};
//!
//! # fn main() -> Result<(), carom::Error> {
//! // Room for 16 bodies and 64 contacts, everything inline (no heap): about 84 KB.
//! let mut world: World<'static, 16, 64> = World::new(); // gravity −Y, dt = 1/60 s
//! world.add(
//!     BodyDesc::fixed(Shape::cuboid(Vec3::new(10.0, 0.5, 10.0))?)
//!         .position(Vec3::new(0.0, -0.5, 0.0)), // top face at y = 0
//! )?;
//! let ball = world.add(BodyDesc::dynamic(Shape::sphere(0.5)?).position(Vec3::new(0.0, 3.0, 0.0)))?;
//! for _ in 0..120 {
//!     world.step(); // two seconds
//! }
//! let y = world.body(ball)?.position().y;
//! assert!((y - 0.5).abs() < 0.01, "the ball rests on the ground: y = {y}");
//! # Ok(())
//! # }
//! ```
//!
//! # Concepts
//!
//! The crate has two layers:
//! - [`shape`] and [`collide`]: stateless geometry, pure functions of (shape, pose)
//!   pairs: GJK distance, EPA penetration, clipped contact manifolds, time of impact, ray
//!   casts.
//! - [`World`]: bodies in fixed-capacity pools and one fixed step, with
//!   [`FixedTimestep`] to drive it from a game's variable frame times.
//!
//! The pieces:
//! - **[`World`]`<'a, BODIES, CONTACTS, EVENTS>`**: the bodies, their contacts and the
//!   events of the last step, configured by a [`WorldConfig`] (gravity, `dt`, sub-steps,
//!   solver and sleep settings; [`WorldConfig::DEFAULT`] to start from). `'a` is the
//!   lifetime of the convex hulls its bodies borrow.
//! - **Bodies**: described by a [`BodyDesc`] ([`BodyDesc::dynamic`], [`BodyDesc::fixed`],
//!   [`BodyDesc::kinematic`] and builder methods for pose, velocity, mass, material,
//!   collision filter, sensor, continuous collision), added with [`World::add`], which
//!   returns a [`BodyHandle`]; read through [`World::body`] (a [`BodyRef`]) and changed
//!   through `World`'s setters ([`World::set_pose`], [`World::apply_impulse_at`], ...).
//!   A removed body's handle is stale ([`Error::StaleHandle`]), never another body's.
//! - **Shapes** ([`Shape`]): sphere, capsule (along local Y), cuboid, convex hull
//!   ([`ConvexHull`], borrowed, so many bodies share one), and for static bodies only a
//!   half-space and a triangle. Shapes are small `Copy` values checked when built.
//! - **Materials** ([`Material`]): restitution, static and kinetic friction, rolling and
//!   twist resistance; a contact combines its two bodies' by the world's rules
//!   ([`WorldConfig::friction_combine`], [`WorldConfig::restitution_combine`]; see
//!   [`CombineRule`] and [`Material::combine_with`]).
//! - **Contacts**: made and kept by the step (one manifold of up to four points per
//!   touching pair, warm-started by feature ids); [`StepReport`] counts them, and the
//!   stateless [`collide::contact`] computes one for any two posed shapes.
//! - **Events** ([`Event`]): contact begin and end, hits faster than a threshold, sensor
//!   enter and leave, in [`World::events`] after each step (`EVENTS` of them; more are
//!   counted as dropped).
//! - **Queries**: [`World::cast_ray`], [`World::cast_ray_all`] and [`World::overlap`]
//!   against the world's bodies, filtered by a [`QueryFilter`]; [`Shape::cast_ray`] and
//!   the [`collide`] functions against single shapes.
//! - **Snapshots**: [`World::snapshot`] writes the whole dynamic state to a byte buffer
//!   and [`World::restore`] puts it back, bit for bit (rollback netcode);
//!   [`World::checksum`] hashes it to find a desync.
//!
//! # One fixed step
//!
//! [`World::step`] advances the world by `dt` seconds (1/60 by default) and returns a
//! [`StepReport`]. In order:
//! 1. movement bounds: each moving body's box, enlarged by its motion over the step;
//! 2. broad phase: a dynamic AABB tree finds new candidate pairs for the bodies that
//!    moved;
//! 3. narrow phase: contact manifolds (separating axis test for boxes and hulls, closed
//!    forms, GJK and EPA), reused while a pair barely moves, impulses matched by feature
//!    ids;
//! 4. solve, in `substeps` sub-steps: integrate velocities (gravity, forces), warm start,
//!    soft contacts with a bounded push-out, integrate positions, relax; then
//!    restitution;
//! 5. continuous collision: time of impact for fast bodies (`ccd`), moved back to it;
//! 6. projection: a bounded push-out of the deep penetration that remains;
//! 7. sleep: islands of bodies at rest fall asleep together, and wake together.
//!
//! Events of the step are then in [`World::events`]. A world whose bodies all sleep and
//! that no call has changed steps in O(bodies). [`World::step_traced`] records a digest
//! after every stage; [`World::step_observed`] calls back as each stage ends, to time
//! the stages on the target (a cycle counter on a Cortex-M, `Instant` on a host).
//!
//! # Units
//!
//! SI throughout: metres, kilograms, seconds, radians (and m/s, rad/s, N, N·s). Y is up:
//! the default gravity is `(0, −9.81, 0)` m/s². Tolerances suit bodies from about 5 cm to
//! 10 m and worlds within about 1 km of the origin; positions beyond
//! ±[`MAX_COORDINATE`] (10 km) are refused. Normals point from body A to body B;
//! separations are negative when penetrating.
//!
//! # Determinism
//!
//! carom gives bit-identical results on every target (x86_64, aarch64, wasm32,
//! Cortex-M with or without an FPU), in debug and release, when the user keeps to these
//! rules:
//! - **Same inputs, same order of calls.** Build worlds by the same calls in the same
//!   order (removals and re-additions included) and call the same setters in the same
//!   order between steps: a world built in another order may differ.
//! - **Same world type and configuration.** Capacities are part of the result (what does
//!   not fit is dropped by a rule that depends on them), and so is every
//!   [`WorldConfig`] field.
//! - **Same math backend.** The `micromath` feature gives other bits than the default
//!   libm (deterministic too; snapshots record which).
//! - **No host floats mixed in.** Feed the world values that are the same on every peer:
//!   not frame times from a clock (step a fixed number of times, or use
//!   [`FixedTimestep`] with the same frame times on every peer), not results of the
//!   platform's `sin`/`cos`/`sqrt` or of fused multiply-adds that differ by target
//!   (compute them with [`math::scalar`], which is libm's code on every target but the
//!   square root of an x86 build with AVX or a wasm32 build with SIMD, the same
//!   correctly rounded root as an instruction,
//!   or send the inputs, not the results),
//!   not values from an unordered container's iteration order.
//! - **Step, do not interpolate, the state you compare.** [`FrameSteps::alpha`] is
//!   for drawing only.
//!
//! The step itself uses only `+ − × ÷ √`, compares and selects, iterates in slot order
//! and sorts on integer keys; 32-bit x86 without SSE2 (x87) is refused at build time.
//! [`World::checksum`] and [`World::body_checksum`] find where two worlds differ.
//!
//! # WebAssembly: build with SIMD
//!
//! The solver works on four contacts (and integrates four bodies) at a time in plain
//! `[f32; 4]` lanes, which compilers turn into vector instructions on x86_64 (SSE2) and
//! aarch64 (NEON) by default. On wasm32 they do so only when WebAssembly's 128-bit SIMD
//! is enabled, which every current browser and Node run: build with
//! `RUSTFLAGS="-C target-feature=+simd128"`, or in the game's `.cargo/config.toml`:
//!
//! ```toml
//! [target.wasm32-unknown-unknown]
//! rustflags = ["-C", "target-feature=+simd128"]
//! ```
//!
//! A step is then 1.9 to 2.6 times faster (`demos/wasm/bench.sh`: `pyramid20`, `boxes`,
//! `hulls`, `spheres` under Node) and its bits do not change: the lanes do the scalar
//! operations in the scalar order, and the square root becomes the `f32x4.sqrt`
//! instruction, the IEEE root that libm's software routine (a wasm32 build without SIMD)
//! computes too. CI runs the math tests of such a build (the roots against libm's, bit
//! for bit) and checks the golden checksums of a wasm32 build with and without it (and of
//! the web page, built with it, in Chromium).
//!
//! # Capacity planning
//!
//! `World<'a, BODIES, CONTACTS, EVENTS = 256>` holds everything inline, so its size is
//! known at compile time and nothing is allocated:
//! - `BODIES`: body slots. [`World::add`] on a full pool is [`Error::PoolFull`].
//! - `CONTACTS`: contact slots, one per candidate pair whose enlarged boxes overlap,
//!   touching or not (about three per touching contact in a pile of boxes at the default
//!   `aabb_margin`), and as many new candidate pairs per step. Within a step, what does
//!   not fit is dropped by a fixed rule (lowest body-slot keys kept) and counted in
//!   [`StepReport::dropped_pairs`] and [`StepReport::dropped_contacts`]: size it so those
//!   stay zero.
//! - `EVENTS`: events per step; more are counted in [`StepReport::dropped_events`].
//!
//! Memory is a fixed part (under 6 KiB) plus, on 64-bit hosts, **680 bytes per body
//! slot** and **1113 bytes per contact slot**: a `World<128, 512>` is about 0.66 MB, a
//! `World<1024, 8192>` about 9.8 MB. [`World::max_snapshot_len`] gives the snapshot
//! buffer a world type can need. A big world belongs in a `static` (`World::new` is a
//! `const fn`) or, in optimised builds, a `Box`: see [`World`] and the README's
//! "Capacity" section.
//!
//! # Features
//!
//! None is on by default: `micromath` (the other math backend), `arbitrary`, `serde`,
//! `defmt`, `mint` (interop), and two test-support modules: `scenes` (the standard scenes
//! of SCENES.md, for demos and benchmarks) and `props` (the property checkers the tests
//! and fuzz targets assert).
//!
//! # Narrow phase on its own
//!
//! ```
//! use carom::collide::contact;
//! use carom::math::{Iso, Vec3};
//! use carom::shape::Shape;
//!
//! # fn main() -> Result<(), carom::Error> {
//! let ground = Shape::cuboid(Vec3::new(5.0, 0.5, 5.0))?;
//! let crate_box = Shape::cuboid(Vec3::new(0.5, 0.5, 0.5))?;
//! let ground_pose = Iso::from_position(Vec3::new(0.0, -0.5, 0.0));
//! let box_pose = Iso::from_position(Vec3::new(0.0, 0.49, 0.0)); // 1 cm deep
//! let m = contact(&ground, &ground_pose, &crate_box, &box_pose, 0.02)?.expect("touching");
//! assert_eq!(m.points().len(), 4);
//! # Ok(())
//! # }
//! ```
#![no_std]
#![cfg_attr(docsrs, feature(doc_cfg))]
#![forbid(unsafe_code)]
#![deny(missing_docs)]
#![warn(clippy::std_instead_of_core, clippy::alloc_instead_of_core)]

// x87 floating point (32-bit x86 without SSE2, such as i586) rounds intermediates to 80
// bits: every golden checksum differs there. Refuse to build rather than give other bits.
#[cfg(all(target_arch = "x86", not(target_feature = "sse2")))]
compile_error!(
    "carom needs IEEE single-precision arithmetic: x87 floating point (x86 without SSE2, \
     e.g. i586 targets) would give other bits than every other target; build for a target \
     with SSE2 (i686) instead"
);

// Tests use std; so does the code `arbitrary`'s derive generates (a host-only feature).
#[cfg(any(test, feature = "arbitrary"))]
extern crate std;

/// The README's example, compiled and run as a doctest.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
pub struct ReadmeDoctests;

pub mod collide;
pub mod config;
pub mod dynamics;
pub mod error;
pub mod math;
#[cfg(feature = "mint")]
mod mint_interop;
#[cfg(feature = "props")]
pub mod props;
pub mod rng;
#[cfg(feature = "scenes")]
pub mod scenes;
pub mod shape;
mod sort;
pub mod timestep;
mod world;

pub use config::{CombineRule, WorldConfig};
pub use dynamics::body::{BodyDesc, BodyKind, MassSpec, Material};
pub use dynamics::events::{Event, StepReport};
pub use dynamics::query::{QueryFilter, RayCastHit};
#[cfg(feature = "serde")]
pub use dynamics::snapshot::RestoreSeed;
pub use dynamics::snapshot::{Stage, StepTrace};
pub use dynamics::BodyHandle;
pub use error::{Error, HullError, Input, Pool, SnapshotError, MAX_COORDINATE};
pub use math::{Aabb, Iso, Mat3, Quat, Vec3};
pub use shape::{ConvexHull, Ray, Shape};
pub use timestep::{FixedTimestep, FrameSteps};
pub use world::{BodyRef, World};
