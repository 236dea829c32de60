//! Fuzz findings of the `narrow_phase` and `toi` targets as named regressions.
//!
//! Each case is the exact input of a crash, decoded once by hand and written out here as
//! the f32 bit patterns the fuzz decoder produced (`f(0x…)`), so nothing depends on the
//! decoder or on `arbitrary`. The comment above each case names the artifact it came from
//! (`fuzz/artifacts/<target>/crash-<hash>`, kept out of git). Every test calls the same
//! property functions as the fuzz target and asserts `Ok`; a few also check the fixed
//! root cause directly. Tests are grouped by root cause, one case per finding.

use carom::collide::{distance, penetration, time_of_impact, GjkStatus, Motion, SimplexCache};
use carom::error::MAX_COORDINATE;
use carom::math::{Iso, Quat, Vec3};
use carom::props::{
    brute_force_distance, core_vertices, distance_properties, manifold_properties,
    penetration_properties, separation_properties, shape_size_in_range, toi_properties, Violation,
};
use carom::shape::{Capsule, ConvexHull, Cuboid, Shape};
use carom::{Error, Input};

fn f(bits: u32) -> f32 {
    f32::from_bits(bits)
}

fn v(x: u32, y: u32, z: u32) -> Vec3 {
    Vec3::new(f(x), f(y), f(z))
}

fn pose(position: Vec3, [x, y, z, w]: [u32; 4]) -> Iso {
    Iso::new(position, Quat::from_xyzw(f(x), f(y), f(z), f(w)))
}

fn hull(points: &[Vec3]) -> ConvexHull {
    ConvexHull::new(points).expect("the finding's point cloud builds a hull")
}

/// The four properties in the order the `narrow_phase` target checks them.
fn narrow_phase(a: &Shape, pa: &Iso, b: &Shape, pb: &Iso, margin: f32) -> Result<(), Violation> {
    distance_properties(a, pa, b, pb)?;
    penetration_properties(a, pa, b, pb)?;
    separation_properties(a, pa, b, pb)?;
    manifold_properties(a, pa, b, pb, margin)
}

/// Assert the narrow-phase properties for every `(name, a, pose_a, b, pose_b, margin)`.
fn assert_cases(cases: &[(&str, Shape, Iso, Shape, Iso, f32)]) {
    for (name, a, pa, b, pb, margin) in cases {
        assert_eq!(narrow_phase(a, pa, b, pb, *margin), Ok(()), "{name}");
    }
}

/// Root cause: GJK called cores apart when their distance was rounding noise. The overlap
/// test was relative to the current simplex only, which shrinks to the one vertex of `D`
/// at the origin when a sphere's centre sits (within 1e-21 m) on a triangle's or hull's
/// corner; and a `|v|` below the normalisation floor had no direction, so the normal was
/// the +Y fallback (in the triangle's plane: moving the sphere along it by the depth did
/// not separate anything). Fix: the overlap scale is the largest `|w|` GJK has seen, and
/// a `v` too short to normalise counts as touching (`collide::gjk`).
#[test]
fn sphere_centred_on_a_corner_is_touching() {
    let corner_on_origin = Shape::triangle(
        v(0x0029e717, 0x00000000, 0x1e1e2a58),
        v(0x3ff0f000, 0x408afc00, 0x00000000),
        v(0x40f8f800, 0x00000000, 0x00000000),
    )
    .unwrap();
    let hull_0db0d = hull(&[
        v(0xa7a7a7a7, 0xa7a7000f, 0xa7a7a7a7),
        v(0xa7a7a7a7, 0xa7a7a7a7, 0xa7a7a7a7),
        v(0xa7a7a7a7, 0x40dede00, 0xc0b0b200),
        v(0xa7a709a7, 0x40dede00, 0x40dede00),
        v(0x40dede00, 0x40dede00, 0x40dede00),
        v(0x40dede00, 0x00000000, 0x40dede00),
        v(0x00000000, 0x00000000, 0x00000000),
    ]);
    let hull_9fa75 = hull(&[
        v(0x408a8a00, 0x0f0f0f0f, 0x401c9c00),
        v(0x401c9c00, 0x3f70f000, 0x00000000),
        v(0x00000000, 0x3f70f000, 0x87878787),
        v(0x87878787, 0x87878787, 0x87878787),
        v(0x87878787, 0x87878787, 0x87878787),
        v(0x87878787, 0x87878787, 0x87878787),
        v(0x0f0f0f0f, 0x00000000, 0x00000000),
    ]);
    let hull_b0d17 = hull(&[
        v(0x9b9b9b9b, 0x9b9b9bf3, 0x9b3d9b9b),
        v(0x408a8a00, 0x40fafa00, 0xbd710000),
        v(0x007dffff, 0x39800000, 0x3f000000),
        v(0x408a8a00, 0x408a8a00, 0x40f88a00),
        v(0x007c049b, 0x00000000, 0x00000000),
    ]);
    let identity = pose(v(0, 0, 0), [0, 0, 0, 0x3f800000]);
    let cases = [
        // crash-51cf70bd: a triangle corner 8.4e-21 m from the sphere's centre.
        (
            "51cf70bd",
            corner_on_origin,
            identity,
            Shape::sphere(f(0x3c0e0000)).unwrap(),
            identity,
            f(0x3c400000),
        ),
        // crash-6b0cf3cb: the same, turned and 4e-21 m off.
        (
            "6b0cf3cb",
            Shape::triangle(
                v(0x40fafa00, 0x40fafa00, 0x40fafa00),
                v(0x40fafa00, 0x40fafa00, 0x05050505),
                v(0x9b9b9b9b, 0x9b9b9b9b, 0x9b9b9b9b),
            )
            .unwrap(),
            pose(
                v(0x9b9b9b9b, 0x9b9b9b9b, 0x9d9b9b9b),
                [0xbf209d09, 0x37ccc6fb, 0x3f4758bc, 0x3afff8ba],
            ),
            Shape::sphere(f(0x4078fa00)).unwrap(),
            identity,
            f(0x37800000),
        ),
        // crash-fb271112: a corner at the origin, the sphere 2.9e-16 m off it.
        (
            "fb271112",
            Shape::triangle(
                v(0x4040c000, 0x4040c000, 0x4040c000),
                v(0x4040c000, 0x4040c000, 0xbd800000),
                v(0x00000000, 0x00000000, 0x00000000),
            )
            .unwrap(),
            identity,
            Shape::sphere(f(0x4079ec00)).unwrap(),
            pose(
                v(0x00000000, 0xa5a5a5a5, 0xa5a5a5a5),
                [0xbf000000, 0xbf000000, 0xbf000000, 0xbf000000],
            ),
            f(0xa5a5a5a5),
        ),
        // crash-868fa4c3: a corner at the origin, the sphere 2.6e-22 m off it.
        (
            "868fa4c3",
            Shape::triangle(
                v(0x3e000000, 0xbd800000, 0x00000000),
                v(0x00000000, 0x40f8f800, 0x40f8f800),
                v(0x00000000, 0x00000000, 0x00000000),
            )
            .unwrap(),
            identity,
            Shape::sphere(f(0x40791c00)).unwrap(),
            pose(
                v(0x00000000, 0x00000000, 0x9b9b9b9b),
                [0x3b7fff80, 0x3f7fff80, 0x00000000, 0x00000000],
            ),
            f(0x37800000),
        ),
        // crash-bf0793c6: a sphere on a corner 1e-44 m off the origin.
        (
            "bf0793c6",
            Shape::sphere(f(0x40f90100)).unwrap(),
            identity,
            Shape::triangle(
                v(0x00000000, 0xc0c8ca00, 0x40f8f800),
                v(0x00000007, 0x00000000, 0x00000000),
                v(0x00000000, 0x3ef82000, 0x00000000),
            )
            .unwrap(),
            pose(v(0xaaaaaaaa, 0x00000000, 0x00000000), [0, 0, 0, 0x3f800000]),
            f(0x17290aff),
        ),
        // crash-e0a8078a: a corner at 4e-21 m, with subnormal coordinates.
        (
            "e0a8078a",
            Shape::triangle(
                v(0x3cf80000, 0x40f8f800, 0xbd828000),
                v(0x043fffff, 0x00000000, 0x9d9d9d9d),
                v(0x01009d9d, 0x40f8f000, 0x00000000),
            )
            .unwrap(),
            identity,
            Shape::sphere(f(0x3ea7d000)).unwrap(),
            identity,
            f(0x37800000),
        ),
        // crash-030e6c69: a corner 3e-23 m off the sphere's centre, both at 1.6 m.
        (
            "030e6c69",
            Shape::triangle(
                v(0x00000000, 0x1a1a1100, 0x00000000),
                v(0x1a1a1100, 0x3fd0d000, 0x3fd0d000),
                v(0x3fd0d000, 0x3fd0d000, 0x3fd0d000),
            )
            .unwrap(),
            pose(v(0x3fd0d000, 0x3fd0d000, 0x3fd0d000), [0, 0, 0, 0x3f800000]),
            Shape::sphere(f(0x3f50d800)).unwrap(),
            pose(v(0x3fd0d000, 0x3fd0d000, 0x3fd0d000), [0, 0, 0, 0x3f800000]),
            f(0x3e8cf800),
        ),
        // crash-0d5d1180: a corner 2e-11 m off the sphere's centre.
        (
            "0d5d1180",
            Shape::triangle(
                v(0xbd800000, 0xb9800000, 0xadadad00),
                v(0xadadadad, 0x002dadcf, 0x0004adad),
                v(0x00000000, 0x40109000, 0x40109000),
            )
            .unwrap(),
            pose(v(0x40109000, 0x40109000, 0x40109000), [0, 0, 0, 0x3f800000]),
            Shape::sphere(f(0x3f909400)).unwrap(),
            pose(v(0x40109000, 0x40109000, 0x40109000), [0, 0, 0, 0x3f800000]),
            f(0x3e109400),
        ),
        // crash-04cacf98: a corner 8.6e-14 m off the sphere's centre.
        (
            "04cacf98",
            Shape::triangle(
                v(0x01d58bff, 0x00000000, 0xbf800800),
                v(0x0000002e, 0x29c117e0, 0x00000000),
                v(0x3fc0c000, 0x3fc0c000, 0x3fc0c000),
            )
            .unwrap(),
            pose(v(0x3fc0c000, 0x3fc0c000, 0x3fc0c000), [0, 0, 0, 0x3f800000]),
            Shape::sphere(f(0x3f40c800)).unwrap(),
            pose(v(0x3fc0c000, 0x3fc0c000, 0x3fc0c000), [0, 0, 0, 0x3f800000]),
            f(0x3dc0c800),
        ),
        // crash-0db0dc76: a hull corner 4.7e-15 m from the sphere's centre.
        (
            "0db0dc76",
            Shape::sphere(f(0x40a70100)).unwrap(),
            pose(
                v(0xa7a7a7a7, 0xa7a7a7a7, 0xa7a7a7a7),
                [0xbf000000, 0xbf000000, 0xbf000000, 0xbf000000],
            ),
            Shape::hull(&hull_0db0d),
            identity,
            f(0x37800000),
        ),
        // crash-9fa7507e: a hull corner 9e-22 m from the sphere's centre.
        (
            "9fa7507e",
            Shape::hull(&hull_9fa75),
            identity,
            Shape::sphere(f(0x3d008000)).unwrap(),
            pose(
                v(0x00000000, 0x87878787, 0x9c878787),
                [0xbf000000, 0xbf000000, 0xbf000000, 0xbf000000],
            ),
            f(0x9c9c9c9c),
        ),
        // crash-b0d17bd6: a hull corner 3e-22 m from the sphere's centre.
        (
            "b0d17bd6",
            Shape::sphere(f(0x3f38c000)).unwrap(),
            pose(
                v(0x9bbf9b9b, 0x9b9b9b9b, 0x9b9b9b9b),
                [0x3f800000, 0x00000000, 0x00000000, 0x00000000],
            ),
            Shape::hull(&hull_b0d17),
            identity,
            f(0x37800000),
        ),
    ];
    assert_cases(&cases);
    // The root cause itself: GJK reports contact, and the depth is the radius along the
    // triangle's normal (z), not along the +Y fallback that lies in its plane.
    let sphere = Shape::sphere(f(0x3c0e0000)).unwrap();
    let d = distance(
        &corner_on_origin,
        &identity,
        &sphere,
        &identity,
        &mut SimplexCache::default(),
    )
    .unwrap();
    assert_eq!(d.status, GjkStatus::Overlapping);
    let p = penetration(&corner_on_origin, &identity, &sphere, &identity)
        .unwrap()
        .expect("touching");
    // The triangle's normal is z to 1e-20 rad; 1e-6 allows rounding of one normalisation.
    assert!(p.normal.z.abs() > 1.0 - 1.0e-6, "{p:?}");
}

