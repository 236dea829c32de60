//! Runs the newcomer examples (`examples/*.rs`) and checks what they print, so they keep
//! working as the crate changes: each also asserts its own outcome and would exit
//! non-zero. (`rollback_ggrs` is run by `tests/rollback_ggrs.rs`; `showcase` takes longer
//! and is left to the README's command.)
//!
//! `cargo test` builds the examples before it runs the tests, next to the test binaries;
//! a run that did not build them (`cargo test --test examples`) skips with a message.

use std::path::PathBuf;
use std::process::Command;

/// Run the example `name` and return what it printed, or `None` when it was not built.
fn run(name: &str) -> Option<String> {
    // The test runs from target/<profile>/deps/; examples are in target/<profile>/examples/.
    let exe = std::env::current_exe().ok()?;
    let dir: PathBuf = exe.parent()?.parent()?.join("examples");
    let path = dir.join(format!("{name}{}", std::env::consts::EXE_SUFFIX));
    if !path.exists() {
        eprintln!(
            "SKIPPED: example {name} not built at {} (run `cargo test`)",
            path.display()
        );
        return None;
    }
    let out = Command::new(&path).output().expect("the example starts");
    let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
    assert!(
        out.status.success(),
        "example {name} failed ({}):\n{stdout}\n{}",
        out.status,
        String::from_utf8_lossy(&out.stderr)
    );
    Some(stdout)
}

/// Run `name` and check that each of `expected` appears in its output.
fn check(name: &str, expected: &[&str]) {
    if let Some(out) = run(name) {
        for e in expected {
            assert!(
                out.contains(e),
                "example {name} did not print {e:?}:\n{out}"
            );
        }
    }
}

#[test]
fn ball() {
    check(
        "ball",
        &["(asleep)", "the ball rests with its centre at y = 0.50"],
    );
}

#[test]
fn stack() {
    check("stack", &["0 awake", "of 10 boxes moved more than 0.5 m"]);
}

#[test]
fn bullet() {
    check(
        "bullet",
        &[
            "== continuous collision on ==",
            "walls passed: 0 of 5",
            "== continuous collision off ==",
            "walls passed: 5 of 5",
        ],
    );
}

#[test]
fn events() {
    check(
        "events",
        &[
            "ball entered the sensor",
            "ball left the sensor",
            "ground and ball touch",
        ],
    );
}

#[test]
fn queries() {
    check(
        "queries",
        &[
            "line of sight: crate 1 at 1.50 m",
            "a 9 m laser passes through 4 bodies",
            "(scenery only): the ground",
        ],
    );
}

#[test]
fn timestep() {
    check("timestep", &["dropped", "carried over"]);
}

#[test]
fn big_world() {
    check("big_world", &["1001 bodies", "main thread stack"]);
}
