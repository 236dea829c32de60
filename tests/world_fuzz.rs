//! The world-fuzzing properties (`carom::props::world_ops_properties`, the snapshot
//! decoding properties) on stable, with SplitMix64-generated inputs: the same checks the
//! `world` and `snapshot` fuzz targets run on arbitrary bytes.
//!
//! Inputs mix good values (small scenes that collide, settle and sleep) with bad ones
//! (NaN, ±∞, negative, zero, subnormal and huge numbers, unnormalised rotations, stale
//! and garbage handles) about one value in sixteen.

use carom::props::{
    fixture_hull, fnv1a, is_known_finding, snapshot_bytes_properties, snapshot_edit_properties,
    snapshot_fixture, world_ops_properties, BodySpec, HandleRef, OpsWorld, ShapeSpec, SnapshotEdit,
    Violation, WorldOp, MAX_HULL_POINTS, SNAPSHOT_BUFFER,
};
use carom::rng::SplitMix64;
use carom::{
    BodyDesc, BodyHandle, BodyKind, Error, MassSpec, Material, Quat, QueryFilter, Shape, Vec3,
    WorldConfig,
};

/// Worlds are ~100 KiB and the properties keep a few clones and snapshot buffers on the
/// stack: run on a thread with room.
fn with_stack(f: impl FnOnce() + Send + 'static) {
    std::thread::Builder::new()
        .stack_size(64 << 20)
        .spawn(f)
        .unwrap()
        .join()
        .unwrap();
}

// ---------------------------------------------------------------------------------------
// Generators
// ---------------------------------------------------------------------------------------

const BAD: [f32; 12] = [
    f32::NAN,
    f32::INFINITY,
    f32::NEG_INFINITY,
    -1.0,
    0.0,
    -0.0,
    1.0e30,
    3.4e38,
    -3.4e38,
    1.0e-40, // subnormal
    f32::MIN_POSITIVE,
    -1.0e-30,
];

struct Gen(SplitMix64);

