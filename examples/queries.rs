//! Ray casts and overlap queries against a world: line of sight, everything a laser
//! passes through, and "what is inside this explosion radius".
//!
//! Run with `cargo run --release --example queries`.

use carom::{BodyDesc, BodyHandle, Iso, QueryFilter, Ray, RayCastHit, Shape, Vec3, World};

/// Collision groups (bit masks) for the filter example.
const SCENERY: u32 = 1;
const CRATES: u32 = 2;

fn main() -> Result<(), carom::Error> {
    let mut world: World<'static, 16, 32> = World::new();
    let ground = world.add(
        BodyDesc::fixed(Shape::cuboid(Vec3::new(20.0, 0.5, 20.0))?)
            .position(Vec3::new(0.0, -0.5, 0.0))
            .filter(SCENERY, u32::MAX)
            .user_data(0),
    )?;
    // Five crates in a row along +x, at x = 2, 4, 6, 8, 10; user data is their number.
    let cube = Shape::cuboid(Vec3::splat(0.5))?;
    for i in 1..=5u64 {
        world.add(
            BodyDesc::dynamic(cube)
                .position(Vec3::new(2.0 * i as f32, 0.5, 0.0))
                .filter(CRATES, u32::MAX)
                .user_data(i),
        )?;
    }
    let label = |w: &World<'static, 16, 32>, h: BodyHandle| -> Result<String, carom::Error> {
        Ok(match w.body(h)?.user_data() {
            0 => "the ground".to_string(),
            n => format!("crate {n}"),
        })
    };

    // 1. The first body a ray meets (line of sight). `Ray::new` normalises the direction.
    let eye = Ray::new(Vec3::new(0.0, 0.5, 0.0), Vec3::X)?;
    if let Some(hit) = world.cast_ray(&eye, 100.0, QueryFilter::ALL)? {
        println!(
            "line of sight: {} at {:.2} m, point {:?}, normal {:?}",
            label(&world, hit.body)?,
            hit.t,
            hit.point,
            hit.normal
        );
    }

    // 2. Every body along the ray, nearest first, into a caller-provided buffer (no heap
    //    inside carom). A result equal to the buffer's length may mean more exist.
    let mut hits = [RayCastHit::default(); 8];
    let n = world.cast_ray_all(&eye, 9.0, QueryFilter::ALL, &mut hits)?;
    print!("a 9 m laser passes through {n} bodies:");
    for hit in &hits[..n] {
        print!(" {} ({:.1} m)", label(&world, hit.body)?, hit.t);
    }
    println!();

    // 3. A ray pointing down that sees only the scenery group: the crate above the
    //    ground is ignored.
    let down = Ray::new(Vec3::new(4.0, 5.0, 0.0), Vec3::new(0.0, -1.0, 0.0))?;
    let scenery_only = QueryFilter {
        mask: SCENERY,
        ..QueryFilter::ALL
    };
    let all = world.cast_ray(&down, 10.0, QueryFilter::ALL)?;
    let filtered = world.cast_ray(&down, 10.0, scenery_only)?;
    for (what, hit) in [("all groups", all), ("scenery only", filtered)] {
        if let Some(hit) = hit {
            println!(
                "ray down at x = 4 ({what}): {} at height {:.2} m",
                label(&world, hit.body)?,
                hit.point.y
            );
        }
    }

    // 4. Overlap: every body within 3 m of an explosion at (5, 0.5, 0).
    let blast = Shape::sphere(3.0)?;
    let mut inside = [ground; 16]; // any handle: a placeholder to overwrite
    let n = world.overlap(
        &blast,
        &Iso::from_position(Vec3::new(5.0, 0.5, 0.0)),
        QueryFilter {
            mask: CRATES,
            ..QueryFilter::ALL
        },
        &mut inside,
    )?;
    print!("crates within 3 m of the blast at x = 5:");
    for &h in &inside[..n] {
        print!(" {}", label(&world, h)?);
    }
    println!();
    assert_eq!(
        n, 4,
        "crates 1 to 4: their nearest faces are 2.5 m or less away"
    );
    Ok(())
}
