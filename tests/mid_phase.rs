//! The mid phase in the world: bodies on triangle meshes behave like bodies on one
//! plane, compounds rest on their parts, fast bodies do not tunnel through a mesh, and
//! queries and snapshots reach into meshes and compounds.

use carom::scenes::{self, Scene};
use carom::shape::{BvhNode, Compound, CompoundPart, HeightField, TriangleMesh};
use carom::{BodyDesc, Iso, Material, QueryFilter, Ray, Shape, Vec3, World};

/// The comparison ground: a static box whose top face is the plane y = 0.
fn box_ground() -> BodyDesc<'static> {
    BodyDesc::fixed(Shape::cuboid(Vec3::new(10.0, 0.5, 10.0)).unwrap())
        .position(Vec3::new(0.0, -0.5, 0.0))
}

/// A flat grid of `n × n` square cells of `cell` metres at height 0, centred on the
/// origin, two triangles per cell (counter-clockwise seen from +Y), with the node storage
/// its mesh needs.
fn flat_grid(n: u32, cell: f32) -> (Vec<Vec3>, Vec<[u32; 3]>, Vec<BvhNode>) {
    let half = n as f32 * cell * 0.5;
    let mut v = Vec::new();
    for j in 0..=n {
        for i in 0..=n {
            v.push(Vec3::new(
                i as f32 * cell - half,
                0.0,
                j as f32 * cell - half,
            ));
        }
    }
    let mut t = Vec::new();
    let at = |i: u32, j: u32| j * (n + 1) + i;
    for j in 0..n {
        for i in 0..n {
            t.push([at(i, j), at(i, j + 1), at(i + 1, j + 1)]);
            t.push([at(i, j), at(i + 1, j + 1), at(i + 1, j)]);
        }
    }
    let nodes = vec![BvhNode::EMPTY; TriangleMesh::nodes_needed(t.len())];
    (v, t, nodes)
}

type Small<'a> = World<'a, 16, 512>;

/// Run `steps` steps and give the body's (position, velocity) after each.
fn track(world: &mut Small<'_>, h: carom::BodyHandle, steps: usize) -> Vec<(Vec3, Vec3)> {
    (0..steps)
        .map(|_| {
            world.step();
            let b = world.body(h).unwrap();
            (b.position(), b.linear_velocity())
        })
        .collect()
}

/// A unit box (half 0.5) dropped from 0.2 m above a ground at y = 0, on a flat mesh of
/// 0.4 m cells (the box spans several triangles) or on a box ground: the same resting
/// height, no bounce on the seams.
#[test]
fn a_box_rests_on_a_tessellated_plane_as_on_one_plane() {
    let (v, t, mut nodes) = flat_grid(24, 0.4);
    let mesh = TriangleMesh::build(&v, &t, &mut nodes).unwrap();
    let rest = |ground: BodyDesc<'_>| {
        let mut w: Small<'_> = World::new();
        w.add(ground).unwrap();
        let q = carom::Quat::from_axis_angle(Vec3::Y, 0.3);
        let h = w
            .add(
                BodyDesc::dynamic(Shape::cuboid(Vec3::splat(0.5)).unwrap())
                    .position(Vec3::new(0.13, 0.7, -0.21))
                    .rotation(q),
            )
            .unwrap();
        track(&mut w, h, 180)
    };
    let on_mesh = rest(BodyDesc::fixed(Shape::Mesh(&mesh)));
    let on_box = rest(box_ground());
    let (mesh_end, box_end) = (on_mesh.last().unwrap().0, on_box.last().unwrap().0);
    assert!(
        (mesh_end.y - box_end.y).abs() < 1e-3,
        "{mesh_end:?} vs {box_end:?}"
    );
    assert!((mesh_end.y - 0.5).abs() < 5e-3, "rests at {}", mesh_end.y);
    // It came to rest where it landed: no sideways walk on the seams.
    assert!(
        (mesh_end.x - 0.13).abs() < 2e-3 && (mesh_end.z + 0.21).abs() < 2e-3,
        "{mesh_end:?} vs box {box_end:?}"
    );
    // After landing (the first 0.5 s), no vertical kick.
    for (p, vel) in &on_mesh[30..] {
        assert!(vel.y.abs() < 0.05, "vertical speed {} at {p:?}", vel.y);
    }
}