impl Gen {
    fn below(&mut self, n: u64) -> u64 {
        self.0.next_u64() % n
    }
    fn chance(&mut self, one_in: u64) -> bool {
        self.below(one_in) == 0
    }
    fn bad(&mut self) -> f32 {
        BAD[self.below(BAD.len() as u64) as usize]
    }
    /// Uniform in `[lo, hi)`, or (one in 16) a bad value.
    fn num(&mut self, lo: f32, hi: f32) -> f32 {
        if self.chance(16) {
            self.bad()
        } else {
            self.0.range(lo, hi)
        }
    }
    fn vec(&mut self, lo: f32, hi: f32) -> Vec3 {
        Vec3::new(self.num(lo, hi), self.num(lo, hi), self.num(lo, hi))
    }
    fn rotation(&mut self) -> Quat {
        match self.below(10) {
            0 => Quat::IDENTITY,
            1 => Quat::from_xyzw(self.num(-2.0, 2.0), self.num(-2.0, 2.0), 0.0, 1.0),
            _ => self.0.rotation(),
        }
    }
    fn shape(&mut self) -> ShapeSpec {
        match self.below(12) {
            0..=2 => ShapeSpec::Sphere {
                radius: self.num(0.05, 1.0),
            },
            3..=4 => ShapeSpec::Capsule {
                half_height: self.num(0.05, 0.8),
                radius: self.num(0.05, 0.5),
            },
            5..=7 => ShapeSpec::Cuboid {
                half_extents: self.vec(0.05, 1.0),
            },
            8..=9 => {
                let mut points = [Vec3::ZERO; MAX_HULL_POINTS];
                for p in points.iter_mut() {
                    *p = self.vec(-0.6, 0.6);
                }
                ShapeSpec::Hull {
                    points,
                    count: self.below(MAX_HULL_POINTS as u64 + 1) as u8,
                }
            }
            10 => ShapeSpec::HalfSpace {
                normal: self.vec(-1.0, 1.0),
            },
            _ => ShapeSpec::Triangle {
                corners: [
                    self.vec(-2.0, 2.0),
                    self.vec(-2.0, 2.0),
                    self.vec(-2.0, 2.0),
                ],
            },
        }
    }
    fn material(&mut self) -> Material {
        Material {
            restitution: self.num(0.0, 1.0),
            static_friction: self.num(0.0, 1.2),
            kinetic_friction: self.num(0.0, 1.0),
            ..Material::DEFAULT
        }
    }
    fn body(&mut self) -> BodySpec {
        let kind = match self.below(10) {
            0..=6 => BodyKind::Dynamic,
            7..=8 => BodyKind::Static,
            _ => BodyKind::Kinematic,
        };
        let mass = if self.chance(2) {
            MassSpec::Density(self.num(100.0, 3000.0))
        } else {
            MassSpec::Mass(self.num(0.1, 20.0))
        };
        BodySpec {
            kind,
            shape: self.shape(),
            position: Vec3::new(
                self.num(-3.0, 3.0),
                self.num(-0.5, 4.0),
                self.num(-3.0, 3.0),
            ),
            rotation: self.rotation(),
            linear_velocity: self.vec(-5.0, 5.0),
            angular_velocity: self.vec(-5.0, 5.0),
            mass,
            material: self.material(),
            linear_damping: self.num(0.0, 1.0),
            angular_damping: self.num(0.0, 1.0),
            group: if self.chance(8) {
                self.0.next_u64() as u32
            } else {
                1
            },
            mask: if self.chance(8) {
                self.0.next_u64() as u32
            } else {
                u32::MAX
            },
            sensor: self.chance(10),
            ccd: !self.chance(4),
            user_data: self.0.next_u64(),
        }
    }
    fn handle(&mut self) -> HandleRef {
        if self.chance(7) {
            HandleRef::Raw(BodyHandle {
                index: self.below(20) as u32,
                generation: self.below(3) as u32,
            })
        } else {
            HandleRef::Created(self.0.next_u64() as u8)
        }
    }
    fn filter(&mut self) -> QueryFilter {
        if self.chance(4) {
            QueryFilter {
                group: self.0.next_u64() as u32,
                mask: self.0.next_u64() as u32,
                include_sensors: self.chance(2),
            }
        } else {
            QueryFilter::ALL
        }
    }
    /// The default configuration with one to three fields changed (often to bad values).
    fn config(&mut self) -> WorldConfig {
        let mut c = WorldConfig::DEFAULT;
        for _ in 0..1 + self.below(3) {
            match self.below(12) {
                0 => c.gravity = self.vec(-20.0, 20.0),
                1 => c.dt = self.num(1.0 / 240.0, 1.0 / 30.0),
                2 => c.substeps = self.below(6) as u32,
                3 => c.velocity_iterations = self.below(20) as u32,
                4 => c.position_iterations = self.below(6) as u32,
                5 => c.restitution_threshold = self.num(0.0, 2.0),
                6 => c.slop = self.num(0.0, 0.02),
                7 => c.projection_factor = self.num(0.0, 1.0),
                8 => c.speculative_margin = self.num(0.0, 0.1),
                9 => c.sleep_enabled = self.chance(2),
                10 => c.max_linear_speed = self.num(1.0, 2000.0),
                _ => c.sleep_time = self.num(0.0, 1.0),
            }
        }
        c
    }
    fn op(&mut self) -> WorldOp {
        match self.below(40) {
            0..=9 => WorldOp::Add(self.body()),
            10..=11 => WorldOp::Remove(self.handle()),
            12 => WorldOp::SetPose(self.handle(), self.vec(-3.0, 3.0), self.rotation()),
            13 => WorldOp::SetVelocity(self.handle(), self.vec(-10.0, 10.0)),
            14 => WorldOp::SetAngularVelocity(self.handle(), self.vec(-10.0, 10.0)),
            15 => WorldOp::ApplyForce(self.handle(), self.vec(-100.0, 100.0)),
            16 => WorldOp::ApplyTorque(self.handle(), self.vec(-10.0, 10.0)),
            17 => WorldOp::ApplyImpulseAt(self.handle(), self.vec(-5.0, 5.0), self.vec(-3.0, 3.0)),
            18 => WorldOp::Wake(self.handle()),
            19 => WorldOp::Sleep(self.handle()),
            20 => WorldOp::SetMaterial(self.handle(), self.material()),
            21 => WorldOp::SetConfig(self.config()),
            22..=29 => WorldOp::Step(self.below(9) as u8),
            30..=31 => {
                let direction = if self.chance(3) {
                    self.vec(-1.0, 1.0) // raw: rarely unit
                } else {
                    self.0.unit_vector()
                };
                WorldOp::CastRay {
                    origin: self.vec(-4.0, 4.0),
                    direction,
                    max_t: self.num(0.0, 20.0),
                    filter: self.filter(),
                }
            }
            32..=33 => WorldOp::Overlap {
                shape: self.shape(),
                position: self.vec(-3.0, 3.0),
                rotation: self.rotation(),
                filter: self.filter(),
            },
            34..=35 => WorldOp::SnapshotRestore,
            36..=37 => WorldOp::CorruptRestore {
                at: self.0.next_u64() as u32,
                xor: self.0.next_u64() as u8,
                truncate: self.chance(2),
            },
            _ => WorldOp::Checksum,
        }
    }
    /// A ground box first (so bodies collide and rest), then `len` random operations.
    fn ops(&mut self, len: usize) -> Vec<WorldOp> {
        let mut ops = vec![ground()];
        ops.extend((0..len).map(|_| self.op()));
        ops
    }
}

