"""``drill_sim tune``'s study (``study.gain_tuning``): the objective is the documented one
computed from ``drill_sim control``'s own scores, the reference gains are the first trial, the
study resumes from its journal, and bad requests are refused by name."""

from __future__ import annotations

import pytest
import yaml

from drill_sim.control.closed_loop import run_loop
from drill_sim.control.evaluation import LoopSettings
from drill_sim.control.scenarios import named
from drill_sim.core import ParameterError, load_preset
from drill_sim.study import gain_tuning as gt

SHORT = """description: "a short stick-slip run for tests: 60 rpm, 100 kN, 8 s"
initial_state: steady
duration_s: 8.0
window_start_s: 4.0
points:
  - {at_s: 0.0, rpm: 60.0, wob_kn: 100.0}
"""


@pytest.fixture
def short(tmp_path):
    path = tmp_path / "short.yaml"
    path.write_text(SHORT)
    return str(path)


def _job(scenario: str, law: str = "z_torque", **gains: float) -> gt.TrialJob:
    job = gt.TrialJob(preset="base", law=law, gains={}, scenarios=(scenario,))
    return gt.TrialJob(**{**job.__dict__, "gains": {**gt.reference_for(job), **gains}})


def test_the_objective_is_ssi_plus_ten_stick_plus_ten_saturation_over_five_percent(
        short, monkeypatch):
    """From the offline loop's own scores: a stiff PI that sticks, run for real; then the
    saturation term on scores given by hand (below 5 %: free)."""
    job = _job(short, "stiff_pi")
    r = run_loop(load_preset("base"), named([short])[0],
                 LoopSettings(law="stiff_pi", gains=dict(job.gains)))
    got = gt.score(job)
    assert r.stick_fraction > 0.05                                # it does stick
    assert got.objective == pytest.approx(r.ssi + 10.0 * r.stick_fraction
                                          + 10.0 * max(0.0, r.saturation_fraction - 0.05),
                                          rel=1e-12)
    assert (got.ssi, got.stick_fraction) == (r.ssi, r.stick_fraction)

    class Scored:
        def __init__(self, ssi, stick, saturation):
            self.ssi, self.stick_fraction, self.saturation_fraction = ssi, stick, saturation
    runs = iter([Scored(0.3, 0.1, 0.2), Scored(0.5, 0.0, 0.03)])
    monkeypatch.setattr(gt, "run_loop", lambda *a, **k: next(runs))
    monkeypatch.setattr(gt, "named", lambda names: [None, None])
    two = gt.score(job)
    assert two.objective == pytest.approx(((0.3 + 1.0 + 1.5) + 0.5) / 2, rel=1e-12)
    assert two.saturation_fraction == pytest.approx(0.115)


def test_the_reference_is_the_first_trial_and_a_study_resumes(short, tmp_path):
    job = _job(short)
    space = gt.search_space("z_torque", ["alpha"], job.gains, {})
    assert space["alpha"] == gt.Range(0.125, 2.0, True)          # 0.5 / 4 to x 4, log
    journal = tmp_path / "study.journal"
    first = gt.tune(job, space, trials=3, journal=journal, seed=1)
    assert len(first.trials) == 3 and first.trials[0][0]["alpha"] == 0.5
    assert first.reference is not None
    assert first.reference.objective == pytest.approx(gt.score(job).objective, rel=1e-12)
    again = gt.tune(job, space, trials=5, journal=journal, seed=1)
    assert len(again.trials) == 5
    assert [g for g, _ in again.trials[:3]] == [g for g, _ in first.trials]
    assert again.best.objective <= first.best.objective
    assert again.improved == (again.best.objective < 0.99 * again.reference.objective)
    other = gt.TrialJob(**{**job.__dict__, "sensor_seed": 3})
    with pytest.raises(ParameterError, match="was run with other settings"):
        gt.tune(other, space, trials=6, journal=journal, seed=1)
    kp = gt.search_space("z_torque", ["kp_nm_s_rad"], job.gains, {})
    with pytest.raises(ParameterError, match="searched other gains or ranges"):
        gt.tune(job, kp, trials=6, journal=journal, seed=1)
    assert len(gt.tune(job, space, trials=5, journal=journal, seed=1).trials) == 5   # intact