/// A box sliding at 4 m/s across 0.25 m triangles slows at the same rate as on a box
/// ground (kinetic friction), with no vertical velocity spike on the seams.
#[test]
fn a_box_slides_across_triangle_seams_like_on_one_plane() {
    let (v, t, mut nodes) = flat_grid(40, 0.25);
    let mesh = TriangleMesh::build(&v, &t, &mut nodes).unwrap();
    let slide = |ground: BodyDesc<'_>| {
        let mut w: Small<'_> = World::new();
        w.add(ground).unwrap();
        let h = w
            .add(
                BodyDesc::dynamic(Shape::cuboid(Vec3::new(0.3, 0.2, 0.3)).unwrap())
                    .position(Vec3::new(-3.0, 0.2, 0.07))
                    .velocity(Vec3::new(4.0, 0.0, 0.0)),
            )
            .unwrap();
        track(&mut w, h, 90)
    };
    let on_mesh = slide(BodyDesc::fixed(Shape::Mesh(&mesh)));
    let on_box = slide(box_ground());
    let stop = |track: &[(Vec3, Vec3)]| track.last().unwrap().0.x;
    let (d_mesh, d_box) = (stop(&on_mesh) + 3.0, stop(&on_box) + 3.0);
    // v² / (2 μk g) = 16 / (2 · 0.4 · 9.81) = 2.04 m.
    assert!((d_box - 2.04).abs() < 0.1, "box ground: {d_box}");
    assert!(
        (d_mesh - d_box).abs() < 0.02 * d_box,
        "mesh {d_mesh} vs box {d_box}"
    );
    for (p, vel) in &on_mesh {
        assert!(vel.y.abs() < 0.05, "vertical speed {} at {p:?}", vel.y);
        assert!(vel.z.abs() < 0.02, "sideways speed {} at {p:?}", vel.z);
    }
}

/// A ball rolling across the seams of a mesh keeps the speed it has on one plane.
#[test]
fn a_ball_rolls_across_seams_without_losing_speed() {
    let (v, t, mut nodes) = flat_grid(20, 0.5);
    let mesh = TriangleMesh::build(&v, &t, &mut nodes).unwrap();
    let roll = |ground: BodyDesc<'_>| {
        let mut w: Small<'_> = World::new();
        w.add(ground).unwrap();
        let r = 0.25;
        let h = w
            .add(
                BodyDesc::dynamic(Shape::sphere(r).unwrap())
                    .position(Vec3::new(-4.0, r, 0.1))
                    .velocity(Vec3::new(2.0, 0.0, 0.0))
                    .angular_velocity(Vec3::new(0.0, 0.0, -2.0 / r)),
            )
            .unwrap();
        track(&mut w, h, 120)
    };
    let on_mesh = roll(BodyDesc::fixed(Shape::Mesh(&mesh)));
    let on_box = roll(box_ground());
    let (vm, vb) = (on_mesh.last().unwrap().1, on_box.last().unwrap().1);
    assert!(vb.x > 1.8, "rolling on a box ground: {vb:?}");
    assert!((vm.x - vb.x).abs() < 0.02, "mesh {vm:?} vs box {vb:?}");
    for (p, vel) in &on_mesh {
        assert!(vel.y.abs() < 0.05, "vertical speed {} at {p:?}", vel.y);
        assert!((p.y - 0.25).abs() < 5e-3, "height {} at {p:?}", p.y);
    }
}