fn ground() -> WorldOp {
    WorldOp::Add(BodySpec {
        kind: BodyKind::Static,
        shape: ShapeSpec::Cuboid {
            half_extents: Vec3::new(8.0, 0.5, 8.0),
        },
        position: Vec3::new(0.0, -0.5, 0.0),
        rotation: Quat::IDENTITY,
        linear_velocity: Vec3::ZERO,
        angular_velocity: Vec3::ZERO,
        mass: MassSpec::Density(1000.0),
        material: Material::DEFAULT,
        linear_damping: 0.0,
        angular_damping: 0.0,
        group: 1,
        mask: u32::MAX,
        sensor: false,
        ccd: false,
        user_data: 0,
    })
}

fn ball(y: f32) -> WorldOp {
    let WorldOp::Add(mut b) = ground() else {
        unreachable!()
    };
    b.kind = BodyKind::Dynamic;
    b.shape = ShapeSpec::Sphere { radius: 0.5 };
    b.position = Vec3::new(0.0, y, 0.0);
    WorldOp::Add(b)
}

// ---------------------------------------------------------------------------------------
// World operations
// ---------------------------------------------------------------------------------------

/// Sequences of random operations tested per run, and the most operations in one.
const SEQUENCES: u64 = 4000;
const MAX_SEQUENCE: u64 = 64;

/// Drop operations one at a time while the sequence still fails with `v`: a short
/// input to report and to turn into a regression test.
fn shrink(ops: &[WorldOp], v: Violation) -> Vec<WorldOp> {
    let mut ops = ops.to_vec();
    let mut i = 0;
    while i < ops.len() {
        let mut fewer = ops.clone();
        fewer.remove(i);
        if world_ops_properties(&fewer) == Err(v) {
            ops = fewer;
        } else {
            i += 1;
        }
    }
    ops
}

#[test]
fn snapshot_buffer_fits_the_ops_world() {
    assert!(OpsWorld::max_snapshot_len() <= SNAPSHOT_BUFFER);
}

#[test]
fn seeded_op_sequences_hold_the_world_properties() {
    with_stack(|| {
        let mut known = 0;
        for seed in 0..SEQUENCES {
            let mut g = Gen(SplitMix64::new(0x5EED_0000 + seed));
            let len = 1 + g.below(MAX_SEQUENCE) as usize;
            let ops = g.ops(len);
            match world_ops_properties(&ops) {
                Ok(()) => {}
                Err(v) if is_known_finding(&v) => known += 1,
                Err(v) => {
                    let small = shrink(&ops, v);
                    panic!("seed {seed}: {v:?}\nshrunk ops: {small:?}");
                }
            }
        }
        eprintln!("{known} of {SEQUENCES} sequences hit a known finding");
        assert_eq!(known, 0, "every known finding is fixed");
    });
}

