//! Prints the cross-target narrow-phase line `narrow <count> 0x<hash>` (see
//! `demos/workload.rs`). Built for `wasm32-wasip1` it runs under Node's WASI (`run.mjs`);
//! built for the host it gives the reference line the other targets are diffed against.

#[path = "../../workload.rs"]
mod workload;

fn main() {
    println!("{}", workload::run_narrow_workload());
}

#[cfg(test)]
mod tests {
    use super::workload::{run_narrow_workload, Fnv1a64, WORKLOAD_PAIRS};

    #[test]
    fn fnv1a64_matches_the_published_test_vectors() {
        // Reference values from the FNV test suite: "" and "a".
        assert_eq!(Fnv1a64::new().finish(), 0xcbf2_9ce4_8422_2325);
        let mut h = Fnv1a64::new();
        h.write_u8(b'a');
        assert_eq!(h.finish(), 0xaf63_dc4c_8601_ec8c);
    }

    #[test]
    fn negative_zero_and_nan_payloads_hash_canonically() {
        let hash_of = |x: f32| {
            let mut h = Fnv1a64::new();
            h.write_f32(x);
            h.finish()
        };
        assert_eq!(hash_of(-0.0), hash_of(0.0));
        assert_eq!(hash_of(f32::from_bits(0x7fc0_0001)), hash_of(f32::NAN));
        assert_ne!(hash_of(f32::NAN), hash_of(0.0));
        assert_ne!(hash_of(1.0), hash_of(-1.0));
    }

    #[test]
    fn workload_runs_every_pair_and_repeats_bit_for_bit() {
        let first = run_narrow_workload();
        assert_eq!(first.count, WORKLOAD_PAIRS);
        assert_eq!(first, run_narrow_workload());
        let line = first.to_string();
        assert!(line.starts_with("narrow 256 0x"), "{line}");
        assert_eq!(line.len(), "narrow 256 0x".len() + 16, "{line}");
    }
}