/// A dumbbell (two balls on a bar) dropped on the ground rests on both balls, level.
#[test]
fn a_compound_rests_on_its_parts() {
    let parts = [
        CompoundPart::new(
            Iso::from_position(Vec3::new(-0.6, 0.0, 0.0)),
            Shape::sphere(0.2).unwrap(),
        ),
        CompoundPart::new(
            Iso::IDENTITY,
            Shape::cuboid(Vec3::new(0.5, 0.05, 0.05)).unwrap(),
        ),
        CompoundPart::new(
            Iso::from_position(Vec3::new(0.6, 0.0, 0.0)),
            Shape::sphere(0.2).unwrap(),
        ),
    ];
    let dumbbell = Compound::new(&parts).unwrap();
    let mut w: Small<'_> = World::new();
    w.add(box_ground()).unwrap();
    let h = w
        .add(BodyDesc::dynamic(Shape::Compound(&dumbbell)).position(Vec3::new(0.0, 1.0, 0.0)))
        .unwrap();
    let end = track(&mut w, h, 240);
    let b = w.body(h).unwrap();
    assert!(
        (b.position().y - 0.2).abs() < 5e-3,
        "rests at {:?}",
        b.position()
    );
    // Level: the bar's axis stays horizontal.
    let axis = b.rotation().rotate(Vec3::X);
    assert!(axis.y.abs() < 1e-2, "tilted: {axis:?}");
    assert!(end.last().unwrap().1.length() < 0.05);
    // The two balls touch the ground, the bar does not: one patch of two points.
    assert_eq!(w.contact_count(), 1);
    assert_eq!(w.last_report().points, 2);
}

/// A small fast ball (ccd on) fired down at a mesh one triangle thick stops on it.
#[test]
fn a_fast_ball_does_not_tunnel_through_a_mesh() {
    let (v, t, mut nodes) = flat_grid(8, 1.0);
    let mesh = TriangleMesh::build(&v, &t, &mut nodes).unwrap();
    let mut w: Small<'_> = World::new();
    w.add(BodyDesc::fixed(Shape::Mesh(&mesh))).unwrap();
    let h = w
        .add(
            BodyDesc::dynamic(Shape::sphere(0.05).unwrap())
                .position(Vec3::new(0.3, 2.0, 0.2))
                .velocity(Vec3::new(0.0, -150.0, 0.0))
                .ccd(true),
        )
        .unwrap();
    let mut lowest = f32::INFINITY;
    for _ in 0..60 {
        w.step();
        lowest = lowest.min(w.body(h).unwrap().position().y);
    }
    assert!(lowest > 0.0, "tunnelled to {lowest}");
    assert!((w.body(h).unwrap().position().y - 0.05).abs() < 0.01);
}

/// Ray casts and overlap queries reach into meshes and compounds.
#[test]
fn queries_reach_into_meshes_and_compounds() {
    let (v, t, mut nodes) = flat_grid(8, 1.0);
    let mesh = TriangleMesh::build(&v, &t, &mut nodes).unwrap();
    let parts = [
        CompoundPart::new(
            Iso::from_position(Vec3::new(-1.0, 0.0, 0.0)),
            Shape::sphere(0.5).unwrap(),
        ),
        CompoundPart::new(
            Iso::from_position(Vec3::new(1.0, 0.0, 0.0)),
            Shape::sphere(0.5).unwrap(),
        ),
    ];
    let pair = Compound::new(&parts).unwrap();
    let mut w: Small<'_> = World::new();
    let ground = w
        .add(BodyDesc::fixed(Shape::Mesh(&mesh)).position(Vec3::new(0.0, -1.0, 0.0)))
        .unwrap();
    let balls = w
        .add(BodyDesc::fixed(Shape::Compound(&pair)).position(Vec3::new(0.0, 2.0, 0.0)))
        .unwrap();
    let down = |x: f32| Ray::new(Vec3::new(x, 10.0, 0.0), -Vec3::Y).unwrap();
    // Between the balls the ray meets the mesh; over a ball, the ball.
    let hit = w
        .cast_ray(&down(0.0), 100.0, QueryFilter::default())
        .unwrap()
        .unwrap();
    assert_eq!(hit.body, ground);
    assert!((hit.t - 11.0).abs() < 1e-5);
    let hit = w
        .cast_ray(&down(1.0), 100.0, QueryFilter::default())
        .unwrap()
        .unwrap();
    assert_eq!(hit.body, balls);
    assert!((hit.t - 7.5).abs() < 1e-5);
    // A small box between the balls touches neither; on a ball, that ball's body.
    let probe = Shape::cuboid(Vec3::splat(0.1)).unwrap();
    let mut out = [ground; 4];
    let at = |x: f32, y: f32| Iso::from_position(Vec3::new(x, y, 0.0));
    let n = w
        .overlap(&probe, &at(0.0, 2.0), QueryFilter::default(), &mut out)
        .unwrap();
    assert_eq!(n, 0);
    let n = w
        .overlap(&probe, &at(1.0, 2.5), QueryFilter::default(), &mut out)
        .unwrap();
    assert_eq!(&out[..n], &[balls]);
    let n = w
        .overlap(&probe, &at(3.3, -1.05), QueryFilter::default(), &mut out)
        .unwrap();
    assert_eq!(&out[..n], &[ground]);
}

