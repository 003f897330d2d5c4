"""Converts an MRPT rawlog of 2-D laser scans and odometry (the "actions-observations" format: a sensory frame
of CObservation2DRangeScan, then a CActionCollection holding the CActionRobotMovement2D odometry increment that
led to the next one) into a ROS 2 bag in rosbag2's MCAP storage: /robot1/odom (nav_msgs/msg/Odometry, frame
"odom", the increments integrated from the origin, stamped with each scan's time) and /robot1/scan
(sensor_msgs/msg/LaserScan, frame "laser": beams with no return are +inf). Written with the reference writer
(mcap-ros2-support), the message definitions read from the project's msg_defs folder.

Made for the real logs Debian's `mrpt-common` ships, e.g. "2006-01ENE-21-SENA_Telecom Faculty_one_loop_only
.rawlog" (225 scans of a SICK LMS, 361 beams over 180°, 59 s, a loop through a faculty building). `--laps N`
drives the loop N times: each lap is the same scans and poses re-stamped after the previous one (a robot
localised in its map patrolling its round), so a 4 000-scan replay of real data is `--laps 18`.

Prints one JSON line: scans, odometry messages, duration, the laser's pose on the robot (give it to shiftd as
`[zenoh] scan_offset_x_m` / `_y_m` / `_yaw_rad`) and the box of every return in the odometry frame.

Usage: rawlog_to_mcap.py RAWLOG OUT.mcap MSG_DEFS_DIR [--laps N] [--robot NAME]
"""

import argparse
import gzip
import json
import math
import os
import re
import struct
import sys

from mcap_ros2.writer import Writer

# A serialised object starts with one byte, 0x80 | the length of its class name, then the name and a version
# byte; 0x88 ends it. Only the classes below are read, each at the version the files carry.
HEADER = re.compile(rb"\x91CActionCollection|\x97CObservation2DRangeScan")
# MRPT timestamps: 100 ns ticks since 1601-01-01.
EPOCH_1601_NS = 11_644_473_600 * 10**9


class RawlogError(Exception):
    """A rawlog this converter cannot read."""


def read_object_name(b: bytes, i: int, name: bytes) -> int:
    """Checks that an object of class `name` starts at `i`; returns the offset past its version byte."""
    want = bytes([0x80 | len(name)]) + name
    if b[i : i + len(want)] != want:
        raise RawlogError(f"expected {name.decode()} at byte {i}, found {b[i:i + len(want)]!r}")
    return i + len(want) + 1


def read_scan(b: bytes, i: int) -> dict:
    """A CObservation2DRangeScan (version 6) whose class name ends at `i`."""
    version = b[i]
    if version != 6:
        raise RawlogError(f"CObservation2DRangeScan version {version} at byte {i}: only 6 is read")
    i += 1
    aperture, right_to_left, max_range = struct.unpack_from("<f?f", b, i)
    i += 9
    # The sensor's pose on the robot: a CPose3D holding its 4x4 homogeneous matrix (a CMatrixD).
    i = read_object_name(b, i, b"CPose3D")
    i = read_object_name(b, i, b"CMatrixD")
    rows, cols = struct.unpack_from("<II", b, i)
    i += 8
    if (rows, cols) != (4, 4):
        raise RawlogError(f"sensor pose is a {rows}x{cols} matrix at byte {i}")
    m = struct.unpack_from("<16d", b, i)
    i += 16 * 8 + 2  # the matrix, then the end marks of CMatrixD and CPose3D
    (n,) = struct.unpack_from("<I", b, i)
    i += 4
    if n < 2 or n > 100_000:
        raise RawlogError(f"{n} beams at byte {i}")
    ranges = struct.unpack_from(f"<{n}f", b, i)
    i += 4 * n
    valid = b[i : i + n]
    i += n
    _std_error, stamp = struct.unpack_from("<fQ", b, i)
    return {
        "aperture": aperture,
        "right_to_left": right_to_left,
        "max_range": max_range,
        "offset": (m[3], m[7], math.atan2(m[4], m[0])),
        "ranges": ranges,
        "valid": valid,
        "stamp_ns": stamp * 100 - EPOCH_1601_NS,
    }


def read_increment(b: bytes, i: int) -> tuple:
    """The raw odometry increment (x, y, yaw) of the CActionRobotMovement2D in the CActionCollection at `i`."""
    j = b.find(b"\x87CPose2D", i)
    if j < 0 or b[j + 8] != 1:
        raise RawlogError(f"no CPose2D (version 1) in the action at byte {i}")
    return struct.unpack_from("<3d", b, j + 9)


def read_rawlog(path: str) -> list:
    """The log's events in order: ("scan", dict) and ("move", (dx, dy, dyaw))."""
    with open(path, "rb") as f:
        raw = f.read()
    b = gzip.decompress(raw) if raw[:2] == b"\x1f\x8b" else raw
    events = []
    for m in HEADER.finditer(b):
        if m.group(0).endswith(b"Collection"):
            events.append(("move", read_increment(b, m.end())))
        else:
            events.append(("scan", read_scan(b, m.end())))
    if not any(kind == "scan" for kind, _ in events):
        raise RawlogError(f"{path}: no CObservation2DRangeScan")
    return events