/// Root cause: GJK's closest point on a segment (and a triangle's plane offset) was
/// computed from the first vertex; when that is the far end of a long edge of `D` (12 m)
/// with the origin 0.2 mm from the edge, the point is off by an ulp of 12 m, its direction
/// by 3e-3 rad, and the support point along it is the far end again: GJK stopped on the
/// wrong feature, 6e-5 m too far and with its normal 30° off. Fix: project from the
/// vertex nearest the origin (`s1d`, `s2d`), and compute triangle normals at the corner
/// opposite the longest edge (`triangle_normal`).
#[test]
fn projections_start_from_the_nearer_end() {
    let sliver_95514 = hull(&[
        v(0x40fafa00, 0x9b9b0000, 0x40fafa00),
        v(0x40fa8a00, 0x40fa8a00, 0x40fafa00),
        v(0x3f1c4000, 0x3f109000, 0x3f109000),
        v(0x3f109000, 0x3f109000, 0x3f109000),
        v(0x3f109000, 0x3f109000, 0x3f109000),
        v(0x3f109000, 0x3f109000, 0x3f109000),
    ]);
    let sliver_9fc25 = hull(&[
        v(0x40fafa00, 0x9b9b0000, 0x40fafa00),
        v(0x40fa8a00, 0x40fa8a00, 0x40fafa00),
        v(0x3f109000, 0x3f109000, 0x3f109000),
        v(0x3f109000, 0x3f109000, 0x3f109000),
        v(0x3f109000, 0x3f109000, 0x3f109000),
        v(0x3f109000, 0x3f109000, 0x3f130000),
        v(0x3f109000, 0x3f109000, 0x3f109000),
        v(0x3f109000, 0x3f12f000, 0x3f109000),
        v(0x3f109000, 0x3f109000, 0x3f109000),
        v(0x3f109000, 0x3f109000, 0x3aa00000),
    ]);
    let wedge_8507e = hull(&[
        v(0x40fafa00, 0x40fafa00, 0x3f70f000),
        v(0x3f71f000, 0x3f70f000, 0x3f70f000),
        v(0x3f70f000, 0x00000000, 0x3f700000),
        v(0x3f70f000, 0x3f70f000, 0x3f70f000),
        v(0x00000000, 0x00000000, 0x3f700000),
        v(0x40fafa00, 0x40fafa00, 0x00000000),
    ]);
    let identity = pose(v(0, 0, 0), [0, 0, 0, 0x3f800000]);
    let sphere_at = pose(v(0x3f40c000, 0x3f40c000, 0x3f40c000), [0, 0, 0, 0x3f800000]);
    let tri_b_808991 = Shape::triangle(
        v(0x3ee00000, 0x3b100000, 0x4081fe00),
        v(0xc0f8f800, 0x3f200000, 0x00000000),
        v(0x00000000, 0x00000000, 0x00000000),
    )
    .unwrap();
    let shifted = pose(v(0xbd800000, 0, 0), [0, 0, 0, 0x3f800000]);
    let cases = [
        // crash-95514eb8: a sphere 0.23 mm from a 12 m sliver of a hull.
        (
            "95514eb8",
            Shape::sphere(f(0x3ec0d000)).unwrap(),
            sphere_at,
            Shape::hull(&sliver_95514),
            identity,
            f(0x3d101000),
        ),
        // crash-9fc255b1: the same sliver with more points.
        (
            "9fc255b1",
            Shape::sphere(f(0x3ec0d000)).unwrap(),
            sphere_at,
            Shape::hull(&sliver_9fc25),
            identity,
            f(0x37800000),
        ),
        // crash-8507e450: a sphere on a thin 11 m wedge of a hull.
        (
            "8507e450",
            Shape::hull(&wedge_8507e),
            pose(v(0, 0, 0x39800000), [0, 0, 0, 0x3f800000]),
            Shape::sphere(f(0x3f000800)).unwrap(),
            pose(
                v(0x3f70f000, 0x3f70f000, 0x3f70f000),
                [0x3ea44a28, 0x3ea44a28, 0x3ea3e7f7, 0x3f54e50b],
            ),
            f(0x7d7d7ddc),
        ),
        // crash-808991b0: a 0.5 m triangle against an 8 m one (sliver faces of D).
        (
            "808991b0",
            Shape::triangle(
                v(0x00000000, 0x00000000, 0x3d7f0000),
                v(0x3cea0000, 0x00000000, 0x00000000),
                v(0x00000000, 0x00000000, 0x3f000000),
            )
            .unwrap(),
            shifted,
            tri_b_808991,
            identity,
            f(0x37800000),
        ),
        // crash-e89e39a1: a needle triangle against the same 8 m one.
        (
            "e89e39a1",
            Shape::triangle(
                v(0x3e000000, 0x00000000, 0x40ebfe00),
                v(0x00000000, 0x3a400000, 0x00000000),
                v(0x00000000, 0x00000000, 0x3f000000),
            )
            .unwrap(),
            shifted,
            Shape::triangle(
                v(0x403c0000, 0x3b100000, 0x4081fe00),
                v(0xc0f8f800, 0x3f200000, 0x00000000),
                v(0x00000000, 0x00000000, 0x00000000),
            )
            .unwrap(),
            identity,
            f(0x37800000),
        ),
        // crash-da38d43e: two nearly coplanar 8 m triangles.
        (
            "da38d43e",
            Shape::triangle(
                v(0x3e000000, 0xbd800000, 0x00000000),
                v(0xc1000000, 0x00000000, 0x00000000),
                v(0x3f000000, 0xbd580000, 0x00000000),
            )
            .unwrap(),
            pose(v(0xbd580000, 0, 0), [0, 0, 0, 0x3f800000]),
            Shape::triangle(
                v(0xc1000000, 0x3b100000, 0x00000000),
                v(0x00000000, 0x3f200000, 0x00000000),
                v(0x00000000, 0x00000000, 0x00000000),
            )
            .unwrap(),
            identity,
            f(0x37800000),
        ),
    ];
    assert_cases(&cases);
}

/// Root cause: even from the nearer end, a segment of `D` with both ends 8 m away and the
/// origin on its line left the closest point off by an ulp of 8 m, which zeroed the one
/// component that decides between two support vertices 15 m apart: GJK repeated a vertex
/// and stopped 1 mm short of contact (a triangle's edge passing exactly through another
/// triangle's corner; two 7.8 m boxes). Fix: one step of iterative refinement of the
/// projection in `s1d`.
#[test]
fn segment_projection_is_refined() {
    let cases = [
        // crash-48cd66de (second run): an 8 m triangle edge through a small one's corner.
        (
            "48cd66de",
            Shape::triangle(
                v(0xc0f80000, 0x00000000, 0x00000000),
                v(0x40f80000, 0x00000000, 0x00000000),
                v(0xc1000000, 0x3ff00000, 0x00000000),
            )
            .unwrap(),
            pose(v(0, 0, 0), [0x3c04ada1, 0x00000000, 0x3f7ffdaf, 0x3b11af98]),
            Shape::triangle(
                v(0x3e004000, 0x00000000, 0x00000000),
                v(0x00000000, 0x3cf80000, 0x00000000),
                v(0x00000000, 0x00000000, 0x00000000),
            )
            .unwrap(),
            pose(v(0, 0, 0), [0, 0, 0, 0x3f800000]),
            f(0x37800000),
        ),
        // crash-828d6583 (second run): two 7.8 m boxes 8 mm deep, one turned by 1e-3.
        (
            "828d6583",
            Shape::cuboid(v(0x4078fa00, 0x4078fa00, 0x4078fa00)).unwrap(),
            pose(
                v(0xaaaaaaaa, 0x40f8f800, 0x40f8f800),
                [0x3eff889b, 0x3f00169f, 0x3f000e63, 0x3f00169f],
            ),
            Shape::cuboid(v(0x4078ea00, 0x4078fa00, 0x4078fa00)).unwrap(),
            pose(v(0x40f8f800, 0x40f8f800, 0x40f8f800), [0, 0, 0, 0x3f800000]),
            f(0x37800000),
        ),
    ];
    assert_cases(&cases);
    // The triangles touch exactly (an edge of A passes through B's corner at the origin).
    let (_, a, pa, b, pb, _) = &cases[0];
    let d = distance(a, pa, b, pb, &mut SimplexCache::default()).unwrap();
    assert_eq!(d.distance, 0.0, "{d:?}");
}

/// Root cause: on a sliver triangle of `D` (15 m long, 0.5 mm wide: two 7.8 m boxes
/// touching along an edge) the barycentric coordinates, ratios of tiny areas, summed to
/// 0.998 instead of 1, so the witness points `Σ λ a`, `Σ λ b` were not convex
/// combinations and fell 8 mm outside B. (Found in the third run, after the larger overlap
/// scale above made GJK stop on that sliver; the original GJK took another path.) Fix:
/// `s1d` and `s2d` divide the coordinates by their own sum.
#[test]
fn witnesses_are_convex_combinations() {
    // crash-778cb39a (third run): two 7.8 m boxes touching, one turned by 5e-5 rad.
    let a = Shape::cuboid(v(0x4078fa00, 0x4078fa00, 0x4078fa00)).unwrap();
    let b = Shape::cuboid(v(0x4078fa00, 0x4078fa00, 0x4078f200)).unwrap();
    let pa = pose(
        v(0x00000000, 0xb9800000, 0x40f80000),
        [0x3f000083, 0x3f000083, 0x3efffcea, 0x3f000083],
    );
    let pb = pose(
        v(0x40f8f800, 0x3cf80000, 0x40f8f800),
        [0x3f000000, 0x3f000000, 0x3f000000, 0x3f000000],
    );
    assert_cases(&[("778cb39a", a, pa, b, pb, f(0x3ef80a00))]);
}

