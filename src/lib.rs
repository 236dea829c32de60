//! # carom
//!
//! A `no_std`, allocation-free, deterministic 3D rigid-body collision engine with a fixed
//! time step.
//!
//! **The principle:** the same inputs give bit-identical results on every target, in
//! bounded memory and bounded time, and no input makes it panic.
//!
//! The crate has two layers:
//! - [`shape`] and [`collide`]: stateless geometry, pure functions of (shape, pose)
//!   pairs: GJK distance, EPA penetration, clipped contact manifolds, time of impact, ray
//!   casts.
//! - [`World`]: bodies in fixed-capacity pools and one fixed step, with
//!   [`FixedTimestep`] to drive it from a game's variable frame times.
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

pub use config::WorldConfig;
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
