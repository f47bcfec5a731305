#!/usr/bin/env bash
# Run a command inside the test VM (tests/vm/README.md): Debian's stock amd64 kernel under QEMU
# (TCG), the host's root filesystem as the guest's root (read-only 9p under a RAM overlay: the guest
# sees every host file and its writes stay in its memory), usbip-core + vhci-hcd loaded.
#
#   tests/vm/run.sh [options] -- CMD [ARGS...]
#
# Options:
#   --timeout S        kill the VM after S seconds (exit status 124); default 300
#   --env NAME=VALUE   set a variable for CMD (repeatable)
#   --pass-env NAME    copy NAME from this environment, if set (repeatable)
#   --modules A,B      kernel modules to modprobe before CMD (default: usbip-core,vhci-hcd);
#                      e.g. --modules usbip-core,vhci-hcd,uvcvideo,vcan
#   --mem M            guest memory in MiB (default 1024)
#   --smp N            guest CPUs (default 2)
#   --no-net           no network card (default: QEMU user networking, guest 10.0.2.15, host 10.0.2.2)
#   --console          show the guest kernel's console on stderr (default: kept in a temp file,
#                      printed when the VM dies without an exit status)
#
# CMD runs as root in the guest, in this directory, with PATH as here, HOME=/root, TERM=dumb and the
# --env/--pass-env variables (RUST_BACKTRACE and RUST_LOG are passed when set). Its stdout and
# stderr come out on this script's stdout and stderr; the script exits with CMD's status, 124 on
# timeout, 125 when the VM failed before reporting a status.
set -euo pipefail

here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
repo_root="$(cd "${here}/../.." && pwd)"
vm_dir="${repo_root}/target/vm"
kroot="${vm_dir}/kernel/current"

timeout_s=300 mem=1024 smp=2 net=1 console=0 mods="usbip-core,vhci-hcd"
envs=()
for v in RUST_BACKTRACE RUST_LOG; do
    [ -n "${!v+x}" ] && envs+=("${v}=${!v}")
done
while [ $# -gt 0 ]; do
    case "$1" in
        --timeout) timeout_s="$2"; shift 2 ;;
        --env) envs+=("$2"); shift 2 ;;
        --pass-env) [ -n "${!2+x}" ] && envs+=("$2=${!2}"); shift 2 ;;
        --modules) mods="$2"; shift 2 ;;
        --mem) mem="$2"; shift 2 ;;
        --smp) smp="$2"; shift 2 ;;
        --no-net) net=0; shift ;;
        --console) console=1; shift ;;
        --) shift; break ;;
        -h|--help) sed -n '2,/^set -e/p' "${BASH_SOURCE[0]}" | sed '$d; s/^# \{0,1\}//'; exit 0 ;;
        *) echo "vm/run.sh: unknown option $1 (use -- before the command)" >&2; exit 2 ;;
    esac