/// Root cause: GJK's "no progress" test held the grown simplex's `|v|²` to `1e-6 |v|²`,
/// but its closest point is off by ulps of the simplex's size, not of `|v|`: with the
/// origin 0.6 mm from an 11 m diagonal of `D` (a sphere centred inside a 3 cm thin box),
/// the triangle's exact gain was below that rounding and GJK stopped, calling the cores
/// 0.6 mm apart. Fix: the test allows `1e-6 |v| max |w|`.
#[test]
fn progress_test_allows_rounding_of_a_large_simplex() {
    // crash-a30332e7: a sphere centred 1.7 mm inside a 3 cm thin box of 7.8 m.
    let plate = Shape::cuboid(v(0x3c7a0000, 0x4078fc00, 0x4078fa00)).unwrap();
    let plate_at = pose(
        v(0x40f90600, 0x40f8f800, 0x40f8f800),
        [0x3f13cd22, 0x3f13cd22, 0x3f13cd22, 0x3b1339e8],
    );
    let ball = Shape::sphere(f(0x4078fa00)).unwrap();
    let ball_at = pose(
        v(0x40f8f800, 0x40f8f800, 0x40f8f800),
        [0x3f000108, 0x3f000108, 0x3f000108, 0x3efff9d6],
    );
    assert_cases(&[("a30332e7", plate, plate_at, ball, ball_at, f(0x00017c7c))]);
    let d = distance(
        &ball,
        &ball_at,
        &plate,
        &plate_at,
        &mut SimplexCache::default(),
    )
    .unwrap();
    assert_eq!(d.status, GjkStatus::Overlapping, "{d:?}");
}

/// Root cause: EPA's seed for a flat `D` (a 2 mm capsule segment across a 6 m one) took
/// the sliver triangle's normal from its far corner, off by 2e-4 rad, so the triangle's
/// own third vertex read 1 mm off its plane; the seed kept re-adding it until its step
/// budget ran out and answered "flat along +Y", a direction in the plane. Fix: triangle
/// normals at the corner opposite the longest edge, and a support point that is already a
/// seed vertex never lifts the seed off its plane.
#[test]
fn epa_seed_of_a_sliver_difference() {
    // crash-35cc97d2: a 2.2 mm capsule segment across a 6 m one, both centred together.
    let short = Shape::capsule(f(0x3a900000), f(0x4040c200)).unwrap();
    let long = Shape::capsule(f(0x4040d600), f(0x4040c200)).unwrap();
    let centre = v(0x40c0c000, 0x40c0c000, 0x40c0c000);
    let pa = pose(centre, [0xbefa2f6a, 0x3efac360, 0xbf07cba0, 0x3efad05b]);
    let pb = pose(centre, [0xbf07c3dd, 0x3f13715c, 0x3e76612c, 0x3f12de7d]);
    assert_cases(&[("35cc97d2", short, pa, long, pb, f(0x3ef8fa00))]);
    // Crossing segments: the depth is the sum of the radii along their common normal.
    let p = penetration(&short, &pa, &long, &pb)
        .unwrap()
        .expect("overlap");
    let axis_a = pa.rotation.rotate(Vec3::Y);
    let axis_b = pb.rotation.rotate(Vec3::Y);
    let common = axis_a.cross(axis_b).normalize_or(Vec3::ZERO);
    // 1e-4: the normal is exact to rounding of the 6 m segment (1e-7) over the 2 mm one.
    assert!(p.normal.dot(common).abs() > 1.0 - 1.0e-4, "{p:?}");
}

/// Root cause: two concentric boxes, one turned by 2 mrad, put several corners of `D` on
/// one face plane. A new EPA vertex on the plane of a neighbour face kept that face on
/// the sign of rounding, and the new face on their shared edge lay in the same plane
/// turned the other way: the polytope folded inside out (a face at distance −6.3 m), and
/// EPA converged on a face whose witnesses were 2.5 cm off `−depth · normal`. Fix: such
/// a fold refuses the expansion, which is retried with the coplanar face counted as seen.
#[test]
fn epa_refuses_inside_out_folds() {
    // crash-eae1d278: concentric boxes of 3.9 m and 3.1 m, one tilted by 2e-3 rad.
    let centre = v(0x40c8c800, 0x40c8c800, 0x40c8c800);
    assert_cases(&[(
        "eae1d278",
        Shape::cuboid(v(0x407cca00, 0x4048ca00, 0x4048ca00)).unwrap(),
        pose(centre, [0x3a7ffff8, 0x00000000, 0x00000000, 0x3f7ffff8]),
        Shape::cuboid(v(0x4048ca00, 0x4048ca00, 0x4048ca00)).unwrap(),
        pose(centre, [0x3effffff, 0x3effffff, 0x3effffff, 0x3effffff]),
        f(0xffffffff),
    )]);
}

/// Root cause: for two capsules whose segments cross at a small angle, the normal was the
/// direction between the segments' closest points, whose parameters carry `ε / sin²θ` of
/// rounding: for nearly coaxial, deeply overlapping capsules it was noise of 0.01–0.02
/// rad, and `contact(b, a)` did not reverse `contact(a, b)`. Fix: when both closest
/// points are inside their segments, the normal is the lines' common perpendicular
/// `d₁ × d₂` (`analytic::line_gap`).
#[test]
fn crossing_capsules_use_the_common_perpendicular() {
    let cap = |h: u32, r: u32| Shape::capsule(f(h), f(r)).unwrap();
    let cases = [
        // crash-8dc06933
        (
            "8dc06933",
            cap(0x401c9e00, 0x401c9e00),
            pose(v(0x409c9c00, 0x409c9c00, 0x409c9c00), [0, 0, 0, 0x3f800000]),
            cap(0x401c9e00, 0x401c9e00),
            pose(
                v(0x409c9c00, 0x409c9c00, 0x409c9c00),
                [0x3b34f62d, 0x3f35135d, 0x00000000, 0x3f34f62d],
            ),
            f(0x3f167d00),
        ),
        // crash-ae8186ef
        (
            "ae8186ef",
            cap(0x405ee000, 0x4030b200),
            pose(
                v(0x40b0b000, 0x40b0b000, 0x40b0b000),
                [0x3f001f9d, 0xbefe40ba, 0xbf002110, 0x3f009dc9],
            ),
            cap(0x405ee000, 0x4030b200),
            pose(
                v(0x40b0b000, 0x40b0b000, 0x40b0b000),
                [0x3f000000, 0x3f000000, 0x3f000000, 0x3f000000],
            ),
            f(0x3eecee00),
        ),
        // crash-6cafea21
        (
            "6cafea21",
            cap(0x4040c200, 0x4040c200),
            pose(
                v(0x40c0c000, 0x40c0c000, 0x40c0e000),
                [0x3d0494c0, 0x00000000, 0xbf3c47e1, 0x3f2d4193],
            ),
            cap(0x4040d600, 0x40ff6100),
            pose(
                v(0x40c0c000, 0x40c0c000, 0x40c0c000),
                [0xbf0008f7, 0x3efffa06, 0x3efffa06, 0x3efffa06],
            ),
            f(0x3ec0c200),
        ),
        // crash-46ed5238
        (
            "46ed5238",
            cap(0x3fd0d400, 0x3fd0d400),
            pose(
                v(0x4050d000, 0x4050d000, 0x4050d000),
                [0x3f011436, 0x3f011436, 0x3f00d470, 0x3ef9edd2],
            ),
            cap(0x3fd0d400, 0x407a0200),
            pose(
                v(0x4050d000, 0x4050d000, 0x4050d000),
                [0x3f000000, 0x3f000000, 0x3f000000, 0x3f000000],
            ),
            f(0x3efb3800),
        ),
        // crash-b79de7ab
        (
            "b79de7ab",
            cap(0x4072fc00, 0x407afc00),
            pose(
                v(0x3e5f4000, 0x00000000, 0x400df400),
                [0x3f0055d3, 0x3f0055d3, 0x3f0055d3, 0x3efdfa5b],
            ),
            cap(0x4072fc00, 0x407afc00),
            pose(
                v(0x3e5f4000, 0x00000000, 0x400df400),
                [0xbf000000, 0xbf000000, 0xbf000000, 0xbf000000],
            ),
            f(0x3ed2d400),
        ),
        // crash-2a238780
        (
            "2a238780",
            cap(0x4078fa00, 0x3fd0d400),
            pose(v(0x4050d000, 0x4058d000, 0x4050d000), [0, 0, 0, 0x3f800000]),
            cap(0x3fd0d400, 0x3fd0d400),
            pose(
                v(0x4050d000, 0x4050d000, 0x4050d000),
                [0x3f7ffedd, 0x3b7effdd, 0x3b7effdd, 0x3b0bd6a2],
            ),
            f(0x37800000),
        ),
        // crash-1f6b5193
        (
            "1f6b5193",
            cap(0x400a8c00, 0x400aec00),
            pose(
                v(0x408a8a00, 0x408a8a00, 0x3c8a0000),
                [0x3efff5d7, 0xbf000d65, 0xbefff989, 0x3efff5d7],
            ),
            cap(0x400a8c00, 0x400ab800),
            pose(
                v(0x408a8a00, 0x408a8a00, 0x81818181),
                [0x3effd5d5, 0x3effd5d5, 0x3f003f2e, 0x3effd5d5],
            ),
            f(0x3b590000),
        ),
        // crash-4753e522
        (
            "4753e522",
            cap(0x40f70200, 0x4040c200),
            pose(
                v(0x40c0c000, 0x40c0c000, 0x40c0c000),
                [0xbeef79a6, 0x3f0be45c, 0xbf033980, 0x3ef013b4],
            ),
            cap(0x4040d600, 0x4040c200),
            pose(
                v(0x40c0c000, 0x40c0c000, 0x40c0f600),
                [0x3f000000, 0x3f000000, 0x3f000000, 0x3f000000],
            ),
            f(0x3e50d400),
        ),
    ];
    assert_cases(&cases);
}

/// Root cause: for two capsules 3 cm apart whose segments are parallel within 1e-4 rad,
/// Ericson's closest-point parameters (relative error `ε / sin²θ`, over 1 here) picked
/// either end of the overlap, and the two ends' normals differ by 0.008 rad: the query
/// orders disagreed. Fix: `segment_closest_points` also compares the four end-to-segment
/// pairs and keeps the closest.
#[test]
fn nearly_parallel_capsules_pick_the_closer_end() {
    // crash-2b4b2abe
    let a = Shape::capsule(f(0x3ff00800), f(0x40c17d00)).unwrap();
    let b = Shape::capsule(f(0x401c9e00), f(0x4078fa00)).unwrap();
    let pa = pose(
        v(0x00000000, 0x3d010000, 0x00000000),
        [0x3f800000, 0xb80cce1f, 0xb80cce1f, 0xb80cce1f],
    );
    let pb = pose(v(0x00007c74, 0xbe886000, 0x3cf80000), [0, 0, 0, 0x3f800000]);
    assert_cases(&[("2b4b2abe", a, pa, b, pb, f(0x37800000))]);
    // The segments' closest pair is at the end where they are nearer: A's end at
    // y = +1.9 m, 3.0148 cm from B's axis, against 3.0400 cm for its end at y = −1.8 m
    // (point-to-segment distances in f64).
    let (a0, a1) = (
        pa.transform_point(Vec3::new(0.0, -f(0x3ff00800), 0.0)),
        pa.transform_point(Vec3::new(0.0, f(0x3ff00800), 0.0)),
    );
    let (b0, b1) = (
        pb.transform_point(Vec3::new(0.0, -f(0x401c9e00), 0.0)),
        pb.transform_point(Vec3::new(0.0, f(0x401c9e00), 0.0)),
    );
    for (p1, q1, p2, q2) in [(a0, a1, b0, b1), (b0, b1, a0, a1)] {
        let (s, t) = carom::collide::segment_closest_points(p1, q1, p2, q2);
        let gap = (p2 + (q2 - p2) * t - p1 - (q1 - p1) * s).length();
        // 1e-5 m: rounding of the points at this 2 m scale, far below the 0.25 mm between
        // the two ends' gaps.
        assert!((gap - 0.030_148).abs() < 1.0e-5, "{gap}");
    }
}

