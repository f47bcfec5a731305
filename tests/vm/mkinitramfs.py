#!/usr/bin/env python3
"""Build the test VM's initramfs (tests/vm/README.md).

Contents: busybox-static as /bin/busybox, tests/vm/init as /init, and the few kernel modules the
guest needs before it can reach the host's filesystem (virtio PCI, 9p over virtio, virtio console,
virtio net, overlayfs), with their dependencies from modules.dep, in load order
(/modules/order). Everything else (usbip-core, vhci-hcd, ...) is loaded later with modprobe from
the unpacked module tree, which the guest sees through 9p.

Writes target/vm/initramfs.cpio (uncompressed newc: the kernel unpacks it faster than a
compressed one under TCG). Rebuilds only when an input is newer than the output, or with --force.
"""
import os
import stat
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(os.path.dirname(HERE))
VM = os.path.join(REPO, "target", "vm")
KROOT = os.path.join(VM, "kernel", "current")
BUSYBOX = os.path.join(VM, "busybox", "bin", "busybox")
INIT = os.path.join(HERE, "init")
OUT = os.path.join(VM, "initramfs.cpio")
VMLINUX = os.path.join(VM, "vmlinux")

BOOT_MODULES = ["virtio_pci", "virtio_console", "9pnet_virtio", "9p", "overlay", "virtio_net"]


def kernel_version():
    return sorted(os.listdir(os.path.join(KROOT, "lib", "modules")))[0]


def load_order(moddir):
    deps = {}
    by_name = {}
    with open(os.path.join(moddir, "modules.dep")) as f:
        for line in f:
            path, _, rest = line.partition(":")
            deps[path] = rest.split()
            name = os.path.basename(path).split(".ko")[0].replace("-", "_")
            by_name[name] = path
    order = []

    def visit(path):
        if path in order:
            return
        for d in deps[path]:
            visit(d)
        order.append(path)

    for m in BOOT_MODULES:
        if m not in by_name:
            sys.exit(f"mkinitramfs: module {m} not found in {moddir}/modules.dep")
        visit(by_name[m])
    return order


class Cpio:
    def __init__(self, f):
        self.f = f
        self.ino = 1

    def _entry(self, name, mode, data=b"", nlink=1):
        name_b = name.encode() + b"\0"
        hdr = "070701" + "".join(
            f"{v:08X}"
            for v in (self.ino, mode, 0, 0, nlink, 0, len(data), 0, 0, 0, 0, len(name_b), 0)
        )
        self.ino += 1
        self.f.write(hdr.encode() + name_b)
        self.f.write(b"\0" * ((4 - (110 + len(name_b)) % 4) % 4))
        self.f.write(data)
        self.f.write(b"\0" * ((4 - len(data) % 4) % 4))

    def dir(self, name):
        self._entry(name, stat.S_IFDIR | 0o755, nlink=2)

    def file(self, name, data, perm=0o644):
        self._entry(name, stat.S_IFREG | perm, data)

    def symlink(self, name, target):
        self._entry(name, stat.S_IFLNK | 0o777, target.encode())

    def trailer(self):
        self._entry("TRAILER!!!", 0)


def extract_vmlinux(kver):
    """The uncompressed ELF kernel inside vmlinuz: QEMU boots it directly through its PVH entry
    point (CONFIG_PVH=y), which skips the xz decompression that costs about 3 s under TCG."""
    src = os.path.join(KROOT, "boot", "vmlinuz-" + kver)
    if os.path.exists(VMLINUX) and os.path.getmtime(VMLINUX) >= os.path.getmtime(src):
        return
    import lzma
    with open(src, "rb") as f:
        data = f.read()
    i = data.find(b"\xfd7zXZ\x00")
    if i < 0:
        print("mkinitramfs: no xz payload in vmlinuz; run.sh will boot vmlinuz")
        return
    elf = lzma.LZMADecompressor().decompress(data[i:])
    if elf[:4] != b"\x7fELF":
        print("mkinitramfs: xz payload is not an ELF; run.sh will boot vmlinuz")
        return
    with open(VMLINUX + ".tmp", "wb") as f:
        f.write(elf)
    os.replace(VMLINUX + ".tmp", VMLINUX)
    print(f"mkinitramfs: wrote {VMLINUX} ({len(elf) // 1048576} MiB)")


def main():
    kver = kernel_version()
    extract_vmlinux(kver)
    moddir = os.path.join(KROOT, "lib", "modules", kver)
    inputs = [INIT, BUSYBOX, __file__, os.path.join(moddir, "modules.dep")]
    if (
        "--force" not in sys.argv
        and os.path.exists(OUT)
        and all(os.path.getmtime(p) <= os.path.getmtime(OUT) for p in inputs)
    ):
        print(f"mkinitramfs: {OUT} is up to date")
        return
    order = load_order(moddir)
    tmp = OUT + ".tmp"
    with open(tmp, "wb") as f:
        c = Cpio(f)
        for d in ["bin", "dev", "etc", "lib", "lib/modules", "lib/modules/" + kver, "proc", "sys",
                  "tmp", "run", "lower", "upper", "newroot", "modules"]:
            c.dir(d)
        with open(BUSYBOX, "rb") as b:
            c.file("bin/busybox", b.read(), 0o755)
        c.symlink("bin/sh", "busybox")
        with open(INIT, "rb") as i:
            c.file("init", i.read(), 0o755)
        names = []
        for rel in order:
            with open(os.path.join(moddir, rel), "rb") as m:
                data = m.read()
            name = os.path.basename(rel)
            if name.endswith(".xz") or name.endswith(".zst"):
                sys.exit(f"mkinitramfs: compressed module {name} is not supported")
            c.file("modules/" + name, data)
            names.append(name)
        c.file("modules/order", ("\n".join(names) + "\n").encode())
        c.trailer()
    os.replace(tmp, OUT)
    print(f"mkinitramfs: wrote {OUT} ({os.path.getsize(OUT) // 1024} KiB; kernel {kver}; "
          f"boot modules: {' '.join(n.split('.ko')[0] for n in names)})")


if __name__ == "__main__":
    main()
