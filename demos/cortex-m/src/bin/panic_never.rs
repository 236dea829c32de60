//! The panic-never check: a release firmware that calls every public entry point of
//! carom with inputs the optimiser cannot see (`core::hint::black_box`), and whose panic
//! handler calls a function that exists nowhere. If any panic is reachable from these
//! calls, the handler stays in the image and the link fails with
//! `undefined reference to 'carom_panic_is_reachable'`, naming the function that can
//! panic. `.ci/run` builds it; under QEMU it runs and exits 0 (nothing printed: the
//! formatting machinery would bring its own panics).
//!
//! Entry points covered: shape constructors and queries (support, faces, bounds, mass,
//! ray casts), hull building, GJK distance and intersection, EPA penetration, contact
//! manifolds, time of impact and movement bounds, and the world: add with every shape
//! and option, every setter, step and traced step, ray casts and overlap queries,
//! checksums, snapshot and restore (valid and corrupt), remove, reset, the standard scenes;
//! triangle meshes, height fields and compounds built and stepped in a world (the mid
//! phase), with ray casts, overlaps and a snapshot round trip.
#![no_std]
#![no_main]

use carom::collide::{contact, distance, intersects, penetration, SimplexCache};
use carom::collide::{movement_bounds, segment_closest_points, time_of_impact, Motion, Toi};
use carom::scenes::{self, Scene, TerrainData, TerrainShapes};
use carom::shape::{BvhNode, Compound, CompoundPart, HeightField, TriangleMesh};
use carom::{
    BodyDesc, ConvexHull, Iso, Material, Quat, QueryFilter, Ray, RayCastHit, Shape, StepTrace,
    Vec3, World, WorldConfig,
};
use core::hint::black_box;
use cortex_m_rt::entry;
use cortex_m_semihosting::debug;

type W = World<'static, 24, 96, 16>;

extern "C" {
    /// Defined nowhere: referencing it fails the link.
    fn carom_panic_is_reachable() -> !;
}

#[panic_handler]
fn panic(_: &core::panic::PanicInfo) -> ! {
    // SAFETY: never called in a linked image; if the call were reachable the link fails.
    unsafe { carom_panic_is_reachable() }
}

/// A value the optimiser must treat as unknown.
fn v(x: f32, y: f32, z: f32) -> Vec3 {
    black_box(Vec3::new(x, y, z))
}

fn f(x: f32) -> f32 {
    black_box(x)
}

/// Every shape constructor, with unknown inputs.
fn shapes(hull: &'static ConvexHull) -> [Shape<'static>; 6] {
    let fallback = Shape::hull(hull);
    [
        Shape::sphere(f(0.5)).unwrap_or(fallback),
        Shape::capsule(f(0.4), f(0.2)).unwrap_or(fallback),
        Shape::cuboid(v(0.5, 0.3, 0.4)).unwrap_or(fallback),
        Shape::half_space(v(0.0, 1.0, 0.0)).unwrap_or(fallback),
        Shape::triangle(v(0.0, 0.0, 0.0), v(1.0, 0.0, 0.0), v(0.0, 0.0, 1.0)).unwrap_or(fallback),
        fallback,
    ]
}