/// Sizes below [`carom::shape::MIN_SIZE`] (class (a) of the issue): a 1.1e-38 m box under
/// a 3.6 m capsule (crash-22ada3bc), a 0.12 mm box against a 4.4 m capsule
/// (crash-ffbef777). Their faces are thinner than the rounding of the coordinates they sit
/// at, so clipping against their side planes is noise. The constructors now refuse them;
/// built around the constructors, the properties leave their geometry unchecked (and
/// still hold: no panic, finite output).
#[test]
fn sizes_outside_the_range_are_refused_and_not_judged() {
    assert_eq!(
        Shape::cuboid(v(0x007c8c84, 0x39000000, 0x39000000)),
        Err(Error::OutOfRange(Input::HalfExtents))
    );
    assert_eq!(
        Shape::capsule(f(0x408b7d00), f(0x39000000)),
        Err(Error::OutOfRange(Input::Radius))
    );
    let cases = [
        // crash-22ada3bc
        (
            "22ada3bc",
            Shape::Capsule(Capsule {
                half_height: f(0x40640200),
                radius: f(0x39000000),
            }),
            pose(
                v(0x00000000, 0x39800000, 0x40440000),
                [0x3f000000, 0x3f000000, 0x3f000000, 0x3f000000],
            ),
            Shape::Cuboid(Cuboid {
                half_extents: v(0x007c8c84, 0x39000000, 0x39000000),
            }),
            pose(v(0, 0, 0), [0, 0, 0, 0x3f800000]),
            f(0x37800000),
        ),
        // crash-ffbef777
        (
            "ffbef777",
            Shape::Capsule(Capsule {
                half_height: f(0x408b7d00),
                radius: f(0x39000000),
            }),
            pose(
                v(0xb9800000, 0x000000ff, 0x29c11737),
                [0x3f13fd75, 0x3ae44119, 0x3f136c6b, 0x3f13fd75],
            ),
            Shape::Cuboid(Cuboid {
                half_extents: v(0x39000000, 0x39000000, 0x39000000),
            }),
            pose(v(0, 0, 0), [0, 0, 0, 0x3f800000]),
            f(0x37800000),
        ),
    ];
    for (name, a, _, b, _, _) in &cases {
        assert!(!shape_size_in_range(a) && !shape_size_in_range(b), "{name}");
    }
    assert_cases(&cases);
}

/// A position beyond ±[`MAX_COORDINATE`] (5.2e36 m, crash-7b247a69 of the second run) is
/// refused by every query; the properties count that refusal as right.
#[test]
fn far_positions_are_refused() {
    let a = Shape::capsule(f(0x3c7a0000), f(0x4078fa00)).unwrap();
    let b = Shape::sphere(f(0x3eb00000)).unwrap();
    let pa = pose(
        v(0x40f8f800, 0x40f8f800, 0x7c7c7c7c),
        [0xbefe7ed8, 0xbf003ff2, 0xbf003ff2, 0xbf003ff2],
    );
    let pb = pose(v(0, 0, 0), [0, 0, 0, 0x3f800000]);
    assert!(pa.position.z > MAX_COORDINATE);
    assert_eq!(
        distance(&a, &pa, &b, &pb, &mut SimplexCache::default()),
        Err(Error::OutOfRange(Input::Position))
    );
    assert_cases(&[("7b247a69", a, pa, b, pb, f(0x37800000))]);
}

/// Class (b) of the issue: a time of impact whose gap at the hit disagrees with GJK. With
/// a tolerance (0.1 mm) below GJK's touching threshold for the sizes involved (1e-5 of
/// about 150 m), no time has a gap in `(0, tolerance]`: GJK reads 0.8 mm one way and
/// "touching" the other (the warm-started query and a cold one see different simplices).
/// The time of impact then stops within GJK's resolution of contact, which the property
/// no longer judges (`props::toi`'s `resolvable`); a tolerance GJK can resolve is held to
/// the full property. Found by a seeded stress run of `toi_properties` (two boxes of
/// 10–50 m moving at up to 200 m/s, seed 1, case 311); neither saved `toi` artifact
/// reproduces on this GJK, and both now use sizes the constructors refuse.
#[test]
fn toi_tolerance_below_gjk_resolution() {
    let a = Shape::cuboid(v(0x41139061, 0x42529d3c, 0x421bee7a)).unwrap();
    let b = Shape::cuboid(v(0x422c6011, 0x42095b61, 0x42459dc3)).unwrap();
    let motion_a = Motion {
        pose: pose(
            v(0x42a3a0b0, 0x427d715a, 0xc0d9542d),
            [0xbeedea60, 0xbe497ed7, 0x3e038f1a, 0xbf5a8dc9],
        ),
        linear: v(0xc23fc21f, 0x42bab113, 0x41acb479),
        angular: v(0xc0699173, 0x3fc6a940, 0x3fdf1e80),
    };
    let motion_b = Motion {
        pose: pose(
            v(0x40a01957, 0x42478b3d, 0x416dd15a),
            [0xbee5382d, 0x3f469965, 0xbeae53ce, 0x3e9271af],
        ),
        linear: v(0x420ea1d9, 0x41ef38a3, 0x419d8875),
        angular: v(0x4033c06c, 0x3f235fd6, 0xbf590bbf),
    };
    let t_max = f(0x3ebc05c0);
    for tolerance in [f(0x38d1b717), 0.05] {
        assert_eq!(
            toi_properties(&a, &motion_a, &b, &motion_b, t_max, tolerance),
            Ok(()),
            "tolerance {tolerance}"
        );
    }
    // The fine tolerance stops later than the coarse one, at a configuration GJK cannot
    // tell from contact: its distance is within GJK's touching threshold, 1e-5 of the
    // numbers it works with (both bounding radii plus the distance between the origins).
    let hit = |tolerance: f32| match time_of_impact(&a, &motion_a, &b, &motion_b, t_max, tolerance)
    {
        Ok(carom::collide::Toi::Hit { time, .. }) => time,
        other => panic!("{other:?}"),
    };
    let (fine, coarse) = (hit(f(0x38d1b717)), hit(0.05));
    assert!(coarse <= fine, "{coarse} {fine}");
    let (pa, pb) = (motion_a.pose_at(fine), motion_b.pose_at(fine));
    let d = distance(&a, &pa, &b, &pb, &mut SimplexCache::default()).unwrap();
    let size = a.bounding_radius() + b.bounding_radius() + (pb.position - pa.position).length();
    assert!(
        d.distance <= 1.0e-5 * size,
        "{} {}",
        d.distance,
        1.0e-5 * size
    );
}

/// Root cause: the separating axis test took an edge pair's separation from the two edges'
/// points, `n · (p_B − p_A)`, which is the separation only when the edges are the shapes'
/// supporting features along `±n`; the Gauss-map test decides that from the faces'
/// normals. Hull B has a quad face merged from nearly coplanar triangles that meets its
/// neighbour along a 0.24 mm edge not running along the cross product of the two faces'
/// normals, so the test passed a pair whose points were not the supports and read the
/// hulls 4 mm apart (more than the 3.9 mm margin) while they overlap by 39 mm: `contact`
/// said `None`. The old GJK hid it by calling the pair apart too; the exact-touching GJK
/// (and the brute-force oracle) see the overlap. Fix: a pair that would end the test or
/// become the best edge axis is measured again with both shapes' support points
/// (`collide::sat::support_separation`), which is exact for any axis.
#[test]
fn sat_edge_of_a_merged_face() {
    // crash-ae15fa4c (narrow_phase, this branch's 2-minute run).
    let a = hull(&[
        v(0x9f9f9f9f, 0x089f9f9f, 0x9f9f9f9f),
        v(0x407cfc00, 0xc07cfc00, 0x3f3fbdc0),
        v(0x407cfc00, 0x407cfc00, 0x407cfc00),
        v(0x407cfc00, 0x407cfc00, 0x3d9f8000),
        v(0x0102fffe, 0x3d808000, 0x407cfc00),
        v(0x407cfc00, 0x407cfc00, 0x82828282),
    ]);
    let b = hull(&[
        v(0x9f9f9f9f, 0x9f959f9f, 0x9f9f9f9f),
        v(0x9f9f9f9f, 0x9f9f9f9f, 0x3f3f3f9f),
        v(0x407cfc00, 0x407cfc00, 0x407cf800),
        v(0x3d9f8000, 0xbd808000, 0x3d808000),
        v(0x407cfc00, 0x407cfc00, 0x407cfc00),
        v(0xc0fafc00, 0x827c8282, 0x82828282),
    ]);
    let (a, b) = (Shape::hull(&a), Shape::hull(&b));
    let pa = pose(v(0x82828282, 0x82828282, 0x00138282), [0, 0, 0, 0x3f800000]);
    let pb = Iso::new(
        v(0x82828282, 0x00000000, 0x407cfc00),
        Quat::from_xyzw(14896.0, 16187.0, 16191.0, 16191.0).normalize(),
    );
    let margin = f(0x3b808000);
    assert_cases(&[("ae15fa4c", a, pa, b, pb, margin)]);
    // The root cause itself: both orders find the 39 mm overlap.
    let depth = penetration(&a, &pa, &b, &pb)
        .unwrap()
        .expect("overlap")
        .depth;
    for m in [
        carom::collide::contact(&a, &pa, &b, &pb, margin).unwrap(),
        carom::collide::contact(&b, &pb, &a, &pa, margin).unwrap(),
    ] {
        let m = m.expect("the hulls overlap");
        assert!((m.min_separation() + depth).abs() < 1e-4, "{m:?} {depth}");
    }
}

/// Root cause: the brute-force oracle of `distance_properties` certifies "apart" with a
/// separating axis among the closest pair's vector, the normals of vertex triples and the
/// cross products of vertex pairs. For a sphere (one core point) against a triangle the
/// Minkowski difference is flat, and its sides (normal to the triangle's edges, in its
/// plane) are none of those. Here the sphere's centre lies on the line of an edge, 3 cm past
/// its end and exactly level (in x) with the triangle's far corner: the closest pair's
/// vector, along −x, shows a gap of exactly 0 in f32, no other candidate separates, and
/// the oracle called the shapes overlapping while GJK (rightly) found them 1.5 cm apart.
/// Fix (`props`): for a set of at most 3 points, the flat difference's side normals are
/// candidates too.
#[test]
fn oracle_misses_the_sides_of_a_flat_difference() {
    // crash-d5744f6c (narrow_phase, this branch's second run; fails on the old code too).
    let ball = Shape::sphere(f(0x3c7a0000)).unwrap();
    let ball_at = Iso::new(
        v(0x40f8f800, 0, 0),
        Quat::from_xyzw(31832.0, 380.0, 245.0, 293.0).normalize(),
    );
    let triangle = Shape::triangle(
        v(0x40f8f800, 0x40f8f800, 0x40f8f800),
        v(0x40f80000, 0, 0),
        v(0, 0, 0),
    )
    .unwrap();
    let identity = pose(v(0, 0, 0), [0, 0, 0, 0x3f800000]);
    assert_cases(&[("d5744f6c", ball, ball_at, triangle, identity, 0.0)]);
    // The oracle itself: apart by the distance to the near corner (7.75 m), minus the radius.
    let va = core_vertices(&ball, &ball_at).unwrap();
    let vb = core_vertices(&triangle, &identity).unwrap();
    let o = brute_force_distance(va.points(), vb.points()).unwrap();
    assert!(
        (o.distance - (f(0x40f8f800) - f(0x40f80000))).abs() < 1e-6,
        "{o:?}"
    );
}