/// Every operation kind once on a world with bodies, with good values: the property
/// function must accept all of it (a good call refused would be a violation).
#[test]
fn every_operation_with_good_values_holds() {
    with_stack(|| {
        let created = HandleRef::Created(1);
        let ops = [
            ground(),
            ball(1.0),
            ball(3.0),
            WorldOp::Step(8),
            WorldOp::SetPose(created, Vec3::new(1.0, 2.0, 0.0), Quat::IDENTITY),
            WorldOp::SetVelocity(created, Vec3::new(0.0, -1.0, 0.0)),
            WorldOp::SetAngularVelocity(created, Vec3::new(0.0, 1.0, 0.0)),
            WorldOp::ApplyForce(created, Vec3::new(10.0, 0.0, 0.0)),
            WorldOp::ApplyTorque(created, Vec3::new(0.0, 0.0, 1.0)),
            WorldOp::ApplyImpulseAt(created, Vec3::X, Vec3::new(1.0, 2.5, 0.0)),
            WorldOp::Sleep(created),
            WorldOp::Wake(created),
            WorldOp::SetMaterial(created, Material::DEFAULT),
            WorldOp::SetConfig(WorldConfig {
                substeps: 2,
                ..WorldConfig::DEFAULT
            }),
            WorldOp::Step(8),
            WorldOp::CastRay {
                origin: Vec3::new(0.0, 10.0, 0.0),
                direction: -Vec3::Y,
                max_t: 20.0,
                filter: QueryFilter::ALL,
            },
            WorldOp::Overlap {
                shape: ShapeSpec::Sphere { radius: 1.0 },
                position: Vec3::ZERO,
                rotation: Quat::IDENTITY,
                filter: QueryFilter::ALL,
            },
            WorldOp::SnapshotRestore,
            WorldOp::CorruptRestore {
                at: 100,
                xor: 0x40,
                truncate: false,
            },
            WorldOp::CorruptRestore {
                at: 100,
                xor: 0,
                truncate: true,
            },
            WorldOp::Checksum,
            WorldOp::Remove(HandleRef::Created(2)),
            WorldOp::Remove(HandleRef::Created(2)), // now stale: must be refused
            WorldOp::Step(8),
        ];
        assert_eq!(world_ops_properties(&ops), Ok(()));
    });
}

// ---------------------------------------------------------------------------------------
// Snapshot decoding
// ---------------------------------------------------------------------------------------

const MUTATIONS: u64 = 1500;

fn edit(g: &mut Gen) -> SnapshotEdit {
    let at = g.0.next_u64() as u32;
    match g.below(10) {
        0..=3 => SnapshotEdit::Xor {
            at,
            mask: 1 << g.below(8),
        },
        4..=6 => SnapshotEdit::Word {
            at,
            bits: match g.below(3) {
                0 => g.bad().to_bits(),
                1 => g.0.next_u64() as u32,
                _ => g.0.range(-10.0, 10.0).to_bits(),
            },
        },
        7 => SnapshotEdit::Truncate { len: at },
        8 => SnapshotEdit::Delete { at },
        _ => SnapshotEdit::Insert {
            at,
            byte: g.0.next_u64() as u8,
        },
    }
}

#[test]
fn unchanged_snapshots_restore_at_every_fixture_step() {
    with_stack(|| {
        for steps in 0..=carom::props::FIXTURE_MAX_STEPS as u8 {
            assert_eq!(snapshot_edit_properties(steps, &[], false), Ok(()));
            assert_eq!(snapshot_edit_properties(steps, &[], true), Ok(()));
        }
    });
}

#[test]
fn seeded_snapshot_mutations_are_refused_or_sound() {
    with_stack(|| {
        let mut known = 0;
        for seed in 0..MUTATIONS {
            let mut g = Gen(SplitMix64::new(0x5_4A95_0000 + seed));
            let steps = g.below(33) as u8;
            let edits: Vec<SnapshotEdit> = (0..1 + g.below(3)).map(|_| edit(&mut g)).collect();
            let reseal = !g.chance(4);
            match snapshot_edit_properties(steps, &edits, reseal) {
                Ok(()) => {}
                Err(v) if is_known_finding(&v) => known += 1,
                Err(v) => {
                    panic!("seed {seed}: {v:?}\nsteps {steps} reseal {reseal} edits {edits:?}")
                }
            }
        }
        eprintln!("{known} of {MUTATIONS} mutations hit a known finding");
        assert_eq!(known, 0, "every known finding is fixed");
    });
}

