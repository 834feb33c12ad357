"""The bag tools stream: metrics sums a chunk at a time (memory does not grow with the bag) over
a window that can be the last seconds; export writes times after the first sample at full
precision beside the absolute stamps; info shows the rig's simulated time beside the wall-clock
duration."""

from __future__ import annotations

import csv
import json
import tracemalloc

import numpy as np
import pytest
from bagutil import T0_NS, rig_bag
from sessionutil import session_bag

from drill_sim.bag.series import rig_series
from drill_sim.cli.main import main


def _peak_bytes(argv: list[str]) -> int:
    tracemalloc.start()
    try:
        assert main(argv) == 0
        return tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()


@pytest.mark.slow("tracemalloc traces every allocation while bags of 10 000 and 40 000 "
                  "samples are read: flat memory shows only against a bag four times the size")
def test_metrics_memory_does_not_grow_with_the_bag(tmp_path, capsys):
    warm, short, long = tmp_path / "warm", tmp_path / "short", tmp_path / "long"
    rig_bag(warm, 1_000)
    rig_bag(short, 10_000)
    rig_bag(long, 40_000)
    argv = ["bag", "metrics", "--json"]
    _peak_bytes([*argv, str(warm)])                  # imports and caches out of the way
    peaks = [_peak_bytes([*argv, str(bag)]) for bag in (short, long)]
    capsys.readouterr()
    assert peaks[1] < 1.5 * peaks[0], peaks


def test_metrics_over_the_stream_equal_the_whole_series(tmp_path, capsys):
    bag = tmp_path / "rig"
    rig_bag(bag, 5000, command_every=7)
    assert main(["bag", "metrics", str(bag), "--json"]) == 0
    m = json.loads(capsys.readouterr().out)
    s = rig_series(bag)
    w = s.bit_speed_rad_s
    assert m["samples"] == 5000
    assert m["mean_bit_speed_rad_s"] == pytest.approx(np.mean(w), rel=1e-12)
    assert m["ssi"] == pytest.approx((w.max() - w.min()) / (2 * np.mean(w)), rel=1e-9)
    assert m["mean_wob_n"] == pytest.approx(np.mean(s.wob_n), rel=1e-12)
    assert m["stick_fraction"] == np.mean(s.stuck)


def test_metrics_last_seconds(tmp_path, capsys):
    bag = tmp_path / "rig"
    rig_bag(bag, 3000)
    assert main(["bag", "metrics", str(bag), "--last", "0.5", "--json"]) == 0
    m = json.loads(capsys.readouterr().out)
    assert 499 <= m["samples"] <= 501 and m["duration_s"] == pytest.approx(0.5, abs=2e-3)
    assert main(["bag", "metrics", str(bag), "--last", "1", "--start", "0"]) == 2
    assert main(["bag", "metrics", str(bag), "--last", "0"]) == 2
    capsys.readouterr()
    assert main(["bag", "metrics", str(bag), "--start", "2", "--end", "1"]) == 2
    assert "the window ends before it starts" in capsys.readouterr().err
    # a window past the end says where the samples are; a wrong topic, which there are
    assert main(["bag", "metrics", str(bag), "--start", "100"]) != 0
    assert "its samples span 0 to 2.999 s after the first" in capsys.readouterr().err
    assert main(["bag", "metrics", str(bag), "--topic", "/drill_sim/joint_state"]) != 0
    assert "(its sensor_msgs/msg/JointState topics: /drill_sim/joint_states)" in \
        capsys.readouterr().err


def test_export_writes_time_after_the_first_sample_at_full_precision(tmp_path, capsys):
    """Real-time sessions stamp with the epoch: 9 significant digits would give 10 s steps."""
    bag, out = tmp_path / "rig", tmp_path / "rig.csv"
    samples = rig_bag(bag, 500)
    assert main(["bag", "export", str(bag), "--out", str(out)]) == 0
    rows = list(csv.reader(out.open()))
    header, rows = rows[0], rows[1:]
    assert header[0] == "time_s" and header[-1] == "stamp_ns"
    stamps = [int(r[-1]) for r in rows]
    assert stamps == [T0_NS + round(s.time_s * 1e9) for s in samples]
    times = [float(r[0]) for r in rows]
    assert times == [(t - stamps[0]) / 1e9 for t in stamps]
    assert [float(r[header.index("wob_n")]) for r in rows] == [s.wob_n for s in samples]


def test_info_shows_simulated_time_beside_the_wall_clock_duration(tmp_path, capsys):
    bag = tmp_path / "simtime"
    session_bag(bag, 600, rate_hz=100.0, speedup=10.0)     # 6 s simulated in 0.6 s
    assert main(["bag", "info", str(bag)]) == 0
    out = capsys.readouterr().out
    assert "Duration:          0.599 s of log time" in out
    assert "Simulated time:    5.990 s" in out and "/drill_sim/joint_states" in out