/// A world with a mesh ground and a compound restores from its snapshot and replays
/// bit for bit; the convex-shape queries refuse meshes and compounds.
#[test]
fn snapshots_carry_mesh_and_compound_worlds() {
    let (v, t, mut nodes) = flat_grid(12, 0.5);
    let mesh = TriangleMesh::build(&v, &t, &mut nodes).unwrap();
    let parts = [
        CompoundPart::new(
            Iso::from_position(Vec3::new(-0.4, 0.0, 0.0)),
            Shape::cuboid(Vec3::splat(0.2)).unwrap(),
        ),
        CompoundPart::new(
            Iso::from_position(Vec3::new(0.4, 0.1, 0.0)),
            Shape::sphere(0.25).unwrap(),
        ),
    ];
    let c = Compound::new(&parts).unwrap();
    let mut w: Small<'_> = World::new();
    w.add(BodyDesc::fixed(Shape::Mesh(&mesh))).unwrap();
    for k in 0..4 {
        w.add(
            BodyDesc::dynamic(Shape::Compound(&c))
                .position(Vec3::new(
                    k as f32 * 0.7 - 1.0,
                    0.6 + 0.5 * k as f32,
                    0.1 * k as f32,
                ))
                .angular_velocity(Vec3::new(0.3, 1.0, -0.2))
                .material(Material {
                    restitution: 0.3,
                    ..Material::DEFAULT
                }),
        )
        .unwrap();
    }
    for _ in 0..40 {
        w.step();
    }
    assert!(w.contact_count() > 0);
    let mut buf = vec![0u8; w.snapshot_len()];
    let n = w.snapshot(&mut buf).unwrap();
    let mut replay: Vec<u64> = Vec::new();
    for _ in 0..40 {
        w.step();
        replay.push(w.checksum());
    }
    let mut again: Small<'_> = World::new();
    again.add(BodyDesc::fixed(Shape::Mesh(&mesh))).unwrap();
    again.add(BodyDesc::dynamic(Shape::Compound(&c))).unwrap();
    again.restore(&buf[..n]).unwrap();
    for want in replay {
        again.step();
        assert_eq!(again.checksum(), want);
    }
    // A world without the mesh cannot restore it.
    let mut bare: Small<'_> = World::new();
    bare.add(BodyDesc::dynamic(Shape::Compound(&c))).unwrap();
    assert_eq!(
        bare.restore(&buf[..n]),
        Err(carom::Error::Snapshot(carom::SnapshotError::MissingShape))
    );
    // The narrow-phase doors refuse shapes with parts.
    let ball = Shape::sphere(0.5).unwrap();
    let far = Iso::from_position(Vec3::new(0.0, 3.0, 0.0));
    assert_eq!(
        carom::collide::contact(&Shape::Mesh(&mesh), &Iso::IDENTITY, &ball, &far, 0.1),
        Err(carom::Error::NotConvex)
    );
    assert_eq!(
        carom::collide::separation(&ball, &far, &Shape::Compound(&c), &Iso::IDENTITY).map(|_| ()),
        Err(carom::Error::NotConvex)
    );
}

/// A flat height field of `n × n` cells of `cell` metres, centred on the origin by its
/// body's position.
fn flat_field(n: u32, cell: f32) -> (Vec<f32>, Iso) {
    let heights = vec![0.0; ((n + 1) * (n + 1)) as usize];
    let half = n as f32 * cell * 0.5;
    (heights, Iso::from_position(Vec3::new(-half, 0.0, -half)))
}

