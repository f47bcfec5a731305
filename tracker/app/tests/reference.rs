//! docs/commands.md is the command reference `eventtrack6d reference` renders from the command line's own doc
//! comments. This test fails when the two differ, so the document cannot drift from `--help`. After changing a
//! command or its doc comments, regenerate the file with `ET6D_WRITE_DOCS=1 cargo test -p eventtrack6d --test
//! reference`.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::process::Command;

#[test]
fn docs_commands_md_is_the_generated_reference() {
    let out = Command::new(env!("CARGO_BIN_EXE_eventtrack6d"))
        .arg("reference")
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "eventtrack6d reference failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let generated = String::from_utf8(out.stdout).unwrap();
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../../docs/commands.md");
    if std::env::var_os("ET6D_WRITE_DOCS").is_some() {
        std::fs::write(path, &generated).unwrap();
    }
    let shipped =
        std::fs::read_to_string(path).unwrap_or_else(|e| format!("(cannot read it: {e})\n"));
    if shipped != generated {
        let line = shipped
            .lines()
            .zip(generated.lines())
            .position(|(a, b)| a != b)
            .unwrap_or_else(|| shipped.lines().count().min(generated.lines().count()))
            + 1;
        panic!(
            "docs/commands.md differs from `eventtrack6d reference` (first at line {line}); after changing a command \
             or its doc comments, regenerate it with `ET6D_WRITE_DOCS=1 cargo test -p eventtrack6d --test reference`"
        );
    }
}

#[test]
fn the_reference_command_is_hidden_from_help() {
    let out = Command::new(env!("CARGO_BIN_EXE_eventtrack6d"))
        .arg("--help")
        .output()
        .unwrap();
    let help = String::from_utf8(out.stdout).unwrap();
    assert!(help.contains("demo"), "{help}");
    assert!(!help.contains("reference"), "{help}");
}
