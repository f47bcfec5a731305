#!/usr/bin/env python3
"""Attach a USB/IP device to this machine's vhci-hcd, as `usbip attach` does (the tool is not needed).

    attach.py HOST:PORT BUSID

Connects to the server, imports BUSID (OP_REQ_IMPORT), and hands the socket to the kernel by writing
"<port> <sockfd> <devid> <speed>" to /sys/devices/platform/vhci_hcd.0/attach, on a free port of the root hub the
device's speed needs. Prints the port. Exits 1 with the reason when the import is refused or no port is free.
"""
import socket
import struct
import sys

VHCI = "/sys/devices/platform/vhci_hcd.0"
USB2_PORTS = range(0, 15)
USB3_PORTS = range(15, 30)


def free_port(speed):
    """The first free port of the hub that carries `speed` (5: SuperSpeed), from the status file."""
    wanted = "ss" if speed >= 5 else "hs"
    with open(f"{VHCI}/status") as f:
        for line in f.read().splitlines()[1:]:
            fields = line.split()
            if len(fields) >= 3 and fields[0] == wanted and fields[2] == "004":  # VDEV_ST_NULL
                return int(fields[1])
    sys.exit(f"attach: no free {wanted} port on {VHCI}")


def main():
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    host, port = sys.argv[1].rsplit(":", 1)
    busid = sys.argv[2].encode()
    s = socket.create_connection((host, int(port)), timeout=10)
    s.sendall(struct.pack(">HHI", 0x0111, 0x8003, 0) + busid.ljust(32, b"\0"))
    head = b""
    while len(head) < 8:
        chunk = s.recv(8 - len(head))
        if not chunk:
            sys.exit("attach: the server closed the connection during the import")
        head += chunk
    version, code, status = struct.unpack(">HHI", head)
    if code != 0x0003 or status != 0:
        sys.exit(f"attach: import of {busid.decode()} refused (reply {code:#06x}, status {status})")
    record = b""
    while len(record) < 0x138:
        chunk = s.recv(0x138 - len(record))
        if not chunk:
            sys.exit("attach: truncated device record")
        record += chunk
    busnum, devnum, speed = struct.unpack(">III", record[288:300])
    vhci_port = free_port(speed)
    with open(f"{VHCI}/attach", "w") as f:
        f.write(f"{vhci_port} {s.fileno()} {(busnum << 16) | devnum} {speed}")
    print(vhci_port)


main()
