#!/usr/bin/env bash
# The wgpu renderer's checks on a machine with a real GPU, from binaries built here: such a machine needs neither
# Rust nor a network. Two steps:
#
#   bash tests/gpu/check.sh prepare      # on the build machine: release builds of the tick and render benchmarks
#                                        # and of the CPU/GPU render agreement tests, stripped, into .gpucheck/,
#                                        # plus the Vulkan loader's Debian package (libvulkan1) if apt can fetch it
#   bash tests/gpu/check.sh run [DIR]    # on the GPU machine, in a copy of this checkout with .gpucheck/ in it:
#                                        # runs them and writes gpu-check.log (and a summary) into DIR
#                                        # (default: $OUT if set, else gpucheck-out)
#
# `run` takes about 3-4 minutes. It needs a Vulkan driver for the GPU (NVIDIA's ICD is looked for under
# /usr/local/nvidia and /usr/share/vulkan) and exits non-zero when a step fails or when wgpu draws on a CPU driver
# (lavapipe) instead of a GPU. What it measures is the tracker issue's one-tick goal with the wgpu renderer
# (BENCHMARKS.md, "One tracker tick"): `tick_gpu_160` back to back, on all cores and pinned to one core, and the
# paced ticks.
set -euo pipefail
cd "$(dirname "$0")/../.."
DIR=.gpucheck

