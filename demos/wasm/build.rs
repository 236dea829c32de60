//! The benchmark's world (`src/bin/bench.rs`, about 20 MB) is built on the stack before
//! it is boxed: its wasm32 build gets a 64 MiB stack (wasm's default is 1 MiB). The
//! demo's own binary keeps the default.

fn main() {
    if std::env::var("CARGO_CFG_TARGET_ARCH").as_deref() == Ok("wasm32") {
        println!("cargo:rustc-link-arg-bin=bench=-zstack-size=67108864");
    }
    println!("cargo:rerun-if-changed=build.rs");
}