/// On a flat height field a box rests at the same height as on a box ground and a ball
/// rolls across its cells at the same speed.
#[test]
fn bodies_on_a_flat_height_field_behave_as_on_one_plane() {
    let (h, at) = flat_field(20, 0.5);
    let field = HeightField::new(&h, 21, 21, 0.5).unwrap();
    let ground = || BodyDesc::fixed(Shape::HeightField(&field)).position(at.position);
    let drop_box = |g: BodyDesc<'_>| {
        let mut w: Small<'_> = World::new();
        w.add(g).unwrap();
        let h = w
            .add(
                BodyDesc::dynamic(Shape::cuboid(Vec3::splat(0.5)).unwrap())
                    .position(Vec3::new(0.13, 0.7, -0.21))
                    .rotation(carom::Quat::from_axis_angle(Vec3::Y, 0.3)),
            )
            .unwrap();
        track(&mut w, h, 180)
    };
    let (on_field, on_box) = (drop_box(ground()), drop_box(box_ground()));
    let (f, b) = (on_field.last().unwrap().0, on_box.last().unwrap().0);
    assert!((f - b).length() < 2e-3, "{f:?} vs {b:?}");
    let roll = |g: BodyDesc<'_>| {
        let mut w: Small<'_> = World::new();
        w.add(g).unwrap();
        let h = w
            .add(
                BodyDesc::dynamic(Shape::sphere(0.25).unwrap())
                    .position(Vec3::new(-4.0, 0.25, 0.1))
                    .velocity(Vec3::new(2.0, 0.0, 0.0))
                    .angular_velocity(Vec3::new(0.0, 0.0, -8.0)),
            )
            .unwrap();
        track(&mut w, h, 120)
    };
    let (on_field, on_box) = (roll(ground()), roll(box_ground()));
    let (vf, vb) = (on_field.last().unwrap().1, on_box.last().unwrap().1);
    assert!((vf - vb).length() < 0.02, "{vf:?} vs {vb:?}");
    for (p, v) in &on_field {
        assert!(v.y.abs() < 0.05 && (p.y - 0.25).abs() < 5e-3, "{p:?} {v:?}");
    }
}

/// A ball on a height field sloping at θ (heights `x tan θ`), without rolling
/// resistance, rolls down with a = 5/7 g sin θ (a solid ball rolling without slipping).
#[test]
fn a_ball_rolls_down_a_height_field_slope_at_five_sevenths_g_sin_theta() {
    let theta = 0.15f32;
    let (n, cell) = (40u32, 0.5f32);
    let mut heights = Vec::new();
    for _j in 0..=n {
        for i in 0..=n {
            heights.push((n - i) as f32 * cell * theta.tan());
        }
    }
    let field = HeightField::new(&heights, n + 1, n + 1, cell).unwrap();
    // No rolling resistance on either side (the world combines the two materials).
    let smooth = Material {
        rolling_resistance: 0.0,
        twist_friction: 0.0,
        ..Material::DEFAULT
    };
    let mut w: Small<'_> = World::new();
    w.add(
        BodyDesc::fixed(Shape::HeightField(&field))
            .position(Vec3::new(0.0, 0.0, -10.0))
            .material(smooth),
    )
    .unwrap();
    let r = 0.3;
    // Resting on the slope near its top, x = 3: the centre r along the slope's normal.
    let x0 = 3.0f32;
    let surface = (20.0 - x0) * theta.tan();
    let normal = Vec3::new(theta.sin(), theta.cos(), 0.0);
    let h = w
        .add(
            BodyDesc::dynamic(Shape::sphere(r).unwrap())
                .position(Vec3::new(x0, surface, 0.3) + normal * r)
                .material(smooth),
        )
        .unwrap();
    let steps = 90;
    let path = track(&mut w, h, steps);
    let t = steps as f32 / 60.0;
    let speed = path.last().unwrap().1.length();
    let want = 5.0 / 7.0 * 9.81 * theta.sin() * t;
    assert!(
        (speed - want).abs() < 0.02 * want,
        "speed {speed} vs {want}"
    );
    // It stays on the slope: no hop off a seam.
    for (p, _) in &path {
        let height_over = p.y - (20.0 - p.x) * theta.tan();
        assert!((height_over * theta.cos() - r).abs() < 5e-3, "{p:?}");
    }
}

