"""Memory and time of the bag tools against the length of the session [issue targets: peak RSS
of `drill_sim bag metrics` on one hour at 1000 Hz under 1 GB and not growing with the length;
`bag metrics` on one hour within 10 s].

Writes (once; kept with --keep) sessions of the given lengths at 1000 Hz, every output topic of
the node, as the node records them (``bench_bag.write_session``), then runs each tool on each
as a user does (a fresh process) and reports its wall time and peak resident set size (the
process's own high-water mark, VmHWM, mapped file pages included).

Run: .venv/bin/python benchmarks/bench_bag_memory.py [--minutes 10 60] [--keep DIR]
"""

from __future__ import annotations

import argparse
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parent))
from bench_bag import write_session

# the tool as its console script runs it, then its own high-water mark; measured from inside,
# because a child forked from this process (which wrote the bags) would inherit its peak
_RUN = ("import re, sys\n"
        "from drill_sim.cli.main import main\n"
        "status = main(sys.argv[1:])\n"
        "with open('/proc/self/status') as f:\n"
        "    print('VmHWM', re.search(r'VmHWM:\\s+(\\d+)', f.read()).group(1), file=sys.stderr)\n"
        "sys.exit(status)\n")


def measured(*args: str) -> tuple[float, float]:
    """(wall time [s], peak RSS [MB]) of ``drill_sim *args`` in a fresh process."""
    t = time.perf_counter()
    done = subprocess.run([sys.executable, "-c", _RUN, *args], stdout=subprocess.DEVNULL,
                          stderr=subprocess.PIPE, text=True)
    seconds = time.perf_counter() - t
    if done.returncode != 0:
        raise SystemExit(f"drill_sim {' '.join(args)}: exit {done.returncode}: {done.stderr}")
    kib = int(done.stderr.rsplit("VmHWM", 1)[1].split()[0])
    return seconds, kib / 1024


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--minutes", type=float, nargs="+", default=[10.0, 60.0])
    parser.add_argument("--keep", type=Path, help="write the bags here and keep them (reused "
                                                  "if they exist)")
    parser.add_argument("--tools", nargs="+", default=["metrics", "info"])
    args = parser.parse_args()
    root = args.keep or Path(tempfile.mkdtemp())
    root.mkdir(parents=True, exist_ok=True)
    rows = []
    for minutes in args.minutes:
        bag = root / f"session_{minutes:g}min"
        if not bag.exists():
            t = time.perf_counter()
            n = write_session(bag, 60.0 * minutes)
            print(f"wrote {bag.name}: {n} messages in {time.perf_counter() - t:.0f} s")
        size = sum(f.stat().st_size for f in bag.iterdir()) / 1e6
        for tool in args.tools:
            seconds, rss = measured("bag", tool, str(bag))
            rows.append((minutes, size, tool, seconds, rss))
            print(f"{minutes:6g} min {size:8.0f} MB  bag {tool:<8} {seconds:6.2f} s  "
                  f"peak RSS {rss:7.0f} MB", flush=True)
    if args.keep is None:
        shutil.rmtree(root)


if __name__ == "__main__":
    main()
