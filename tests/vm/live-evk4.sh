#!/usr/bin/env bash
# Runs inside the test VM (tests/vm/run.sh): an emulated EVK4 (hil-sim usb-camera) attached through the guest
# kernel's vhci-hcd, and the live tracker reading it through usbfs, as on a robot PC.
#
#   live-evk4.sh BIN_DIR RECORDING CONFIG SECONDS [usb-camera options...]
#
# Prints `eventtrack6d devices`, the run's summary, then the pose CSV and the camera's statistics between
# `=== poses.csv ===` / `=== camera.json ===` markers (the guest's files do not reach the host).
set -euo pipefail
bin="$1" rec="$2" config="$3" seconds="$4"
shift 4
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"

"${bin}/hil-sim" usb-camera "${rec}" --listen 127.0.0.1:3240 --stats /tmp/camera.json "$@" &
camera=$!
trap 'kill ${camera} 2>/dev/null || true' EXIT
for _ in $(seq 100); do
    (exec 3<>/dev/tcp/127.0.0.1/3240) 2>/dev/null && break
    sleep 0.1
done
python3 "${here}/attach.py" 127.0.0.1:3240 1-1 >/dev/null
for _ in $(seq 100); do
    grep -qs 04b4 /sys/bus/usb/devices/*/idVendor && break
    sleep 0.1
done
"${bin}/eventtrack6d" devices
status=0
"${bin}/eventtrack6d" run --config "${config}" --seconds "${seconds}" --no-accuracy || status=$?
echo "=== poses.csv ==="
cat /tmp/live-out/poses.csv 2>/dev/null || true
echo "=== camera.json ==="
sleep 0.2
cat /tmp/camera.json 2>/dev/null || true
exit "${status}"
