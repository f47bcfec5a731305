#!/usr/bin/env bash
# Runs inside the test VM (tests/vm/run.sh): the live camera's data path at full speed. The emulated EVK4
# (hil-sim usb-camera, as fast as the host reads) streams RECORDING through the guest kernel's vhci-hcd, and
# `eventtrack6d record` (no tracker) writes it, printing the bytes, events, drops and throughput.
#
#   record-throughput.sh BIN_DIR RECORDING SECONDS [RING_MIB]
set -euo pipefail
bin="$1" rec="$2" seconds="$3" ring="${4:-1024}"
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
printf '[source]\nkind = "live"\n[live]\nevent_camera = "evk4"\ndepth_camera = "recording"\ndepth_recording = "%s"\nring_mib = %s\n' \
    "${rec}" "${ring}" >/tmp/record-throughput.toml
"${bin}/hil-sim" usb-camera "${rec}" --pace fast --listen 127.0.0.1:3240 &
camera=$!
trap 'kill ${camera} 2>/dev/null || true' EXIT
for _ in $(seq 300); do (exec 3<>/dev/tcp/127.0.0.1/3240) 2>/dev/null && break; sleep 0.1; done
python3 "${here}/attach.py" 127.0.0.1:3240 1-1 >/dev/null
for _ in $(seq 100); do grep -qs 04b4 /sys/bus/usb/devices/*/idVendor && break; sleep 0.1; done
"${bin}/eventtrack6d" record --config /tmp/record-throughput.toml --out /tmp/recorded --seconds "${seconds}"
