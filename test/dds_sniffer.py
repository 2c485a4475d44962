"""Counts DDS packets (UDP datagrams carrying RTPS) on any interface but lo.

A packet socket (AF_PACKET, root only) sees every frame of every interface; a thread reads
them while a test runs. Every RTPS message starts with the protocol id b'RTPS' (DDSI-RTPS
§9.4.1), so a UDP datagram whose payload starts with it on a non-loopback interface is DDS
traffic that left the machine's loopback. The ports alone cannot tell: RTPS uses 7400 +
250·domain + offsets, a range that holds most ephemeral ports too, and other traffic of
the host (package downloads, name lookups from source port 46935) is not DDS.
"""

from __future__ import annotations

import socket
import struct
import threading

ETH_P_ALL = 0x0003
RTPS = b'RTPS'


def _udp_ports(frame: bytes) -> tuple[int, int] | None:
    """The UDP ports of an RTPS datagram, None for any other frame."""
    if len(frame) < 14:
        return None
    ethertype = struct.unpack_from('!H', frame, 12)[0]
    if ethertype == 0x0800 and len(frame) >= 34:  # IPv4
        ihl = (frame[14] & 0x0F) * 4
        if frame[23] != 17:
            return None
        off = 14 + ihl
    elif ethertype == 0x86DD and len(frame) >= 62:  # IPv6 (no extension headers)
        if frame[20] != 17:
            return None
        off = 54
    else:
        return None
    if frame[off + 8 : off + 12] != RTPS:  # after the 8-byte UDP header
        return None
    return struct.unpack_from('!HH', frame, off)


class DdsSniffer:
    """with DdsSniffer() as s: ...; s.count — DDS packets seen off loopback."""

    def __init__(self) -> None:
        self.count = 0
        self.examples: list[str] = []
        self._stop = threading.Event()

    def __enter__(self) -> DdsSniffer:
        self._sock = socket.socket(socket.AF_PACKET, socket.SOCK_RAW, socket.ntohs(ETH_P_ALL))
        self._sock.settimeout(0.2)
        self._thread = threading.Thread(target=self._run, daemon=True)
        self._thread.start()
        return self

    def _run(self) -> None:
        while not self._stop.is_set():
            try:
                frame, address = self._sock.recvfrom(65535)
            except TimeoutError:
                continue
            except OSError:
                return
            if address[0] == 'lo':
                continue
            ports = _udp_ports(frame)
            if ports:
                self.count += 1
                if len(self.examples) < 5:
                    self.examples.append(f'{address[0]}: udp {ports[0]} -> {ports[1]}')

    def __exit__(self, *exc: object) -> None:
        self._stop.set()
        self._thread.join(timeout=2)
        self._sock.close()
