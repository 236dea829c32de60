//! The world's doors: every bad input returns its exact error and leaves the world
//! unchanged; full pools and stale handles are errors, never panics.

use carom::{
    BodyDesc, BodyKind, Error, Input, Iso, Material, Pool, Quat, Shape, Vec3, World, WorldConfig,
};

type W = World<'static, 8, 32>;

fn ball() -> Shape<'static> {
    Shape::sphere(0.5).unwrap()
}

/// A 10 m square ground, its top face at y = 0.
fn add_ground(w: &mut World<'_, 8, 32>) {
    w.add(
        BodyDesc::fixed(Shape::cuboid(Vec3::new(5.0, 0.5, 5.0)).unwrap())
            .position(Vec3::new(0.0, -0.5, 0.0)),
    )
    .unwrap();
}

fn small_world() -> W {
    let mut w = W::new();
    add_ground(&mut w);
    w.add(BodyDesc::dynamic(ball()).position(Vec3::new(0.0, 1.0, 0.0)))
        .unwrap();
    w
}

/// Apply `f`, expect `err`, and check the world's checksum and body count did not move.
fn refused(w: &mut W, err: Error, f: impl FnOnce(&mut W) -> Result<(), Error>) {
    let (sum, n) = (w.checksum(), w.body_count());
    assert_eq!(f(w), Err(err));
    assert_eq!(w.checksum(), sum, "world changed after {err:?}");
    assert_eq!(w.body_count(), n);
}

