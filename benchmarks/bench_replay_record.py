"""Replay into the recorder, as a user chains them: how fast the pair goes and whether anything
is lost [issue target: lossless at 2x and 5x with one core busy].

A rig session is recorded offline in the node's format (``drill_sim control --record``, a
steady point for --seconds of simulated time at 1 kHz, every topic), then ``drill_sim_record -e
'^/drill_sim/'`` is started and ``drill_sim_replay BAG --rate R' --wait-for all --topics <every
/drill_sim/ topic>`` plays into it, R' chosen so that the replay asks R times the session's
simulated time (the offline recording's log times are its wall clock, far faster). The copy
is counted topic by topic with the ``mcap`` library (not drill_sim's reader) against the
original. Prints messages, lost, the time taken and what the recorder and the player said.
``--busy`` adds a busy loop on one core for the run.

Run: .venv/bin/python benchmarks/bench_replay_record.py [--rate 2] [--seconds 20] [--busy]
"""

from __future__ import annotations

import argparse
import os
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from collections import Counter
from pathlib import Path

from mcap.reader import make_reader

BIN = Path(sys.executable).parent


def counts(bag: Path) -> tuple[Counter, float]:
    """Messages per topic, read with the mcap library, and the span of their log times [s]."""
    found: Counter = Counter()
    first, last = None, None
    for file in sorted(bag.glob("*.mcap")):
        with open(file, "rb") as fh:
            for _, channel, message in make_reader(fh).iter_messages():
                found[channel.topic] += 1
                t = message.log_time
                first, last = (t if first is None else min(first, t),
                               t if last is None else max(last, t))
    return found, ((last - first) * 1e-9 if found else 0.0)


def session(tmp: Path, seconds: float) -> Path:
    """A rig session in the node's format, its log times spread over real time."""
    out = tmp / "rec"
    subprocess.run([str(BIN / "drill_sim"), "control", "--rpm", "60", "--wob-kn", "100",
                    "--duration", str(seconds), "--laws", "z_torque", "--record", str(out)],
                   check=True, capture_output=True)
    return next(out.iterdir())


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--rate", type=float, default=2.0, help="replay rate (x the recording)")
    parser.add_argument("--seconds", type=float, default=20.0, help="simulated seconds")
    parser.add_argument("--busy", action="store_true", help="one core busy meanwhile")
    args = parser.parse_args()
    os.environ.setdefault("ROS_DOMAIN_ID", str(100 + os.getpid() % 100))
    os.environ.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
    tmp = Path(tempfile.mkdtemp())
    original = session(tmp, args.seconds)
    found, log_span_s = counts(original)
    topics = sorted(t for t in found if t.startswith("/drill_sim/"))
    expected = {t: n for t, n in found.items() if t in topics}
    rate = args.rate * log_span_s / args.seconds       # R x the simulated time
    copy = tmp / "copy"
    busy = subprocess.Popen([sys.executable, "-c", "while True: pass"]) if args.busy else None
    rec = subprocess.Popen([str(BIN / "drill_sim_record"), "-e", "^/drill_sim/", "-o",
                            str(copy)], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                           text=True)
    try:
        t0 = time.perf_counter()
        play = subprocess.run([str(BIN / "drill_sim_replay"), str(original), "--rate",
                               repr(rate), "--wait-for", "all", "--topics", *topics],
                              capture_output=True, text=True, timeout=3600)
        wall = time.perf_counter() - t0
    finally:
        if busy is not None:
            busy.kill()
        rec.send_signal(signal.SIGINT)
        _, err = rec.communicate(timeout=120)
    got, _ = counts(copy)
    lost = sum(max(n - got.get(t, 0), 0) for t, n in expected.items())
    total = sum(expected.values())
    reported = re.search(r"LOST (\d+) messages", err)
    held = re.search(r"played at ([0-9.]+)x", play.stderr)
    held_sim = float(held.group(1)) * args.seconds / log_span_s if held else None
    print(f"{total} messages on {len(topics)} topics, {args.seconds:g} s simulated, --rate "
          f"{args.rate:g} x simulated time{' with one core busy' if args.busy else ''}: "
          f"lost {lost} (mcap "
          f"count); the recorder reported {reported.group(1) if reported else 0} lost; replay "
          f"and wait took {wall:.1f} s ({total / wall:.0f} msg/s including the subscription "
          f"wait){f'; the player was held back to {held_sim:.2f}x' if held else ''}")
    shutil.rmtree(tmp)


if __name__ == "__main__":
    main()
