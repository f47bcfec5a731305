#!/usr/bin/env bash
# Runs inside the test VM (tests/vm/run.sh): an emulated EVK4 (hil-sim usb-camera) attached through the guest
# kernel's vhci-hcd, and the live tracker reading it through usbfs, as on a robot PC.
#
#   live-evk4.sh BIN_DIR RECORDING CONFIG SECONDS [usb-camera options...]
#
# Prints `eventtrack6d devices`, the run's summary, then the pose CSV and the camera's statistics between
# `=== poses.csv ===` / `=== camera.json ===` markers (the guest's files do not reach the host). With REPLUG=1 in
# the environment, the camera is attached again after it unplugs (as a user plugs the cable back in). With
# MODE=record, `eventtrack6d record` captures the session instead and `eventtrack6d track` tracks the recording.
# With STOP_WHEN_FINISHED=1, the run is stopped (Ctrl-C) two seconds after the camera has sent the whole recording.
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
if [ "${REPLUG:-0}" = 1 ]; then
    (
        while grep -qs 04b4 /sys/bus/usb/devices/*/idVendor; do sleep 0.05; done
        echo "replug: the camera is gone; attaching it again in 0.5 s" >&2
        sleep 0.5
        python3 "${here}/attach.py" 127.0.0.1:3240 1-1 >/dev/null
    ) &
fi
if [ "${STOP_WHEN_FINISHED:-0}" = 1 ]; then
    (
        until grep -qs '"finished": true' /tmp/camera.json; do sleep 0.2; done
        sleep 2
        pkill -INT -f "eventtrack6d run --config" || true
    ) &
fi
status=0
if [ "${MODE:-run}" = record ]; then
    # Record the session, then track the recording offline (inside the guest: its files stay here).
    "${bin}/eventtrack6d" record --config "${config}" --out /tmp/recorded --seconds "${seconds}" || status=$?
    [ "${status}" = 0 ] && { "${bin}/eventtrack6d" track /tmp/recorded --out /tmp/live-out.csv || status=$?; }
    echo "=== poses.csv ==="
    cat /tmp/live-out.csv 2>/dev/null || true
else
    "${bin}/eventtrack6d" run --config "${config}" --seconds "${seconds}" --no-accuracy || status=$?
    echo "=== poses.csv ==="
    cat /tmp/live-out/poses.csv 2>/dev/null || true
fi
echo "=== camera.json ==="
sleep 0.2
cat /tmp/camera.json 2>/dev/null || true
exit "${status}"
