//! Contact events and sensors: a ball falls through a sensor volume, hits the ground and
//! bounces; every event of every step is printed.
//!
//! Run with `cargo run --release --example events`.

use carom::{BodyDesc, BodyHandle, Event, Material, Shape, Vec3, World};

fn main() -> Result<(), carom::Error> {
    let mut world: World<'static, 8, 16> = World::new();
    let ground = world.add(
        BodyDesc::fixed(Shape::cuboid(Vec3::new(10.0, 0.5, 10.0))?)
            .position(Vec3::new(0.0, -0.5, 0.0)),
    )?;
    // A sensor: a 1 m thick slab between y = 1.5 and 2.5 that detects, never pushes.
    let sensor = world.add(
        BodyDesc::fixed(Shape::cuboid(Vec3::new(2.0, 0.5, 2.0))?)
            .position(Vec3::new(0.0, 2.0, 0.0))
            .sensor(true),
    )?;
    let ball = world.add(
        BodyDesc::dynamic(Shape::sphere(0.25)?)
            .position(Vec3::new(0.0, 5.0, 0.0))
            .material(Material {
                restitution: 0.6,
                ..Material::DEFAULT
            }),
    )?;
    let name = |h: BodyHandle| match h {
        h if h == ground => "ground",
        h if h == sensor => "sensor",
        h if h == ball => "ball",
        _ => "?",
    };

    // `World::events` holds the events of the last step only: read them after each step.
    let mut counts = [0u32; 5];
    for step in 1..=240 {
        world.step();
        let t = step as f32 / 60.0;
        for event in world.events() {
            match *event {
                Event::SensorEnter { sensor, other } => {
                    counts[0] += 1;
                    println!("{t:5.2} s: {} entered the {}", name(other), name(sensor));
                }
                Event::SensorLeave { sensor, other } => {
                    counts[1] += 1;
                    println!("{t:5.2} s: {} left the {}", name(other), name(sensor));
                }
                Event::ContactBegin { a, b } => {
                    counts[2] += 1;
                    println!("{t:5.2} s: {} and {} touch", name(a), name(b));
                }
                Event::ContactEnd { a, b } => {
                    counts[3] += 1;
                    println!("{t:5.2} s: {} and {} part", name(a), name(b));
                }
                Event::Hit { a, b, speed, .. } => {
                    counts[4] += 1;
                    // Sent when the contact appears, usually a step before the bodies
                    // touch (the solver then stops them).
                    println!(
                        "{t:5.2} s: {} and {} hit at {speed:.2} m/s",
                        name(a),
                        name(b)
                    );
                }
            }
        }
    }
    println!(
        "{} sensor enters, {} leaves, {} contact begins, {} ends, {} hits",
        counts[0], counts[1], counts[2], counts[3], counts[4]
    );
    assert!(counts[0] >= 1 && counts[2] >= 1 && counts[4] >= 1);
    Ok(())
}
