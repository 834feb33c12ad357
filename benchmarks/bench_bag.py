"""Speed of the bag tools on a long session [issue target: `drill_sim bag metrics` on one hour at
1000 Hz in under 10 s].

Writes (once; kept with --keep) an hour of the base rig in stick-slip at 1000 Hz, every output
topic of the node, exactly as the node records them (same encoders, same writer), then times
`drill_sim bag metrics` and `drill_sim bag info` on it as a user runs them (fresh processes).

Run: .venv/bin/python benchmarks/bench_bag.py [--hours 1] [--keep DIR]
"""

from __future__ import annotations

import argparse
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from drill_sim.bag.writer import BagWriter
from drill_sim.core import RPM, Rig, load_preset
from drill_sim.session.rig_messages import RigEncoders

BIN = Path(sys.executable).parent
EPOCH_NS = 1_700_000_000_000_000_000


def write_session(path: Path, seconds: float, rate_hz: float = 1000.0) -> int:
    preset = load_preset("base")
    rig = Rig(preset.rig)
    rig.start_steady(60 * RPM, preset.rig.submerged_weight_n - 100e3)
    enc = RigEncoders(with_clock=False)
    topics = [t.under("/drill_sim") for t in enc.topics]
    n = int(seconds * rate_hz)
    t0 = time.perf_counter()
    with BagWriter(path, metadata={"session": {"preset": "base"}}) as w:
        for topic, t in zip(topics, enc.topics, strict=True):
            w.add_topic(topic, t.type_name)
        write = w.write
        for k in range(1, n + 1):
            rig.advance_to(k / rate_hz)
            stamp = EPOCH_NS + round(rig.time_s * 1e9)
            for topic, data in zip(topics, enc.sample(stamp, rig.sample()), strict=True):
                write(topic, data, stamp)
            if k % 100_000 == 0:
                done = k / n
                spent = time.perf_counter() - t0
                print(f"\rwriting the session: {100 * done:5.1f} %, "
                      f"{spent * (1 - done) / done:4.0f} s left", end="", file=sys.stderr)
    print(file=sys.stderr)
    return n * len(topics)


def timed(*args: str) -> tuple[float, str]:
    t = time.perf_counter()
    done = subprocess.run([str(BIN / "drill_sim"), *args], capture_output=True, text=True,
                          check=True)
    return time.perf_counter() - t, done.stdout


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--hours", type=float, default=1.0)
    parser.add_argument("--keep", type=Path, help="write the bag here and keep it (reused if "
                                                  "it exists)")
    args = parser.parse_args()
    bag = args.keep or Path(tempfile.mkdtemp()) / "hour"
    if not bag.exists():
        t = time.perf_counter()
        n = write_session(bag, 3600.0 * args.hours)
        print(f"wrote {n} messages in {time.perf_counter() - t:.0f} s")
    size = sum(f.stat().st_size for f in bag.iterdir())
    print(f"bag: {bag}, {size / 1e6:.0f} MB")
    for tool in ("metrics", "info"):
        seconds, out = timed("bag", tool, str(bag))
        print(f"drill_sim bag {tool}: {seconds:.2f} s")
    print(out if len(out) < 2000 else out[:2000])
    if args.keep is None:
        shutil.rmtree(bag.parent)


if __name__ == "__main__":
    main()