#[test]
fn bad_body_descriptions_are_refused_with_their_error() {
    let mut w = small_world();
    let nan = f32::NAN;
    let cases: [(BodyDesc<'static>, Error); 10] = [
        (
            BodyDesc::dynamic(ball()).position(Vec3::new(nan, 0.0, 0.0)),
            Error::NonFinite(Input::Position),
        ),
        (
            BodyDesc::dynamic(ball()).rotation(Quat::from_xyzw(0.0, 0.0, 0.0, 2.0)),
            Error::NotUnit(Input::Rotation),
        ),
        (
            BodyDesc::dynamic(ball()).rotation(Quat::from_xyzw(nan, 0.0, 0.0, 1.0)),
            Error::NonFinite(Input::Rotation),
        ),
        (
            BodyDesc::dynamic(ball()).velocity(Vec3::new(0.0, f32::INFINITY, 0.0)),
            Error::NonFinite(Input::LinearVelocity),
        ),
        (
            BodyDesc::dynamic(ball()).angular_velocity(Vec3::splat(nan)),
            Error::NonFinite(Input::AngularVelocity),
        ),
        (
            BodyDesc::dynamic(ball()).density(-1.0),
            Error::NotPositive(Input::Density),
        ),
        (
            BodyDesc::dynamic(ball()).mass(0.0),
            Error::NotPositive(Input::Mass),
        ),
        (
            BodyDesc::dynamic(ball()).material(Material {
                restitution: 1.5,
                ..Material::DEFAULT
            }),
            Error::OutOfRange(Input::Material),
        ),
        (
            BodyDesc::dynamic(ball()).damping(-0.1, 0.0),
            Error::Negative(Input::Damping),
        ),
        (
            BodyDesc::dynamic(Shape::half_space(Vec3::Y).unwrap()),
            Error::StaticOnly,
        ),
    ];
    for (desc, err) in cases {
        refused(&mut w, err, |w| w.add(desc).map(|_| ()));
    }
}

#[test]
fn full_body_pool_is_an_error_and_changes_nothing() {
    let mut w = small_world();
    for i in 0..6 {
        w.add(BodyDesc::dynamic(ball()).position(Vec3::new(i as f32 * 2.0, 3.0, 0.0)))
            .unwrap();
    }
    assert_eq!(w.body_count(), 8);
    refused(&mut w, Error::PoolFull(Pool::Bodies), |w| {
        w.add(BodyDesc::dynamic(ball())).map(|_| ())
    });
    // The world goes on.
    w.step();
    assert_eq!(w.body_count(), 8);
}

#[test]
fn stale_handles_are_refused_everywhere() {
    let mut w = small_world();
    let h = w
        .add(BodyDesc::dynamic(ball()).position(Vec3::new(3.0, 1.0, 0.0)))
        .unwrap();
    w.remove(h).unwrap();
    assert_eq!(w.remove(h), Err(Error::StaleHandle));
    assert!(matches!(w.body(h), Err(Error::StaleHandle)));
    refused(&mut w, Error::StaleHandle, |w| w.set_pose(h, Iso::IDENTITY));
    refused(&mut w, Error::StaleHandle, |w| {
        w.set_linear_velocity(h, Vec3::X)
    });
    refused(&mut w, Error::StaleHandle, |w| {
        w.apply_impulse_at(h, Vec3::X, Vec3::ZERO)
    });
    refused(&mut w, Error::StaleHandle, |w| w.wake(h));
    // The slot is reused with a new generation; the old handle stays stale.
    let h2 = w.add(BodyDesc::dynamic(ball())).unwrap();
    assert_eq!(h2.index, h.index);
    assert_ne!(h2.generation, h.generation);
    assert!(w.body(h).is_err());
    assert!(w.body(h2).is_ok());
}

#[test]
fn bad_setter_values_are_refused() {
    let mut w = small_world();
    let h = w.handles().nth(1).unwrap();
    let bad_pose = Iso::new(Vec3::ZERO, Quat::from_xyzw(1.0, 1.0, 0.0, 0.0));
    refused(&mut w, Error::NotUnit(Input::Rotation), |w| {
        w.set_pose(h, bad_pose)
    });
    refused(&mut w, Error::NonFinite(Input::LinearVelocity), |w| {
        w.set_linear_velocity(h, Vec3::new(f32::NAN, 0.0, 0.0))
    });
    refused(&mut w, Error::NonFinite(Input::Force), |w| {
        w.apply_force(h, Vec3::splat(f32::INFINITY))
    });
    refused(&mut w, Error::NonFinite(Input::Position), |w| {
        w.apply_impulse_at(h, Vec3::X, Vec3::new(0.0, f32::NAN, 0.0))
    });
    refused(&mut w, Error::Negative(Input::Material), |w| {
        w.set_material(
            h,
            Material {
                restitution: -2.0,
                ..Material::DEFAULT
            },
        )
    });
}

#[test]
fn bad_configs_are_refused_and_the_old_one_kept() {
    let mut w = small_world();
    let bad = [
        (
            WorldConfig {
                dt: 0.0,
                ..WorldConfig::DEFAULT
            },
            Error::OutOfRange(Input::Time),
        ),
        (
            WorldConfig {
                dt: 1.0e6,
                ..WorldConfig::DEFAULT
            },
            Error::OutOfRange(Input::Time),
        ),
        (
            WorldConfig {
                max_linear_speed: 3.0e38,
                ..WorldConfig::DEFAULT
            },
            Error::OutOfRange(Input::Config),
        ),
        (
            WorldConfig {
                relax_iterations: 0,
                ..WorldConfig::DEFAULT
            },
            Error::OutOfRange(Input::Iterations),
        ),
        (
            WorldConfig {
                gravity: Vec3::new(0.0, -1.0e5, 0.0),
                ..WorldConfig::DEFAULT
            },
            Error::OutOfRange(Input::Gravity),
        ),
        (
            WorldConfig {
                dt: f32::NAN,
                ..WorldConfig::DEFAULT
            },
            Error::NonFinite(Input::Time),
        ),
        (
            WorldConfig {
                substeps: 0,
                ..WorldConfig::DEFAULT
            },
            Error::OutOfRange(Input::Iterations),
        ),
        (
            WorldConfig {
                gravity: Vec3::splat(f32::NAN),
                ..WorldConfig::DEFAULT
            },
            Error::NonFinite(Input::Gravity),
        ),
        (
            WorldConfig {
                projection_factor: 1.5,
                ..WorldConfig::DEFAULT
            },
            Error::OutOfRange(Input::Config),
        ),
    ];
    for (cfg, err) in bad {
        assert_eq!(w.set_config(cfg), Err(err));
        assert_eq!(*w.config(), WorldConfig::DEFAULT);
        assert!(matches!(W::with_config(cfg), Err(e) if e == err));
    }
}

#[test]
fn static_bodies_never_move_and_report_infinite_mass() {
    let mut w = small_world();
    let ground = w.handles().next().unwrap();
    w.set_linear_velocity(ground, Vec3::X).unwrap();
    for _ in 0..10 {
        w.step();
    }
    let g = w.body(ground).unwrap();
    assert_eq!(g.kind(), BodyKind::Static);
    assert_eq!(g.position(), Vec3::new(0.0, -0.5, 0.0));
    assert_eq!(g.mass(), f32::INFINITY);
}

#[test]
fn free_fall_matches_the_integrator_exactly() {
    // Semi-implicit Euler over sub-steps h = dt / s: after k sub-steps v_k = -g h k,
    // y_k = y0 - g h² k(k+1)/2. No contact in reach.
    let mut w = W::new();
    let h = w
        .add(BodyDesc::dynamic(ball()).position(Vec3::new(0.0, 100.0, 0.0)))
        .unwrap();
    let g = 9.81f32;
    let sub = 1.0f32 / 60.0 / WorldConfig::DEFAULT.substeps as f32;
    for _ in 0..60 {
        w.step();
    }
    let b = w.body(h).unwrap();
    let n = 60.0 * WorldConfig::DEFAULT.substeps as f32;
    assert!((b.linear_velocity().y + g * sub * n).abs() < 1e-3);
    let y = 100.0 - g * sub * sub * n * (n + 1.0) / 2.0;
    assert!(
        (b.position().y - y).abs() < 1e-3,
        "{} vs {y}",
        b.position().y
    );
    // Mass of a 0.5 m ball of water.
    let m = 1000.0 * 4.0 / 3.0 * core::f32::consts::PI * 0.125;
    assert!((b.mass() - m).abs() / m < 1e-5);
}

/// Shapes built from their public fields go through the same checks as their
/// constructors at `World::add`: NaN, negative, zero, too small or too large sizes and
/// unnormalised half-space normals are refused with the constructor's error, and the
/// world is unchanged.
#[test]
fn shapes_from_public_fields_are_checked_at_add() {
    use carom::shape::{Capsule, Cuboid, HalfSpace, Sphere, Triangle};
    let mut w = small_world();
    let before = w.checksum();
    let bad = [
        Shape::Sphere(Sphere { radius: f32::NAN }),
        Shape::Sphere(Sphere { radius: -1.0 }),
        Shape::Sphere(Sphere { radius: 5000.0 }),
        Shape::Sphere(Sphere { radius: 1.0e-7 }),
        Shape::Capsule(Capsule {
            half_height: f32::INFINITY,
            radius: 0.5,
        }),
        Shape::Capsule(Capsule {
            half_height: 0.5,
            radius: 0.0,
        }),
        Shape::Cuboid(Cuboid {
            half_extents: Vec3::new(1.0, -1.0, 1.0),
        }),
        Shape::HalfSpace(HalfSpace {
            normal: Vec3::new(0.0, 2.0, 0.0),
        }),
        Shape::Triangle(Triangle {
            vertices: [Vec3::ZERO, Vec3::X, Vec3::X * 2.0],
        }),
    ];
    for shape in bad {
        let fixed = matches!(shape, Shape::HalfSpace(_) | Shape::Triangle(_));
        let desc = if fixed {
            BodyDesc::fixed(shape)
        } else {
            BodyDesc::dynamic(shape)
        };
        assert!(w.add(desc).is_err(), "{shape:?} was accepted");
        assert_eq!(w.checksum(), before);
    }
    // A valid one written by hand is accepted.
    assert!(w
        .add(BodyDesc::dynamic(Shape::Sphere(Sphere { radius: 0.5 })).position(Vec3::Y * 3.0))
        .is_ok());
}

/// A 100 m ball of water (inside the size range) has an inertia whose determinant is
/// beyond `f32`; its mass properties are still derived (the inverse is taken scaled).
#[test]
fn a_100_m_ball_of_water_is_accepted() {
    let mut w = small_world();
    let h = w
        .add(BodyDesc::dynamic(Shape::sphere(100.0).unwrap()).position(Vec3::Y * 200.0))
        .unwrap();
    let m = w.body(h).unwrap().mass();
    let want = 1000.0 * 4.0 / 3.0 * core::f32::consts::PI * 1.0e6;
    assert!((m - want).abs() / want < 1e-5, "{m} vs {want}");
    for _ in 0..10 {
        w.step();
    }
    assert!(w.body(h).unwrap().position().is_finite());
}

/// A material set on a body already in contact takes effect at the next step: a box
/// sliding at 3 m/s on ice that turns rough stops after `v²/(2 μ_k g)`, and one that
/// stays on ice keeps its speed.
#[test]
fn a_new_material_reaches_existing_contacts() {
    let slide = |mu_after: f32| -> f32 {
        let mut w = W::new();
        w.add(
            BodyDesc::fixed(Shape::cuboid(Vec3::new(50.0, 0.5, 5.0)).unwrap())
                .position(Vec3::new(0.0, -0.5, 0.0)),
        )
        .unwrap();
        let ice = Material {
            static_friction: 0.0,
            kinetic_friction: 0.0,
            restitution: 0.0,
            ..Material::DEFAULT
        };
        let h = w
            .add(
                BodyDesc::dynamic(Shape::cuboid(Vec3::splat(0.25)).unwrap())
                    .position(Vec3::new(-40.0, 0.25, 0.0))
                    .material(ice),
            )
            .unwrap();
        // The ground's friction is 1: the pair's friction is √(μ_box · 1) = √μ_box.
        let handles: Vec<_> = w.handles().collect();
        let rough = Material {
            static_friction: 1.0,
            kinetic_friction: 1.0,
            restitution: 0.0,
            ..Material::DEFAULT
        };
        w.set_material(handles[0], rough).unwrap();
        for _ in 0..30 {
            w.step();
        }
        w.set_linear_velocity(h, Vec3::new(3.0, 0.0, 0.0)).unwrap();
        w.step();
        assert!(w.pair_count() >= 1, "the box rests on the ground");
        w.set_material(
            h,
            Material {
                static_friction: mu_after,
                kinetic_friction: mu_after,
                ..ice
            },
        )
        .unwrap();
        let x0 = w.body(h).unwrap().position().x;
        for _ in 0..120 {
            w.step();
        }
        w.body(h).unwrap().position().x - x0
    };
    // Frictionless: 2 s at ~3 m/s.
    let free = slide(0.0);
    assert!((free - 6.0).abs() < 0.1, "frictionless slide {free} m");
    // μ_box = 0.25, so μ = 0.5: stops after v²/(2 μ g) = 9 / 9.81 = 0.92 m.
    let stopped = slide(0.25);
    let d = 9.0 / (2.0 * 0.5 * 9.81);
    assert!(
        (stopped - d).abs() < 0.1,
        "slide {stopped} m, analytic {d} m"
    );
}

/// The centre of mass a body reports is `pose · c` (its shape's centre `c` of mass in the
/// body frame) to the bit, after everything that moves a body: steps with contacts and
/// projection, continuous collision of a fast body, a teleport, and a snapshot restored
/// into another world. (The world keeps it with the pose rather than forming it on
/// every read.)
#[test]
fn the_centre_of_mass_follows_every_pose_change() {
    use carom::ConvexHull;
    // An asymmetric hull: its centre of mass is off the body origin.
    let hull = ConvexHull::new(&[
        Vec3::ZERO,
        Vec3::new(2.0, 0.0, 0.0),
        Vec3::new(0.0, 1.0, 0.0),
        Vec3::new(0.0, 0.0, 0.5),
        Vec3::new(0.3, 0.4, 0.2),
    ])
    .unwrap();
    let hulls = [hull];
    let shape = Shape::Hull(&hulls[0]);
    let local = shape.mass_properties(1.0).unwrap().center;
    assert!(local.length() > 0.3, "off-centre: {local:?}");
    let mut w: World<'_, 8, 32> = World::new();
    add_ground(&mut w);
    let tumbling = w
        .add(
            BodyDesc::dynamic(shape)
                .position(Vec3::new(0.0, 0.2, 0.0))
                .angular_velocity(Vec3::new(3.0, 1.0, -2.0)),
        )
        .unwrap();
    let fast = w
        .add(
            BodyDesc::dynamic(shape)
                .position(Vec3::new(3.0, 4.0, 0.0))
                .velocity(Vec3::new(0.0, -80.0, 0.0)),
        )
        .unwrap();
    let check = |w: &World<'_, 8, 32>, when: &str| {
        for h in [tumbling, fast] {
            let b = w.body(h).unwrap();
            let want = Iso::new(b.position(), b.rotation()).transform_point(local);
            let got = b.center_of_mass();
            let bits = |v: Vec3| [v.x.to_bits(), v.y.to_bits(), v.z.to_bits()];
            assert_eq!(bits(got), bits(want), "{when}: {got:?} against {want:?}");
        }
    };
    check(&w, "added");
    for k in 0..90 {
        w.step();
        check(&w, &format!("step {k}"));
    }
    w.set_pose(
        tumbling,
        Iso::new(
            Vec3::new(-1.0, 2.0, 0.5),
            Quat::from_axis_angle(Vec3::Z, 0.7),
        ),
    )
    .unwrap();
    check(&w, "teleported");
    let mut buf = vec![0u8; w.snapshot_len()];
    let n = w.snapshot(&mut buf).unwrap();
    let mut other: World<'_, 8, 32> = World::new();
    other.restore_with_hulls(&buf[..n], &hulls).unwrap();
    check(&other, "restored");
    for k in 0..30 {
        other.step();
        check(&other, &format!("restored, step {k}"));
    }
}

