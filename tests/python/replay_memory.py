"""Memory of shiftd while a real laser log is replayed into it (issue 22's memory item): prints the daemon's RSS
curve and where its memory goes, per component, from its /metrics.

What it does:
1. Fetches the real log, unless --rawlog names one: Debian's `mrpt-common` package (`apt-get download`, unpacked
   with `dpkg-deb -x` into the work folder, nothing installed) ships "2006-01ENE-21-SENA_Telecom Faculty_one_loop
   _only.rawlog", 225 scans of a SICK LMS (361 beams) and the odometry of a loop through a faculty building.
2. Converts it to a ROS 2 bag (`rawlog_to_mcap.py`, beside this file), driven --laps times (18: 4 050 scans).
3. Starts `shiftd serve` on loopback (HTTP and Zenoh on free ports, a fresh store, the embedded defaults but for
   the default site and the laser's offset), uploads an all-free map of the log's extent as site `sena`, and
   runs `shiftd replay BAG --speed S` against it.
4. Samples the daemon every second: VmRSS and VmHWM from /proc, and the gauges of GET /metrics.
5. After the replay, waits --settle-s (jemalloc hands freed pages back after its decay time), then prints
   the RSS curve (start, after the upload, peak, end of replay, settled) and the per-component figures, and
   stops the daemon (SIGTERM to the PID it started).

Usage (from the repository root, after `cargo build --release -p shiftd --bin shiftd`):
    python3 tests/python/replay_memory.py [--laps 18] [--speed 8] [--csv samples.csv]
Needs the Python packages mcap and mcap-ros2-support, and apt-get/dpkg-deb unless --rawlog is given.
"""

import argparse
import glob
import json
import math
import os
import re
import signal
import socket
import subprocess
import sys
import tempfile
import time
import urllib.request

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
RAWLOG_NAME = "2006-01ENE-21-SENA_Telecom Faculty_one_loop_only.rawlog"
SITE = "sena"
METRIC = re.compile(r'^([a-zA-Z_:][a-zA-Z0-9_:]*)(\{[^}]*\})?\s+(\S+)$')


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def fetch_rawlog(work: str) -> str:
    """The SENA log from Debian's mrpt-common, downloaded and unpacked into `work` (once)."""
    found = glob.glob(os.path.join(work, "mrpt", "**", RAWLOG_NAME), recursive=True)
    if found:
        return found[0]
    os.makedirs(os.path.join(work, "mrpt"), exist_ok=True)
    deb_dir = os.path.join(work, "mrpt")
    subprocess.run(["apt-get", "download", "mrpt-common"], cwd=deb_dir, check=True, capture_output=True)
    debs = glob.glob(os.path.join(deb_dir, "mrpt-common_*.deb"))
    if not debs:
        sys.exit("replay_memory: apt-get download mrpt-common left no .deb")
    subprocess.run(["dpkg-deb", "-x", debs[0], os.path.join(deb_dir, "x")], check=True)
    found = glob.glob(os.path.join(deb_dir, "x", "**", RAWLOG_NAME), recursive=True)
    if not found:
        sys.exit(f"replay_memory: {RAWLOG_NAME} is not in {debs[0]}")
    return found[0]


def get(url: str, timeout: float = 5.0) -> bytes:
    with urllib.request.urlopen(url, timeout=timeout) as r:
        return r.read()


def metrics(http: str) -> dict:
    """Every sample of GET /metrics: {(name, labels): value}."""
    out = {}
    for line in get(f"{http}/metrics").decode().splitlines():
        m = METRIC.match(line)
        if m and not line.startswith("#"):
            try:
                out[(m.group(1), m.group(2) or "")] = float(m.group(3))
            except ValueError:
                pass
    return out


def pick(ms: dict, name: str, **labels) -> float:
    """The sum of a metric's samples whose labels include `labels`."""
    total = 0.0
    for (n, lab), v in ms.items():
        if n == name and all(f'{k}="{val}"' in lab for k, val in labels.items()):
            total += v
    return total


def by_label(ms: dict, name: str, label: str) -> dict:
    out = {}
    for (n, lab), v in ms.items():
        if n == name:
            m = re.search(label + r'="([^"]*)"', lab)
            out[m.group(1) if m else ""] = v
    return out


def proc_status(pid: int) -> dict:
    out = {}
    with open(f"/proc/{pid}/status", encoding="ascii") as f:
        for line in f:
            if line.startswith(("VmRSS", "VmHWM", "Threads", "RssAnon", "RssFile")):
                k, v = line.split(":", 1)
                out[k] = int(v.split()[0]) * 1024 if "kB" in v else int(v)
    return out


