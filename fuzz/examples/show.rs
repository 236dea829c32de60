//! Print a fuzz input as the values the target sees, to turn a finding into a test.
//!
//! Usage: `cargo run --manifest-path fuzz/Cargo.toml --example show -- TARGET FILE`
//! (TARGET: `narrow_phase`, `toi` or `hull`).
use arbitrary::{Arbitrary, Unstructured};
use carom::shape::ConvexHull;
use carom::shape::Shape;
use carom_fuzz::{points, PairInput, ToiInput, Vec3Input, TIME_UNIT, TOLERANCE_UNIT};

fn describe(s: &Shape) -> String {
    match s {
        Shape::Hull(h) => format!("hull {:?}", h.vertices()),
        other => format!("{other:?}"),
    }
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let (Some(target), Some(file)) = (args.get(1), args.get(2)) else {
        eprintln!("usage: show TARGET FILE");
        std::process::exit(2);
    };
    let bytes = std::fs::read(file).expect("read the input");
    let u = Unstructured::new(&bytes);
    match target.as_str() {
        "toi" => {
            let input = ToiInput::arbitrary_take_rest(u).expect("decode");
            let (Some(a), Some(b)) = (input.a.build(), input.b.build()) else {
                println!("a shape is refused");
                return;
            };
            println!("a: {}", describe(&a.shape()));
            println!("b: {}", describe(&b.shape()));
            println!("motion_a: {:?}", input.motion_a.motion());
            println!("motion_b: {:?}", input.motion_b.motion());
            println!("t_max: {:?}", input.t_max.value(TIME_UNIT));
            println!("tolerance: {:?}", input.tolerance.value(TOLERANCE_UNIT));
        }
        "narrow_phase" => {
            let input = PairInput::arbitrary_take_rest(u).expect("decode");
            let (Some(a), Some(b)) = (input.a.build(), input.b.build()) else {
                println!("a shape is refused");
                return;
            };
            println!("a: {}", describe(&a.shape()));
            println!("b: {}", describe(&b.shape()));
            println!("pose_a: {:?}", input.pose_a.iso());
            println!("pose_b: {:?}", input.pose_b.iso());
            println!("margin: {:?}", input.margin.value(TOLERANCE_UNIT));
        }
        "hull" => {
            let cloud = Vec::<Vec3Input>::arbitrary_take_rest(u).expect("decode");
            let pts = points(&cloud);
            println!("points ({}): {pts:?}", pts.len());
            match ConvexHull::new(&pts) {
                Err(e) => println!("refused: {e:?}"),
                Ok(h) => {
                    // How far the worst input point lies outside a face plane.
                    let mut worst = 0.0f32;
                    for p in &pts {
                        for f in 0..h.face_count() {
                            let (n, d) = h.plane(f);
                            worst = worst.max(n.dot(*p) - d);
                        }
                    }
                    println!(
                        "hull: {} vertices, {} faces, tolerance {:e}, reduced {}, worst point {:e} outside",
                        h.vertices().len(),
                        h.face_count(),
                        h.tolerance(),
                        h.is_reduced(),
                        worst
                    );
                }
            }
        }
        _ => eprintln!("unknown target {target}"),
    }
}
