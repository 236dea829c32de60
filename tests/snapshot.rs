//! Snapshots and checksums: a restored world continues bit-identically; every bad buffer
//! is refused with its own error and leaves the world unchanged.

use carom::scenes::{self, Scene};
use carom::{BodyDesc, ConvexHull, Error, Shape, SnapshotError, Vec3, World};

type W<'a> = World<'a, 160, 512>;

fn hulls() -> &'static [ConvexHull] {
    use std::sync::OnceLock;
    static H: OnceLock<Vec<ConvexHull>> = OnceLock::new();
    H.get_or_init(|| {
        let mut v = vec![ConvexHull::UNIT_TETRAHEDRON; 8];
        scenes::make_hulls(&mut v, 7).unwrap();
        v
    })
}

fn mixed() -> Box<W<'static>> {
    let mut w = Box::new(W::new());
    Scene::Mixed.build(&mut *w, hulls()).unwrap();
    w
}

#[test]
fn rollback_replays_bit_identically() {
    // First run: record the checksum of every step.
    let mut w = mixed();
    let mut sums = Vec::new();
    let mut buf = vec![0u8; W::max_snapshot_len()];
    let mut saved = 0;
    for step in 0..300 {
        if step == 100 {
            saved = w.snapshot(&mut buf).unwrap();
        }
        w.step();
        sums.push(w.checksum());
    }
    // Roll back to step 100 and replay.
    w.restore(&buf[..saved]).unwrap();
    assert_eq!(w.step_count(), 100);
    for (step, sum) in sums.iter().enumerate().skip(100) {
        w.step();
        assert_eq!(w.checksum(), *sum, "diverged at step {}", step + 1);
    }
    // Restore into a freshly built world with the same static setup.
    let mut fresh = mixed();
    fresh.restore(&buf[..saved]).unwrap();
    for sum in sums.iter().skip(100) {
        fresh.step();
        assert_eq!(fresh.checksum(), *sum);
    }
}

#[test]
fn clone_continues_identically() {
    let mut a = mixed();
    for _ in 0..50 {
        a.step();
    }
    let mut b = a.clone();
    for _ in 0..50 {
        a.step();
        b.step();
        assert_eq!(a.checksum(), b.checksum());
    }
}

#[test]
fn bad_buffers_are_refused_with_their_error_and_change_nothing() {
    let mut w = mixed();
    for _ in 0..20 {
        w.step();
    }
    let n = w.snapshot_len();
    let mut buf = vec![0u8; n];
    assert_eq!(
        w.snapshot(&mut buf[..n - 1]),
        Err(Error::BufferTooSmall(n as u32))
    );
    assert_eq!(w.snapshot(&mut buf), Ok(n));
    for _ in 0..5 {
        w.step();
    }
    let before = w.checksum();
    let check = |w: &mut W<'static>, bytes: &[u8], e: SnapshotError| {
        assert_eq!(w.restore(bytes), Err(Error::Snapshot(e)));
        assert_eq!(w.checksum(), before);
    };
    check(&mut w, &buf[..10], SnapshotError::Truncated);
    check(&mut w, &buf[..n - 1], SnapshotError::Truncated);
    let mut bad = buf.clone();
    bad[0] ^= 1;
    check(&mut w, &bad, SnapshotError::BadMagic);
    let mut bad = buf.clone();
    bad[8] = 99;
    check(&mut w, &bad, SnapshotError::Version);
    let mut bad = buf.clone();
    bad[10] ^= 1;
    check(&mut w, &bad, SnapshotError::MathBackend);
    let mut bad = buf.clone();
    bad[n - 3] ^= 0x40;
    check(&mut w, &bad, SnapshotError::Checksum);
    // Another capacity.
    let mut other: Box<World<'static, 161, 512>> = Box::new(World::new());
    assert_eq!(
        other.restore(&buf),
        Err(Error::Snapshot(SnapshotError::Capacity))
    );
    // A hull the target world does not know.
    let mut plain: Box<W<'static>> = Box::new(W::new());
    assert_eq!(
        plain.restore(&buf),
        Err(Error::Snapshot(SnapshotError::MissingHull))
    );
    assert_eq!(plain.body_count(), 0);
    // ... unless the hulls are handed over.
    plain.restore_with_hulls(&buf, hulls()).unwrap();
    assert_eq!(plain.body_count(), w.body_count());
}

#[test]
fn every_truncation_is_refused_without_panic() {
    let mut w: World<'static, 8, 16> = World::new();
    w.add(BodyDesc::fixed(
        Shape::cuboid(Vec3::new(5.0, 0.5, 5.0)).unwrap(),
    ))
    .unwrap();
    w.add(BodyDesc::dynamic(Shape::sphere(0.5).unwrap()).position(Vec3::new(0.0, 1.0, 0.0)))
        .unwrap();
    for _ in 0..30 {
        w.step();
    }
    let mut buf = vec![0u8; w.snapshot_len()];
    let n = w.snapshot(&mut buf).unwrap();
    let sum = w.checksum();
    for cut in 0..n {
        assert!(w.restore(&buf[..cut]).is_err());
        assert_eq!(w.checksum(), sum);
    }
    // Flip every byte of the payload in turn: refused (the integrity check catches it).
    for i in 36..n {
        let mut bad = buf.clone();
        bad[i] ^= 0x10;
        assert!(w.restore(&bad).is_err(), "byte {i}");
    }
}

