//! Conversions between carom's math types and `mint`'s (feature `mint`), so users of
//! glam, nalgebra, cgmath and other math crates that speak mint pass their own vectors
//! and quaternions.
//!
//! | carom | mint |
//! | --- | --- |
//! | [`Vec3`] | `mint::Vector3<f32>`, `mint::Point3<f32>` |
//! | [`Quat`] | `mint::Quaternion<f32>` (`v` is `(x, y, z)`, `s` is `w`) |
//!
//! Both ways are `From`, so `.into()` works, and `Vec3` and `Quat` implement
//! `mint::IntoMint`. The conversions copy the components and check nothing: a
//! non-finite vector or a quaternion that is not of unit length is refused, as always,
//! where it enters a world or a shape (`Error::NonFinite`, `Error::NotUnit`).
//!
//! ```
//! use carom::{Quat, Vec3};
//!
//! let theirs = mint::Vector3 { x: 1.0f32, y: 2.0, z: 3.0 };
//! let ours: Vec3 = theirs.into();
//! assert_eq!(ours, Vec3::new(1.0, 2.0, 3.0));
//! let back: mint::Vector3<f32> = ours.into();
//! assert_eq!(back, theirs);
//!
//! let q: mint::Quaternion<f32> = Quat::IDENTITY.into();
//! assert_eq!((q.v.x, q.v.y, q.v.z, q.s), (0.0, 0.0, 0.0, 1.0));
//! assert_eq!(Quat::from(q), Quat::IDENTITY);
//! ```

use crate::math::{Quat, Vec3};

impl From<mint::Vector3<f32>> for Vec3 {
    fn from(v: mint::Vector3<f32>) -> Vec3 {
        Vec3::new(v.x, v.y, v.z)
    }
}

impl From<Vec3> for mint::Vector3<f32> {
    fn from(v: Vec3) -> mint::Vector3<f32> {
        mint::Vector3 {
            x: v.x,
            y: v.y,
            z: v.z,
        }
    }
}

impl From<mint::Point3<f32>> for Vec3 {
    fn from(p: mint::Point3<f32>) -> Vec3 {
        Vec3::new(p.x, p.y, p.z)
    }
}

impl From<Vec3> for mint::Point3<f32> {
    fn from(v: Vec3) -> mint::Point3<f32> {
        mint::Point3 {
            x: v.x,
            y: v.y,
            z: v.z,
        }
    }
}

impl mint::IntoMint for Vec3 {
    type MintType = mint::Vector3<f32>;
}

impl From<mint::Quaternion<f32>> for Quat {
    fn from(q: mint::Quaternion<f32>) -> Quat {
        Quat::from_xyzw(q.v.x, q.v.y, q.v.z, q.s)
    }
}

impl From<Quat> for mint::Quaternion<f32> {
    fn from(q: Quat) -> mint::Quaternion<f32> {
        mint::Quaternion {
            v: mint::Vector3 {
                x: q.x,
                y: q.y,
                z: q.z,
            },
            s: q.w,
        }
    }
}

impl mint::IntoMint for Quat {
    type MintType = mint::Quaternion<f32>;
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trips_keep_every_bit() {
        for v in [
            Vec3::new(1.5, -0.0, f32::MIN_POSITIVE),
            Vec3::new(f32::NAN, f32::INFINITY, -3.25),
        ] {
            let m: mint::Vector3<f32> = v.into();
            let p: mint::Point3<f32> = v.into();
            for back in [Vec3::from(m), Vec3::from(p)] {
                assert_eq!(back.x.to_bits(), v.x.to_bits());
                assert_eq!(back.y.to_bits(), v.y.to_bits());
                assert_eq!(back.z.to_bits(), v.z.to_bits());
            }
        }
        let q = Quat::from_axis_angle(Vec3::new(0.0, 1.0, 0.0), 0.7);
        let m: mint::Quaternion<f32> = q.into();
        assert_eq!((m.v.x, m.v.y, m.v.z, m.s), (q.x, q.y, q.z, q.w));
        assert_eq!(Quat::from(m), q);
    }

    #[test]
    fn a_world_refuses_a_converted_rotation_that_is_not_unit() {
        use crate::{BodyDesc, Error, Input, Shape, World};
        let mut world: World<'static, 2, 2> = World::new();
        let q = Quat::from(mint::Quaternion {
            v: mint::Vector3 {
                x: 0.0,
                y: 0.0,
                z: 0.0,
            },
            s: 2.0,
        });
        let shape = Shape::sphere(0.5).unwrap();
        assert_eq!(
            world.add(BodyDesc::dynamic(shape).rotation(q)),
            Err(Error::NotUnit(Input::Rotation))
        );
    }
}
