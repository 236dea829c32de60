//! A 500 m/s bullet fired at five thin walls, with and without continuous collision.
//!
//! At 500 m/s a body moves 8.3 m in one 1/60 s step: far more than a 10 cm wall is
//! thick. Switched off, continuous collision lets the bullet tunnel through every wall.
//! Switched on (`BodyDesc::ccd`, the default), carom does two things for a fast body: the
//! narrow phase keeps contacts out to the distance the pair can close in one step
//! (a speculative contact), so the solver stops the bullet at the wall within the step;
//! and a time-of-impact sweep after the solve moves back any fast body that still passed
//! through something (counted in `StepReport::ccd_hits`; here the speculative contact
//! already did the job).
//!
//! Run with `cargo run --release --example bullet`.

use carom::{BodyDesc, Shape, Vec3, World, WorldConfig};

fn main() -> Result<(), carom::Error> {
    for ccd in [true, false] {
        fire(ccd)?;
    }
    Ok(())
}

fn fire(ccd: bool) -> Result<(), carom::Error> {
    // No gravity: only the walls can stop the bullet.
    let config = WorldConfig {
        gravity: Vec3::ZERO,
        ..WorldConfig::DEFAULT
    };
    let mut world: World<'static, 8, 16> = World::with_config(config)?;

    // Five walls 10 cm thick, 2 m apart, from x = 0 to x = 8.
    let wall = Shape::cuboid(Vec3::new(0.05, 5.0, 5.0))?;
    for i in 0..5 {
        world.add(BodyDesc::fixed(wall).position(Vec3::new(2.0 * i as f32, 0.0, 0.0)))?;
    }

    // A 5 cm ball 5 m before the first wall, at 500 m/s.
    let bullet = world.add(
        BodyDesc::dynamic(Shape::sphere(0.05)?)
            .position(Vec3::new(-5.0, 0.0, 0.0))
            .velocity(Vec3::new(500.0, 0.0, 0.0))
            .ccd(ccd),
    )?;

    println!(
        "== continuous collision {} ==",
        if ccd { "on" } else { "off" }
    );
    let (mut sweeps, mut ccd_hits) = (0, 0);
    for step in 1..=6 {
        let report = world.step();
        sweeps += report.ccd_sweeps;
        ccd_hits += report.ccd_hits;
        let b = world.body(bullet)?;
        println!(
            "step {step}: bullet at x = {:+8.3} m, speed {:7.2} m/s",
            b.position().x,
            b.linear_velocity().length()
        );
    }
    let x = world.body(bullet)?.position().x;
    // The first wall's near face is at x = -0.05: the bullet's centre stops one radius
    // before it, at x = -0.1.
    let walls_passed = (0..5).filter(|&i| x > 2.0 * i as f32).count();
    println!(
        "time-of-impact sweeps: {sweeps}, hits: {ccd_hits}; walls passed: {walls_passed} of 5\n"
    );
    if ccd {
        assert!(x <= -0.05, "the bullet must stop at the first wall");
    }
    Ok(())
}