#[test]
fn seeded_arbitrary_bytes_are_refused() {
    with_stack(|| {
        let hull = fixture_hull().unwrap();
        let mut real = vec![0u8; SNAPSHOT_BUFFER];
        let n = snapshot_fixture(&hull)
            .unwrap()
            .snapshot(&mut real)
            .unwrap();
        for seed in 0..300u64 {
            let mut g = Gen(SplitMix64::new(0xB17E_5000 + seed));
            let len = g.below(600) as usize;
            let mut bytes: Vec<u8> = (0..len).map(|_| g.0.next_u64() as u8).collect();
            // Half the inputs keep a real header, so the capacity and hash checks run.
            if g.chance(2) {
                let k = bytes.len().min(36);
                bytes[..k].copy_from_slice(&real[..k]);
            }
            assert_eq!(
                snapshot_bytes_properties(&bytes, seed as u8),
                Ok(()),
                "seed {seed}"
            );
        }
        assert!(n > 36);
    });
}

// ---------------------------------------------------------------------------------------
// Findings of the world fuzz target, kept as regression tests through the public API
// (all fixed: five in snapshot restore, two closed by the size and coordinate limits).
// ---------------------------------------------------------------------------------------

fn sphere(r: f32) -> Shape<'static> {
    Shape::sphere(r).unwrap()
}

fn ground_box() -> BodyDesc<'static> {
    BodyDesc::fixed(Shape::cuboid(Vec3::new(8.0, 0.5, 8.0)).unwrap())
        .position(Vec3::new(0.0, -0.5, 0.0))
}

/// Snapshot `w`, restore the bytes into `w`, and return both buffers: before and after.
fn round_trip(w: &mut OpsWorld<'static>) -> (Result<(), Error>, Vec<u8>, Vec<u8>) {
    let mut before = vec![0u8; SNAPSHOT_BUFFER];
    let n = w.snapshot(&mut before).unwrap();
    before.truncate(n);
    let restored = w.restore(&before);
    let mut after = vec![0u8; SNAPSHOT_BUFFER];
    let m = w.snapshot(&mut after).unwrap();
    after.truncate(m);
    (restored, before, after)
}

/// Rewrite the snapshot header's payload hash (bytes 28..36 over the payload from 36).
fn reseal(buf: &mut [u8]) {
    let sum = fnv1a(&buf[36..]);
    buf[28..36].copy_from_slice(&sum.to_le_bytes());
}

#[test]
fn finding_snapshot_between_remove_and_step_restores() {
    with_stack(|| {
        let mut w = OpsWorld::new();
        let ball = w.add(BodyDesc::dynamic(sphere(0.5))).unwrap();
        w.step();
        w.remove(ball).unwrap();
        let (restored, _, _) = round_trip(&mut w);
        assert_eq!(restored, Ok(()));
    });
}

#[test]
fn finding_restore_keeps_generations_of_free_slots() {
    with_stack(|| {
        let mut w = OpsWorld::new();
        let old = w.add(BodyDesc::dynamic(sphere(0.5))).unwrap();
        w.remove(old).unwrap();
        let (restored, _, _) = round_trip(&mut w);
        assert_eq!(restored, Ok(()));
        let new = w.add(BodyDesc::dynamic(sphere(0.5))).unwrap();
        assert_ne!(new, old, "a removed handle names a new body again");
    });
}

#[test]
fn finding_restore_keeps_half_space_normals_bit_exact() {
    with_stack(|| {
        let mut rng = SplitMix64::new(0xA1F5);
        let mut changed = 0;
        for _ in 0..100 {
            let mut w = OpsWorld::new();
            let n = rng.unit_vector() * rng.range(0.5, 2.0);
            w.add(BodyDesc::fixed(Shape::half_space(n).unwrap()))
                .unwrap();
            let (restored, before, after) = round_trip(&mut w);
            assert_eq!(restored, Ok(()));
            changed += usize::from(before != after);
        }
        assert_eq!(
            changed, 0,
            "restore changed {changed} of 100 half-space normals"
        );
    });
}

