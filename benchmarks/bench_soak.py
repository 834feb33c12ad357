"""The rig node's memory over a soak [issue target: flat RSS].

Starts the node at max speed with /clock (``rate_hz`` 1000, every output every simulated
millisecond) recording everything, plus a 50 Hz driver, and samples the node's resident set
size every ``--every`` seconds for ``--minutes``. Prints each sample and the growth rate over
the second half (after the allocator and the caches have settled), in MB per minute.

The summary an MCAP file must end with (~200 bytes per chunk) waits in a temporary file until
the file is finished, so recording into one file keeps the node's memory flat; ``--split-s``
starts a new file that often.

Run: .venv/bin/python benchmarks/bench_soak.py [--minutes 5] [--every 10] [--no-record]
         [--real-time] [--split-s S]
"""

from __future__ import annotations

import argparse
import os
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

BIN = Path(sys.executable).parent


def rss_mb(pid: int) -> float:
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith("VmRSS:"):
            return int(line.split()[1]) / 1024
    return float("nan")


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--minutes", type=float, default=5.0)
    parser.add_argument("--every", type=float, default=10.0, help="seconds between samples")
    parser.add_argument("--no-record", action="store_true")
    parser.add_argument("--real-time", action="store_true", help="1000 Hz in real time instead")
    parser.add_argument("--split-s", type=float, default=0.0,
                        help="record_split_duration_s (default 0: one file)")
    args = parser.parse_args()
    env = dict(os.environ, ROS_AUTOMATIC_DISCOVERY_RANGE="LOCALHOST")
    env.setdefault("ROS_DOMAIN_ID", str(1 + os.getpid() % 100))
    with tempfile.TemporaryDirectory() as tmp:
        record = () if args.no_record else ("-p", f"record:={tmp}/soak", "-p",
                                            f"record_split_duration_s:={args.split_s}")
        speed = () if args.real_time else ("-p", "publish_clock:=true", "-p", "max_speed:=true")
        node = subprocess.Popen([str(BIN / "drill_sim_node"), "--ros-args", "-r", "__ns:=/soak",
                                 *speed, "-p", "command_timeout_s:=3600.0", *record],
                                env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        drive = subprocess.Popen([str(BIN / "drill_sim_drive"), "step_test", "--loop",
                                  "--ros-args", "-r", "__ns:=/soak"], env=env,
                                 stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        start = time.monotonic()
        times, sizes = [], []
        try:
            while time.monotonic() - start < 60 * args.minutes:
                time.sleep(args.every)
                if node.poll() is not None:
                    raise SystemExit(f"the node stopped with status {node.returncode}")
                times.append((time.monotonic() - start) / 60)
                sizes.append(rss_mb(node.pid))
                print(f"{times[-1]:6.2f} min  node RSS {sizes[-1]:8.1f} MB", flush=True)
        finally:
            for p in (drive, node):
                p.send_signal(signal.SIGINT)
                p.wait(timeout=30)
        bag_mb = sum(f.stat().st_size for f in Path(tmp).rglob("*.mcap")) / 1e6
    t, m = np.array(times), np.array(sizes)
    half = t >= t[-1] / 2
    slope = np.polyfit(t[half], m[half], 1)[0] if half.sum() >= 2 else float("nan")
    print(f"{'recording, ' if not args.no_record else ''}"
          f"{'real time' if args.real_time else 'max speed'}, {args.minutes:g} min: RSS "
          f"{m[0]:.1f} MB after {t[0] * 60:.0f} s, {m[-1]:.1f} MB at the end; growth over the "
          f"second half {slope:+.2f} MB/min" + (f"; bag {bag_mb:.0f} MB" if bag_mb else "")
          + (f" in files of {args.split_s:g} s" if args.split_s else ""))


if __name__ == "__main__":
    main()