#[test]
fn same_calls_in_the_same_order_give_the_same_world() {
    // The promise: worlds built and driven by the same calls in the same order are
    // identical, removals and re-additions included.
    let build = || {
        let mut w: Box<W<'static>> = Box::new(W::new());
        scenes::pyramid(&mut *w, 6).unwrap();
        let extra = w
            .add(BodyDesc::dynamic(Shape::sphere(0.3).unwrap()).position(Vec3::new(0.0, 9.0, 0.0)))
            .unwrap();
        for _ in 0..30 {
            w.step();
        }
        w.remove(extra).unwrap();
        w.add(
            BodyDesc::dynamic(Shape::capsule(0.3, 0.2).unwrap()).position(Vec3::new(0.5, 8.0, 0.0)),
        )
        .unwrap();
        for _ in 0..60 {
            w.step();
        }
        w
    };
    let (a, b) = (build(), build());
    assert_eq!(a.checksum(), b.checksum());
    // The checksum sees every body: a different order of additions changes it.
    let mut c: Box<W<'static>> = Box::new(W::new());
    c.add(BodyDesc::dynamic(Shape::sphere(0.3).unwrap()).position(Vec3::new(0.0, 9.0, 0.0)))
        .unwrap();
    let mut d: Box<W<'static>> = Box::new(W::new());
    d.add(BodyDesc::dynamic(Shape::sphere(0.3).unwrap()).position(Vec3::new(0.0, 9.5, 0.0)))
        .unwrap();
    assert_ne!(c.checksum(), d.checksum());
}

#[test]
fn a_trace_names_the_first_stage_and_body_that_differ() {
    use carom::{Material, Stage, StepTrace};
    let mut a = mixed();
    for _ in 0..90 {
        a.step();
    }
    // Same state, but one body's friction differs on peer b: the peers agree until the
    // velocity solve. The body is the first after the walls whose friction is at work at
    // this step (one sliding or held by friction), so the scene's details may change.
    let frictionless = Material {
        restitution: 0.0,
        static_friction: 0.0,
        kinetic_friction: 0.0,
        ..Material::DEFAULT
    };
    let mut found = None;
    for h in a.handles().skip(scenes::MIXED_WALLS).take(40) {
        let mut b = a.clone();
        b.set_material(h, frictionless).unwrap();
        let mut c = a.clone();
        let (mut tc, mut tb) = (StepTrace::default(), StepTrace::default());
        c.step_traced(Some(&mut tc));
        b.step_traced(Some(&mut tb));
        if tc.first_difference(&tb).is_some() {
            found = Some((h, b, c, tb, tc));
            break;
        }
    }
    let (h, b, a, tb, ta) = found.expect("some body's friction is at work at step 90");
    assert_eq!(ta.first_difference(&tb), Some(Stage::Solve));
    // Per-body checksums then name the body (or its neighbours) that moved differently.
    let differing: Vec<_> = a
        .handles()
        .filter(|h| a.body_checksum(*h) != b.body_checksum(*h))
        .collect();
    assert!(differing.contains(&h), "{differing:?}");
}

/// `step_observed` calls back once per stage, in pipeline order, and steps exactly as
/// `step` does: same report, same state, to the bit, over a chaotic pile.
#[test]
fn an_observed_step_names_every_stage_in_order_and_changes_nothing() {
    use carom::Stage;
    let mut plain = mixed();
    let mut observed = plain.clone();
    for step in 0..200 {
        let mut heard = Vec::new();
        let r_observed = observed.step_observed(&mut |stage| heard.push(stage));
        let r_plain = plain.step();
        assert_eq!(heard, Stage::ALL, "step {step}");
        assert_eq!(r_observed, r_plain, "step {step}");
        assert_eq!(observed.checksum(), plain.checksum(), "step {step}");
    }
}

/// With `serde`, a world serialises as its snapshot bytes and `RestoreSeed` brings them
/// back: the round trip through JSON continues bit-identically.
#[cfg(feature = "serde")]
#[test]
fn serde_round_trip_continues_identically() {
    use serde::de::DeserializeSeed;
    let mut w = mixed();
    for _ in 0..40 {
        w.step();
    }
    let json = serde_json::to_vec(&*w).unwrap();
    let mut buf = vec![0u8; w.snapshot_len()];
    let n = w.snapshot(&mut buf).unwrap();
    let sum = w.checksum();
    for _ in 0..10 {
        w.step();
    }
    let mut scratch = vec![0u8; W::max_snapshot_len()];
    let seed = carom::RestoreSeed {
        world: &mut *w,
        hulls: &[],
        scratch: &mut scratch,
    };
    seed.deserialize(&mut serde_json::Deserializer::from_slice(&json))
        .unwrap();
    assert_eq!(w.checksum(), sum);
    // The serialised bytes are the snapshot's bytes.
    let bytes: Vec<u8> = serde_json::from_slice(&json).unwrap();
    assert_eq!(bytes, buf[..n]);
    // Corrupt JSON bytes are refused through serde's error, world unchanged.
    let mut bad: Vec<u8> = bytes.clone();
    bad[40] ^= 1;
    let bad_json = serde_json::to_vec(&bad).unwrap();
    let seed = carom::RestoreSeed {
        world: &mut *w,
        hulls: &[],
        scratch: &mut scratch,
    };
    assert!(seed
        .deserialize(&mut serde_json::Deserializer::from_slice(&bad_json))
        .is_err());
    assert_eq!(w.checksum(), sum);
}