/// Was: a snapshot with a valid hash could carry an inverse mass of 3e38 or 1e-45, or an
/// inverse-inertia entry of −3.4e38, and the world went non-finite a step later. Mass
/// properties are no longer stored: restore derives them from the shape and the stored
/// density exactly as `add` does, so a crafted density is refused like a bad `add`, and
/// a restored body's mass is what `add` would give. (The broad-phase order, whose
/// repeated slot was another finding here, is no longer stored either: it is derived.)
#[test]
fn finding_restore_derives_mass_properties() {
    with_stack(|| {
        let mut w = OpsWorld::new();
        w.add(ground_box()).unwrap();
        let b = w
            .add(
                BodyDesc::dynamic(Shape::cuboid(Vec3::new(0.5, 0.25, 0.5)).unwrap())
                    .position(Vec3::new(0.0, 0.24, 0.0))
                    .angular_velocity(Vec3::new(0.0, 0.0, 3.0)),
            )
            .unwrap();
        w.step();
        let mass = w.body(b).unwrap().mass();
        let mut buf = vec![0u8; SNAPSHOT_BUFFER];
        let n = w.snapshot(&mut buf).unwrap();
        buf.truncate(n);
        // The box's mass record: tag 0 (density) and 1000 kg/m³; the static ground's is a
        // canonical density 0.
        let mut record = vec![0u8];
        record.extend_from_slice(&1000.0f32.to_le_bytes());
        let at: Vec<usize> = (0..n - 5)
            .filter(|&i| buf[i..i + 5] == record[..])
            .collect();
        assert_eq!(at.len(), 1, "layout moved");
        let at = at[0] + 1;
        let before = w.checksum();
        for bad in [-3.4e38f32, 1.0e-45, 0.0, 3.4e38] {
            let mut crafted = buf.clone();
            crafted[at..at + 4].copy_from_slice(&bad.to_le_bytes());
            reseal(&mut crafted);
            assert_eq!(
                w.restore(&crafted),
                Err(carom::Error::Snapshot(carom::SnapshotError::Corrupt)),
                "density {bad}"
            );
            assert_eq!(w.checksum(), before);
        }
        // Twice the density: accepted, and the mass is what add would derive.
        let mut crafted = buf.clone();
        crafted[at..at + 4].copy_from_slice(&2000.0f32.to_le_bytes());
        reseal(&mut crafted);
        w.restore(&crafted).unwrap();
        let restored = w.body(b).unwrap().mass();
        assert!((restored / mass - 2.0).abs() < 1e-6, "{restored} vs {mass}");
    });
}

#[test]
fn finding_huge_shapes_are_refused() {
    // Was: a 3.4e38 m sphere was accepted and a body touching it got non-finite hit
    // events. Shape sizes are now limited to [MIN_SIZE, MAX_SIZE].
    assert_eq!(
        Shape::sphere(3.4e38),
        Err(carom::Error::OutOfRange(carom::Input::Radius))
    );
}

#[test]
fn finding_huge_coordinates_are_refused() {
    // Was: with a body and a ray 3.4e38 m from the origin, cast_ray hit beyond max_t.
    // Positions are now limited to ±MAX_COORDINATE.
    use carom::{Error, Input, MAX_COORDINATE};
    with_stack(|| {
        let mut w = OpsWorld::new();
        let ground = w.add(ground_box()).unwrap();
        let far = carom::Iso::from_position(Vec3::new(1.58, 3.4e38, -2.3));
        assert_eq!(
            w.set_pose(ground, far),
            Err(Error::OutOfRange(Input::Position))
        );
        let ray = carom::Ray::new(Vec3::new(-3.4e38, 1.44, -1.14), Vec3::X);
        assert_eq!(ray, Err(Error::OutOfRange(Input::Position)));
        let edge = carom::Iso::from_position(Vec3::new(MAX_COORDINATE, 0.0, 0.0));
        assert!(w.set_pose(ground, edge).is_ok());
    });
}

