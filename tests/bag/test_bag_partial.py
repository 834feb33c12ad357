"""Every tool says what it skipped: over a damaged bag, metrics, export, plot, resim and the
player report the damage and exit 1 unless asked for a partial result (``--partial``); info
exits 1 on damage; resim never claims an exact match over part of a session; NaN values and
stamps that go backwards are problems of the bag, and a file listed twice counts once."""

from __future__ import annotations

import json
import os
import subprocess

import pytest
import yaml
from bagutil import T0_NS, rig_bag
from conftest import installed
from sessionutil import samples_bag, session_bag

from drill_sim.bag import reader
from drill_sim.bag.mcap_scan import OP_CHUNK, McapScan
from drill_sim.cli.main import main

TICKS = 2000
JOINTS = "/drill_sim/joint_states"


def _chunk_bodies(path) -> list[tuple[int, int]]:
    with McapScan(path, []) as scan:
        return [(start, end) for op, start, end in scan.records() if op == OP_CHUNK]


def _flip(path, k: int = 1) -> None:
    start, end = _chunk_bodies(path)[k]
    data = bytearray(path.read_bytes())
    data[(start + end) // 2] ^= 0x20
    path.write_bytes(bytes(data))


@pytest.fixture
def damaged(tmp_path):
    """A rig bag with one flipped byte in its second chunk, and its readable sample count."""
    bag = tmp_path / "rig"
    rig_bag(bag, TICKS, chunk_size=60_000)
    _flip(bag / "rig_0.mcap")
    return bag, reader.info(bag).topics[JOINTS].count


def test_metrics_refuses_a_partial_result_unless_asked(damaged, capsys):
    bag, readable = damaged
    assert readable < TICKS
    assert main(["bag", "metrics", str(bag), "--json"]) == 1
    out, err = capsys.readouterr()
    assert out == "" and "chunk 2 of" in err and "--partial" in err
    assert main(["bag", "metrics", str(bag), "--json", "--partial"]) == 0
    m = json.loads(capsys.readouterr().out)
    assert m["samples"] == readable and "chunk 2 of" in m["problems"][0]


@pytest.mark.parametrize("tool", ["export", "plot"])
def test_export_and_plot_write_nothing_from_a_damaged_bag_unless_asked(damaged, tmp_path,
                                                                       capsys, tool):
    bag, readable = damaged
    out = tmp_path / ("out.csv" if tool == "export" else "out.png")
    assert main(["bag", tool, str(bag), "--out", str(out)]) == 1
    assert not out.exists() and "chunk 2 of" in capsys.readouterr().err
    assert main(["bag", tool, str(bag), "--out", str(out), "--partial"]) == 0
    assert out.exists()
    if tool == "export":
        assert len(out.read_text().splitlines()) == 1 + readable
    assert list(tmp_path.glob("*.tmp")) == []


def test_info_exits_1_on_damage_and_0_on_a_sound_bag(damaged, tmp_path, capsys):
    bag, _ = damaged
    assert main(["bag", "info", str(bag)]) == 1
    assert "chunk 2 of" in capsys.readouterr().out
    sound = tmp_path / "sound"
    rig_bag(sound, 200)
    assert main(["bag", "info", str(sound)]) == 0


def test_info_reports_a_recording_killed_between_two_chunks(tmp_path, capsys):
    bag = tmp_path / "killed"
    rig_bag(bag, TICKS, chunk_size=60_000)
    path = bag / "killed_0.mcap"
    cut = _chunk_bodies(path)[3][0] - 9                 # the file ends at a record boundary
    path.write_bytes(path.read_bytes()[:cut])
    (bag / "metadata.yaml").unlink()
    assert main(["bag", "info", str(bag)]) == 1
    assert "no summary" in capsys.readouterr().out


@pytest.mark.offline                # its program starts no node
def test_resim_never_claims_an_exact_match_over_a_partial_bag(tmp_path):
    bag = tmp_path / "session"
    session_bag(bag, 800)
    done = _resim(bag)
    assert done.returncode == 0 and "reproduced exactly" in done.stdout
    _flip(bag / "session_0.mcap", 3)
    done = _resim(bag)
    assert done.returncode == 1, done.stdout + done.stderr
    assert "reproduced exactly" not in done.stdout
    assert "incomplete" in done.stdout or "the bag is damaged" in done.stdout
    done = _resim(bag, "--json", "--partial")
    r = json.loads(done.stdout)
    # WOB and TOB are means since the previous sample, so the sample after lost ones covers a
    # longer interval in the recording than in the re-run: past the damage they cannot match
    assert not r["exact"] and r["problems"]
    assert done.returncode == (0 if r["matched"] else 1)


@pytest.mark.offline                # its program starts no node
def test_resim_of_a_repaired_crash_compares_only_the_part_kept(tmp_path):
    """A recording cut in the middle (a crash) and then repaired is sound up to the cut, but
    the session went on: resim says the part kept matches, not that it reproduced the session
    (before the repair it said the same of the cut bag)."""
    bag = tmp_path / "session"
    session_bag(bag, 800)
    path = bag / "session_0.mcap"
    start, end = _chunk_bodies(path)[3]
    path.write_bytes(path.read_bytes()[:(start + end) // 2])
    (bag / "metadata.yaml").unlink()
    assert main(["bag", "repair", str(bag)]) == 0
    done = _resim(bag, "--json")
    r = json.loads(done.stdout)
    assert done.returncode == 1 and r["matched"] and not r["exact"], done.stdout
    assert any("was repaired" in p for p in r["problems"]), r["problems"]
    assert _resim(bag, "--partial").returncode == 0


def _resim(bag, *extra: str) -> subprocess.CompletedProcess:
    return subprocess.run([installed("drill_sim"), "bag", "resim", str(bag), *extra],
                          capture_output=True, text=True, timeout=300)


def test_replay_refuses_a_damaged_bag_unless_asked(damaged):
    from rosutil import isolate

    bag, _ = damaged
    readable = reader.info(bag).message_count
    isolate()
    play = [installed("drill_sim_replay"), str(bag), "--wait-for", "0", "--rate", "20"]
    done = subprocess.run(play, capture_output=True, text=True, timeout=120, env=os.environ)
    assert done.returncode == 1 and "chunk 2 of" in done.stderr and "--partial" in done.stderr
    done = subprocess.run([*play, "--partial"], capture_output=True, text=True, timeout=120,
                          env=os.environ)
    assert done.returncode == 0, done.stderr
    assert f"published {readable} messages" in done.stderr


def _stamped(ticks: int, change) -> list:
    """(stamp, sample) pairs of the base rig's bag, each passed through ``change``."""
    import tempfile
    from pathlib import Path
    with tempfile.TemporaryDirectory() as tmp:
        samples = rig_bag(Path(tmp) / "b", ticks)
    return [change(k, T0_NS + round(s.time_s * 1e9), s) for k, s in enumerate(samples)]


def test_nan_values_are_left_out_of_the_metrics_and_reported(tmp_path, capsys):
    bag = tmp_path / "nan"
    samples_bag(bag, _stamped(1000, lambda k, t, s: (t, s._replace(wob_n=float("nan"))
                                                      if k % 100 == 7 else s)))
    assert main(["bag", "metrics", str(bag), "--json"]) == 1
    assert "NaN" in capsys.readouterr().err
    assert main(["bag", "metrics", str(bag), "--json", "--partial"]) == 0
    m = json.loads(capsys.readouterr().out)
    assert m["samples"] == 990 and m["mean_wob_n"] == pytest.approx(100e3, rel=1e-6)
    assert "10 samples hold NaN" in m["problems"][0]


def test_stamps_going_backwards_are_reported_and_the_duration_stays_a_span(tmp_path, capsys):
    bag = tmp_path / "backwards"
    samples_bag(bag, _stamped(1000, lambda k, t, s: (2 * T0_NS - t, s)))     # time reversed
    assert main(["bag", "metrics", str(bag), "--json"]) == 1
    assert "backwards" in capsys.readouterr().err
    assert main(["bag", "metrics", str(bag), "--json", "--partial"]) == 0
    m = json.loads(capsys.readouterr().out)
    assert m["duration_s"] == pytest.approx(0.999, abs=1e-3)
    assert "go backwards 999 times" in m["problems"][0]


def test_a_file_listed_twice_counts_once_in_metrics(tmp_path, capsys):
    bag = tmp_path / "twice"
    rig_bag(bag, 500)
    meta_path = bag / "metadata.yaml"
    meta = yaml.safe_load(meta_path.read_text())
    meta["rosbag2_bagfile_information"]["relative_file_paths"] *= 2
    meta_path.write_text(yaml.safe_dump(meta))
    assert main(["bag", "metrics", str(bag), "--json"]) == 0
    out, err = capsys.readouterr()
    assert json.loads(out)["samples"] == 500 and "listed" not in out
    assert "twice_0.mcap 2 times" in err