def mib(b: float) -> str:
    return f"{b / 2**20:8.1f} MiB"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--shiftd", default=os.path.join(ROOT, "target", "release", "shiftd"))
    ap.add_argument("--rawlog", help="an MRPT rawlog (default: fetched from Debian's mrpt-common)")
    ap.add_argument("--work", default=os.path.join(tempfile.gettempdir(), "shift-replay-memory"))
    ap.add_argument("--laps", type=int, default=18, help="times the loop is driven (18 = 4 050 scans)")
    ap.add_argument("--speed", type=float, default=8.0, help="replay speed (default 8)")
    ap.add_argument("--settle-s", type=float, default=20.0, help="seconds sampled after the replay")
    ap.add_argument("--csv", help="write every sample here")
    ap.add_argument("--env", action="append", default=[], help="KEY=VALUE for the daemon (repeatable)")
    ap.add_argument("--zenoh", action="append", default=[],
                    help="KEY=VALUE added to the daemon's [zenoh] section, e.g. clear_margin_m=0 (repeatable)")
    ap.add_argument("--record", action="store_true", help="the daemon records everything (shiftd serve --record)")
    args = ap.parse_args()
    if not os.access(args.shiftd, os.X_OK):
        sys.exit(f"replay_memory: no {args.shiftd}: cargo build --release -p shiftd --bin shiftd")

    os.makedirs(args.work, exist_ok=True)
    rawlog = args.rawlog or fetch_rawlog(args.work)
    bag = os.path.join(args.work, f"sena-{args.laps}.mcap")
    conv = subprocess.run(
        [sys.executable, os.path.join(HERE, "rawlog_to_mcap.py"), rawlog, bag,
         os.path.join(ROOT, "proto", "src", "ros", "msg_defs"), "--laps", str(args.laps)],
        check=True, capture_output=True, text=True,
    )
    log = json.loads(conv.stdout)
    print(f"dataset: {os.path.basename(rawlog)}: {log['scans_per_lap']} scans x {log['laps']} laps = "
          f"{log['scans']} scans of {log['beams']} beams, {log['duration_s']} s of log, replayed at x{args.speed}")

    run_dir = tempfile.mkdtemp(prefix="run-", dir=args.work)
    http_port, zenoh_port = free_port(), free_port()
    http = f"http://127.0.0.1:{http_port}"
    off = log["scan_offset"]
    config = os.path.join(run_dir, "shiftd.toml")
    with open(config, "w", encoding="utf-8") as f:
        f.write(
            f'[http]\nbind = "127.0.0.1:{http_port}"\n[store]\ndata_dir = "{run_dir}/store"\n'
            f'[zenoh]\nlisten = ["tcp/127.0.0.1:{zenoh_port}"]\nsite = "{SITE}"\n'
            f'scan_offset_x_m = {off["x_m"]}\nscan_offset_y_m = {off["y_m"]}\nscan_offset_yaw_rad = {off["yaw_rad"]}\n'
            + "".join(f"{kv.partition('=')[0]} = {kv.partition('=')[2]}\n" for kv in args.zenoh)
        )
    env = dict(os.environ)
    for kv in args.env:
        k, _, v = kv.partition("=")
        env[k] = v
    daemon_log = open(os.path.join(run_dir, "shiftd.log"), "wb")
    serve = [args.shiftd, "serve", "--config", config]
    if args.record:
        serve += ["--record", os.path.join(run_dir, "recording")]
    daemon = subprocess.Popen(serve, stdout=daemon_log, stderr=daemon_log, env=env)
    samples = []
    marks = {}
    try:
        for _ in range(300):
            try:
                get(f"{http}/readyz", timeout=1.0)
                break
            except OSError:
                time.sleep(0.1)
        else:
            sys.exit("replay_memory: the daemon did not get ready in 30 s")

        t0 = time.monotonic()

        def sample(phase: str) -> dict:
            ms = metrics(http)
            row = {"t_s": round(time.monotonic() - t0, 1), "phase": phase, **proc_status(daemon.pid), "metrics": ms}
            samples.append(row)
            return row

        time.sleep(3.0)
        marks["start"] = sample("start")
        # An all-free map of the log's extent (plus 5 m), 0.1 m cells: every return is a new obstacle.
        x0, y0, x1, y1 = log["box_m"]
        res = 0.1
        ox, oy = math.floor(x0 - 5), math.floor(y0 - 5)
        w, h = math.ceil((x1 + 5 - ox) / res), math.ceil((y1 + 5 - oy) / res)
        body = ('{"resolution":%s,"origin":[%d,%d],"width":%d,"height":%d,"cells":[' % (res, ox, oy, w, h)
                + ",".join(["0"] * (w * h)) + "]}").encode()
        req = urllib.request.Request(f"{http}/v1/sites/{SITE}/map", data=body, method="POST",
                                     headers={"content-type": "application/json"})
        with urllib.request.urlopen(req, timeout=60) as r:
            r.read()
        print(f"site {SITE}: {w} x {h} cells of {res} m ({w * h / 1e6:.2f} M cells)")
        time.sleep(3.0)  # the allocator's figures are refreshed every 2 s
        marks["site"] = sample("site")

        replay = subprocess.Popen([args.shiftd, "replay", bag, "--speed", str(args.speed), "--config", config],
                                  stdout=subprocess.DEVNULL, stderr=open(os.path.join(run_dir, "replay.log"), "wb"))
        last_print = 0.0
        while replay.poll() is None:
            time.sleep(1.0)
            row = sample("replay")
            if row["t_s"] - last_print >= 10:
                last_print = row["t_s"]
                ms = row["metrics"]
                print(f"t={row['t_s']:6.1f} s  RSS {mib(row['VmRSS'])}  scans placed "
                      f"{pick(ms, 'shift_ingest_clouds_total', stream='scan'):6.0f}  live map "
                      f"{pick(ms, 'shift_live_map_points', site=SITE):7.0f} points")
        if replay.returncode != 0:
            sys.exit(f"replay_memory: shiftd replay exited {replay.returncode} (see {run_dir}/replay.log)")
        time.sleep(1.0)
        marks["replayed"] = sample("replayed")
        end = time.monotonic() + args.settle_s
        while time.monotonic() < end:
            time.sleep(1.0)
            sample("settle")
        marks["settled"] = samples[-1]
    finally:
        daemon.send_signal(signal.SIGTERM)
        try:
            daemon.wait(timeout=30)
        except subprocess.TimeoutExpired:
            daemon.kill()
            daemon.wait()

    report(samples, marks)
    if args.csv:
        keys = ["t_s", "phase", "VmRSS", "VmHWM", "RssAnon", "Threads"]
        with open(args.csv, "w", encoding="utf-8") as f:
            f.write(",".join(keys + ["live_points", "live_bytes", "alloc_allocated", "alloc_resident"]) + "\n")
            for r in samples:
                ms = r["metrics"]
                f.write(",".join(str(r.get(k, "")) for k in keys) + ",")
                f.write(",".join(str(v) for v in [
                    pick(ms, "shift_live_map_points", site=SITE), pick(ms, "shift_live_map_bytes", site=SITE),
                    pick(ms, "shift_allocator_bytes", stat="allocated"),
                    pick(ms, "shift_allocator_bytes", stat="resident")]) + "\n")
        print(f"samples: {args.csv}")