prepare() {
    mkdir -p "$DIR"
    local built
    built=$(cargo bench -p eventtrack6d-tests --bench tick --no-run --message-format=json \
        && cargo bench -p eventtrack6d-scene --bench render --no-run --message-format=json \
        && cargo test --release -p eventtrack6d-tests --test render_gpu --no-run --message-format=json)
    for name in tick render render_gpu; do
        local exe
        exe=$(printf '%s\n' "$built" | python3 -c '
import json, sys
name = sys.argv[1]
for line in sys.stdin:
    try:
        m = json.loads(line)
    except ValueError:
        continue
    if m.get("reason") == "compiler-artifact" and m.get("executable") and m["target"]["name"] == name:
        print(m["executable"])
' "$name" | tail -n 1)
        if [ -z "$exe" ]; then
            echo "prepare: cargo built no executable for $name" >&2
            exit 1
        fi
        strip -o "$DIR/$name" "$exe"
        echo "prepare: $DIR/$name from $exe ($(du -h "$DIR/$name" | cut -f1))"
    done
    mkdir -p "$DIR/debs" /tmp/gpucheck-apt/lists/partial
    local apt=(-oAPT::Architecture=amd64 -oAPT::Architectures=amd64 -oDir::State::Lists=/tmp/gpucheck-apt/lists)
    if apt-get "${apt[@]}" update >/dev/null 2>&1 \
        && (cd "$DIR/debs" && apt-get "${apt[@]}" download libvulkan1 >/dev/null 2>&1); then
        echo "prepare: $(ls "$DIR"/debs) (the Vulkan loader, unpacked by run where the GPU machine lacks it)"
    else
        echo "prepare: could not download libvulkan1; run needs the GPU machine's own Vulkan loader" >&2
    fi
    echo "prepare: $(du -sh "$DIR" | cut -f1) in $DIR; next, on the GPU machine: bash tests/gpu/check.sh run"
}

run() {
    local out=${1:-${OUT:-gpucheck-out}}
    for f in tick render render_gpu; do
        [ -x "$DIR/$f" ] || { echo "run: $DIR/$f missing: run 'bash tests/gpu/check.sh prepare' first" >&2; exit 2; }
    done
    mkdir -p "$out"
    local log="$out/gpu-check.log"
    exec > >(tee "$log") 2>&1
    export PATH="$PATH:/usr/sbin:/sbin"
    echo "== gpu-check $(date -u +%FT%TZ) on $(uname -n), $(nproc) cores"
    # grep without -q reads the whole list, so `ldconfig -p` never dies of a closed pipe.
    if ! ldconfig -p 2>/dev/null | grep 'libvulkan\.so\.1' >/dev/null; then
        if [ "$(id -u)" != 0 ]; then
            echo "run: no libvulkan.so.1 (the Vulkan loader) on this machine, and only root may unpack the one in" \
                "$DIR/debs: install libvulkan1, or run as root" >&2
            exit 2
        fi
        for f in "$DIR"/debs/*.deb; do
            if [ -e "$f" ]; then dpkg -x "$f" /; fi
        done
        ldconfig
    fi
    local icd="" f
    for f in /usr/share/vulkan/icd.d/nvidia_icd.json /etc/vulkan/icd.d/nvidia_icd.json; do
        if [ -e "$f" ]; then icd=$f; fi
    done
    if [ -z "${VK_DRIVER_FILES:-}" ] && [ -z "$icd" ] && [ -e /usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json ]; then
        export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
    fi
    echo "VK_DRIVER_FILES=${VK_DRIVER_FILES:-unset, the default search of the loader}"
    nvidia-smi -L 2>/dev/null || echo "(no nvidia-smi)"
    export XDG_RUNTIME_DIR=${XDG_RUNTIME_DIR:-$(mktemp -d)}
    local status=0

    echo "== CPU and wgpu renders agree (tests/tests/render_gpu.rs)"
    "$DIR/render_gpu" --test-threads 1 || status=1

    echo "== renders alone (tracker/scene/benches/render.rs)"
    "$DIR/render" --bench --warm-up-time 1 --measurement-time 3 || status=1

    echo "== one tracker tick (tests/benches/tick.rs), all cores"
    local ticks='^(render_in_)?(depth_)?tick_(cpu|gpu)_160$|^cpu_of_tick_gpu_160$|^paced/(depth_)?tick_(cpu_ahead|gpu)_160_at_120hz$'
    "$DIR/tick" --bench --warm-up-time 1 --measurement-time 3 "$ticks" 2>&1 | tee "$out/tick-all.txt" || status=1

    # The first CPU this process may run on (a container's cpuset need not hold CPU 0).
    local cpu
    cpu=$(awk '/^Cpus_allowed_list/ { split($2, a, /[,-]/); print a[1] }' /proc/self/status 2>/dev/null)
    if command -v taskset >/dev/null && [ -n "$cpu" ]; then
        echo "== one tracker tick, the process pinned to one core (taskset -c $cpu)"
        taskset -c "$cpu" "$DIR/tick" --bench --warm-up-time 1 --measurement-time 3 '^(depth_)?tick_(cpu|gpu)_160$' \
            2>&1 | tee "$out/tick-one.txt" || status=1
    else
        echo "== (no taskset: the ticks pinned to one core are not measured)"
        : > "$out/tick-one.txt"
    fi

    if grep -q 'gpu tick bench skipped' "$log"; then
        echo "FAILED: wgpu found no Vulkan adapter, so no wgpu tick was measured" >&2
        status=1
    elif grep -q '^gpu renderer: .*(rasterised on the CPU)' "$log"; then
        echo "FAILED: wgpu drew on a CPU driver (lavapipe), not a GPU" >&2
        status=1
    fi
    echo "== the one-tick goal with the wgpu renderer: median at most 1 ms"
    : > "$out/goal.txt"
    local where file
    for where in all one; do
        file="$out/tick-$where.txt"
        awk -v where="$where" '$1 ~ /^(depth_)?tick_gpu_160$/ && $2 == "time:" {
            v = $5; u = $6; if (u == "µs" || u == "us") v /= 1000; else if (u == "ns") v /= 1e6; else if (u == "s") v *= 1000
            printf "%-20s %-9s median %.3f ms: %s\n", $1, (where == "all" ? "all cores" : "one core"), v, (v <= 1.0 ? "met" : "NOT met")
        }' "$file" >> "$out/goal.txt"
    done
    cat "$out/goal.txt"
    if ! grep -q 'tick_gpu_160 ' "$out/goal.txt"; then
        echo "FAILED: no wgpu tick median was read from the benchmark output" >&2
        status=1
    fi
    echo "== summary (criterion's median is the middle figure of 'time:')"
    grep -E '^gpu renderer:|^GPU adapter:|^test result:|^[a-z_/0-9]+ *time:|^ +time:|^(paced/)?[a-z_0-9]+$' "$log" \
        | sed -e 's/^ *//' > "$out/summary.txt" || true
    cat "$out/summary.txt"
    echo "== gpu-check exit status $status"
    return "$status"
}

case "${1:-}" in
    prepare) prepare ;;
    run) shift; run "$@" ;;
    *) echo "usage: bash tests/gpu/check.sh prepare | run [DIR]" >&2; exit 2 ;;
esac
