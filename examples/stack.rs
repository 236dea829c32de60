//! A stack of ten boxes settles and falls asleep; then a heavy ball knocks it over.
//!
//! Run with `cargo run --release --example stack`.

use carom::{BodyDesc, Shape, Vec3, World};

fn main() -> Result<(), carom::Error> {
    // 16 bodies, 64 contacts: about 100 KiB, fine on the main thread's stack.
    let mut world: World<'static, 16, 64> = World::new();
    world.add(
        BodyDesc::fixed(Shape::cuboid(Vec3::new(20.0, 0.5, 20.0))?)
            .position(Vec3::new(0.0, -0.5, 0.0)),
    )?;

    // Ten 1 m boxes, each resting exactly on the one below.
    let cube = Shape::cuboid(Vec3::splat(0.5))?;
    let mut boxes = Vec::new();
    for i in 0..10 {
        let y = 0.5 + i as f32;
        boxes.push(world.add(BodyDesc::dynamic(cube).position(Vec3::new(0.0, y, 0.0)))?);
    }
    let top = boxes[9];

    // Let it settle: soft contacts compress a little under the load, then islands sleep.
    for step in 1..=300 {
        let report = world.step();
        if step % 60 == 0 {
            let p = world.body(top)?.position();
            println!(
                "t = {} s: top box at y = {:.4} m (x {:+.5}), {} contacts, {} awake",
                step / 60,
                p.y,
                p.x,
                report.contacts,
                report.awake_bodies
            );
        }
    }

    // A 5 t ball (each box is 1 t: 1 m³ at the default 1000 kg/m³) thrown at 15 m/s
    // into the middle of the stack. Adding a body near sleepers does not wake them; the
    // contact does.
    world.add(
        BodyDesc::dynamic(Shape::sphere(0.6)?)
            .position(Vec3::new(-8.0, 4.5, 0.0))
            .velocity(Vec3::new(15.0, 0.0, 0.0))
            .mass(5000.0),
    )?;
    for _ in 0..180 {
        world.step();
    }
    let knocked = boxes
        .iter()
        .enumerate()
        .filter(|&(i, &b)| {
            world.body(b).is_ok_and(|b| {
                let start = Vec3::new(0.0, 0.5 + i as f32, 0.0);
                b.position().distance(start) > 0.5
            })
        })
        .count();
    println!(
        "three seconds after the ball: {knocked} of 10 boxes moved more than 0.5 m, \
         the top one is at y = {:.2} m",
        world.body(top)?.position().y
    );
    Ok(())
}