def compose(pose: tuple, inc: tuple) -> tuple:
    x, y, yaw = pose
    dx, dy, dyaw = inc
    c, s = math.cos(yaw), math.sin(yaw)
    return (x + c * dx - s * dy, y + s * dx + c * dy, yaw + dyaw)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("rawlog")
    ap.add_argument("out")
    ap.add_argument("msg_defs")
    ap.add_argument("--laps", type=int, default=1, help="times the log is driven (default 1)")
    ap.add_argument("--robot", default="robot1", help="the robot's name in the topics (default robot1)")
    args = ap.parse_args()
    if args.laps < 1:
        ap.error("--laps must be at least 1")

    try:
        events = read_rawlog(args.rawlog)
    except (OSError, RawlogError, struct.error) as e:
        sys.exit(f"rawlog_to_mcap: {e}")

    # One lap: (stamp, pose of the robot, scan), the pose integrated from the increments before the scan.
    lap, pose = [], (0.0, 0.0, 0.0)
    for kind, value in events:
        if kind == "move":
            pose = compose(pose, value)
        else:
            lap.append((value["stamp_ns"], pose, value))
    t0 = lap[0][0]
    period = (lap[-1][0] - t0) / max(len(lap) - 1, 1)
    lap_ns = lap[-1][0] - t0 + round(period)

    def msgdef(name: str) -> str:
        with open(os.path.join(args.msg_defs, name), encoding="utf-8") as f:
            return f.read()

    odom_topic, scan_topic = f"/{args.robot}/odom", f"/{args.robot}/scan"
    box = [math.inf, math.inf, -math.inf, -math.inf]
    seq = 0
    with open(args.out, "wb") as f:
        w = Writer(f)
        odom_schema = w.register_msgdef("nav_msgs/msg/Odometry", msgdef("Odometry.msg"))
        scan_schema = w.register_msgdef("sensor_msgs/msg/LaserScan", msgdef("LaserScan.msg"))
        for k in range(args.laps):
            for stamp0, (x, y, yaw), scan in lap:
                stamp = stamp0 + k * lap_ns
                sec, nanosec = divmod(stamp, 10**9)
                header = lambda frame: {"stamp": {"sec": sec, "nanosec": nanosec}, "frame_id": frame}
                odom = {
                    "header": header("odom"),
                    "child_frame_id": "base_link",
                    "pose": {
                        "pose": {
                            "position": {"x": x, "y": y, "z": 0.0},
                            "orientation": {"x": 0.0, "y": 0.0, "z": math.sin(yaw / 2), "w": math.cos(yaw / 2)},
                        },
                        "covariance": [0.0] * 36,
                    },
                    "twist": {
                        "twist": {"linear": {"x": 0.0, "y": 0.0, "z": 0.0}, "angular": {"x": 0.0, "y": 0.0, "z": 0.0}},
                        "covariance": [0.0] * 36,
                    },
                }
                n = len(scan["ranges"])
                inc = scan["aperture"] / (n - 1)
                ranges = [
                    r if ok and 0.0 < r < scan["max_range"] else math.inf
                    for r, ok in zip(scan["ranges"], scan["valid"])
                ]
                if not scan["right_to_left"]:
                    ranges.reverse()
                msg = {
                    "header": header("laser"),
                    "angle_min": -scan["aperture"] / 2,
                    "angle_max": scan["aperture"] / 2,
                    "angle_increment": inc,
                    "time_increment": 0.0,
                    "scan_time": period * 1e-9,
                    "range_min": 0.01,
                    "range_max": scan["max_range"],
                    "ranges": ranges,
                    "intensities": [],
                }
                if k == 0:
                    ox, oy, oyaw = scan["offset"]
                    lx, ly = x + math.cos(yaw) * ox - math.sin(yaw) * oy, y + math.sin(yaw) * ox + math.cos(yaw) * oy
                    for j, r in enumerate(ranges):
                        if math.isfinite(r):
                            a = yaw + oyaw + msg["angle_min"] + j * inc
                            px, py = lx + r * math.cos(a), ly + r * math.sin(a)
                            box = [min(box[0], px), min(box[1], py), max(box[2], px), max(box[3], py)]
                # Odometry first: the pose that places the scan is there when the scan comes.
                w.write_message(topic=odom_topic, schema=odom_schema, message=odom, log_time=stamp, publish_time=stamp, sequence=seq)
                w.write_message(topic=scan_topic, schema=scan_schema, message=msg, log_time=stamp + 1, publish_time=stamp, sequence=seq)
                seq += 1
        w.finish()

    ox, oy, oyaw = lap[0][2]["offset"]
    print(
        json.dumps(
            {
                "scans": len(lap) * args.laps,
                "scans_per_lap": len(lap),
                "beams": len(lap[0][2]["ranges"]),
                "laps": args.laps,
                "duration_s": round((len(lap) * args.laps - 1) * 1e-9 * (lap_ns / len(lap)), 1),
                "lap_s": round(lap_ns * 1e-9, 2),
                "scan_offset": {"x_m": round(ox, 3), "y_m": round(oy, 3), "yaw_rad": round(oyaw, 4)},
                "box_m": [round(v, 2) for v in box],
            }
        )
    )


if __name__ == "__main__":
    main()
