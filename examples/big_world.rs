//! A world too big for the main thread's stack, built without touching the stack and
//! without `unsafe`: a `static`.
//!
//! `World::new` is a `const fn`, so a `static` world is built by the compiler: it is in
//! the program image when the program starts, and no byte of it ever passes through the
//! stack, in debug builds too. The `Mutex` (from std; on firmware a
//! `critical_section::Mutex<RefCell<..>>`) makes it safely mutable.
//!
//! The price: the empty world's bytes are in the executable's data section (`World::new`
//! is not all zero bits), so this one adds about 9 MiB to the binary. And one `static`
//! is one world.
//!
//! Why not `Box::new(World::new())`? Every safe way to fill a `Box` (`Box::new`,
//! `Box::default`, `Box::write(Box::new_uninit(), ..)`, `vec![..]`, `clone`) moves a
//! `World` value that is built on the stack first. In a debug build (opt-level 0) that
//! costs about 3.6 times the world's size in stack (5.1 MB for a `World<512, 1024>`,
//! measured when it was 1.4 MB), so this world would overflow the 8 MB main stack; optimised
//! builds construct mostly in place (0.4 MB of stack for the same world). See the
//! README's "Capacity" section for the measurements and the other patterns.
//!
//! Run with `cargo run --release --example big_world`.

use std::sync::Mutex;

use carom::{BodyDesc, Shape, Vec3, World};

/// 1024 bodies and 8192 contacts: about 9.8 MB, more than the main thread's 8 MB stack.
type BigWorld = World<'static, 1024, 8192>;

/// Built at compile time: no stack, no heap, no `unsafe`.
static WORLD: Mutex<BigWorld> = Mutex::new(World::new());

fn main() -> Result<(), carom::Error> {
    let stack_before = stack_size();
    // A poisoned lock only means another thread panicked while holding it.
    let mut world = WORLD.lock().unwrap_or_else(|e| e.into_inner());
    println!(
        "World<1024, 8192> is {:.1} MB; the main thread's stack is 8 MB",
        std::mem::size_of::<BigWorld>() as f64 / 1e6
    );

    world.add(
        BodyDesc::fixed(Shape::cuboid(Vec3::new(50.0, 0.5, 50.0))?)
            .position(Vec3::new(0.0, -0.5, 0.0)),
    )?;
    // 1000 boxes in a 10 x 10 x 10 grid.
    let cube = Shape::cuboid(Vec3::splat(0.5))?;
    for i in 0..1000 {
        let (x, y, z) = ((i % 10) as f32, (i / 100) as f32, ((i / 10) % 10) as f32);
        world.add(BodyDesc::dynamic(cube).position(Vec3::new(
            1.2 * x - 5.4,
            2.0 + 1.2 * y,
            1.2 * z - 5.4,
        )))?;
    }
    let t0 = std::time::Instant::now();
    for _ in 0..60 {
        world.step();
    }
    let r = world.last_report();
    println!(
        "{} bodies, one second simulated in {:.0} ms: {} contacts, {} awake, checksum {:#018x}",
        world.body_count(),
        t0.elapsed().as_secs_f64() * 1e3,
        r.contacts,
        r.awake_bodies,
        world.checksum()
    );
    match (stack_before, stack_size()) {
        (Some(a), Some(b)) => println!(
            "main thread stack: {} KiB before, {} KiB after",
            a / 1024,
            b / 1024
        ),
        _ => println!("(stack size not measured: /proc/self/status is Linux only)"),
    }
    Ok(())
}

/// The main thread's stack mapping (Linux's `VmStk`): it grows to the deepest page the
/// program has touched and never shrinks, so it is the peak stack so far.
fn stack_size() -> Option<usize> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmStk:"))?;
    let kib: usize = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}