/// A world after [`World::reset`] is a new world: after a run that left bodies, contacts,
/// events, a removed slot (its generation bumped), a changed config and the solver's and
/// broad phase's scratch behind, its every field prints as a new world's, and driven the
/// same way as a new world it hashes and snapshots the same, step for step.
#[test]
fn a_reset_world_is_a_new_world() {
    type R = World<'static, 16, 64, 16>;
    fn drive(w: &mut R, steps: u32) -> Vec<u64> {
        w.add(
            BodyDesc::fixed(Shape::cuboid(Vec3::new(5.0, 0.5, 5.0)).unwrap())
                .position(Vec3::new(0.0, -0.5, 0.0)),
        )
        .unwrap();
        let cube = Shape::cuboid(Vec3::splat(0.25)).unwrap();
        let mut handles = Vec::new();
        for i in 0..6 {
            let x = 0.3 * i as f32 - 0.75;
            let shape = if i % 2 == 0 { cube } else { ball() };
            let desc = BodyDesc::dynamic(shape).position(Vec3::new(x, 0.6 + 0.55 * i as f32, 0.1));
            handles.push(w.add(desc).unwrap());
        }
        (0..steps)
            .map(|k| {
                if k == steps / 2 {
                    w.remove(handles[3]).unwrap();
                }
                w.step();
                w.checksum()
            })
            .collect()
    }
    let mut used: Box<R> = Box::new(R::new());
    used.set_config(WorldConfig {
        gravity: Vec3::new(0.5, -12.0, 0.0),
        ..WorldConfig::DEFAULT
    })
    .unwrap();
    drive(&mut used, 90);
    assert!(used.step_count() > 0 && used.pair_count() > 0);
    used.reset();
    let fresh: Box<R> = Box::new(R::new());
    assert_eq!(format!("{used:?}"), format!("{fresh:?}"));
    let mut fresh = fresh;
    assert_eq!(drive(&mut used, 120), drive(&mut fresh, 120));
    let (mut a, mut b) = (
        vec![0u8; used.snapshot_len()],
        vec![0u8; fresh.snapshot_len()],
    );
    assert_eq!(used.snapshot(&mut a), fresh.snapshot(&mut b));
    assert_eq!(a, b);
}
