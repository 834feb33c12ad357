"""``drill_sim bag compare``: two sessions the offline loop recorded in the node's format (the
drive's stiff loop against Z-Torque switched on in established stick-slip), their figures as
``bag metrics`` gives each, the differences, the switch where the loop made it, the figure."""

from __future__ import annotations

import json

import pytest

from drill_sim.cli.main import main
from drill_sim.core.effort import EFFORT_KEYS

H = 1e-3
SWITCH_S = 3.0


@pytest.fixture(scope="module")
def bags(tmp_path_factory):
    out = tmp_path_factory.mktemp("compare") / "rec"
    assert main(["control", "--rpm", "60", "--wob-kn", "100", "--duration", "10",
                 "--switch-on", str(SWITCH_S), "--laws", "stiff_pi,z_torque",
                 "--record", str(out)]) == 0
    return sorted(out.iterdir())


def test_the_table_is_each_bags_metrics_and_the_differences_from_the_first(bags, tmp_path,
                                                                           capsys):
    capsys.readouterr()
    png = tmp_path / "c.png"
    assert main(["bag", "compare", *map(str, bags), "--out", str(png), "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert png.stat().st_size > 10_000
    each = []
    for bag in bags:
        assert main(["bag", "metrics", str(bag), "--json"]) == 0
        each.append(json.loads(capsys.readouterr().out))
    first, second = (doc["bags"][str(b)] for b in bags)
    for key in ("ssi", "stick_fraction", "mean_rop_m_s", *EFFORT_KEYS):
        for shown, metrics in ((first, each[0]), (second, each[1])):
            # summed a chunk at a time by one, whole by the other: equal to rounding
            assert shown[key] == pytest.approx(metrics[key], rel=1e-12), key
    diff = doc["differences_from_first"][str(bags[1])]
    assert diff["ssi"] == pytest.approx(second["ssi"] - first["ssi"], abs=1e-15)
    assert diff["settling_time_s"] is None or first["settling_time_s"] is not None
    # each bag's controller switch, recorded at the tick before the law's first sample
    for bag, law in zip(bags, ("stiff_pi", "z_torque"), strict=True):
        switches = [e for e in doc["events"][str(bag)] if e["event"] == "controller"]
        assert [e["law"] for e in switches] == [law]
        assert switches[0]["time_s"] == pytest.approx(SWITCH_S - H, abs=1e-9)


def test_start_takes_the_figures_from_that_time_on(bags, tmp_path, capsys):
    capsys.readouterr()
    assert main(["bag", "compare", *map(str, bags), "--out", str(tmp_path / "c.png"), "--json",
                 "--start", "5"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert main(["bag", "metrics", str(bags[1]), "--json", "--start", "5"]) == 0
    later = json.loads(capsys.readouterr().out)
    shown = doc["bags"][str(bags[1])]
    for key in ("ssi", "duration_s", "motor_torque_rms_nm", "drive_energy_j"):
        assert shown[key] == pytest.approx(later[key], rel=1e-9), key


def test_the_text_table_names_each_bag_and_marks_what_does_not_apply(bags, tmp_path, capsys):
    assert main(["bag", "compare", *map(str, bags), "--out", str(tmp_path / "c.png")]) == 0
    out = capsys.readouterr().out
    assert f"[0] {bags[0]}" in out and f"[1] {bags[1]}" in out
    assert "[1]-[0]" in out and "settling time [s]" in out


@pytest.mark.parametrize(("extra", "words"), [
    ([], "1 bag given; expected two or more"),
    (["/etc/passwd"], "not an MCAP file"),
    (["SAME"], "given twice; expected each bag once"),
])
def test_refusals_are_one_line(bags, tmp_path, capsys, extra, words):
    extra = [str(bags[0]) if e == "SAME" else e for e in extra]
    assert main(["bag", "compare", str(bags[0]), *extra, "--out",
                 str(tmp_path / "c.png")]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and words in err, err