/// The `mesh_pile` scene: 300 mixed bodies fall on 10,368 terrain triangles; none ends
/// below the terrain under it, the run repeats bit for bit, and no pair or contact is
/// dropped at the reference capacities used here.
#[test]
fn the_mesh_pile_settles_on_its_terrain_and_repeats() {
    // A world this size is built on the stack before it is boxed (see `World`'s docs).
    std::thread::Builder::new()
        .stack_size(64 << 20)
        .spawn(mesh_pile_run)
        .unwrap()
        .join()
        .unwrap();
}

/// The scenes' eight hulls ([`scenes::make_hulls`] with the scenes' seed).
fn scene_hulls() -> Vec<carom::ConvexHull> {
    let mut v = vec![carom::ConvexHull::UNIT_TETRAHEDRON; 8];
    scenes::make_hulls(&mut v, scenes::SEED).unwrap();
    v
}

fn mesh_pile_run() {
    let hulls = scene_hulls();
    let mut heights = vec![0.0; scenes::MESH_PILE_SAMPLES];
    scenes::mesh_pile_heights(&mut heights);
    let field = scenes::mesh_pile_field(&heights).unwrap();
    assert_eq!(field.triangle_count(), 10_368);
    let run = || {
        let mut w: Box<World<'_, 512, 8192, 64>> = Box::default();
        assert!(
            Scene::MeshPile.build(&mut w, &hulls).is_err(),
            "needs its terrain"
        );
        Scene::MeshPile
            .build_on(&mut w, &hulls, Some(carom::Shape::HeightField(&field)))
            .unwrap();
        let mut dropped = 0;
        for _ in 0..Scene::MeshPile.steps() {
            let r = w.step();
            dropped += r.dropped_contacts + r.dropped_pairs;
            // The report counts the manifolds the step leaves, part contacts included
            // (their narrow phase runs with their pair's record, after their own visit).
            assert_eq!(r.contacts as usize, w.contact_count());
        }
        assert_eq!(dropped, 0);
        let half = (scenes::MESH_PILE_COLUMNS - 1) as f32 * scenes::MESH_PILE_CELL * 0.5;
        let mut on_terrain = 0;
        for h in w.handles() {
            let b = w.body(h).unwrap();
            let p = b.position();
            if b.kind() != carom::BodyKind::Dynamic || p.x.abs() >= half || p.z.abs() >= half {
                continue;
            }
            on_terrain += 1;
            // The terrain's height under the body: a ray straight down from far above.
            let down = Ray::new(Vec3::new(p.x, 50.0, p.z), -Vec3::Y).unwrap();
            let ground = Shape::HeightField(&field)
                .cast_ray(
                    &Iso::from_position(Vec3::new(-half, 0.0, -half)),
                    &down,
                    100.0,
                )
                .unwrap()
                .unwrap();
            assert!(
                p.y > ground.point.y - 0.05,
                "body at {p:?} below the terrain at {:?}",
                ground.point
            );
        }
        assert!(on_terrain > 250, "{on_terrain} bodies on the terrain");
        w.checksum()
    };
    assert_eq!(run(), run());
}

/// A world restored from its own snapshot before every step starts each step without the
/// caches a snapshot leaves out (the separating axis test's axis, the mid phase's memory
/// of the triangles beyond reach), and still follows the same path to the bit: those
/// caches only ever shorten the way to the same answer. On the `mesh_pile` height field
/// (its first 150 steps, where most bodies fall, land and slide) and on `terrain_mesh`'s
/// triangle mesh (all 600 steps).
#[test]
fn restoring_every_step_drops_the_caches_and_changes_nothing() {
    std::thread::Builder::new()
        .stack_size(64 << 20)
        .spawn(restore_every_step_run)
        .unwrap()
        .join()
        .unwrap();
}

