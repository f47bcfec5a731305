#!/usr/bin/env bash
# Install what the USB/IP test VM needs (tests/vm/README.md, DESIGN section 10).
#
# - qemu-system-x86 10 from Debian bookworm-backports (same source entry as .ci/firmware.sh);
# - Debian's stock amd64 kernel (bookworm linux-image-amd64, i.e. linux-image-6.1.0-N-amd64),
#   fetched with `apt-get download` and unpacked with `dpkg-deb -x` into target/vm/kernel/: nothing
#   goes into /boot or /lib/modules;
# - busybox-static, unpacked the same way (the VM's initramfs uses it as /init's shell);
# - the initramfs itself (tests/vm/mkinitramfs.py), rebuilt only when its inputs change.
#
# Idempotent and non-interactive: a second run downloads and installs nothing. Runs as root (CI
# does); uses sudo only when it is not root and sudo exists.
#   ETVM_KERNEL_PKG=linux-image-6.12...-amd64  picks another kernel package (default: the one
#                                               bookworm's linux-image-amd64 depends on).
set -euo pipefail

here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
repo_root="$(cd "${here}/../.." && pwd)"
vm_dir="${repo_root}/target/vm"
dl_dir="${vm_dir}/downloads"

# as_root, install_from_backports, ensure_qemu10.
source "${repo_root}/.ci/debian.sh"

apt_updated=0
apt_update() {
    if [ "${apt_updated}" -eq 0 ]; then
        as_root env DEBIAN_FRONTEND=noninteractive apt-get update -q
        apt_updated=1
    fi
}

ensure_qemu10 qemu-system-x86_64 qemu-system-x86 vm/setup.sh

# --- Debian packages unpacked into target/vm (kernel, busybox-static) ---------------------------
# unpack PACKAGE DEST: apt-get download + dpkg-deb -x, once (DEST/.done records the package file).
unpack() {
    local pkg="$1" dest="$2" deb
    if [ -f "${dest}/.done" ]; then
        echo "vm/setup.sh: have ${pkg} ($(cat "${dest}/.done"))"
        return 0
    fi
    mkdir -p "${dl_dir}"
    deb="$(ls "${dl_dir}/${pkg}"_*.deb 2>/dev/null | head -n 1 || true)"
    if [ -z "${deb}" ]; then
        echo "vm/setup.sh: downloading ${pkg}"
        apt_update
        (cd "${dl_dir}" && apt-get download -q "${pkg}")
        deb="$(ls "${dl_dir}/${pkg}"_*.deb | head -n 1)"
    fi
    echo "vm/setup.sh: unpacking $(basename "${deb}") into ${dest}"
    rm -rf "${dest}.tmp"
    mkdir -p "${dest}.tmp"
    dpkg-deb -x "${deb}" "${dest}.tmp"
    basename "${deb}" >"${dest}.tmp/.done"
    rm -rf "${dest}"
    mv "${dest}.tmp" "${dest}"
    rm -f "${deb}"
}

kpkg="${ETVM_KERNEL_PKG:-}"
if [ -z "${kpkg}" ]; then
    # The versioned package bookworm's linux-image-amd64 metapackage points at.
    if [ -L "${vm_dir}/kernel/current" ]; then
        kpkg="$(basename "$(readlink "${vm_dir}/kernel/current")")"
    else
        apt_update
        kpkg="$(apt-cache depends linux-image-amd64 | awk '/Depends: linux-image-[0-9]/ {print $2; exit}')"
    fi
fi
unpack "${kpkg}" "${vm_dir}/kernel/${kpkg}"
ln -sfn "${kpkg}" "${vm_dir}/kernel/current"
unpack busybox-static "${vm_dir}/busybox"

kver="$(ls "${vm_dir}/kernel/current/lib/modules" | head -n 1)"
echo "vm/setup.sh: kernel ${kver}: ${vm_dir}/kernel/current/boot/vmlinuz-${kver}"

# The package's postinst would run depmod; we do it on the unpacked tree (the guest's modprobe and
# mkinitramfs.py read modules.dep). depmod comes from kmod.
if ! command -v depmod >/dev/null 2>&1 && [ ! -x /sbin/depmod ]; then
    echo "vm/setup.sh: installing kmod (depmod)"
    apt_update
    as_root env DEBIAN_FRONTEND=noninteractive apt-get install -y -q --no-install-recommends kmod
fi
if [ ! -s "${vm_dir}/kernel/current/lib/modules/${kver}/modules.dep" ]; then
    echo "vm/setup.sh: depmod ${kver}"
    PATH="${PATH}:/sbin:/usr/sbin" depmod -b "${vm_dir}/kernel/current" "${kver}"
fi

# --- initramfs ----------------------------------------------------------------------------------
/usr/bin/python3 "${here}/mkinitramfs.py"
echo "vm/setup.sh: done"