/// Was (fuzz `snapshot`, input `AQgAgBQBVlVVXWyHQgClAAE=`, CI red on main): a real
/// snapshot with −3.4e38 written over a field and the hash recomputed was accepted, and
/// the world went non-finite one step later. Mass properties are now derived on restore,
/// every other number is bounded, and the solver bounds what it warm-starts with. This
/// writes each special float over every 4-byte window of the fixture's snapshot (after
/// 20 steps, its contacts warm) with the hash resealed: restore either refuses (world unchanged) or the
/// world steps finite, the original input included.
#[test]
fn finding_any_resealed_special_float_restores_finite() {
    with_stack(|| {
        let original = SnapshotEdit::Word {
            at: 4_360_044,
            bits: (-3.4e38f32).to_bits(),
        };
        if let Err(v) = snapshot_edit_properties(20, &[original], true) {
            panic!("the original finding: {v:?}");
        }
        // NaN (refused as such), the extremes, a subnormal (it found a division by a
        // subnormal weight), a negative: one of each kind.
        let specials = [f32::NAN, -3.4e38, 1.0e30, 1.0e-40, -1.0];
        let hull = fixture_hull().unwrap();
        for steps in [20u8] {
            let mut w = snapshot_fixture(&hull).unwrap();
            for _ in 0..steps {
                w.step();
            }
            let mut buf = vec![0u8; SNAPSHOT_BUFFER];
            let n = w.snapshot(&mut buf).unwrap() as u32;
            for at in 36..n.saturating_sub(3) {
                for x in specials {
                    let edit = SnapshotEdit::Word {
                        at,
                        bits: x.to_bits(),
                    };
                    if let Err(v) = snapshot_edit_properties(steps, &[edit], true) {
                        panic!("steps {steps}, {x} at byte {at}: {v:?}");
                    }
                }
            }
        }
    });
}

/// Finding `fuzz/findings/world/impulse-on-a-body-of-1e-35-kg`: a sphere of density
/// 1e-38 kg/m³ (mass 4e-38 kg) takes an impulse of 100 N·s 10 m from its centre. The
/// angular velocity change `I⁻¹ (r × j)` (about 6e40 rad/s) overflows f32, so
/// `apply_impulse_at` refuses it with `OutOfRange(Force)` as documented, with the world
/// unchanged; the property function called that refusal a violation because it allowed
/// an overflow only for huge impulses. It now also allows it when `|j| / m` passes
/// 1e20 m/s (and still flags a refusal of an ordinary impulse).
#[test]
fn finding_an_impulse_may_overflow_a_featherweight_body() {
    with_stack(|| {
        let WorldOp::Add(mut feather) = ball(0.0) else {
            unreachable!()
        };
        feather.shape = ShapeSpec::Sphere { radius: 1.0 };
        feather.mass = carom::MassSpec::Density(1.0e-38);
        let push = WorldOp::ApplyImpulseAt(
            HandleRef::Created(0),
            Vec3::new(0.0, 0.0, 100.0),
            Vec3::new(0.0, 10.0, 0.0),
        );
        let mut w = OpsWorld::new();
        let h = w
            .add(BodyDesc::dynamic(sphere(1.0)).density(1.0e-38))
            .unwrap();
        let sum = w.checksum();
        assert_eq!(
            w.apply_impulse_at(h, Vec3::new(0.0, 0.0, 100.0), Vec3::new(0.0, 10.0, 0.0)),
            Err(Error::OutOfRange(carom::Input::Force))
        );
        assert_eq!(w.checksum(), sum, "a refused impulse changes nothing");
        assert_eq!(world_ops_properties(&[WorldOp::Add(feather), push]), Ok(()));
        // The same impulse on a 524 kg ball is applied, and a refusal would be flagged.
        assert_eq!(world_ops_properties(&[ball(0.0), push]), Ok(()));
    });
}