def test_a_damaged_journal_is_refused_by_name_before_any_run(short, tmp_path):
    journal = tmp_path / "study.journal"
    journal.write_text('{"op_code": 0, "worker_id": "x"\nnot a journal line\n')
    job = _job(short)
    space = gt.search_space("z_torque", ["alpha"], job.gains, {})
    with pytest.raises(ParameterError, match=r"study journal .* is damaged"):
        gt.tune(job, space, trials=2, journal=journal, seed=1)


@pytest.mark.parametrize(("law", "names", "ranges", "words"), [
    ("z_torque", ["beta"], {}, "z_torque has no gain 'beta' to tune"),
    ("z_torque", ["torque_max_nm"], {}, "the torque limits are the drive's"),
    ("z_torque", [], {}, "no gains to tune"),
    ("kinematic", ["alpha"], {}, "has no gains to tune"),
    ("z_torque", ["alpha"], {"alpha": (1.0, 0.5)}, "expected finite LOW < HIGH"),
    ("stiff_pi", ["ki_nm_rad"], {}, "ki_nm_rad: no reference value"),
])
def test_bad_requests_are_refused_by_name(law, names, ranges, words):
    with pytest.raises(ParameterError, match=words):
        gt.search_space(law, names, {"alpha": 0.5}, ranges)


def test_the_params_file_names_only_the_controllers_parameters(short, tmp_path):
    """What ``drill_sim tune --out`` writes: every key a drill_sim_controller parameter (as
    the shipped files, tests/control/test_params_files.py) and the tuned gains in it."""
    import argparse

    from drill_sim.cli.tune import _write
    from drill_sim.control import LAWS
    job = _job(short)
    result = gt.tune(job, gt.search_space("z_torque", ["alpha"], job.gains, {}), trials=2,
                     journal=tmp_path / "j", seed=0)
    out = tmp_path / "tuned.yaml"
    _write(out, argparse.Namespace(law="z_torque", preset="base", scenarios=short,
                                   sensor_profile="ideal", string_model="lumped",
                                   sample_period=1e-3), result)
    params = yaml.safe_load(out.read_text())["/**"]["ros__parameters"]
    gains = {k.split(".", 1)[1]: v for k, v in params.items() if k.startswith("z_torque.")}
    assert set(gains) <= set(LAWS["z_torque"].GAINS)
    assert set(params) - {f"z_torque.{g}" for g in gains} <= {
        "law", "rig", "sample_period_s", "impedance_nm_s_rad", "top_drive_inertia_kg_m2",
        "inputs", "manage_drive_mode", "enabled"}
    chosen = result.best_gains if result.improved else result.reference_gains
    assert gains["alpha"] == chosen["alpha"]
    assert (gains["torque_min_nm"], gains["torque_max_nm"]) == (-60e3, 60e3)


@pytest.mark.parametrize(("item", "words"), [
    ("alpha=-1:1", "range of alpha = -1:1: the law refuses alpha = -1"),
    ("speed_lowpass_hz=600:1000", "the law refuses speed_lowpass_hz = 600"),
])
def test_a_range_the_law_refuses_is_refused_before_any_run(item, words, tmp_path, capsys):
    """``drill_sim tune --range``: both ends are built into the law first, so a range the law
    refuses is one line (exit 2) and no journal is started."""
    from drill_sim.cli.main import main
    name = item.split("=")[0]
    assert main(["tune", "--law", "z_torque", "--params", name, "--range", item, "--trials",
                 "2", "--out", str(tmp_path / "t.yaml")]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and words in err, err
    assert not (tmp_path / "t.yaml.journal").exists()
