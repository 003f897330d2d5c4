"""ROS 2 CDR encoding of the one sensor message the robot helper sends: sensor_msgs/PointCloud2 with FLOAT32 x, y,
z (the layout of ``encode_point_cloud2_xyz`` in ``proto/src/ros/point_cloud2/mod.rs``).

Plain little-endian CDR (XCDR1) with its 4-byte encapsulation header ``00 01 00 00``; a primitive of n bytes is
aligned to n counted from the end of the header; a string is a u32 length including the NUL, the bytes and the
NUL; a sequence is a u32 count and its elements.
"""

from __future__ import annotations

import math
import struct
from typing import Iterable, Sequence

FLOAT32 = 7
"""sensor_msgs/PointField datatype code of a 32-bit float."""

CDR_LE_HEADER = b"\x00\x01\x00\x00"


class CdrWriter:
    """Little-endian CDR body writer; :meth:`finish` prepends the encapsulation header."""

    def __init__(self) -> None:
        self._buf = bytearray()

    def _align(self, n: int) -> None:
        self._buf.extend(b"\x00" * (-len(self._buf) % n))

    def u8(self, v: int) -> None:
        self._buf.append(v & 0xFF)

    def bool(self, v: bool) -> None:
        self._buf.append(1 if v else 0)

    def u32(self, v: int) -> None:
        self._align(4)
        self._buf.extend(struct.pack("<I", v))

    def i32(self, v: int) -> None:
        self._align(4)
        self._buf.extend(struct.pack("<i", v))

    def string(self, s: str) -> None:
        raw = s.encode("utf-8")
        self.u32(len(raw) + 1)
        self._buf.extend(raw)
        self._buf.append(0)

    def raw(self, data: bytes) -> None:
        self._buf.extend(data)

    def finish(self) -> bytes:
        return CDR_LE_HEADER + bytes(self._buf)


def split_stamp(stamp_s: float) -> "tuple[int, int]":
    """A builtin_interfaces/Time ``(sec, nanosec)`` of a stamp in seconds (nanosec in [0, 1e9))."""
    ns = int(round(stamp_s * 1e9))
    sec, nanosec = divmod(ns, 1_000_000_000)
    return sec, nanosec


def encode_point_cloud2_xyz(points: Iterable[Sequence[float]], frame_id: str = "map", stamp_s: float = 0.0) -> bytes:
    """An unorganised PointCloud2 (height 1) of ``points`` ``(x, y, z)`` in metres in ``frame_id``, stamped
    ``stamp_s`` seconds; FLOAT32 fields x, y, z at offsets 0, 4, 8, point_step 12, little-endian; ``is_dense``
    when every coordinate is finite."""
    pts = [(float(p[0]), float(p[1]), float(p[2])) for p in points]
    sec, nanosec = split_stamp(stamp_s)
    w = CdrWriter()
    w.i32(sec)
    w.u32(nanosec)
    w.string(frame_id)
    w.u32(1)  # height
    w.u32(len(pts))  # width
    w.u32(3)  # fields
    for i, name in enumerate("xyz"):
        w.string(name)
        w.u32(4 * i)  # offset
        w.u8(FLOAT32)
        w.u32(1)  # count
    w.bool(False)  # is_bigendian
    w.u32(12)  # point_step
    w.u32(12 * len(pts))  # row_step
    w.u32(12 * len(pts))  # data: uint8[] count, then the bytes (4-aligned after the count)
    w.raw(b"".join(struct.pack("<fff", *p) for p in pts))
    w.bool(all(math.isfinite(v) for p in pts for v in p))
    return w.finish()