/// Finding `fuzz/findings/world/subnormal-density-inverse-mass-overflows` (a 25-minute
/// random run of the `world` target): a 6.4 m sphere of density 3.8e-43 kg/m³ (subnormal)
/// weighs 4.2e-40 kg, whose inverse overflows `f32` to infinity. `add` accepted it with
/// `inv_mass = inf`, and then even a zero impulse gave `0 · inf = NaN` and was refused,
/// which the property function rightly calls a violation. Root cause: `add` checked the
/// mass but not its inverse. Fix: a mass whose inverse is not finite is refused as
/// `NotPositive(Mass)`, at `add` and at snapshot restore alike. A second finding of the
/// same root cause (`subnormal-density-snapshot-refused`, a 12 m capsule of density
/// 1.3e-42 kg/m³): restore recomputed the mass, refused it, and so refused the world's
/// own snapshot.
#[test]
fn finding_a_subnormal_density_is_refused_not_inverted_to_infinity() {
    with_stack(|| {
        let mut w = OpsWorld::new();
        let sum = w.checksum();
        let feather = BodyDesc::dynamic(sphere(6.406372)).density(3.8e-43);
        assert_eq!(w.add(feather), Err(Error::NotPositive(carom::Input::Mass)));
        let by_mass = BodyDesc::dynamic(sphere(1.0)).mass(1.0e-40);
        assert_eq!(w.add(by_mass), Err(Error::NotPositive(carom::Input::Mass)));
        assert_eq!(w.checksum(), sum, "a refused add changes nothing");
        // The lightest mass whose inverse is finite is still accepted.
        let light = BodyDesc::dynamic(sphere(1.0)).mass(1.0e-38);
        assert!(w.add(light).is_ok());
        // The finding's call sequence now holds its properties.
        let WorldOp::Add(mut spec) = ball(0.0) else {
            unreachable!()
        };
        spec.shape = ShapeSpec::Sphere { radius: 6.406372 };
        spec.mass = carom::MassSpec::Density(3.8e-43);
        let push = WorldOp::ApplyImpulseAt(HandleRef::Created(0), Vec3::ZERO, Vec3::ZERO);
        assert_eq!(world_ops_properties(&[WorldOp::Add(spec), push]), Ok(()));
    });
}

/// Finding `fuzz/findings/mesh/speed-limit-after-the-solve-aa285ab2` (the `mesh` target,
/// a restore refusing the world's own snapshot): two compounds with 51 km-long sliver
/// hull parts, dropped inside each other, left their first step at 1e21 m/s with a NaN
/// spin and 1e25 m away, past the 1e10 m a snapshot may hold. Root cause: the speed
/// limits were applied when gravity and forces were integrated, not after the contact
/// solve, so one ill-conditioned solve moved the bodies by whatever speed it produced.
/// Fix: the limits also hold where positions integrate and where velocities are written
/// back (a non-finite velocity becomes zero there, as everywhere). Here a clean case of
/// the same gap: a heavy ball at the 10 m/s limit hits a light one elastically; the light
/// one would leave at about 20 m/s.
#[test]
fn finding_the_contact_solve_cannot_fling_a_body_past_the_speed_limits() {
    with_stack(|| {
        let config = WorldConfig {
            gravity: Vec3::ZERO,
            max_linear_speed: 10.0,
            ..WorldConfig::default()
        };
        let mut w = OpsWorld::with_config(config).unwrap();
        let bouncy = Material {
            restitution: 1.0,
            ..Material::default()
        };
        let heavy = w
            .add(
                BodyDesc::dynamic(sphere(1.0))
                    .position(Vec3::new(-2.0, 0.0, 0.0))
                    .velocity(Vec3::new(10.0, 0.0, 0.0))
                    .density(1000.0)
                    .material(bouncy),
            )
            .unwrap();
        let light = w
            .add(
                BodyDesc::dynamic(sphere(0.1))
                    .position(Vec3::new(-0.5, 0.0, 0.0))
                    .density(1.0)
                    .material(bouncy),
            )
            .unwrap();
        let mut fastest = 0.0f32;
        for _ in 0..30 {
            w.step();
            fastest = fastest.max(w.body(light).unwrap().linear_velocity().x);
        }
        // The heavy ball kept going; the light one was hit and runs at the limit.
        assert!(w.body(heavy).unwrap().linear_velocity().x > 9.0);
        assert!(
            fastest > 9.9 && fastest <= 10.0 * (1.0 + 1.0e-6),
            "light ball at {fastest} m/s"
        );
    });
}
