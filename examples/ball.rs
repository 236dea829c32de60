//! A ball dropped on the ground: the smallest complete carom program.
//!
//! Run with `cargo run --release --example ball`.

use carom::{BodyDesc, Material, Shape, Vec3, World};

fn main() -> Result<(), carom::Error> {
    // Room for 8 bodies and 16 contacts, all inline (a few KiB): fine on the stack.
    // Gravity is (0, -9.81, 0) and the step is 1/60 s (`WorldConfig::DEFAULT`).
    let mut world: World<'static, 8, 16> = World::new();

    // The ground: a static box whose top face is at y = 0.
    world.add(
        BodyDesc::fixed(Shape::cuboid(Vec3::new(10.0, 0.5, 10.0))?)
            .position(Vec3::new(0.0, -0.5, 0.0)),
    )?;

    // A ball of radius 0.5 m, 4 m up, that keeps half its speed when it bounces.
    let bouncy = Material {
        restitution: 0.5,
        ..Material::DEFAULT
    };
    let ball = world.add(
        BodyDesc::dynamic(Shape::sphere(0.5)?)
            .position(Vec3::new(0.0, 4.0, 0.0))
            .material(bouncy),
    )?;

    // Four seconds of simulation, one line every quarter second.
    for step in 1..=240 {
        world.step();
        if step % 15 == 0 {
            let b = world.body(ball)?;
            println!(
                "t = {:4.2} s: height {:5.3} m, vertical speed {:+6.3} m/s{}",
                step as f32 / 60.0,
                b.position().y,
                b.linear_velocity().y,
                if b.is_awake() { "" } else { " (asleep)" }
            );
        }
    }
    // Resting on the ground: the centre one radius above y = 0.
    let y = world.body(ball)?.position().y;
    println!("the ball rests with its centre at y = {y:.4} m (radius 0.5 m)");
    assert!((y - 0.5).abs() < 0.02);
    Ok(())
}
