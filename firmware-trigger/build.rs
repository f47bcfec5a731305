//! Linker set-up for the cross-built binaries: picks the memory map of the selected firmware
//! variant and passes cortex-m-rt's (and for the board, defmt's) linker scripts. Host builds of
//! the schedule core need nothing from here.

use std::env;
use std::fs;
use std::path::PathBuf;

fn main() {
    println!("cargo::rerun-if-changed=build.rs");
    println!("cargo::rerun-if-changed=memory");
    if env::var("CARGO_CFG_TARGET_OS").as_deref() != Ok("none") {
        return;
    }
    let board = env::var_os("CARGO_FEATURE_BOARD").is_some();
    let qemu = env::var_os("CARGO_FEATURE_QEMU").is_some();
    let memory = match (board, qemu) {
        (true, false) => "memory/stm32f401re.x",
        (false, true) => "memory/mps2-an386.x",
        (true, true) => {
            println!(
                "cargo::error=features `board` and `qemu` select different memory maps: build one at a time"
            );
            return;
        }
        (false, false) => {
            println!(
                "cargo::error=cross-building firmware-trigger needs `--features board` (Nucleo-F401RE) or `--features qemu` (mps2-an386)"
            );
            return;
        }
    };
    let Some(out) = env::var_os("OUT_DIR").map(PathBuf::from) else {
        println!("cargo::error=OUT_DIR is not set");
        return;
    };
    if let Err(e) = fs::copy(memory, out.join("memory.x")) {
        println!("cargo::error=cannot copy {memory} to OUT_DIR: {e}");
        return;
    }
    println!("cargo::rustc-link-search={}", out.display());
    println!("cargo::rustc-link-arg-bins=--nmagic");
    println!("cargo::rustc-link-arg-bins=-Tlink.x");
    if board {
        println!("cargo::rustc-link-arg-bins=-Tdefmt.x");
    }
}
