#!/usr/bin/env bash
# Install what the trigger firmware needs and cross-build it (DESIGN section 8, issue 7).
#
# - qemu-system-arm 10 from Debian bookworm-backports (bookworm's 7.2 cannot be installed beside the
#   machine's qemu-utils 10, and it loses SysTick interrupts when the core sleeps in WFI);
# - the rustup target thumbv7em-none-eabihf;
# - cross-builds of the board binary (Nucleo-F401RE) and the QEMU variant (mps2-an386).
#
# Idempotent and non-interactive: a second run installs nothing and only rebuilds (a no-op when
# nothing changed). Runs as root (CI does); uses sudo only when it is not root and sudo exists.
set -euo pipefail

repo_root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
target=thumbv7em-none-eabihf
# Same directory the QEMU test in firmware-trigger/tests/ builds into, so CI compiles once.
fw_target_dir="${repo_root}/target/firmware"

# as_root, install_from_backports, ensure_qemu10.
source "${repo_root}/.ci/debian.sh"

ensure_qemu10 qemu-system-arm qemu-system-arm firmware.sh

# Read the list first: grep -q closing the pipe early would fail the pipeline under pipefail.
installed_targets="$(rustup target list --installed)"
if ! grep -qx "${target}" <<<"${installed_targets}"; then
    echo "firmware.sh: adding rustup target ${target}"
    rustup target add "${target}"
fi

cd "${repo_root}/firmware-trigger"
echo "firmware.sh: cross-building the board binary (Nucleo-F401RE)"
CARGO_TARGET_DIR="${fw_target_dir}" cargo build --release --target "${target}" \
    --no-default-features --features board --bin trigger-board
echo "firmware.sh: cross-building the QEMU variant (mps2-an386)"
CARGO_TARGET_DIR="${fw_target_dir}" cargo build --release --target "${target}" \
    --no-default-features --features qemu --bin trigger-qemu
echo "firmware.sh: done"
