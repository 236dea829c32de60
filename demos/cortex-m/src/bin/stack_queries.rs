//! The stack each query needs: for every stateless query and for a world step, paint the
//! free stack, run the query once on inputs the optimiser cannot see
//! (`core::hint::black_box`), and print the peak below the painting frame
//! (`src/stack.rs`, `peak_below_painter`: the query's own need) as
//!
//! ```text
//! stack <query> <bytes> bytes
//! ```
//!
//! then exit 0 (1 on an error or a panic). The figures are the peak of that one call on
//! that input (each query's deepest path for these shapes: hull pairs where a hull can
//! stand, overlapping for the penetration queries), not a bound over every input;
//! `measure.sh` prints them for both cores.
#![no_std]
#![no_main]
#![deny(unsafe_code)]

#[path = "../stack.rs"]
mod stack;

use carom::collide::{contact, distance, penetration, time_of_impact, Motion, SimplexCache};
use carom::{BodyDesc, ConvexHull, Iso, Quat, Shape, Vec3, World};
use core::hint::black_box;
use cortex_m_rt::entry;
use cortex_m_semihosting::{debug, hprintln};

/// The world of the `step` figures: 16 bodies, 64 contacts, in a static.
type SmallWorld = World<'static, 16, 64, 16>;

/// Run `f` on painted stack and print its peak as `stack <name> <bytes> bytes`.
#[inline(never)]
fn measure<R>(name: &str, f: impl FnOnce() -> R) {
    let painted = stack::paint();
    black_box(call(f));
    hprintln!(
        "stack {} {} bytes",
        name,
        stack::peak_below_painter(&painted)
    );
}

/// `f()` in a frame of its own, below the painting frame's stack pointer (inlined into
/// the painting frame, its locals would sit above it and go unmeasured).
#[inline(never)]
fn call<R>(f: impl FnOnce() -> R) -> R {
    f()
}

/// Sixteen points on a rounded cube of radius ~0.5 m, rotated a little per call.
fn cloud(twist: f32) -> [Vec3; 16] {
    let mut pts = [Vec3::ZERO; 16];
    let q = Quat::from_axis_angle(Vec3::new(0.3, 1.0, 0.2), twist);
    for (i, p) in pts.iter_mut().enumerate() {
        let s = |b: usize| if (i >> b) & 1 == 0 { -0.4 } else { 0.4 };
        let bulge = if i % 5 == 0 { 0.15 } else { 0.0 };
        *p = q.rotate(Vec3::new(s(0) + bulge, s(1), s(2) - bulge * 0.5));
    }
    pts
}

#[entry]
fn main() -> ! {
    // Two hulls in a static built from a constant: no hull is staged on the stack.
    static mut HULLS: [ConvexHull; 2] = [ConvexHull::UNIT_TETRAHEDRON; 2];
    let status = match run(HULLS) {
        Ok(()) => debug::EXIT_SUCCESS,
        Err(e) => {
            hprintln!("error: {:?}", e);
            debug::EXIT_FAILURE
        }
    };
    debug::exit(status);
    #[allow(clippy::empty_loop)]
    loop {}
}

fn run(hulls: &'static mut [ConvexHull; 2]) -> Result<(), carom::Error> {
    let refused = carom::Error::OutOfRange(carom::Input::Config);
    let points = black_box(cloud(0.3));
    measure("hull_build_16_points", || ConvexHull::new(&points));
    // The same hull built in place: the builder without a hull of its own.
    let slot = &mut hulls[0];
    measure("hull_rebuild_16_points", || slot.rebuild(&points));
    hulls[0].rebuild(&black_box(cloud(0.0)))?;
    hulls[1].rebuild(&black_box(cloud(0.7)))?;
    let hulls: &'static [ConvexHull; 2] = hulls;
    let (a, b) = (Shape::hull(&hulls[0]), Shape::hull(&hulls[1]));
    let cube = Shape::cuboid(Vec3::new(0.5, 0.3, 0.4))?;
    let ball = Shape::sphere(0.3)?;
    let turn = Quat::from_axis_angle(Vec3::new(1.0, 0.2, -0.4), 0.6);
    let pose_a = black_box(Iso::new(Vec3::ZERO, Quat::IDENTITY));
    let apart = black_box(Iso::new(Vec3::new(1.3, 0.4, 0.2), turn));
    let overlapping = black_box(Iso::new(Vec3::new(0.6, 0.3, 0.1), turn));

    measure("distance_hull_hull", || {
        distance(&a, &pose_a, &b, &apart, &mut SimplexCache::default()).map(|d| d.distance)
    });
    measure("penetration_hull_hull", || {
        penetration(&a, &pose_a, &b, &overlapping).map(|p| p.map(|p| p.depth))
    });
    measure("penetration_sphere_hull", || {
        penetration(&ball, &pose_a, &b, &overlapping).map(|p| p.map(|p| p.depth))
    });
    measure("contact_box_box", || {
        contact(&cube, &pose_a, &cube, &overlapping, 0.02).map(|m| m.map(|m| m.points().len()))
    });
    measure("contact_hull_hull", || {
        contact(&a, &pose_a, &b, &overlapping, 0.02).map(|m| m.map(|m| m.points().len()))
    });
    let still = Motion {
        pose: pose_a,
        linear: Vec3::ZERO,
        angular: Vec3::ZERO,
    };
    let thrown = Motion {
        pose: black_box(Iso::new(Vec3::new(0.0, 4.0, 0.0), turn)),
        linear: black_box(Vec3::new(0.3, -30.0, 0.0)),
        angular: black_box(Vec3::new(2.0, 0.0, 7.0)),
    };
    measure("time_of_impact_hull_hull", || {
        time_of_impact(&a, &still, &b, &thrown, 1.0, 0.001).is_ok()
    });

    // A world step: ten boxes and two hulls falling into a pile on the ground, measured
    // over the step at which the most contacts are live.
    let world: &'static mut SmallWorld =
        cortex_m::singleton!(: SmallWorld = World::new()).ok_or(refused)?;
    world.add(
        BodyDesc::fixed(Shape::cuboid(Vec3::new(5.0, 0.5, 5.0))?)
            .position(Vec3::new(0.0, -0.5, 0.0)),
    )?;
    for i in 0..12u8 {
        let shape = if i < 10 {
            cube
        } else {
            Shape::hull(&hulls[usize::from(i) % 2])
        };
        let x = f32::from(i % 3) * 0.9 - 0.9;
        let y = 0.5 + f32::from(i / 3) * 0.8;
        world.add(BodyDesc::dynamic(shape).position(Vec3::new(x, y, 0.1 * f32::from(i % 2))))?;
    }
    let mut deepest = 0u32;
    for _ in 0..90 {
        let painted = stack::paint();
        black_box(call(|| world.step()));
        deepest = deepest.max(stack::peak_below_painter(&painted));
    }
    hprintln!("stack world_step_13_bodies {} bytes", deepest);
    Ok(())
}

#[panic_handler]
fn panic(info: &core::panic::PanicInfo) -> ! {
    hprintln!("panic: {}", info);
    debug::exit(debug::EXIT_FAILURE);
    #[allow(clippy::empty_loop)]
    loop {}
}