/// Root cause: two capsules of one rank were computed in whichever order the caller gave,
/// each in its own frame. For two nearly coaxial capsules (one turned half a turn about
/// an axis 3e-5 rad off x, 3 cm apart, deep inside each other) the normal comes from the
/// segments' closest points, which for nearly parallel segments is ill-conditioned: the
/// two orders' rounding gave normals that were not reversed. Fix: pairs of one rank on
/// the general path run in a canonical order (`manifold::pair_order`) and are flipped
/// back, so `contact(b, a)` is `contact(a, b)` reversed, to the bit.
#[test]
fn same_rank_pairs_run_in_one_order() {
    // crash-bd34b9f7 (narrow_phase, CI's fixed seed once the target checked separation;
    // fails on the old code too).
    let a = Shape::capsule(f(0x4078fa00), f(0x4078fa00)).unwrap();
    let pa = Iso::new(
        v(0, 0, 0x3cf80000),
        Quat::from_xyzw(31868.0, 1.0, 0.0, 0.0).normalize(),
    );
    let b = Shape::capsule(f(0x4078fa00), f(0x40ff7d00)).unwrap();
    let pb = pose(v(0, 0, 0), [0, 0, 0, 0x3f800000]);
    assert_cases(&[("bd34b9f7", a, pa, b, pb, 0.0)]);
    let m = carom::collide::contact(&a, &pa, &b, &pb, 0.0)
        .unwrap()
        .unwrap();
    let w = carom::collide::contact(&b, &pb, &a, &pa, 0.0)
        .unwrap()
        .unwrap();
    assert_eq!(m.normal, -w.normal);
    assert_eq!(m.min_separation(), w.min_separation());
}

/// Root cause (the oracle, not carom): the brute-force distance projects a point on the
/// plane of every vertex triple, and a sliver triple (three hull vertices nearly on one
/// line, coordinates of 3.3 m next to 1e-23 m) has a normal made mostly of rounding, so
/// the projection landed 0.12 m outside the hull and passed the inside test by rounding:
/// the oracle said 9.63 m where the sphere's centre is 9.75 m from the hull, and GJK was
/// right. Fix (`props`): slivers (sine of the angle below 1e-5) are skipped; their points
/// lie within 1e-5 of their size from their edges, which are candidates anyway.
#[test]
fn oracle_skips_sliver_triangles() {
    // crash-c0c33d30 (narrow_phase, a 30-minute random run; fails on the old oracle).
    let sliver_hull = hull(&[
        v(0x3c540000, 0x4054d400, 0x4054d400),
        v(0x4054d400, 0x00000000, 0x40540000),
        v(0x00000000, 0x40540800, 0x99999999),
        v(0x999999a0, 0x99999999, 0x99999999),
        v(0x99999999, 0x84999999, 0x3f1e89b6),
        v(0x4044c400, 0xc0fa0000, 0x4054d400),
        v(0x40570c00, 0x4054d400, 0x4054d400),
        v(0x00000000, 0x4054d400, 0x00000000),
    ]);
    let a = Shape::hull(&sliver_hull);
    let pa = pose(v(0x4054d400, 0x99999999, 0x8da09999), [0, 0, 0, 0x3f800000]);
    let b = Shape::sphere(f(0x3fd4d800)).unwrap();
    let pb = Iso::new(
        v(0xc0cd9600, 0x99999999, 0x99999999),
        Quat::from_xyzw(f(0xbf35048e), f(0xbf35048e), f(0x3b873adc), 0.0).normalize(),
    );
    assert_cases(&[("c0c33d30", a, pa, b, pb, 0.0)]);
    // The sphere's centre is 9.75 m from the hull's face at x = 3.325 m (world).
    let va = core_vertices(&a, &pa).unwrap();
    let vb = core_vertices(&b, &pb).unwrap();
    let o = brute_force_distance(va.points(), vb.points()).unwrap();
    assert!((o.distance - 9.75).abs() < 1e-5, "{o:?}");
}

/// Root cause: GJK stops on "overlapping" when the support point along `−v` lies clearly
/// past the origin (`v·w < 0`), the rounding case of an origin within `|v|` of a triangle
/// of `D`. For a 1.5 cm sphere 1.2 mm above a box of 8 m × 3 cm × 16 m, seen from the
/// sphere's frame (turned half a turn and 4° off), the support's rounding on the thin `D`
/// gave a negative `v·w` at a `v` of 1.2 mm, not at a `v` of rounding size: the cores read
/// as overlapping, EPA on the touching cores gave the sphere's radius as the depth
/// (0.01526 m instead of 0.01404 m), and the other order disagreed. Fix: only a `v`
/// within the direction tolerance of the origin can be that case.
#[test]
fn gjk_does_not_call_a_thin_gap_an_overlap() {
    // crash-a11fe352 (narrow_phase, a 30-minute random run; fails on the old code too).
    let a = Shape::sphere(f(0x3c7a0000)).unwrap();
    let pa = pose(v(0, 0x3c820000, 0), [0xbf7fd803, 0x38d69a0d, 0x3d0f115e, 0]);
    let b = Shape::cuboid(v(0x4078fa00, 0x3c700000, 0x40ff2b00)).unwrap();
    let pb = pose(v(0, 0, 0), [0, 0, 0, 0x3f800000]);
    let unit = |p: Iso| Iso::new(p.position, p.rotation.normalize());
    assert_cases(&[("a11fe352", a, pa, b, pb, 0.0)]);
    // The sphere's lowest point is 0.61 mm above the box's middle plane: 14.04 mm deep.
    let expected = f(0x3c700000) - (f(0x3c820000) - f(0x3c7a0000));
    for (x, px, y, py) in [(&a, pa, &b, pb), (&b, pb, &a, pa)] {
        let p = carom::collide::penetration(x, &unit(px), y, &unit(py))
            .unwrap()
            .unwrap();
        assert!((p.depth - expected).abs() < 1.0e-6, "{p:?}");
    }
}

/// Root cause: EPA's witnesses come from the barycentric coordinates of the converged
/// face's closest point, and for the face chosen it compared s2d's own closest point with
/// `depth · normal`. Two triangles sharing an edge (7.75 m long), 5e-5 m deep, make a face
/// of `D` that is a sliver through the origin (two vertices nearly opposite): s2d's point
/// was right but `Σ lᵢ wᵢ` of its coordinates was 1 cm off, and so were the witnesses
/// (`point_b − point_a` 1 cm from `−depth · normal`). Fix: coplanar triangles are compared
/// by `Σ lᵢ wᵢ`, the point the witnesses stand for; when even the best misses by more than
/// ten EPA tolerances the answer is `Degenerate`, not `Converged`.
#[test]
fn epa_witnesses_come_from_the_point_they_stand_for() {
    // crash-5c0fad2d (narrow_phase, a 30-minute random run; fails on the old code too).
    let a = Shape::triangle(
        Vec3::new(7.125244, 7.760254, 7.760254),
        Vec3::new(7.75, 0.0056152344, 7.7802734),
        Vec3::new(0.0, 7.7626953, 7.7910156),
    )
    .unwrap();
    let b = Shape::triangle(
        Vec3::new(7.75, 0.0056152344, 7.7802734),
        Vec3::new(0.0, 7.7629395, 7.7910156),
        Vec3::new(-0.56274414, 7.7617188, 7.7910156),
    )
    .unwrap();
    let pa = pose(
        v(0x40b05a00, 0x39800000, 0x40f8f800),
        [0x3f1123c0, 0x3e417891, 0x3f1123c0, 0x3f1123c0],
    );
    let pb = pose(
        v(0x40b05a00, 0x39800000, 0x40f8f800),
        [0x3f1123a0, 0x3e417d10, 0x3f1123a0, 0x3f1123a0],
    );
    assert_cases(&[("5c0fad2d", a, pa, b, pb, 0.0)]);
    let unit = |p: Iso| Iso::new(p.position, p.rotation.normalize());
    let p = carom::collide::penetration(&a, &unit(pa), &b, &unit(pb))
        .unwrap()
        .unwrap();
    let off = (p.point_b - p.point_a + p.normal * p.depth).length();
    assert!(off < 1.0e-4, "witnesses {off} m off: {p:?}");
}

/// A time-of-impact fuzz case of two hulls: their point clouds, A's and B's motions as
/// (position, linear velocity, angular velocity), A's rotation (x, y, z, w; B's is the
/// identity), the time span and the tolerance.
struct HullToi<'c> {
    a: &'c [[f32; 3]],
    b: &'c [[f32; 3]],
    motion_a: [[f32; 3]; 3],
    rotation_a: [f32; 4],
    motion_b: [[f32; 3]; 3],
    t_max: f32,
    tolerance: f32,
}

impl HullToi<'_> {
    fn properties(&self) -> Result<(), Violation> {
        let vec = |[x, y, z]: [f32; 3]| Vec3::new(x, y, z);
        let cloud = |c: &[[f32; 3]]| hull(&c.iter().map(|&p| vec(p)).collect::<Vec<_>>());
        let motion = |[p, v, w]: [[f32; 3]; 3], q: Quat| carom::collide::Motion {
            pose: Iso::new(vec(p), q),
            linear: vec(v),
            angular: vec(w),
        };
        let [x, y, z, w] = self.rotation_a;
        let motion_a = motion(self.motion_a, Quat::from_xyzw(x, y, z, w));
        let motion_b = motion(self.motion_b, Quat::IDENTITY);
        let (ha, hb) = (cloud(self.a), cloud(self.b));
        let (a, b) = (Shape::hull(&ha), Shape::hull(&hb));
        toi_properties(&a, &motion_a, &b, &motion_b, self.t_max, self.tolerance)
    }
}

/// Root cause (the property, not carom): two hulls touch exactly at time 0 (a vertex of
/// each at the same point). `time_of_impact` composes the poses in f32 and read a gap of
/// rounding size, so it answered a hit at time 0; the property's sampler composes them in
/// f64 (`distance`) and read 0, which it took for overlap. Fix (`props`): at the hit time
/// and before it, touching within rounding (EPA depth within the GJK slack) is contact,
/// not overlap.
#[test]
fn toi_touching_at_time_zero_is_a_hit() {
    // crash-02d40795 (toi, a 30-minute random run; fails on the old property).
    let tiny = -3.3110888e-33;
    let case = HullToi {
        a: &[
            [-7.5964355, -7.602783, 1.4418945],
            [1.4431152, 5.709717, 3.7097168],
            [5.709717, 0.3137207, 5.6887207],
            [0.3137207, 5.6887207, 1.0847168],
            [1.4418945, 3.1306152, 5.709717],
            [5.709717, 5.709717, 5.709717],
            [5.709717, 0.0, 0.0],
        ],
        b: &[
            [5.709717, 0.3137207, 5.0822754],
            [5.0822754, 0.3322754, 5.693115],
            [5.709717, 5.709717, 5.709717],
            [0.3137207, 0.3137207, 0.3137207],
            [0.0, 0.0, 5.709717],
            [1.0847168, 5.6916504, 1.0666504],
            [1.0666504, 1.0666504, -7.6208496],
            [5.709717, 1.4431152, 5.709717],
            [0.0, 5.709717, 5.709717],
            [5.709717, 1.0847168, 1.0666504],
            [5.709717, 5.709717, 0.0],
        ],
        motion_a: [[0.0, 0.0, 0.0], [20.078125, tiny, tiny], [tiny, tiny, tiny]],
        rotation_a: [0.57706, 0.57706, 0.57706, 0.031706594],
        motion_b: [
            [5.709717, 1.4431152, 6.2546444e-36],
            [92.359375, 6.278338e-36, 20.078125],
            [4.2666016, 4.2666016, 4.2666016],
        ],
        t_max: 0.36761475,
        tolerance: 0.09020996,
    };
    assert_eq!(case.properties(), Ok(()));
}

