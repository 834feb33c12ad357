"""``drill_sim simulate --sensor-profile``: measured columns beside the exact ones, sampled,
delayed and quantised as the profile says, repeatable by seed; bad uses refused clearly."""

from __future__ import annotations

import numpy as np
import pytest
from test_cli import run

from drill_sim.cli.main import main
from drill_sim.core import ParameterError, load_preset
from drill_sim.core.sensor_profile import CHANNELS

pytestmark = pytest.mark.offline        # its programs start no node


def _simulate(tmp_path, name: str, *extra: str) -> dict[str, np.ndarray]:
    out = tmp_path / f"{name}.csv"
    run("simulate", "--preset", "base", "--rpm", "60", "--wob-kn", "100", "--duration", "50",
        "--output-interval", "0.01", "--out", str(out), "--json", *extra)
    data = np.genfromtxt(out, delimiter=",", names=True)
    return {n: data[n] for n in data.dtype.names}


def test_measured_columns_follow_the_profile_and_the_seed(tmp_path):
    a = _simulate(tmp_path, "a", "--sensor-profile", "mud_pulse", "--sensor-seed", "3")
    for c in CHANNELS:
        assert f"measured_{c}" in a and f"fresh_{c}" in a
    t = a["time_s"]
    # mud pulse: a WOB word every 12 s, shown 20 s after it was taken, in 2 kN steps
    shown_at = t[a["fresh_wob_n"] == 1]
    expected = t[0] + 20.0 + 12.0 * np.arange(3)
    assert len(shown_at) == 3 and np.abs(shown_at - expected).max() <= 0.01 + 1e-9
    wob = a["measured_wob_n"]
    assert np.array_equal(wob / 2000.0, np.round(wob / 2000.0))
    # surface torque at 100 Hz: a fresh value nearly every row (rows are whole model steps,
    # 9.994 ms apart, so one row in ~1600 has no new sample)
    assert 0.998 < a["fresh_surface_torque_nm"].mean() < 1.0
    noise = a["measured_surface_torque_nm"] - a["surface_torque_nm"]
    assert np.std(noise) > 50.0                     # the 150 N m noise is there
    b = _simulate(tmp_path, "b", "--sensor-profile", "mud_pulse", "--sensor-seed", "3")
    c = _simulate(tmp_path, "c", "--sensor-profile", "mud_pulse", "--sensor-seed", "4")
    assert all(np.array_equal(a[k], b[k]) for k in a)
    assert not np.array_equal(a["measured_surface_torque_nm"], c["measured_surface_torque_nm"])
    assert np.array_equal(a["bit_speed_rad_s"], c["bit_speed_rad_s"])   # the model unchanged


@pytest.mark.parametrize("args, words", [
    (("--groups", "n=4,psi=13.73,lambda=6.84,beta=0.36", "--w0", "9.6", "--omega0", "1.32",
      "--sensor-profile", "ideal", "--out", "x.csv"), "expected SI mode"),
    (("--preset", "base", "--sensor-profile", "ideal"), "expected --out"),
    (("--preset", "base", "--sensor-seed", "2", "--out", "x.csv"), "expected --sensor-profile"),
    (("--preset", "base", "--sensor-profile", "nope", "--out", "x.csv"),
     "neither a shipped sensor profile"),
    (("--preset", "base", "--sensor-profile", "ideal", "--sensor-seed", "-1", "--out", "x.csv"),
     "expected a sensor seed: a whole number 0 to 2,147,483,647"),
])
def test_bad_sensor_options_are_refused_with_what_was_expected(tmp_path, args, words):
    proc = run("simulate", *args, "--duration", "1", check=False)
    assert proc.returncode == 2 and words in proc.stderr, proc.stderr
    assert "Traceback" not in proc.stderr


@pytest.mark.parametrize("argv", [
    ["control", "--rpm", "60", "--wob-kn", "100", "--duration", "2"],
    ["simulate", "--preset", "base", "--rpm", "60", "--wob-kn", "100", "--duration", "1",
     "--sensor-profile", "surface_rig", "--out", "{tmp}/x.csv"],
    ["tune", "--law", "z_torque", "--params", "alpha", "--trials", "1", "--out",
     "{tmp}/t.yaml"],
])
def test_every_tool_takes_the_nodes_sensor_seed_range(argv, tmp_path, capsys):
    """One range for a sensor seed, the node's parameter's: 2**31 - 1 is taken where the node
    takes it, 2**31 is refused in one line by every tool, as by the node and the core."""
    from drill_sim.core.sensors import MAX_SENSOR_SEED, SensorBank
    from drill_sim.session.parameter_table import specs
    spec = next(s for s in specs(load_preset("base")) if s.name == "sensor_seed")
    assert (spec.low, spec.high) == (0, MAX_SENSOR_SEED) == (0, 2**31 - 1)
    SensorBank("ideal", 1e-3, MAX_SENSOR_SEED)
    with pytest.raises(ParameterError, match="from 0 to 2147483647"):
        SensorBank("ideal", 1e-3, MAX_SENSOR_SEED + 1)
    args = [a.replace("{tmp}", str(tmp_path)) for a in argv]
    assert main([*args, "--sensor-seed", str(MAX_SENSOR_SEED + 1)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "0 to 2,147,483,647" in err, err
