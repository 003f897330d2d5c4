#!/usr/bin/env python3
"""Reads SHIFT MCAP recordings with the reference Python readers (`mcap`, `mcap-ros2-support`) and prints, as one
JSON document, what a test needs to check: per file whether it has a summary (it was finished), the channels
(topic, schema, encodings, metadata, message count), and every sensor_msgs/PointCloud2 decoded by
mcap-ros2-support with its x, y, z read by field name and offset.

Usage: read_recording.py FILE.mcap [FILE.mcap ...]
Exit codes: 0 ok, 2 usage or read error, 3 a Python package is missing (the message names it).
"""

import json
import struct
import sys

try:
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory
except ImportError as e:  # pragma: no cover - depends on the machine
    print(f"missing python package: {e} (python3 -m pip install mcap mcap-ros2-support)", file=sys.stderr)
    sys.exit(3)

# sensor_msgs/PointField datatypes
FORMATS = {1: "b", 2: "B", 3: "h", 4: "H", 5: "i", 6: "I", 7: "f", 8: "d"}


def cloud_xyz(msg):
    fields = {f.name: f for f in msg.fields}
    if not all(k in fields for k in ("x", "y", "z")):
        return []
    order = ">" if msg.is_bigendian else "<"
    data = bytes(msg.data)
    points = []
    for row in range(msg.height):
        for col in range(msg.width):
            base = row * msg.row_step + col * msg.point_step
            p = []
            for k in ("x", "y", "z"):
                f = fields[k]
                fmt = order + FORMATS[f.datatype]
                (v,) = struct.unpack_from(fmt, data, base + f.offset)
                p.append(v)
            points.append(p)
    return points


def main(paths):
    out = {"files": [], "channels": {}, "clouds": [], "undecodable": 0}
    factory = DecoderFactory()
    for path in paths:
        with open(path, "rb") as f:
            reader = make_reader(f)
            summary = reader.get_summary()
            header = reader.get_header()
            out["files"].append(
                {
                    "path": path,
                    "profile": header.profile,
                    "summary": summary is not None,
                    "messages": summary.statistics.message_count if summary and summary.statistics else None,
                }
            )
            decoders = {}
            for schema, channel, message in reader.iter_messages(log_time_order=True):
                c = out["channels"].setdefault(
                    channel.topic,
                    {
                        "schema": schema.name if schema else None,
                        "schema_encoding": schema.encoding if schema else None,
                        "message_encoding": channel.message_encoding,
                        "metadata": dict(channel.metadata),
                        "count": 0,
                    },
                )
                c["count"] += 1
                if schema is None or channel.message_encoding != "cdr":
                    continue
                if schema.id not in decoders:
                    decoders[schema.id] = factory.decoder_for(channel.message_encoding, schema)
                try:
                    decoded = decoders[schema.id](message.data)
                except Exception:  # noqa: BLE001 - a malformed payload recorded as it came
                    out["undecodable"] += 1
                    continue
                if schema.name == "sensor_msgs/msg/PointCloud2":
                    out["clouds"].append(
                        {
                            "topic": channel.topic,
                            "log_time": message.log_time,
                            "frame_id": decoded.header.frame_id,
                            "points": cloud_xyz(decoded),
                        }
                    )
    json.dump(out, sys.stdout)
    print()


if __name__ == "__main__":
    if len(sys.argv) < 2:
        print(__doc__, file=sys.stderr)
        sys.exit(2)
    try:
        main(sys.argv[1:])
    except Exception as e:  # noqa: BLE001 - one clear line for the calling test
        print(f"error: {type(e).__name__}: {e}", file=sys.stderr)
        sys.exit(2)
