//! Running the `eventtrack6d` binary from the CLI tests.

use std::process::{Command, Output};

/// Runs `eventtrack6d` with `args` and returns what it did.
pub fn eventtrack6d(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_eventtrack6d"))
        .args(args)
        .output()
        .unwrap()
}

/// Runs `eventtrack6d` with `args` and checks that it fails, without a panic, saying `needle` on stderr.
pub fn fails_with(args: &[&str], needle: &str) {
    let out = eventtrack6d(args);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "{args:?} succeeded");
    assert!(!stderr.contains("panicked"), "{args:?} panicked: {stderr}");
    assert!(
        stderr.contains(needle),
        "{args:?}: expected `{needle}` in: {stderr}"
    );
}
