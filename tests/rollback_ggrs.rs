//! Runs the GGRS rollback example (`examples/rollback_ggrs.rs`): a `SyncTestSession` and
//! two `P2PSession` peers over a lossy in-memory network must agree with a plain run on
//! every confirmed frame, and a deliberate desync must be caught.

#[allow(dead_code)]
#[path = "../examples/rollback_ggrs.rs"]
mod rollback_ggrs;

#[test]
fn sync_test_and_two_lossy_peers_agree_with_the_plain_run() {
    if let Err(e) = rollback_ggrs::run(false) {
        panic!("{e}");
    }
}

#[test]
fn a_desync_on_one_peer_is_detected_by_ggrs() {
    match rollback_ggrs::run(true) {
        Ok(()) => panic!("a nudged peer went unnoticed"),
        Err(e) => assert!(
            e.to_string().contains("GGRS detected"),
            "expected GGRS's desync detection, got: {e}"
        ),
    }
}