/// Root cause (the property, not carom): `separation_properties` compared the two orders'
/// separations whatever their status. A 7.9 m capsule around a hull that is nearly flat
/// in its frame got a `Bounded` answer one way (EPA could not expand the flat Minkowski
/// difference: depth 7.920 m, an upper bound) and a converged one the other (7.890 m).
/// Fix (`props`): as for `penetration`, only exact answers are compared.
#[test]
fn separation_compares_only_exact_answers() {
    // crash-a73bb2b0 (narrow_phase, a 30-minute random run; fails on the old property).
    let a = Shape::capsule(f(0x3fdce000), f(0x40fc7d00)).unwrap();
    let pa = pose(v(0, 0, 0), [0x3f3fddda, 0x3f2972e8, 0x3b48cc5c, 0x3c472dcf]);
    let flat = hull(&[
        v(0x2c2c2c47, 0x00000000, 0xbfe5c800),
        v(0x000c657c, 0x00000000, 0x4024a400),
        v(0x00000000, 0x39800000, 0xc0fa0000),
        v(0x4024a400, 0x4024c400, 0x4024fc00),
        v(0x4024a400, 0x00000000, 0x00000000),
    ]);
    let b = Shape::hull(&flat);
    let pb = pose(v(0, 0, 0), [0, 0, 0, 0x3f800000]);
    assert_cases(&[("a73bb2b0", a, pa, b, pb, 0.0)]);
    let unit = |p: Iso| Iso::new(p.position, p.rotation.normalize());
    let s = carom::collide::separation(&a, &unit(pa), &b, &unit(pb)).unwrap();
    let w = carom::collide::separation(&b, &unit(pb), &a, &unit(pa)).unwrap();
    // Whatever the statuses, both say the shapes overlap by about the capsule's radius.
    assert!(s.separation < -7.8 && w.separation < -7.8, "{s:?} {w:?}");
}

/// The mirror of `toi_touching_at_time_zero_is_a_hit`: two hulls touching exactly at time
/// 0, `time_of_impact` (f32 poses) read 0 and answered `Overlapping`, the sampler (f64
/// poses) read a gap of rounding size. Fix (`props`): `Overlapping` allows a gap within
/// the GJK slack at time 0.
#[test]
fn toi_touching_at_time_zero_may_read_as_overlapping() {
    // crash-adc4a3f4 (toi, a 30-minute random run; fails on the old property).
    let tiny = -3.3110888e-33;
    let case = HullToi {
        a: &[
            [-7.5964355, -7.602783, 1.4418945],
            [1.4431152, 5.709717, 3.7097168],
            [5.709717, 4.709717, 5.709717],
            [5.709717, 0.0, 0.3137207],
            [0.3137207, 0.32666016, 5.709717],
            [1.0666504, 1.1444008e-28, 1.0666504],
            [1.4418945, 3.1306152, 5.709717],
            [5.709717, 5.709717, 5.709717],
            [5.709717, 0.0, 0.0],
        ],
        b: &[
            [5.709717, 0.3137207, 5.0822754],
            [5.0822754, 0.3322754, 5.693115],
            [5.709717, 5.709717, 5.709717],
            [0.3137207, 0.3137207, 0.3137207],
            [0.0, 0.0, 5.709717],
            [1.0666504, 1.0666504, -7.6208496],
            [5.709717, 5.333252, 5.709717],
            [0.0, 5.709717, 5.709717],
            [5.709717, 1.0847168, 1.0666504],
            [5.709717, 5.709717, 0.0],
        ],
        motion_a: [[0.0, 0.0, 0.0], [20.078125, tiny, tiny], [tiny, tiny, tiny]],
        rotation_a: [0.57705915, 0.57705915, 0.57705915, 0.031755894],
        motion_b: [
            [5.709717, 1.6543611e-24, 1.2650716e-35],
            [20.078125, -5.0603046e-35, 20.078125],
            [4.2666016, 0.0, 4.2666016],
        ],
        t_max: 0.26672363,
        tolerance: 0.06668091,
    };
    assert_eq!(case.properties(), Ok(()));
}

/// Root cause: the fallback after the conservative advances marched the rest of the
/// window in 32 equal steps without certifying them. A 7.6 m hull spinning at 40 rad/s
/// (5.2 rad in all) flies beside a 16 cm sphere at the same 365 m/s; the closing-speed
/// bound (442 m/s, mostly the hull's spin times its reach) far exceeds the real closing
/// speed, so the advances crawled to 7 cm and the march stepped over a contact shorter
/// than one 2 ms step: `Separated`, while a sample found them overlapping. Fix
/// (`collide::toi`): a certified search, bisection in which each interval is cleared by
/// the bound run forwards from its left sample and backwards from its right one, or split;
/// its budget ends in `Toi::Unresolved`, never in a silent miss.
#[test]
fn toi_spinning_hull_passing_a_small_sphere_is_not_missed() {
    // spinning-hull-passes-a-small-sphere-357f321c (toi, a 24-minute random run; the
    // values the decoder produced, printed by `fuzz/examples/show.rs`).
    let cloud = [
        [-7.5964355, -7.602783, 1.4418945],
        [5.709717, 0.3137207, 0.3137207],
        [5.772461, 0.3137207, 5.709717],
        [0.0, 5.709717, 3.7097168],
        [5.709717, 5.709717, 3.7097168],
        [5.709717, -2.9816895, 5.709717],
        [0.3137207, 0.0, 5.693115],
        [5.709717, -7.592285, 1.4431152],
        [5.693115, 5.727051, 5.709717],
        [3.8347168, -7.5964355, -7.602783],
    ];
    let points: Vec<Vec3> = cloud.iter().map(|&[x, y, z]| Vec3::new(x, y, z)).collect();
    let h = hull(&points);
    let a = Shape::hull(&h);
    let b = Shape::sphere(0.15637207).unwrap();
    let speed = Vec3::splat(365.42188);
    let motion_a = Motion {
        pose: Iso::new(
            Vec3::new(1.4431152, 1.4431152, 5.709717),
            Quat::from_xyzw(0.35121864, 0.5405693, 0.5405693, 0.5405693),
        ),
        linear: speed,
        angular: Vec3::splat(22.838867),
    };
    let motion_b = Motion {
        pose: Iso::new(Vec3::new(5.709717, 0.3137207, 0.0), Quat::IDENTITY),
        linear: speed,
        angular: Vec3::new(0.0009765625, 0.0, 22.838867),
    };
    let (t_max, tolerance) = (0.083740234, 0.019622803);
    assert_eq!(
        toi_properties(&a, &motion_a, &b, &motion_b, t_max, tolerance),
        Ok(())
    );
    let toi = time_of_impact(&a, &motion_a, &b, &motion_b, t_max, tolerance).unwrap();
    assert!(
        matches!(toi, carom::collide::Toi::Hit { .. }),
        "the pass touches: {toi:?}"
    );
}

/// The capsule (radius 7.890259 m, half-height `half_height`) at its pose and the nearly
/// flat hull (three points on the line x = y = 0 and the two `corners`) of the
/// `capsule-core-touching-a-hull-*` findings, values as the decoder produced them.
fn capsule_over_flat_hull(
    half_height: f32,
    corners: [Vec3; 2],
) -> (Shape<'static>, Iso, ConvexHull) {
    let capsule = Shape::capsule(half_height, 7.890259).unwrap();
    let pose = Iso::new(
        Vec3::ZERO,
        Quat::from_xyzw(0.71619636, 0.6325157, 0.2568031, -0.14504795),
    );
    let [c0, c1] = corners;
    let flat = hull(&[
        Vec3::new(2.446725e-12, 0.0, -1.795166),
        Vec3::new(1.138432e-39, 0.0, 2.5725098),
        Vec3::new(0.0, 0.00024414063, -7.8125),
        c0,
        c1,
    ]);
    (capsule, pose, flat)
}

/// Root cause (the property; a known limit of carom): a 7.9 m capsule whose core segment
/// just touches a nearly flat hull. With the capsule first, GJK sees the cores apart by
/// rounding and the depth is exact (7.890 m, the radius); with the hull first, the order
/// the manifold runs in for this pair whatever the argument order, GJK calls the cores
/// overlapping, EPA cannot expand their thin Minkowski difference and answers its bound,
/// 8.163 m, flagged `Degenerate`. The manifold stands on that bound in both orders; the
/// property compared it with the converged depth of the argument order. Fix (`props`):
/// a bound met in either order allows the manifold to be as deep as it, never deeper.
/// The manifold is then 0.27 m (3.5 %) deeper than exact here (a documented limit).
#[test]
fn a_manifold_may_stand_on_the_bound_epa_met_in_its_own_order() {
    // capsule-core-touching-a-hull-549aad0e (narrow_phase, an 8-minute random run; the
    // values the decoder produced, printed by `fuzz/examples/show.rs`).
    let (a, pa, flat) = capsule_over_flat_hull(
        1.7255859,
        [
            Vec3::new(2.5725098, 2.574463, 2.5778809),
            Vec3::new(2.5725098, 0.0, 0.0),
        ],
    );
    let b = Shape::hull(&flat);
    let pb = Iso::IDENTITY;
    assert_cases(&[("549aad0e", a, pa, b, pb, 1.5258789e-5)]);
    let exact = penetration(&a, &pa, &b, &pb)
        .unwrap()
        .expect("they overlap");
    assert_eq!(exact.status, carom::collide::EpaStatus::Converged);
    assert!((exact.depth - 7.890259).abs() < 1e-4, "{exact:?}");
    let bounded = penetration(&b, &pb, &a, &pa)
        .unwrap()
        .expect("they overlap");
    assert_ne!(bounded.status, carom::collide::EpaStatus::Converged);
    // Both argument orders give the same manifold, on the bound, not deeper.
    let m = carom::collide::contact(&a, &pa, &b, &pb, 1.5258789e-5)
        .unwrap()
        .unwrap();
    let w = carom::collide::contact(&b, &pb, &a, &pa, 1.5258789e-5)
        .unwrap()
        .unwrap();
    assert_eq!(m.min_separation(), w.min_separation());
    assert!(m.min_separation() >= -bounded.depth - 1e-4, "{m:?}");
}

/// Root cause (the property; the same limit of carom as `549aad0e`): the capsule of that
/// finding 5 mm longer, over the same nearly flat hull. Here both public orders converge
/// (7.890 m: they compose the relative pose in f64), but the manifold composes it in f32
/// for its canonical order, and in that pose GJK calls the cores overlapping and EPA only
/// bounds the depth (8.163 m). Fix: the manifold says so (`Manifold::depth_bound`), and
/// the property then asks only that the bound is not shallower than the exact depth.
#[test]
fn a_manifold_on_a_bound_says_so() {
    // capsule-core-touching-a-hull-7d7caaf2 (narrow_phase, a 30-minute random run at
    // 96317d7; the values printed by `fuzz/examples/show.rs`).
    let (a, pa, flat) = capsule_over_flat_hull(
        1.7305908,
        [
            Vec3::new(2.5725098, 2.574707, 2.5778809),
            Vec3::new(2.6015625, 0.0, 0.0),
        ],
    );
    let b = Shape::hull(&flat);
    let pb = Iso::IDENTITY;
    assert_cases(&[("7d7caaf2", a, pa, b, pb, 1.5258789e-5)]);
    for (x, px, y, py) in [(&a, &pa, &b, &pb), (&b, &pb, &a, &pa)] {
        let p = penetration(x, px, y, py).unwrap().expect("they overlap");
        assert!((p.depth - 7.890259).abs() < 1e-4, "{p:?}");
        let m = carom::collide::contact(x, px, y, py, 1.5258789e-5)
            .unwrap()
            .unwrap();
        assert!(m.depth_bound, "{m:?}");
        assert!(m.min_separation() <= -p.depth + 1e-4, "{m:?}");
    }
}