done
[ $# -gt 0 ] || { echo "usage: vm/run.sh [options] -- CMD [ARGS...]" >&2; exit 2; }

if [ ! -L "${kroot}" ] || ! command -v qemu-system-x86_64 >/dev/null 2>&1; then
    echo "vm/run.sh: run tests/vm/setup.sh first" >&2
    exit 2
fi
kver="$(ls "${kroot}/lib/modules" | head -n 1)"
# Resolve the symlink: the guest sees the same path through 9p.
kdir="$(cd "${kroot}/lib/modules/${kver}" && pwd -P)"
/usr/bin/python3 "${here}/mkinitramfs.py" >/dev/null
# The uncompressed kernel (PVH entry, about 3 s faster under TCG) when mkinitramfs.py made one.
kernel="${vm_dir}/vmlinux"
[ -f "${kernel}" ] || kernel="${kroot}/boot/vmlinuz-${kver}"

# The job script lives on the host's filesystem, under target/vm/jobs.
mkdir -p "${vm_dir}/jobs"
work="$(mktemp -d "${vm_dir}/jobs/job.XXXXXX")"
qemu_pid= cat_out= cat_err= cat_con=
cleanup() {
    [ -n "${qemu_pid}" ] && kill "${qemu_pid}" 2>/dev/null || true
    for p in ${cat_out} ${cat_err} ${cat_con}; do kill "${p}" 2>/dev/null || true; done
    rm -rf "${work}"
}
trap cleanup EXIT
trap 'exit 130' INT TERM

{
    echo "cd $(printf %q "${PWD}") 2>/dev/null || cd /"
    printf 'export %q\n' "PATH=${PATH}" HOME=/root TERM=dumb USER=root LOGNAME=root
    for e in ${envs[@]+"${envs[@]}"}; do printf 'export %q\n' "${e}"; done
    printf 'exec'; printf ' %q' "$@"; printf '\n'
} >"${work}/job.sh"
: >"${work}/status"
: >"${work}/console.log"

# QEMU writes the guest's streams into FIFOs that cat copies to our own stdout/stderr: QEMU
# reopening /proc/self/fd/1 would get a new open file description (own offset), which corrupts
# the output when the caller redirects into a regular file.
mkfifo "${work}/stdout" "${work}/stderr"
cat "${work}/stdout" &
cat_out=$!
cat "${work}/stderr" >&2 &
cat_err=$!
serial="file:${work}/console.log"
cat_con=
if [ "${console}" = 1 ]; then
    mkfifo "${work}/console"
    cat "${work}/console" >&2 &
    cat_con=$!
    serial="file:${work}/console"
fi
netargs=(-nic none)
[ "${net}" = 1 ] && netargs=(-netdev user,id=net0 -device virtio-net-pci,netdev=net0,romfile=)

append="console=ttyS0 loglevel=4 edd=off panic=-1 mitigations=off no_timer_check tsc=reliable"
append+=" 8250.nr_uarts=1 rdinit=/init etvm.job=${work}/job.sh etvm.kdir=${kdir} etvm.mods=${mods}"
[ "${console}" = 1 ] && append+=" etvm.verbose=1"

timeout "${timeout_s}" qemu-system-x86_64 \
    -machine pc,accel=tcg -bios qboot.rom -cpu max -smp "${smp}" -m "${mem}" \
    -nodefaults -no-user-config -nographic -no-reboot \
    -kernel "${kernel}" -initrd "${vm_dir}/initramfs.cpio" -append "${append}" \
    -serial "${serial}" \
    -fsdev local,id=root,path=/,security_model=none,readonly=on,multidevs=remap \
    -device virtio-9p-pci,fsdev=root,mount_tag=hostroot \
    -device virtio-serial-pci \
    -chardev file,id=out,path="${work}/stdout" \
    -device virtserialport,chardev=out,name=etvm.stdout \
    -chardev file,id=err,path="${work}/stderr" \
    -device virtserialport,chardev=err,name=etvm.stderr \
    -chardev file,id=st,path="${work}/status" \
    -device virtserialport,chardev=st,name=etvm.status \
    "${netargs[@]}" </dev/null &
qemu_pid=$!

set +e
wait "${qemu_pid}"
qrc=$?
set -e
qemu_pid=
# The cats see end-of-file once QEMU has closed the FIFOs; if QEMU never opened one (early
# failure), opening it here for writing releases its cat.
release() {
    if [ -n "$1" ] && kill -0 "$1" 2>/dev/null; then
        timeout 5 sh -c ': >"$1"' _ "$2" 2>/dev/null || true
    fi
}
release "${cat_out}" "${work}/stdout"
release "${cat_err}" "${work}/stderr"
release "${cat_con}" "${work}/console"
wait ${cat_out} ${cat_err} ${cat_con}
cat_out= cat_err= cat_con=

if [ "${qrc}" = 124 ]; then
    echo "vm/run.sh: timed out after ${timeout_s} s" >&2
    [ "${console}" = 1 ] || tail -n 30 "${work}/console.log" >&2
    exit 124
fi
status="$(tr -dc '0-9' <"${work}/status")"
if [ -z "${status}" ]; then
    echo "vm/run.sh: the VM stopped (qemu status ${qrc}) without reporting an exit status" >&2
    [ "${console}" = 1 ] || tail -n 40 "${work}/console.log" >&2
    exit 125
fi
exit "${status}"
