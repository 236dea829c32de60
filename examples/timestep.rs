//! A game loop with a fixed physics step and interpolated rendering, using
//! `carom::FixedTimestep`.
//!
//! The frames here are simulated (uneven frame times from a seeded generator, one
//! 400 ms hitch) so the run is instant and repeatable; in a real game `elapsed` comes
//! from `std::time::Instant` or your engine's frame clock.
//!
//! Run with `cargo run --release --example timestep`.

use carom::rng::SplitMix64;
use carom::{BodyDesc, FixedTimestep, Shape, Vec3, World};

fn main() -> Result<(), carom::Error> {
    let mut world: World<'static, 8, 16> = World::new();
    world.add(
        BodyDesc::fixed(Shape::cuboid(Vec3::new(10.0, 0.5, 10.0))?)
            .position(Vec3::new(0.0, -0.5, 0.0)),
    )?;
    let ball = world.add(
        BodyDesc::dynamic(Shape::sphere(0.5)?)
            .position(Vec3::new(0.0, 10.0, 0.0))
            .velocity(Vec3::new(2.0, 0.0, 0.0)),
    )?;

    // Steps of the world's dt (1/60 s); at most 5 per frame, so a long frame cannot make
    // the next one longer still (the "spiral of death").
    let mut clock = FixedTimestep::new(world.config().dt, 5)?;

    // The renderer draws between the last two physics states.
    let mut previous = world.body(ball)?.position();
    let mut current = previous;

    let mut rng = SplitMix64::new(2024);
    let (mut wall_clock, mut total_steps, mut total_dropped) = (0.0f64, 0u64, 0u64);
    println!("frame  elapsed  steps dropped  alpha  physics y  drawn y");
    for frame in 0..120 {
        // This frame's duration: 4 to 30 ms, and one 400 ms hitch at frame 60.
        let elapsed = if frame == 60 {
            0.4
        } else {
            f64::from(rng.range(0.004, 0.030))
        };
        wall_clock += elapsed;

        let s = clock.advance(elapsed)?;
        for _ in 0..s.steps {
            previous = current;
            world.step();
            current = world.body(ball)?.position();
        }
        total_steps += u64::from(s.steps);
        total_dropped += s.dropped;

        // Draw the ball `alpha` of the way from the previous state to the current one.
        let drawn = previous.lerp(current, s.alpha);
        if frame % 12 == 0 || s.dropped > 0 {
            println!(
                "{frame:5} {:6.1} ms {:5} {:7} {:6.3} {:9.4} {:8.4}",
                elapsed * 1e3,
                s.steps,
                s.dropped,
                s.alpha,
                current.y,
                drawn.y
            );
        }
    }
    let dt = f64::from(clock.dt());
    println!(
        "wall clock {wall_clock:.4} s = {total_steps} steps run + {total_dropped} dropped \
         ({:.4} s) + {:.4} s carried over",
        (total_steps + total_dropped) as f64 * dt,
        clock.accumulator()
    );
    let simulated = (total_steps + total_dropped) as f64 * dt + clock.accumulator();
    assert!((simulated - wall_clock).abs() < 1e-9);
    Ok(())
}