def report(samples: list, marks: dict) -> None:
    peak = max(samples, key=lambda r: r["VmRSS"])
    print("\nRSS (VmRSS), and what jemalloc says is allocated and resident:")
    for name in ["start", "site", "replayed", "settled"]:
        r = marks.get(name)
        if r:
            alloc = by_label(r["metrics"], "shift_allocator_bytes", "stat")
            extra = ""
            if "allocated" in alloc:
                extra = f"   allocated {mib(alloc['allocated'])}   resident {mib(alloc.get('resident', 0))}"
            print(f"  {name:9} t={r['t_s']:6.1f} s {mib(r['VmRSS'])}{extra}")
    print(f"  {'peak':9} t={peak['t_s']:6.1f} s {mib(peak['VmRSS'])}   (VmHWM {mib(samples[-1]['VmHWM']).strip()})")
    for name in ["replayed", "settled"]:
        r = marks.get(name)
        if not r:
            continue
        ms = r["metrics"]
        print(f"\ncomponents at '{name}' (t={r['t_s']} s, RSS {mib(r['VmRSS']).strip()}):")
        print(f"  scans placed in the live map   {pick(ms, 'shift_ingest_clouds_total', stream='scan'):10.0f}")
        dropped = by_label(ms, "shift_ingest_dropped_total", "reason")
        print(f"  scans dropped                  {sum(dropped.values()):10.0f} {dropped or ''}")
        print(f"  live map points ({SITE})        {pick(ms, 'shift_live_map_points', site=SITE):10.0f}")
        print(f"  live map bytes ({SITE})        {mib(pick(ms, 'shift_live_map_bytes', site=SITE))}")
        for comp, v in sorted(by_label(ms, "shift_memory_bytes", "component").items()):
            print(f"  {comp:30} {mib(v)}")
        alloc = by_label(ms, "shift_allocator_bytes", "stat")
        for stat in ["allocated", "active", "metadata", "resident", "mapped", "retained"]:
            if stat in alloc:
                print(f"  allocator {stat:20} {mib(alloc[stat])}")
        if "allocated" in alloc:
            print(f"  RSS - allocator allocated      {mib(r['VmRSS'] - alloc['allocated'])}")


if __name__ == "__main__":
    main()
