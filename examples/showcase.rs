//! carom's showcase: the narrow phase at work, then the standard scenes stepping.
//!
//! Run with `cargo run --release --example showcase`.

use carom::collide::{self, SimplexCache};
use carom::scenes::{self, Scene};
use carom::shape::Ray;
use carom::{ConvexHull, Iso, Quat, Shape, Vec3, World};

fn main() -> Result<(), carom::Error> {
    narrow_phase()?;
    // Worlds are large (everything is inline): run them on a thread with a big stack.
    std::thread::Builder::new()
        .stack_size(256 << 20)
        .spawn(worlds)
        .map_err(|_| carom::Error::PoolFull(carom::Pool::Output))?
        .join()
        .map_err(|_| carom::Error::PoolFull(carom::Pool::Output))??;
    Ok(())
}

fn narrow_phase() -> Result<(), carom::Error> {
    println!("== narrow phase ==");
    let cube = Shape::cuboid(Vec3::splat(0.5))?;
    let ground = Shape::cuboid(Vec3::new(5.0, 0.5, 5.0))?;
    let ground_pose = Iso::from_position(Vec3::new(0.0, -0.5, 0.0));
    for (what, pose) in [
        (
            "flat, 1 cm deep",
            Iso::from_position(Vec3::new(0.0, 0.49, 0.0)),
        ),
        (
            "on an edge",
            Iso::new(
                Vec3::new(0.0, 0.69, 0.0),
                Quat::from_axis_angle(Vec3::Z, core::f32::consts::FRAC_PI_4),
            ),
        ),
        (
            "on a corner",
            Iso::new(
                Vec3::new(0.0, 0.85, 0.0),
                Quat::from_axis_angle(Vec3::new(1.0, 0.0, 1.0), 0.9553),
            ),
        ),
    ] {
        match collide::contact(&ground, &ground_pose, &cube, &pose, 0.02)? {
            Some(m) => println!(
                "box {what:16}: {} point(s), normal {:?}, deepest {:+.4} m",
                m.points().len(),
                m.normal,
                m.min_separation()
            ),
            None => println!("box {what:16}: apart"),
        }
    }
    let mut hulls = vec![ConvexHull::new(&[Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z])?; 2];
    scenes::make_hulls(&mut hulls, 1)?;
    let (a, b) = (Shape::hull(&hulls[0]), Shape::hull(&hulls[1]));
    let pa = Iso::IDENTITY;
    let mut cache = SimplexCache::default();
    for x in [3.0f32, 2.0, 1.5] {
        let pb = Iso::new(Vec3::new(x, 0.2, 0.0), Quat::from_axis_angle(Vec3::Y, 0.7));
        let d = collide::distance(&a, &pa, &b, &pb, &mut cache)?;
        let pen = collide::penetration(&a, &pa, &b, &pb)?;
        println!(
            "hulls at x = {x}: distance {:.4} m in {} GJK iterations, penetration {}",
            d.distance,
            d.iterations,
            pen.map_or("none".to_string(), |p| format!("{:.4} m", p.depth))
        );
    }
    let ray = Ray::new(Vec3::new(-5.0, 0.0, 0.0), Vec3::X)?;
    if let Some(hit) = a.cast_ray(&pa, &ray, 100.0)? {
        println!(
            "ray hits the hull at t = {:.4}, normal {:?}",
            hit.t, hit.normal
        );
    }
    Ok(())
}

fn worlds() -> Result<(), carom::Error> {
    let mut hulls = vec![ConvexHull::new(&[Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z])?; 64];
    scenes::make_hulls(&mut hulls, scenes::SEED)?;
    for scene in [Scene::Pyramid20, Scene::Mixed, Scene::Bullet, Scene::Tower] {
        let mut world: Box<World<'_, 256, 2048>> = Box::new(World::new());
        world.set_config(scene.config())?;
        let watch = scene.build(&mut world, &hulls)?;
        let start = world.body(watch)?.position();
        println!(
            "== {} ({} bodies, {} steps) ==",
            scene.name(),
            world.body_count(),
            scene.steps()
        );
        let t0 = std::time::Instant::now();
        let mut lowest = f32::INFINITY;
        for step in 1..=scene.steps() {
            let r = world.step();
            lowest = lowest.min(world.body(watch)?.position().y);
            if step % (scene.steps() / 4).max(1) == 0 {
                let b = world.body(watch)?;
                println!(
                    "step {step:4}: awake {:4}, contacts {:4}, points {:5}, ccd hits {}, watched body at {:?}",
                    r.awake_bodies,
                    r.contacts,
                    r.points,
                    r.ccd_hits,
                    b.position()
                );
            }
        }
        let end = world.body(watch)?.position();
        println!(
            "moved {:?} -> {:?} (lowest y {lowest:.3}); {:.2} ms/step; checksum {:#018x}",
            start,
            end,
            t0.elapsed().as_secs_f64() * 1e3 / scene.steps() as f64,
            world.checksum()
        );
    }
    Ok(())
}
