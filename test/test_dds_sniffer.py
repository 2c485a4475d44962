"""The loopback check's sniffer counts RTPS datagrams and nothing else (no root needed)."""

from __future__ import annotations

import struct

from test.dds_sniffer import _udp_ports


def _ipv4_udp(src: int, dst: int, payload: bytes) -> bytes:
    ethernet = b'\x00' * 12 + struct.pack('!H', 0x0800)
    ip = bytes([0x45]) + b'\x00' * 8 + bytes([17]) + b'\x00' * 10  # IHL 5, protocol UDP
    udp = struct.pack('!HHHH', src, dst, 8 + len(payload), 0)
    return ethernet + ip + udp + payload


def test_an_rtps_datagram_is_dds_traffic() -> None:
    frame = _ipv4_udp(7410, 7412, b'RTPS\x02\x03' + b'\x00' * 14)
    assert _udp_ports(frame) == (7410, 7412)


def test_a_name_lookup_from_a_port_in_the_rtps_range_is_not() -> None:
    assert _udp_ports(_ipv4_udp(46935, 53, b'\x12\x34\x01\x00' + b'\x00' * 20)) is None
    assert _udp_ports(_ipv4_udp(7400, 7401, b'')) is None