/// Shape queries and every pair query on every pair of shapes.
fn queries(shapes: &[Shape<'static>]) -> u32 {
    let mut acc = 0u32;
    let pose_a = black_box(Iso::new(v(0.0, 0.0, 0.0), Quat::IDENTITY));
    let pose_b = black_box(Iso::new(
        v(0.3, 0.6, 0.1),
        Quat::from_axis_angle(v(0.3, 1.0, 0.2), f(0.7)),
    ));
    for s in shapes {
        let face = s.supporting_face(v(0.2, -1.0, 0.1));
        acc += face.points().len() as u32 + face.transformed(&pose_b).points().len() as u32;
        acc += s.support(v(1.0, 2.0, 3.0)).x.to_bits();
        acc += s.core_support(v(-1.0, 0.5, 0.0)).1 + s.core_vertex(black_box(3)).y.to_bits();
        acc += s.aabb(&pose_b).max.x.to_bits() + s.local_aabb().min.y.to_bits();
        acc += s.bounding_radius().to_bits() + s.min_extent().to_bits() + s.radius().to_bits();
        acc += s.is_static_only() as u32;
        if let Ok(m) = s.mass_properties(f(1000.0)) {
            acc += m.mass.to_bits();
        }
        if let Ok(ray) = Ray::new(v(0.0, 3.0, 0.0), v(0.0, -1.0, 0.1)) {
            if let Ok(Some(hit)) = s.cast_ray(&pose_a, &ray, f(10.0)) {
                acc += hit.t.to_bits();
            }
            acc += ray.at(f(1.0)).y.to_bits();
        }
    }
    for a in shapes {
        for b in shapes {
            let mut cache = SimplexCache::default();
            if let Ok(d) = distance(a, &pose_a, b, &pose_b, &mut cache) {
                acc += d.distance.to_bits();
            }
            if let Ok(hit) = intersects(a, &pose_a, b, &pose_b) {
                acc += hit as u32;
            }
            if let Ok(Some(p)) = penetration(a, &pose_a, b, &pose_b) {
                acc += p.depth.to_bits();
            }
            if let Ok(Some(m)) = contact(a, &pose_a, b, &pose_b, f(0.02)) {
                acc += m.points().len() as u32 + m.min_separation().to_bits();
            }
            let ma = Motion {
                pose: pose_a,
                linear: v(0.0, 0.0, 0.0),
                angular: v(0.0, 0.0, 0.0),
            };
            let mb = Motion {
                pose: pose_b,
                linear: v(0.0, -30.0, 0.0),
                angular: v(1.0, 0.0, 2.0),
            };
            if let Ok(Toi::Hit { time, .. }) = time_of_impact(a, &ma, b, &mb, f(1.0), f(0.001)) {
                acc += time.to_bits();
            }
            acc += movement_bounds(b, &mb, f(0.016)).max.y.to_bits();
        }
    }
    let (s, t) = segment_closest_points(v(0., 0., 0.), v(1., 0., 0.), v(0., 1., 0.), v(1., 1., 1.));
    acc + s.to_bits() + t.to_bits()
}

/// The world: every door, with a valid and a corrupt snapshot.
fn world(w: &mut W, shapes: &[Shape<'static>], hulls: &'static [ConvexHull]) -> u32 {
    let mut acc = 0u32;
    let _ = w.set_config(black_box(WorldConfig::DEFAULT));
    let mut handles = [None; 8];
    for (i, s) in shapes.iter().enumerate() {
        let p = v(i as f32 * 1.5, 2.0, 0.0);
        let desc = if s.is_static_only() {
            BodyDesc::fixed(*s)
        } else if i % 3 == 1 {
            BodyDesc::kinematic(*s)
        } else {
            BodyDesc::dynamic(*s)
        };
        let desc = desc
            .position(p)
            .rotation(black_box(Quat::IDENTITY))
            .velocity(v(0.0, -1.0, 0.0))
            .angular_velocity(v(0.0, 1.0, 0.0))
            .density(f(900.0))
            .material(black_box(Material::DEFAULT))
            .damping(f(0.01), f(0.01))
            .filter(black_box(1), black_box(u32::MAX))
            .sensor(black_box(false))
            .ccd(black_box(i % 2 == 0))
            .user_data(black_box(i as u64));
        if let (Ok(h), Some(slot)) = (w.add(desc), handles.get_mut(i)) {
            *slot = Some(h);
        }
    }
    if let Some(s) = shapes.first() {
        if let (Ok(h), Some(slot)) = (
            w.add(BodyDesc::dynamic(*s).mass(f(2.0)).sensor(true)),
            handles.last_mut(),
        ) {
            *slot = Some(h);
        }
    }
    for h in handles.iter().flatten() {
        let h = *h;
        let _ = w.set_pose(h, black_box(Iso::new(v(0.0, 1.0, 0.0), Quat::IDENTITY)));
        let _ = w.set_linear_velocity(h, v(1.0, 0.0, 0.0));
        let _ = w.set_angular_velocity(h, v(0.0, 0.0, 1.0));
        let _ = w.apply_force(h, v(0.0, 10.0, 0.0));
        let _ = w.apply_torque(h, v(0.0, 1.0, 0.0));
        let _ = w.apply_impulse_at(h, v(0.0, 1.0, 0.0), v(0.1, 1.0, 0.0));
        let _ = w.set_material(h, black_box(Material::DEFAULT));
        let _ = w.wake(h);
        if let Ok(b) = w.body(h) {
            acc += b.position().x.to_bits() + b.velocity_at(v(0., 0., 0.)).y.to_bits();
            acc += b.kinetic_energy().to_bits() + b.mass().to_bits() + b.user_data() as u32;
        }
        if let Ok(sum) = w.body_checksum(h) {
            acc += sum as u32;
        }
    }
    let mut trace = StepTrace::default();
    for _ in 0..black_box(3) {
        let r = w.step_traced(Some(&mut trace));
        acc += r.contacts;
        acc += w.events().len() as u32;
    }
    let other = StepTrace::default();
    acc += trace.first_difference(&other).is_some() as u32;
    w.step();
    acc += w.contact_count() as u32 + w.pair_count() as u32 + w.handles().count() as u32;
    if let Ok(ray) = Ray::new(v(-5.0, 1.0, 0.0), v(1.0, 0.0, 0.0)) {
        if let Ok(Some(hit)) = w.cast_ray(&ray, f(50.0), QueryFilter::ALL) {
            acc += hit.t.to_bits();
        }
        let mut hits = [RayCastHit::default(); 4];
        acc += w
            .cast_ray_all(&ray, f(50.0), QueryFilter::ALL, &mut hits)
            .unwrap_or(0) as u32;
    }
    let mut found = [carom::BodyHandle {
        index: 0,
        generation: 0,
    }; 4];
    for s in shapes {
        acc += w
            .overlap(s, &black_box(Iso::IDENTITY), QueryFilter::ALL, &mut found)
            .unwrap_or(0) as u32;
    }
    // Snapshots: round trip, then a corrupt copy with its hash left wrong and one resealed.
    let mut buf = [0u8; 8192];
    if let Ok(n) = w.snapshot(&mut buf) {
        let _ = w.restore(buf.get(..n).unwrap_or(&[]));
        let cut = black_box(n / 2);
        let _ = w.restore(buf.get(..cut).unwrap_or(&[]));
        if let Some(byte) = buf.get_mut(black_box(60)) {
            *byte ^= black_box(0xA5);
        }
        let _ = w.restore_with_hulls(buf.get(..n).unwrap_or(&[]), hulls);
    }
    acc += w.snapshot_len() as u32 + W::max_snapshot_len() as u32;
    acc += w.checksum() as u32;
    for h in handles.iter().flatten() {
        let _ = w.sleep(*h);
        let _ = w.remove(*h);
    }
    acc += w.body_count() as u32 + w.step_count() as u32;
    // Emptied where it lies, then stepped as a new world.
    w.reset();
    w.step();
    acc + w.step_count() as u32
}

/// The standard scenes: built into a world too small for most of them (the pool-full
/// error paths; the terrain scenes on their ground), and the smallest run.
fn scene_doors(w: &mut W, hulls: &'static [ConvexHull]) -> u32 {
    let mut acc = 0u32;
    let terrain = match cortex_m::singleton!(: TerrainData = TerrainData::EMPTY) {
        Some(data) => data.shapes().ok(),
        None => None,
    };
    let terrain: Option<&'static TerrainShapes<'static>> =
        terrain.and_then(|t| cortex_m::singleton!(: TerrainShapes<'static> = t).map(|t| &*t));
    for scene in Scene::ALL {
        let scene = black_box(scene);
        acc += scene.name().len() as u32 + scene.steps() + scene.body_count() as u32;
        acc += Scene::from_name(scene.name()).is_some() as u32;
        *w = W::new();
        let ground = terrain.and_then(|t| t.ground(scene));
        if scene.build_on(w, hulls, ground).is_ok() {
            w.step();
            acc += scene.line(w.checksum()).checksum as u32;
        }
    }
    *w = W::new();
    acc += scenes::tower(w, black_box(4)).is_ok() as u32;
    acc
}

#[entry]
fn main() -> ! {
    let cloud = [
        v(0.0, 0.0, 0.0),
        v(1.0, 0.0, 0.0),
        v(0.0, 1.0, 0.0),
        v(0.0, 0.0, 1.0),
        v(0.6, 0.6, 0.6),
    ];
    let Ok(first) = ConvexHull::new(black_box(&cloud[..])) else {
        debug_exit(false)
    };
    let hulls: &'static mut [ConvexHull; 2] = match cortex_m::singleton!(: [ConvexHull; 2] = [first; 2])
    {
        Some(h) => h,
        None => debug_exit(false),
    };
    if let Some((_, rest)) = hulls.split_first_mut() {
        let _ = scenes::make_hulls(rest, black_box(7));
    }
    let hulls: &'static [ConvexHull; 2] = hulls;
    let shapes = shapes(&hulls[0]);
    let w: &'static mut W = match cortex_m::singleton!(: W = W::new()) {
        Some(w) => w,
        None => debug_exit(false),
    };
    let mut acc = queries(&shapes);
    acc = acc.wrapping_add(world(w, &shapes, hulls));
    acc = acc.wrapping_add(scene_doors(w, hulls));
    acc = acc.wrapping_add(timestep());
    acc = acc.wrapping_add(parts(w));
    black_box(acc);
    debug_exit(true)
}

/// The fixed-timestep helper: construction, frames of every kind, alpha, reset.
fn timestep() -> u32 {
    let Ok(mut clock) = carom::FixedTimestep::new(f(1.0 / 60.0), black_box(4)) else {
        return 0;
    };
    let mut acc = 0u32;
    for elapsed in [0.016, 0.05, -1.0, f64::NAN, f64::INFINITY, 1.0e300, 0.0] {
        if let Ok(s) = clock.advance(black_box(elapsed)) {
            acc = acc
                .wrapping_add(s.steps)
                .wrapping_add(s.dropped as u32)
                .wrapping_add(s.alpha.to_bits());
        }
    }
    acc = acc.wrapping_add(clock.alpha().to_bits());
    clock.reset();
    acc
}

fn debug_exit(ok: bool) -> ! {
    debug::exit(if ok {
        debug::EXIT_SUCCESS
    } else {
        debug::EXIT_FAILURE
    });
    #[allow(clippy::empty_loop)]
    loop {}
}

/// Shapes with parts: a mesh, a height field and a compound built from unknown inputs,
/// added to the world, stepped (the mid phase), queried and snapshotted.
fn parts(w: &mut W) -> u32 {
    let mut acc = 0u32;
    let Some(vertices) = cortex_m::singleton!(: [Vec3; 4] = [Vec3::ZERO; 4]) else {
        return 0;
    };
    *vertices = [
        v(-4.0, 0.0, -4.0),
        v(4.0, 0.0, -4.0),
        v(4.0, 0.0, 4.0),
        v(-4.0, 0.0, 4.0),
    ];
    let Some(indices) = cortex_m::singleton!(: [[u32; 3]; 2] = [[0, 2, 1], [0, 3, 2]]) else {
        return 0;
    };
    *indices = black_box(*indices);
    let Some(nodes) = cortex_m::singleton!(: [BvhNode; 3] = [BvhNode::EMPTY; 3]) else {
        return 0;
    };
    let vertices: &'static [Vec3; 4] = vertices;
    let indices: &'static [[u32; 3]; 2] = indices;
    let Ok(mesh) = TriangleMesh::build(vertices, indices, nodes) else {
        return 0;
    };
    let Some(mesh) = cortex_m::singleton!(: TriangleMesh<'static> = mesh) else {
        return 0;
    };
    let Some(heights) = cortex_m::singleton!(: [f32; 9] = [0.0; 9]) else {
        return 0;
    };
    for (i, h) in heights.iter_mut().enumerate() {
        *h = f(i as f32 * 0.1);
    }
    let heights: &'static [f32; 9] = heights;
    let Ok(field) = HeightField::new(heights, black_box(3), black_box(3), f(1.0)) else {
        return 0;
    };
    let Some(field) = cortex_m::singleton!(: HeightField<'static> = field) else {
        return 0;
    };
    let ball = Shape::sphere(f(0.3)).unwrap_or(Shape::Mesh(mesh));
    let brick = Shape::cuboid(v(0.2, 0.1, 0.3)).unwrap_or(Shape::Mesh(mesh));
    let Some(pieces) = cortex_m::singleton!(: [CompoundPart<'static>; 2] = [
        CompoundPart::new(Iso::IDENTITY, ball),
        CompoundPart::new(Iso::IDENTITY, brick),
    ]) else {
        return 0;
    };
    pieces[1].pose = Iso::from_position(v(0.5, 0.0, 0.0));
    let pieces: &'static [CompoundPart<'static>; 2] = pieces;
    let Ok(compound) = Compound::new(pieces) else {
        return 0;
    };
    let Some(compound) = cortex_m::singleton!(: Compound<'static> = compound) else {
        return 0;
    };
    let _ = w.add(BodyDesc::fixed(Shape::Mesh(mesh)).position(v(0.0, -1.0, 0.0)));
    let _ = w.add(BodyDesc::fixed(Shape::HeightField(field)).position(v(-1.0, -0.5, -1.0)));
    let _ = w.add(BodyDesc::dynamic(Shape::Compound(compound)).position(v(0.0, 0.5, 0.0)));
    let _ = w.add(BodyDesc::dynamic(ball).position(v(0.5, 0.2, 0.5)).ccd(true));
    for _ in 0..black_box(4) {
        acc = acc.wrapping_add(w.step().contacts);
    }
    if let Ok(ray) = Ray::new(v(0.0, 5.0, 0.0), v(0.0, -1.0, 0.0)) {
        if let Ok(Some(hit)) = w.cast_ray(&ray, f(50.0), QueryFilter::ALL) {
            acc = acc.wrapping_add(hit.t as u32);
        }
    }
    let mut out = [carom::BodyHandle {
        index: 0,
        generation: 0,
    }; 4];
    acc += w
        .overlap(
            &Shape::Compound(compound),
            &black_box(Iso::IDENTITY),
            QueryFilter::ALL,
            &mut out,
        )
        .unwrap_or(0) as u32;
    let _ = contact(
        &Shape::Mesh(mesh),
        &Iso::IDENTITY,
        &ball,
        &Iso::IDENTITY,
        f(0.1),
    );
    let mut buf = [0u8; 8192];
    if let Ok(n) = w.snapshot(&mut buf) {
        let _ = w.restore(buf.get(..n).unwrap_or(&[]));
    }
    acc.wrapping_add(w.checksum() as u32)
}
