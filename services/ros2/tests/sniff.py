#!/usr/bin/env python3
"""Counts the packets crossing one network interface, by direction and kind
(udp, icmp, igmp, tcp, arp, ipv6, ...), and the first destinations of the
outgoing UDP ones, until STOPFILE exists or SECONDS have passed; prints one
JSON object. For phri-ros2's localhost test (tests/localhost.rs), run in
the cell's network namespace: an AF_PACKET socket sees what the kernel
sends and receives on the interface, whoever sent it.

  sniff.py IFACE STOPFILE SECONDS
"""
import errno
import json
import os
import socket
import sys
import time

KINDS = {1: "icmp", 2: "igmp", 6: "tcp", 17: "udp"}


def main():
    iface, stopfile, seconds = sys.argv[1], sys.argv[2], float(sys.argv[3])
    s = socket.socket(socket.AF_PACKET, socket.SOCK_RAW, socket.ntohs(0x0003))
    s.bind((iface, 0))
    s.settimeout(0.05)
    counts = {"out": {}, "in": {}}
    udp_out = []
    end = time.monotonic() + seconds
    print("sniffing", file=sys.stderr, flush=True)
    while time.monotonic() < end and not os.path.exists(stopfile):
        try:
            data, addr = s.recvfrom(65535)
        except socket.timeout:
            continue
        except OSError as e:
            # the interface went up after the socket was bound to it
            if e.errno == errno.ENETDOWN:
                continue
            raise
        direction = "out" if addr[2] == socket.PACKET_OUTGOING else "in"
        proto = addr[1]
        if proto == 0x0800 and len(data) >= 14 + 20:
            kind = KINDS.get(data[14 + 9], "ipv4")
            if kind == "udp" and direction == "out" and len(udp_out) < 10:
                ihl = (data[14] & 0x0F) * 4
                dst = ".".join(str(b) for b in data[14 + 16:14 + 20])
                port = int.from_bytes(data[14 + ihl + 2:14 + ihl + 4], "big")
                udp_out.append(f"{dst}:{port}")
        elif proto == 0x0806:
            kind = "arp"
        elif proto == 0x86DD:
            kind = "ipv6"
        else:
            kind = hex(proto)
        counts[direction][kind] = counts[direction].get(kind, 0) + 1
    counts["udp_out_to"] = udp_out
    print(json.dumps(counts), flush=True)


if __name__ == "__main__":
    main()