/// Root cause: a box deep in a sliver hull (a triangle face with a 0.24 mm edge and 10 m
/// sides, so its two long side planes meet at an angle of 2e-5 rad). SAT took that face as
/// the reference; a clipped point 2 cm past the sliver's tip lay within `f32` rounding of
/// both long side planes, passed them, and stood off B (`point_b not on B`). Fix
/// (`collide::clip`): clipped points whose projection leaves the reference face's box
/// (grown by 1e-5 of its coordinates) are dropped; the two points inside remain.
#[test]
fn a_sliver_reference_face_keeps_its_points_on_the_face() {
    // sliver-reference-face-7d4378d2 (narrow_phase, a 30-minute random run at 861af8b;
    // the values printed by `fuzz/examples/show.rs`).
    let tiny = -1.5881867e-23;
    let a = Shape::cuboid(Vec3::new(3.8902588, 2.8902588, 3.7961426)).unwrap();
    let pa = Iso::new(
        Vec3::new(7.592041, 7.592041, tiny),
        Quat::from_xyzw(-0.5, -0.5, -0.5, -0.5),
    );
    let sliver = hull(&[
        Vec3::new(tiny, tiny, 7.592041),
        Vec3::new(7.592041, 7.592041, 7.592041),
        Vec3::new(7.772461, 7.592041, 7.592041),
        Vec3::new(-0.00024414063, tiny, tiny),
        Vec3::new(-2.0327963e-23, tiny, tiny),
        Vec3::new(7.592041, 7.592041, 0.092041016),
    ]);
    let b = Shape::hull(&sliver);
    let pb = Iso::IDENTITY;
    assert_cases(&[("7d4378d2", a, pa, b, pb, 1.5258789e-5)]);
    let m = carom::collide::contact(&a, &pa, &b, &pb, 1.5258789e-5)
        .unwrap()
        .unwrap();
    assert!(m.len >= 2, "{m:?}");
    for p in m.points() {
        // Nothing past the sliver's tip at x = y = 7.592.
        assert!(p.point_b.x <= 7.5921 && p.point_b.y <= 7.5921, "{p:?}");
    }
}

/// Root cause (the property; a documented limit of carom's GJK): two boxes 2.97 m apart,
/// face to face. GJK's distance is exact (2.968506 m, the brute-force oracle's), but its
/// normal leans by 3.8e-4 rad: `v` is measured by `|v|²`, and in `f32` that cannot tell
/// lateral offsets apart below `|v| · √(2⁻²³)`. Along the leaning normal, the closest
/// point on A's face falls 3 mm short of A's support over its 7.8 m face. Fix (`props`):
/// the support checks allow the tilt `props::GJK_NORMAL_ANGLE` times the shape's span.
#[test]
fn a_gjk_normal_between_parallel_faces_leans_within_the_documented_angle() {
    // parallel-faces-47774539 (narrow_phase, a 30-minute random run at 54541f7; the values
    // printed by `fuzz/examples/show.rs`).
    let a = Shape::cuboid(Vec3::new(3.8902588, 1.2652588, 3.8902588)).unwrap();
    let b = Shape::cuboid(Vec3::new(3.8902588, 3.8902588, 3.5465088)).unwrap();
    let pa = Iso::new(
        Vec3::ZERO,
        Quat::from_xyzw(0.5000078, 0.5000078, 0.5000078, 0.49997646),
    );
    let pb = Iso::new(Vec3::new(7.779297, 7.7802734, 7.7802734), Quat::IDENTITY);
    assert_cases(&[("47774539", a, pa, b, pb, 0.53718567)]);
    let d = distance(&a, &pa, &b, &pb, &mut SimplexCache::default()).unwrap();
    assert!((d.distance - 2.9685056).abs() < 1e-5, "{d:?}");
    // A's face normal is world +z to 1e-4 here; GJK's leans by less than the bound.
    let lean = (d.normal.x * d.normal.x + d.normal.y * d.normal.y).sqrt();
    assert!(lean < carom::props::GJK_NORMAL_ANGLE, "{d:?}");
}

/// Root cause (the property; the same limit of GJK as `parallel-faces-47774539`): a 1.5 cm
/// sphere whose centre lies on an edge of a hull (within 2e-7 m). The cores are apart by
/// rounding, so the penetration is the radius, exact, along an exact normal; but GJK's
/// closest point on the hull is a barycentric combination on a sliver of the simplex and
/// slid 3.4 mm along the 11 m edge, so `point_b − point_a` leaned off `−depth · n`. Fix
/// (`props`): along the normal the points must be `depth` apart to the slack; across it
/// they may slide by `GJK_NORMAL_ANGLE` of the shapes' spans.
#[test]
fn deepest_points_of_touching_cores_may_slide_along_the_edge() {
    // sphere-on-a-hull-edge-5c8d31d2 (narrow_phase, a long run at 47376b3; the values
    // printed by `fuzz/examples/show.rs`).
    let a = Shape::sphere(0.015258789).unwrap();
    let pa = Iso::new(
        Vec3::new(0.0, 9.1e-44, 0.25),
        Quat::from_xyzw(0.71869814, 0.6347252, 0.25770015, -0.11911169),
    );
    let h = hull(&[
        Vec3::new(2.446725e-12, 0.0, -1.795166),
        Vec3::new(1.138432e-39, 0.0, 2.5725098),
        Vec3::new(0.0, 0.00024414063, -7.8125),
        Vec3::new(2.5725098, 2.574463, 2.5778809),
        Vec3::new(0.030273438, 7.7802734, 5.2478027),
        Vec3::new(5.2077637, 1.4105931e-38, 0.0),
    ]);
    let b = Shape::hull(&h);
    let pb = Iso::IDENTITY;
    assert_cases(&[("5c8d31d2", a, pa, b, pb, 1.5258789e-5)]);
    let p = penetration(&a, &pa, &b, &pb).unwrap().unwrap();
    // The depth is the radius: the centre is on the edge.
    assert!((p.depth - 0.015258789).abs() < 1e-6, "{p:?}");
}

/// Root cause: GJK's f32 loop stopped on "no progress" with the support along `−v`
/// clearly past the origin, and read that as "apart" unless `v` was within the direction
/// tolerance of the origin. With a metres-long simplex whose closest point is a fraction
/// of a millimetre from the origin, `v`'s direction carries the rounding of the vertices
/// (an ulp of 8 m over 0.24 mm: 2e-3 rad), the support along it lands on a far vertex
/// past the origin, and the sub-algorithm, rounding the same way, drops it: the cores were
/// called apart while overlapping by millimetres, in one argument order only. A sphere's
/// centre 3.5 mm inside an 8 m plate 7.6 mm thick (f50bc49a: the depth was the radius
/// alone, 3.8 mm short); two 3.3 m boxes 7.6 mm deep read as 0.24 mm apart (5c2ee9ea);
/// a 1.5 cm sphere against a hull with coordinates of 1e-12 to 1e-44 m next to metres
/// (d78939cf: a depth along which moving the sphere out did not separate). Reading every
/// such stop as overlap broke the opposite case (a11fe352 above: a sphere 1.2 mm over a
/// thin box, truly apart). Fix (`collide::gjk_f64`): such an undecided stop continues
/// the search from its simplex with the closest point computed in f64 from the same f32
/// vertices, exact for the polytopes they describe.
#[test]
fn gjk_refines_an_undecided_stop_in_f64() {
    // plate-through-a-sphere-core-f50bc49a (narrow_phase, CI's fixed-seed run at fa3945a).
    let a = Shape::sphere(3.8902588).unwrap();
    let pa = Iso::new(
        Vec3::new(-0.00024414063, 0.0, 1.44055e-40),
        Quat::from_xyzw(0.5538662, 0.55383146, 0.28244224, 0.55383146),
    );
    let b = Shape::cuboid(Vec3::new(0.0037841797, 7.984009, 3.8902588)).unwrap();
    let pb = Iso::IDENTITY;
    // big-boxes-tilted-normal-5c2ee9ea (narrow_phase, a long run at cd1e567).
    let cube = Shape::cuboid(Vec3::splat(3.2941895)).unwrap();
    let pc = Iso::new(Vec3::splat(6.588135), Quat::from_xyzw(0.5, 0.5, 0.5, 0.5));
    let pd = Iso::new(
        Vec3::new(-0.00048828125, 6.588135, 6.588135),
        Quat::from_xyzw(0.4991098, 0.50029635, 0.50029635, 0.50029635),
    );
    // epa-depth-sphere-hull-d78939cf (narrow_phase, a long run at 8096638).
    let s = Shape::sphere(0.015258789).unwrap();
    let ps = Iso::new(
        Vec3::new(0.0, 9.1e-44, 0.25),
        Quat::from_xyzw(0.6680313, -0.11003178, -0.5164182, 0.5243468),
    );
    let h = hull(&[
        Vec3::new(2.446725e-12, 0.0, 7.892334),
        Vec3::new(1.138432e-39, 0.0, 2.5725098),
        Vec3::new(0.0, 0.00024414063, -7.8125),
        Vec3::new(0.030273438, 7.7802734, 5.2478027),
        Vec3::new(5.2077637, 2.14e-43, 0.0),
    ]);
    let hull_shape = Shape::hull(&h);
    assert_cases(&[
        ("f50bc49a", a, pa, b, pb, 1.5258789e-5),
        ("5c2ee9ea", cube, pc, cube, pd, 0.41177368),
        ("d78939cf", s, ps, hull_shape, Iso::IDENTITY, 1.5258789e-5),
    ]);
    // The sphere's centre is 0.244 mm off the plate's middle plane: the depth is the
    // radius plus the half thickness minus that offset, in both orders.
    let expected = 3.8902588 + 0.0037841797 - 0.00024414063;
    for (x, px, y, py) in [(&a, pa, &b, pb), (&b, pb, &a, pa)] {
        let p = penetration(x, &px, y, &py).unwrap().unwrap();
        assert!((p.depth - expected).abs() < 1.0e-6, "{p:?}");
        assert_eq!(p.status, carom::collide::EpaStatus::Converged, "{p:?}");
    }
    // Both orders find the boxes overlapping by the depth an f64 separating axis test
    // over the 15 axes gives (7.5686 mm).
    for (px, py) in [(pc, pd), (pd, pc)] {
        let s = carom::collide::separation(&cube, &px, &cube, &py).unwrap();
        assert!((s.separation + 0.0075686).abs() < 2.0e-6, "{s:?}");
    }
}

/// Root cause: the capsule–triangle test takes a face contact from the core segment
/// clipped to the triangle's side planes when its deepest point is at least as deep as
/// the closest pair of segment and triangle, but it did not ask that it be no deeper. A
/// 7.9 m capsule crossing the triangle's plane 0.73 mm past an edge (the cores apart, the
/// triangle's normal tilted 3e-4 rad off the capsule's plane): the prism over the
/// triangle, slanted by that tilt, holds the part of the segment 2.5 m behind the face
/// chosen, and the manifold read 2.55 m deep where the shapes overlap by 7.2 mm. Fix
/// (`collide::sat::capsule_triangle`): a face contact deeper than the closest pair (beyond
/// the guard) is refused; the one point along the closest pair stands.
#[test]
fn capsule_face_contact_is_never_deeper_than_the_closest_pair() {
    // capsule-past-a-triangle-edge-1f4f15f4 (narrow_phase, a 20-minute random run at
    // 0ddd3e0; fails on the code before it too).
    let a = Shape::capsule(3.9527588, 0.00793457).unwrap();
    let b = Shape::triangle(
        Vec3::new(1.5016133e-36, 7.7783203, 7.7802734),
        Vec3::new(-6.0117188, 0.0024414063, 0.0),
        Vec3::new(0.0, 0.0, 0.0),
    )
    .unwrap();
    let pa = Iso::new(
        Vec3::new(0.0007324219, -8.829435e-20, 0.00024414063),
        Quat::IDENTITY,
    );
    assert_cases(&[("1f4f15f4", a, pa, b, Iso::IDENTITY, 1.5258789e-5)]);
    let m = carom::collide::contact(&a, &pa, &b, &Iso::IDENTITY, 1.5258789e-5)
        .unwrap()
        .unwrap();
    // The radius less the core's 0.73 mm gap to the edge x = 0, along −x.
    let expected = 0.0007324219 - 0.00793457;
    assert!((m.min_separation() - expected).abs() < 1.0e-5, "{m:?}");
    assert!(m.normal.x < -0.999, "{m:?}");
}