/// Step `plain` and `restored` side by side for `steps` steps, `restored` restored from
/// its own snapshot before each; their checksums must agree after every step.
fn step_beside_a_restored_copy<const B: usize, const C: usize, const E: usize>(
    plain: &mut World<'_, B, C, E>,
    restored: &mut World<'_, B, C, E>,
    steps: u32,
    name: &str,
) {
    let mut buf = Vec::new();
    for step in 0..steps {
        buf.resize(restored.snapshot_len(), 0);
        let n = restored.snapshot(&mut buf).unwrap();
        restored.restore(&buf[..n]).unwrap();
        plain.step();
        restored.step();
        assert_eq!(
            plain.checksum(),
            restored.checksum(),
            "{name}: the restored copy left the path at step {}",
            step + 1
        );
    }
}

fn restore_every_step_run() {
    let hulls = scene_hulls();
    let mut heights = vec![0.0; scenes::MESH_PILE_SAMPLES];
    scenes::mesh_pile_heights(&mut heights);
    let field = scenes::mesh_pile_field(&heights).unwrap();
    let pile = || {
        let mut w: Box<World<'_, 512, 8192, 64>> = Box::default();
        Scene::MeshPile
            .build_on(&mut w, &hulls, Some(carom::Shape::HeightField(&field)))
            .unwrap();
        w
    };
    let (mut plain, mut restored) = (pile(), pile());
    step_beside_a_restored_copy(&mut plain, &mut restored, 150, "mesh_pile");

    let mut data: Box<scenes::TerrainData> = Box::default();
    let shapes = data.shapes().unwrap();
    let scene = Scene::TerrainMesh;
    let terrain = || {
        let mut w: Box<scenes::ReferenceWorld<'_>> = Box::default();
        w.set_config(scene.config()).unwrap();
        scene
            .build_on(&mut w, &hulls, shapes.ground(scene))
            .unwrap();
        w
    };
    let (mut plain, mut restored) = (terrain(), terrain());
    step_beside_a_restored_copy(&mut plain, &mut restored, scene.steps(), scene.name());
}

/// A pair with parts raises its events once, as a pair: a ball bouncing across several
/// triangles of a mesh begins touching once per landing and hits once per landing, however
/// many triangles it touches.
#[test]
fn a_pair_with_parts_raises_its_events_once() {
    let (v, t, mut nodes) = flat_grid(8, 0.25);
    let mesh = TriangleMesh::build(&v, &t, &mut nodes).unwrap();
    let mut w: Small<'_> = World::new();
    let ground = w.add(BodyDesc::fixed(Shape::Mesh(&mesh))).unwrap();
    // Dropped onto a grid vertex, where six triangles meet.
    let ball = w
        .add(BodyDesc::dynamic(Shape::sphere(0.3).unwrap()).position(Vec3::new(0.0, 1.0, 0.0)))
        .unwrap();
    let (mut begins, mut ends, mut hits) = (0, 0, 0);
    for _ in 0..120 {
        w.step();
        for e in w.events() {
            match *e {
                carom::Event::ContactBegin { a, b } => {
                    assert_eq!((a, b), (ground, ball));
                    begins += 1;
                }
                carom::Event::ContactEnd { .. } => ends += 1,
                carom::Event::Hit { a, b, normal, .. } => {
                    assert_eq!((a, b), (ground, ball));
                    assert!((normal - Vec3::Y).length() < 1e-3, "{normal:?}");
                    hits += 1;
                }
                _ => {}
            }
        }
    }
    assert_eq!((begins, ends, hits), (1, 0, 1));
    assert!(w.body(ball).unwrap().position().y > 0.29);
}

