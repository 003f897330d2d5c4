"""Writes a ROS 2 bag in rosbag2's MCAP storage format, as a real robot's log would be: /robot1/odom
(nav_msgs/msg/Odometry, frame "odom") and /robot1/scan (sensor_msgs/msg/LaserScan) at 10 Hz with equal stamps,
the scan logged first every third time (odometry and scans travel separately). Written with the reference
writer (mcap-ros2-support), the message definitions read from the project's msg_defs folder.

Usage: make_ros2_bag.py OUT.mcap MSG_DEFS_DIR
"""

import math
import os
import sys

from mcap_ros2.writer import Writer


def main() -> None:
    out, defs = sys.argv[1], sys.argv[2]

    def msgdef(name: str) -> str:
        with open(os.path.join(defs, name), encoding="utf-8") as f:
            return f.read()

    t0 = 1_700_000_000 * 10**9
    with open(out, "wb") as f:
        w = Writer(f)
        odom_schema = w.register_msgdef("nav_msgs/msg/Odometry", msgdef("Odometry.msg"))
        scan_schema = w.register_msgdef("sensor_msgs/msg/LaserScan", msgdef("LaserScan.msg"))
        n_beams = 61
        for k in range(30):
            stamp = t0 + k * 100_000_000
            sec, nanosec = divmod(stamp, 10**9)
            header = lambda frame: {"stamp": {"sec": sec, "nanosec": nanosec}, "frame_id": frame}
            x = 1.0 + 0.05 * k
            odom = {
                "header": header("odom"),
                "child_frame_id": "base_link",
                "pose": {
                    "pose": {
                        "position": {"x": x, "y": 1.0, "z": 0.0},
                        "orientation": {"x": 0.0, "y": 0.0, "z": 0.0, "w": 1.0},
                    },
                    "covariance": [0.0] * 36,
                },
                "twist": {
                    "twist": {"linear": {"x": 0.5, "y": 0.0, "z": 0.0}, "angular": {"x": 0.0, "y": 0.0, "z": 0.0}},
                    "covariance": [0.0] * 36,
                },
            }
            inc = 1.2 / (n_beams - 1)
            scan = {
                "header": header("laser"),
                "angle_min": -0.6,
                "angle_max": 0.6,
                "angle_increment": inc,
                "time_increment": 0.0,
                "scan_time": 0.1,
                "range_min": 0.05,
                "range_max": 20.0,
                # A wall 1.5 m ahead.
                "ranges": [1.5 / math.cos(-0.6 + i * inc) for i in range(n_beams)],
                "intensities": [],
            }
            msgs = [("/robot1/odom", odom_schema, odom), ("/robot1/scan", scan_schema, scan)]
            if k % 3 == 0:
                msgs.reverse()
            for j, (topic, schema, msg) in enumerate(msgs):
                w.write_message(topic=topic, schema=schema, message=msg, log_time=stamp + j, publish_time=stamp, sequence=k)
        w.finish()


if __name__ == "__main__":
    main()