/// Root cause: a sphere's centre 0.4 mm outside a hull, by an edge 15.7 m long: GJK's f32
/// loop stopped with the cores apart on a simplex whose closest point it placed poorly,
/// the hull's deepest point 19 mm along the edge from the centre's foot and the depth 0.1
/// mm off the other argument order's. Fix (`collide::gjk::refined_near`): when the cores
/// stop apart within 1e-3 of the simplex's size on a segment or a triangle, the
/// penetration finishes the search in f64 (`collide::gjk_f64`) before it reads the
/// witnesses and the normal.
#[test]
fn near_touching_cores_are_finished_in_f64_for_the_penetration() {
    // sphere-by-a-long-hull-edge-eaadbf85 (narrow_phase, a 10-minute random run at
    // c1377a8 from the corpus of the one before; fails on the code before it too).
    let a = Shape::sphere(0.015258789).unwrap();
    let h = hull(&[
        Vec3::new(2.446725e-12, 0.0, 7.892334),
        Vec3::new(1.138432e-39, 0.0, 2.5625),
        Vec3::new(0.0, 0.00024414063, -7.8125),
        Vec3::new(2.5725098, 0.029052734, -0.06225586),
        Vec3::new(5.7109375, 5.51e-41, 0.0),
    ]);
    let b = Shape::hull(&h);
    let pa = Iso::new(
        Vec3::new(-0.00048828125, 9.1834e-41, 0.25),
        Quat::from_xyzw(-0.66830236, 0.110050775, -0.5156854, 0.5247186),
    );
    assert_cases(&[("eaadbf85", a, pa, b, Iso::IDENTITY, 1.5258789e-5)]);
    let unit = Iso::new(pa.position, pa.rotation.normalize());
    let p = penetration(&a, &unit, &b, &Iso::IDENTITY).unwrap().unwrap();
    let q = penetration(&b, &Iso::IDENTITY, &a, &unit).unwrap().unwrap();
    // Both orders agree on the depth to 1e-6 m, and the hull's deepest point is the
    // centre's foot on the edge (z = 0.25), not 19 mm along it.
    assert!((p.depth - q.depth).abs() < 1.0e-6, "{p:?} {q:?}");
    assert!((p.point_b.z - 0.25).abs() < 1.0e-4, "{p:?}");
}

/// Root cause: a sphere resting exactly on a thin box (its centre 1.220703125 mm over the
/// top face, its radius the same, both exact in f32): the f32 search finds the shapes
/// touching (`distance` 0), and `refined_near` then finished it in f64, which put the
/// cores apart by a rounding, and the penetration answered `None` for shapes `distance`
/// calls touching. Fix (`collide::epa::penetration_from_gjk`): whether the shapes overlap
/// is decided by the f32 search, as `distance` decides it; the f64 finish gives the
/// witnesses and the normal, and a depth of 0 for shapes that part only in f64.
#[test]
fn touching_in_f32_is_touching_after_the_f64_finish() {
    // sphere-touching-a-thin-box-55a0fb45 (narrow_phase, a 15-minute random run at
    // 2a841cb; fails on e804af0 too). The box is a11fe352's.
    let a = Shape::sphere(f(0x3aa00000)).unwrap();
    let pa = Iso::new(
        v(0, 0x3c820000, 0x40280000),
        Quat::from_xyzw(0.17769945, 0.9678949, 0.17769945, 0.005041119),
    );
    let b = Shape::cuboid(v(0x4078fa00, 0x3c700000, 0x40ff2b00)).unwrap();
    assert_cases(&[("55a0fb45", a, pa, b, Iso::IDENTITY, 1.5258789e-5)]);
    let unit = Iso::new(pa.position, pa.rotation.normalize());
    let d = distance(&a, &unit, &b, &Iso::IDENTITY, &mut SimplexCache::default()).unwrap();
    assert_eq!(d.distance, 0.0);
    for p in [
        penetration(&a, &unit, &b, &Iso::IDENTITY).unwrap().unwrap(),
        penetration(&b, &Iso::IDENTITY, &a, &unit).unwrap().unwrap(),
    ] {
        assert_eq!(p.depth, 0.0, "{p:?}");
        assert!(p.normal.y.abs() > 0.999_999, "{p:?}");
    }
}

/// Root cause: a 3.89 m sphere centred on a hull edge where the hull is a sliver (vertices
/// 0.1 to 0.5 mm off the edge): the cores touch, EPA's polytope stalled on a face whose
/// plane was off by rounding, and the stall was certified by the bracket of EPA's and the
/// separating axes' upper bounds. The depth was right to the tolerance, but the answer
/// took the stalled face's normal, along which `D` reaches 2.7 m: moving B by the depth
/// along it left the shapes 0.23 m overlapped. Fix (`collide::epa`): a certified stall
/// whose own normal's support lies more than 100 tolerances beyond the smallest upper
/// bound answers along the direction of that bound (status `Degenerate`: its points are
/// the supports along it, not a closest pair).
#[test]
fn a_certified_stall_answers_along_its_upper_bound() {
    // sphere-on-a-sliver-hull-edge-d1bb2040 (narrow_phase, a 7-minute random run at
    // 87aa4bb; fails on b27cf03 too).
    let a = Shape::sphere(3.8900146).unwrap();
    let h = hull(&[
        Vec3::new(2.446725e-12, 0.0, -1.795166),
        Vec3::new(1.138432e-39, 0.0, 2.5725098),
        Vec3::new(0.0, 0.00024414063, -7.8125),
        Vec3::new(2.5927734, 7.4677734, 2.6345215),
        Vec3::new(0.0, 0.00024414063, 6.21167),
        Vec3::new(6.21167, 6.21167, 6.21167),
        Vec3::new(0.00048828125, 0.0, -6.4172363),
    ]);
    let b = Shape::hull(&h);
    let pa = Iso::new(
        Vec3::new(0.0, 9.1e-44, 0.25),
        Quat::from_xyzw(0.7106986, 0.62766033, 0.2548318, -0.18976486),
    );
    assert_cases(&[("d1bb2040", a, pa, b, Iso::IDENTITY, 1.5258789e-5)]);
    let unit = Iso::new(pa.position, pa.rotation.normalize());
    let p = penetration(&a, &unit, &b, &Iso::IDENTITY).unwrap().unwrap();
    // The radius deep (the cores touch), and B moved by it (plus 0.1 mm) along the
    // normal is clear of the sphere.
    assert!((p.depth - 3.8900146).abs() < 1.0e-4, "{p:?}");
    let moved = Iso::new(p.normal * (p.depth + 1.0e-4), Quat::IDENTITY);
    let d = distance(&a, &unit, &b, &moved, &mut SimplexCache::default()).unwrap();
    assert!(d.distance > 0.0, "{p:?} {d:?}");
}

/// Root cause: GJK stopped with the cores apart on a sliver triangle of `D` (the sphere's
/// centre against two 8 m hull edges that meet at 3·10⁻⁵ rad, 3.9 cm away). The closest
/// point, the origin's projection on the triangle's plane, was right, and so was the
/// distance; but the barycentric coordinates come from projected areas, each carrying a
/// few ulps of the 8 m edges squared against a total area of 10⁻³ m², and the hull's
/// witness slid 6.6 mm along the edge: the witnesses stood 0.9 mm further apart than the
/// distance. Fix (`collide::gjk::is_sliver`): a search that stops apart on a sliver
/// finishes its coordinates in f64.
#[test]
fn witnesses_on_a_sliver_of_the_difference_are_finished_in_f64() {
    // sphere-by-a-bent-sliver-hull-496c6ce0 (narrow_phase, about 3 minutes into a random
    // run at 84dc321 from the corpus of the ones before; fails on the code before it too).
    let a = Shape::sphere(f(0x3c7a0000)).unwrap();
    let h = hull(&[
        v(0x2c2c2c47, 0, 0x40fc8e00),
        v(0, 0x39800000, 0xc0f97800),
        v(0x4024a400, 0x4024c400, 0x4024fc00),
        v(0x4024a400, 0, 0xb9800000),
        v(0, 0, 0),
    ]);
    let b = Shape::hull(&h);
    let pa = pose(
        v(0, 0x41, 0),
        [0x3f1ae694, 0xbdcc1c37, 0xbf219498, 0x3ef32ad6],
    );
    let pb = Iso::new(v(0x3d1e0000, 0xff, 0), Quat::IDENTITY);
    assert_cases(&[("496c6ce0", a, pa, b, pb, f(0x3ea6a800))]);
    // The hull's point is its corner at its origin (the edges run along ±z from there),
    // and the witnesses are the distance apart.
    let d = distance(&a, &pa, &b, &pb, &mut SimplexCache::default()).unwrap();
    assert!(d.point_b.z.abs() < 1.0e-5, "{d:?}");
    let gap = (d.point_b - d.point_a).length();
    assert!((gap - d.distance).abs() < 1.0e-6, "{gap} {d:?}");
}

/// Root cause: a 3.89 m sphere whose centre lies inside a box 2.4 mm thick and 1 km wide:
/// the cores' difference is thinner than EPA's tolerance there (1e-5 of the scale), so
/// EPA answers "touching through a flat difference" at core depth 0, with GJK's simplex
/// for witnesses. That simplex was a tetrahedron nearly as flat as the box, and its
/// barycentric coordinates put the witness on the box 16 m across the normal from the
/// one on the sphere's centre. Fix (`collide::epa::flat_witnesses`): the witnesses are
/// the simplex's point over the origin seen along the flat normal, a convex combination
/// from the widest triangle that holds the origin in the plane across the normal, so
/// they differ along the normal only.
#[test]
fn touching_through_a_flat_difference_keeps_its_witnesses_together() {
    // sphere-in-a-thin-box-flat-difference-03da1638 (narrow_phase, CI's seeded run at
    // 2fecfd9; the narrow phase is 45540b3's).
    let a = Shape::sphere(f(0x40790200)).unwrap();
    let pa = pose(
        v(0x8383f783, 0xc06e0800, 0xbe800000),
        [0x3f19b79c, 0xbb22ff6d, 0x3f0731db, 0x3f19b79c],
    );
    let b = Shape::cuboid(v(0x3aa00000, 0x40bc0100, 0x44000000)).unwrap();
    assert_cases(&[("03da1638", a, pa, b, Iso::IDENTITY, 0.0)]);
    let unit = Iso::new(pa.position, pa.rotation.normalize());
    let p = penetration(&a, &unit, &b, &Iso::IDENTITY).unwrap().unwrap();
    // The points differ along the normal only (to a micrometre), and the one on the box
    // is within its 1.2 mm half-thickness of the sphere's centre.
    let gap = p.point_b - p.point_a + p.normal * p.depth;
    let across = (gap - p.normal * p.normal.dot(gap)).length();
    assert!(across < 1.0e-5, "{p:?}");
    assert!((p.point_b - unit.position).length() < 1.3e-3, "{p:?}");
}