/// A box landing flat on a mesh raises the `Hit`s it raises on one plane (when its
/// manifold appears, at its landing speed, and when it starts touching), whether its
/// triangles' manifolds are rebuilt or reused on those steps: the box is dropped at
/// speeds from 0.2 to 3 m/s (a few millimetres to five centimetres per step, on both
/// sides of the reuse slack) and its hits are compared with the same box's on a box
/// ground.
#[test]
fn a_box_landing_on_a_mesh_hits_as_on_a_plane_at_any_speed() {
    let (v, t, mut nodes) = flat_grid(8, 0.5);
    let mesh = TriangleMesh::build(&v, &t, &mut nodes).unwrap();
    let hits = |ground: BodyDesc<'_>, speed: f32| {
        let mut w: Small<'_> = World::new();
        let mut cfg = *w.config();
        cfg.hit_event_speed = 0.1;
        cfg.gravity = Vec3::ZERO;
        w.set_config(cfg).unwrap();
        w.add(ground).unwrap();
        // Falling from 0.35 m above the ground at `speed`, without gravity.
        w.add(
            BodyDesc::dynamic(Shape::cuboid(Vec3::new(0.3, 0.2, 0.3)).unwrap())
                .position(Vec3::new(0.1, 0.55, -0.05))
                .velocity(Vec3::new(0.0, -speed, 0.0)),
        )
        .unwrap();
        let mut speeds = Vec::new();
        for _ in 0..120 {
            w.step();
            for e in w.events() {
                if let carom::Event::Hit { speed, .. } = *e {
                    speeds.push(speed);
                }
            }
        }
        speeds
    };
    for k in 0..15 {
        let speed = 0.2 + 0.2 * k as f32;
        let on_mesh = hits(BodyDesc::fixed(Shape::Mesh(&mesh)), speed);
        let on_box = hits(box_ground(), speed);
        assert!(
            !on_box.is_empty() && on_box.len() == on_mesh.len(),
            "{speed} m/s: {on_mesh:?} on the mesh, {on_box:?} on the box"
        );
        // The first at the landing speed (the manifold appears), any later one (touching,
        // after the speculative point has slowed the box) no faster.
        let landing =
            |h: &[f32]| (h[0] - speed).abs() < 0.01 * speed && h.iter().all(|&x| x < 1.01 * speed);
        assert!(
            landing(&on_mesh) && landing(&on_box),
            "{speed} m/s: {on_mesh:?} on the mesh, {on_box:?} on the box"
        );
    }
}

/// The `terrain` and `terrain_mesh` reference scenes in their reference world: the bowl
/// keeps every body (none below y = 0, none outside it), nothing is dropped, the pile is
/// asleep 200 steps after the last, and the height field and the mesh of its triangles give the
/// same checksum.
#[test]
fn the_terrain_scene_piles_up_in_its_bowl_without_dropping_a_contact() {
    let hulls = scene_hulls();
    let mut data: Box<scenes::TerrainData> = Box::default();
    let shapes = data.shapes().unwrap();
    let mut sums = Vec::new();
    for scene in [Scene::Terrain, Scene::TerrainMesh] {
        let mut w: Box<scenes::ReferenceWorld<'_>> = Box::default();
        w.set_config(scene.config()).unwrap();
        scene
            .build_on(&mut w, &hulls, shapes.ground(scene))
            .unwrap();
        let mut dropped = 0;
        let mut peak = 0;
        for _ in 0..scene.steps() {
            let r = w.step();
            dropped += r.dropped_contacts + r.dropped_pairs;
            peak = peak.max(w.contact_count());
        }
        assert_eq!(dropped, 0, "{} peak {peak}", scene.name());
        sums.push(w.checksum());
        // The last capsule rolling to and fro in the bowl stops within 200 more steps.
        for _ in 0..200 {
            w.step();
        }
        let mut awake = 0;
        for h in w.handles() {
            let b = w.body(h).unwrap();
            if b.kind() != carom::BodyKind::Dynamic {
                continue;
            }
            let p = b.position();
            assert!(p.y > 0.0 && p.x.abs() < 8.0 && p.z.abs() < 8.0, "{p:?}");
            awake += usize::from(b.is_awake());
        }
        assert_eq!(awake, 0, "{}: the pile sleeps by step 800", scene.name());
    }
    // The same triangles in the same order through the cell walk and through the
    // hierarchy: part keys, contacts and so every bit of the run are the same.
    assert_eq!(sums[0], sums[1]);
}
