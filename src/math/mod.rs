//! Small, deterministic 3D math: [`Vec3`], [`Quat`], [`Mat3`], [`Iso`] and [`Aabb`].
//!
//! This is the only module that calls `libm` (or, with the feature `micromath`, micromath's
//! approximate trigonometry and a square root refined from its inverse-square-root guess):
//! everything else reaches square roots and trigonometry through [`scalar`]. The simulation step itself uses only `+ − × ÷ √`, comparisons and selects,
//! so it gives the same bits on every target. No `mul_add`, no SIMD intrinsics but one:
//! `lanes` runs four contacts side by side as plain `[f32; 4]` arithmetic, lane for lane
//! the scalar operations, which compilers may vectorise without changing a bit; the one
//! intrinsic is x86's square root (four lanes at once in every x86 build, the scalar root
//! in a build that enables AVX: [`scalar::sqrt`]), IEEE's correctly rounded root as
//! libm's is.

mod aabb;
mod iso;
pub(crate) mod lanes;
mod mat3;
mod quat;
pub mod scalar;
mod vec3;
pub(crate) mod vec64;

pub use aabb::Aabb;
pub use iso::Iso;
pub use mat3::Mat3;
pub use quat::Quat;
pub(crate) use quat::UNIT_TOLERANCE;
pub use vec3::Vec3;
