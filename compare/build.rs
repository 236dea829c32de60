//! Built for wasm32 (wasip1, run under Node: `BENCHMARKS.md`), the benchmark runs on the
//! main thread, which then needs the big stack the native build gets from a thread:
//! 512 MiB, set at link time (wasm's default is 1 MiB).

fn main() {
    if std::env::var("CARGO_CFG_TARGET_ARCH").as_deref() == Ok("wasm32") {
        println!("cargo:rustc-link-arg-bins=-zstack-size=536870912");
    }
    println!("cargo:rerun-if-changed=build.rs");
}
