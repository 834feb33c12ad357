"""The offline closed loop runs the rig node's own session: its bag re-simulates exactly, its
commands pass the node's rules, and it starts as the node does (``initial_perturbation``)."""

from __future__ import annotations

import dataclasses
import math

import pytest

from drill_sim.bag.series import rig_series
from drill_sim.control.closed_loop import run_loop
from drill_sim.control.evaluation import LoopSettings, Scenario
from drill_sim.core import ParameterError, load_preset
from drill_sim.session.resim import resimulate


@pytest.fixture(scope="module")
def base():
    return load_preset("base")


def test_a_recorded_loop_resimulates_exactly_and_holds_what_the_loop_saw(base, tmp_path):
    """A WOB step with the law switched on, under noisy, late sensors: the bag re-runs bit for
    bit, and its samples are the loop's own series."""
    scenario = Scenario.of_points("step", ((0.0, 60.0),),
                                  ((0.0, 90.0), (1.0, 90.0), (1.5, 110.0)),
                                  duration_s=3.0, window_start_s=1.0, switch_on_s=1.0)
    bag = tmp_path / "loop"
    r = run_loop(base, scenario, LoopSettings(law="z_torque", sensor_profile="surface_rig",
                                              sensor_seed=4), record=bag)
    result = resimulate(bag)
    assert result.exact, result.explanation()
    assert result.preset == "base"                      # the session names its preset
    assert result.samples == 3001 and result.refused == 0
    # the law takes over from the torque the drive holds (the steady start's), not from the
    # noisy reading of it: stiff PI's first output is exactly the applied motor torque
    assert r.series["law_output"][0] == pytest.approx(r.series["motor_torque_nm"][0],
                                                      rel=1e-12)
    assert result.max_difference["measured top_drive_speed_rad_s"] == 0.0
    recorded = rig_series(bag)
    assert (recorded.bit_speed_rad_s == r.series["bit_speed_rad_s"]).all()
    assert (recorded.wob_n == r.series["wob_n"]).all()


def test_the_loops_commands_pass_the_nodes_rules(base):
    """A set-point the rig node would refuse (above its largest top-drive speed) stops the
    loop with the node's refusal, as it would stop a lockstep run."""
    with pytest.raises(ParameterError, match="top-drive speed"):
        run_loop(base, Scenario.of_points("fast", ((0.0, 60.0), (0.5, 600.0)),
                                          ((0.0, 100.0),), duration_s=1.0, window_start_s=0.5),
                 LoopSettings(law="kinematic"))


YAML_SWITCH = {"duration_s": 2.0, "points": [{"at_s": 0.0, "rpm": 60.0, "wob_kn": 100.0}],
               "controller": {"law": "z_torque", "on_at_s": 1.0}}


def test_a_rig_scenario_is_the_evaluations_experiment(base):
    """The driller's scenario (a YAML a node plays) and the evaluation's switch-on are one
    experiment: the same points and switch run the offline loop bit for bit alike, and the
    metrics window starts at the switch."""
    from drill_sim.session.scenario import scenario_from_dict
    rig = scenario_from_dict("yaml_switch", YAML_SWITCH)
    made = Scenario.of_points("made", ((0.0, 60.0),), ((0.0, 100.0),), duration_s=2.0,
                              window_start_s=1.0, switch_on_s=1.0)
    assert rig.switch_on_s == made.switch_on_s == 1.0 and rig.metrics_from_s == 1.0
    settings = LoopSettings(law="z_torque")
    a, b = run_loop(base, rig, settings), run_loop(base, made, settings)
    for key in ("bit_speed_rad_s", "motor_torque_nm", "law_output"):
        assert (a.series[key] == b.series[key]).all(), key
    assert a.ssi == b.ssi


def test_a_scenarios_parameter_change_lands_on_its_tick_offline_and_replays(base, tmp_path):
    """A harder formation at 1.5 s: the loop is the unchanged one's, bit for bit, up to that
    tick and not after; the bag records the change and re-simulates exactly."""
    from drill_sim.session.scenario import scenario_from_dict
    plain = scenario_from_dict("plain", YAML_SWITCH)
    harder = scenario_from_dict("harder", {**YAML_SWITCH, "changes": [
        {"at_s": 1.5, "intrinsic_specific_energy_pa": 1.3e8}]})
    settings = LoopSettings(law="z_torque")
    a = run_loop(base, plain, settings)
    b = run_loop(base, harder, settings, record=tmp_path / "harder")
    k = 1500                                            # the tick at 1.5 s (h = 1 ms)
    wob_a, wob_b = a.series["wob_n"], b.series["wob_n"]
    assert (wob_a[:k + 1] == wob_b[:k + 1]).all()
    assert wob_b[k + 1] != wob_a[k + 1]                 # from the step after that tick
    assert abs(wob_b[k + 2:] - wob_a[k + 2:]).max() > 1e3     # a harder rock: another weight
    result = resimulate(tmp_path / "harder")
    assert result.exact, result.explanation()


def test_a_bad_scenario_change_is_refused_before_the_loop_runs(base):
    from drill_sim.session.scenario import scenario_from_dict
    bad = scenario_from_dict("bad", {**YAML_SWITCH, "changes": [
        {"at_s": 1.0, "intrinsic_specific_energy_pa": -1.0}]})
    with pytest.raises(ParameterError, match=r"change at 1 s: intrinsic_specific_energy_pa"):
        run_loop(base, bad, LoopSettings(law="z_torque"))


def test_a_hook_load_scenario_is_refused_by_the_evaluation(base):
    from drill_sim.session.scenario import scenario_from_dict
    hook = scenario_from_dict("hook", {"duration_s": 2.0, "points": [
        {"at_s": 0.0, "rpm": 60.0, "hook_load_kn": 900.0}]})
    with pytest.raises(ParameterError, match="hook load: expected weight on bit"):
        run_loop(base, hook, LoopSettings(law="z_torque"))


def test_the_evaluation_takes_the_rigs_shipped_scenarios_by_name():
    from drill_sim.control.scenarios import named
    [on] = named(["controller_on"])
    assert on.switch_on_s == 35.0 and on.metrics_from_s == 50.0      # its window_start_s
    with pytest.raises(ParameterError, match="controller_on"):      # the refusal lists them
        named(["no_such_set"])


@pytest.mark.parametrize("suffix", [".yaml", ".yml"])
def test_the_evaluation_takes_a_scenario_file(tmp_path, suffix):
    import yaml

    from drill_sim.control.scenarios import named
    path = tmp_path / f"mine{suffix}"
    path.write_text(yaml.safe_dump(YAML_SWITCH))
    [mine] = named([str(path)])
    assert (mine.duration_s, mine.switch_on_s) == (2.0, 1.0)


@pytest.mark.parametrize("switch_on_s", [0.3, 0.0])
def test_the_loop_is_the_rig_ticked_by_hand_under_the_supervisor(base, tmp_path, switch_on_s):
    """The offline loop's semantics, computed independently on a bare ``Rig``: set-point and
    hook load k held over k..k+1, the motor torque answered to sample k applied over
    k..k+1, the drive's stiff loop until sample ceil(switch_on_s / h), then the law, bumpless;
    the window from sample ceil(window_start_s / h). Speed and WOB both ramp, so a set-point
    or a load a tick early or late shows. Its bag holds the speed set-point, the hook load
    and the motor torque each as a driver sends it, once per change, stamped at its tick."""
    from drill_sim.control.closed_loop import session_parameters, tick_commands
    from drill_sim.control.evaluation import ideal_measurement, law_gains, law_top_drive
    from drill_sim.control.supervisor import Supervisor
    from drill_sim.control.tuning import pipe_impedance
    from drill_sim.session import rules
    scenario = Scenario.of_points("ramps", ((0.0, 60.0), (0.9, 70.0)),
                                  ((0.0, 100.0), (0.2, 100.0), (0.8, 110.0)), duration_s=1.0,
                                  window_start_s=0.6, switch_on_s=switch_on_s)
    settings = LoopSettings(law="z_torque")
    h = settings.sample_period_s
    result = run_loop(base, scenario, settings, record=tmp_path / "z")

    p = session_parameters(base, scenario, settings)
    rig = rules.make_rig(p)
    rules.start(rig, p)
    speed, hook = tick_commands(base, scenario, h)
    drive = law_top_drive(base, "z_torque", None)
    first = ("stiff_pi", {"torque_min_nm": drive.motor_torque_min_nm,
                          "torque_max_nm": drive.motor_torque_max_nm}) if switch_on_s else (
        "z_torque", law_gains(settings, drive))
    sup = Supervisor(h, pipe_impedance(base), drive.top_drive_inertia_kg_m2, *first,
                     speed_set_rad_s=float(speed[0]))
    sup.last_output = rig.commanded_motor_torque_nm
    out = sup.step(ideal_measurement(rig.sample()))
    steps = round(h / rig.dt_s)
    samples, law_out = [rig.sample()], [out]
    for k in range(1, speed.size):
        rig.command(float(speed[k - 1]), float(hook[k - 1]))
        rig.command_motor_torque(out)
        rig.advance_steps(steps)
        if k == 600:
            rig.reset_metrics_window()
        s = rig.sample()
        if k == 300 and switch_on_s:
            sup.replace_law("z_torque", law_gains(settings, drive))
        sup.set_speed(float(speed[k]))
        out = sup.step(ideal_measurement(s))
        samples.append(s)
        law_out.append(out)
    for column in ("time_s", "bit_speed_rad_s", "top_drive_speed_rad_s", "surface_torque_nm",
                   "motor_torque_nm", "stuck", "bit_depth_m", "top_drive_angle_rad", "wob_n"):
        assert list(result.series[column]) == [float(getattr(x, column)) for x in samples], column
    assert list(result.series["law_output"]) == law_out
    # the result's figures, from the hand loop's own window (samples 600.., rpm = 2 pi/60)
    metrics, rpm = rig.metrics(), 2.0 * math.pi / 60.0
    assert result.window_s == pytest.approx(0.4, abs=1e-9)
    assert (result.law, result.scenario, result.sensor_profile, result.string_model) == (
        "z_torque", "ramps", "ideal", "lumped")
    assert result.mean_bit_speed_rpm == pytest.approx(metrics["mean_bit_speed_rad_s"] / rpm,
                                                      rel=1e-12)
    assert result.min_bit_speed_rpm == pytest.approx(metrics["min_bit_speed_rad_s"] / rpm,
                                                     rel=1e-12)
    assert result.max_bit_speed_rpm == pytest.approx(metrics["max_bit_speed_rad_s"] / rpm,
                                                     rel=1e-12)
    on_limit = [abs(abs(o) - 6e4) < 1e-4 for o in law_out[600:]]
    assert result.saturation_fraction == pytest.approx(sum(on_limit) / len(on_limit))
    assert result.saturation_time_s == pytest.approx(result.saturation_fraction * 0.4)
    sent = _commands_in_bag(tmp_path / "z", ("top_drive", "hook_load", "top_drive_torque"))
    for rule, values, place in (("top_drive", speed, 5), ("hook_load", hook, 2),
                                ("top_drive_torque", law_out, 5)):
        _assert_sent_once_per_change(sent[rule], values, place, h, rule)


def test_a_kinematic_loop_is_the_rig_commanded_by_hand_and_its_bag_holds_each_command_once(
        base, tmp_path):
    """The kinematic row: set-point and hook load k held over k..k+1 on a bare ``Rig``; the
    bag holds each command as a driver sends it (its one component, stamped at the tick it
    was given) and once per change, not once per tick."""
    from drill_sim.control.closed_loop import session_parameters, tick_commands
    from drill_sim.session import rules
    scenario = Scenario.of_points("ramps", ((0.0, 60.0), (0.1, 60.0), (0.3, 70.0)),
                                  ((0.0, 100.0), (0.2, 100.0), (0.25, 110.0)),
                                  duration_s=0.4, window_start_s=0.2)
    settings = LoopSettings(law="kinematic")
    result = run_loop(base, scenario, settings, record=tmp_path / "k")
    p = session_parameters(base, scenario, settings)
    rig = rules.make_rig(p)
    rules.start(rig, p)
    speed, hook = tick_commands(base, scenario, 1e-3)
    bit = [rig.sample().bit_speed_rad_s]
    for k in range(1, speed.size):
        rig.command(float(speed[k - 1]), float(hook[k - 1]))
        rig.advance_steps(round(1e-3 / rig.dt_s))
        bit.append(rig.sample().bit_speed_rad_s)
    assert list(result.series["bit_speed_rad_s"]) == bit
    assert list(result.series["law_output"]) == list(speed)        # the pass-through

    sent = _commands_in_bag(tmp_path / "k", ("top_drive", "hook_load"))
    for rule, values, place in (("top_drive", speed, 5), ("hook_load", hook, 2)):
        _assert_sent_once_per_change(sent[rule], values, place, 1e-3, rule)


def _commands_in_bag(path, rules: tuple[str, ...]) -> dict[str, list]:
    """(stamp [s], the six components) of each command a bag holds, by the node's rule."""
    from drill_sim.bag.bag import opened
    from drill_sim.wire import cdr_decode, rig_topics
    sent = {rule: [] for rule in rules}
    with opened(path) as bag:
        for m in bag.messages():
            for rule in sent:
                topic = rig_topics.COMMAND_BY_RULE[rule]
                if m.topic == topic.under("/" + rig_topics.NODE_NAME):
                    _, sec, nsec, six = cdr_decode.decode_command(topic.type_name, m.data)
                    sent[rule].append((sec + nsec * 1e-9, six))
    return sent


def _assert_sent_once_per_change(sent, values, place: int, tick_s: float, rule: str) -> None:
    """A command per change of ``values`` (ticks 0 .. n-2: the last tick has no step after
    it), stamped at its tick, the value in component ``place`` and the others 0."""
    changes = [k for k in range(len(values) - 1) if k == 0 or values[k] != values[k - 1]]
    assert len(sent) == len(changes), rule                             # once per change
    for (stamp_s, six), k in zip(sent, changes, strict=True):
        assert stamp_s == pytest.approx(k * tick_s, abs=1e-9), rule    # given at tick k
        assert six[place] == values[k], rule
        assert [v for i, v in enumerate(six) if i != place] == [0.0] * 5, rule


def test_the_loops_session_parameters_are_the_settings_and_the_scenarios(base):
    """What the loop's rig session is built from: its tick, start, drive, string and sensors."""
    from drill_sim.control.closed_loop import session_parameters
    from drill_sim.core.top_drive import TopDriveParameters
    drive = TopDriveParameters(top_drive_inertia_kg_m2=1234.0, motor_torque_max_nm=5e4,
                               motor_torque_min_nm=-4e4, drive_kp_nm_s_rad=1e4)
    scenario = dataclasses.replace(Scenario.of_points(
        "s", ((0.0, 60.0),), ((0.0, 90.0),), duration_s=2.0, window_start_s=1.0,
        start_rpm=55.0), initial_state="rest")
    settings = LoopSettings(law="z_torque", sample_period_s=2e-3, top_drive=drive,
                            string_model="distributed", sensor_profile="surface_rig",
                            sensor_seed=7, perturbation=0.01)
    p = session_parameters(base, scenario, settings)
    assert p["rate_hz"] == 500.0 and p["max_speed"] is True and p["publish_clock"] is True
    assert p["initial_top_drive_speed_rad_s"] == pytest.approx(55.0 * 2 * math.pi / 60)
    assert p["initial_weight_on_bit_n"] == 90e3 and p["initial_state"] == "rest"
    assert p["initial_perturbation"] == 0.01
    assert (p["string_model"], p["sensor_profile"], p["sensor_seed"]) == (
        "distributed", "surface_rig", 7)
    assert (p["top_drive_mode"], p["top_drive_inertia_kg_m2"], p["motor_torque_max_nm"],
            p["motor_torque_min_nm"]) == ("torque", 1234.0, 5e4, -4e4)
    assert p["motor_torque_rate_nm_s"] == 0.0            # the table's "no rate limit"
    assert p["max_top_drive_speed_rad_s"] == 40.0        # a set-point ramp up to 380 rpm
    assert session_parameters(base, Scenario.steady(60.0, 90.0), settings)[
        "initial_top_drive_speed_rad_s"] == pytest.approx(60.0 * 2 * math.pi / 60)
    for bad in (0.0, 1.5, math.nan):
        with pytest.raises(ParameterError, match="sample_period_s"):
            session_parameters(base, scenario, LoopSettings(law="z_torque",
                                                            sample_period_s=bad))


@pytest.mark.parametrize(("duration_s", "every"), [(0.2, 1), (0.6, 3), (0.7, 3)])
def test_progress_is_the_fraction_done_about_200_times(base, duration_s, every):
    seen = []
    run_loop(base, Scenario.steady(60.0, 100.0, duration_s=duration_s, window_start_s=0.1),
             LoopSettings(law="kinematic"), progress=seen.append)
    n = round(duration_s / 1e-3)
    assert seen == [k / n for k in range(every, n + 1, every)]


def test_the_ticks_commands_are_the_scenario_at_k_h(base):
    """speed_ramp: 120 rpm to 10 s, 40 rpm at 40 s, 100 kN throughout; at 10 ms ticks, tick
    2500 is 25 s (80 rpm). A weight of all of W_s is a hook load of 0, taken."""
    from drill_sim.control.closed_loop import tick_commands
    from drill_sim.control.scenarios import speed_ramp
    rpm = 2 * math.pi / 60
    speed, hook = tick_commands(base, speed_ramp(), 0.01)
    assert speed.size == hook.size == 5001
    assert speed[[0, 1000, 2500, 4000, 5000]] == pytest.approx(
        [120 * rpm, 120 * rpm, 80 * rpm, 40 * rpm, 40 * rpm], rel=1e-12)
    assert hook == pytest.approx(base.rig.submerged_weight_n - 100e3, rel=1e-12)
    all_of_it = Scenario.steady(60.0, base.rig.submerged_weight_n / 1e3, duration_s=1.0,
                                window_start_s=0.5)
    assert tick_commands(base, all_of_it, 0.01)[1] == pytest.approx(0.0, abs=1e-6)


def test_the_loop_runs_the_distributed_string_of_its_preset(base):
    """The session is built with the preset's pipe: the distributed string runs offline (a
    torsional wave takes L/c = 1000 m / 3220 m/s = 0.31 s to reach the top, so a WOB step's
    torque reaches the surface only after it)."""
    step = Scenario.of_points("step", ((0.0, 60.0),), ((0.0, 100.0), (0.1, 130.0)),
                              duration_s=0.6, window_start_s=0.3)
    r = run_loop(base, step, LoopSettings(law="kinematic", string_model="distributed"))
    assert r.string_model == "distributed"
    torque, t = r.series["surface_torque_nm"], r.series["time_s"]
    before = torque[t < 0.1].mean()
    travel_s = base.string.pipe_length_m / math.sqrt(base.string.shear_modulus_pa
                                                     / base.string.steel_density_kg_m3)
    quiet = (t > 0.1) & (t < 0.1 + 0.9 * travel_s)
    assert abs(torque[quiet] - before).max() < 0.01 * before
    assert torque[-1] > 1.1 * before


def test_a_custom_sensor_is_what_the_law_reads(base):
    """``LoopSettings.measure``: the law reads what it returns. The ideal view returned gives
    the plain loop bit for bit; a speed reading 0.5 rad/s high makes the stiff loop hold the
    top drive 0.5 rad/s lower once its integral has settled (K_p/K_i ≈ 1 s)."""
    from drill_sim.control.evaluation import ideal_measurement
    scenario = Scenario.steady(60.0, 100.0, duration_s=1.0, window_start_s=0.5)
    plain = run_loop(base, scenario, LoopSettings(law="stiff_pi"))
    same = run_loop(base, scenario, LoopSettings(law="stiff_pi", measure=ideal_measurement))
    assert list(same.series["law_output"]) == list(plain.series["law_output"])

    def high(sample):
        return ideal_measurement(sample)._replace(
            top_drive_speed_rad_s=sample.top_drive_speed_rad_s + 0.5)
    longer = Scenario.steady(60.0, 100.0, duration_s=4.0, window_start_s=2.0)
    plain = run_loop(base, longer, LoopSettings(law="stiff_pi"))
    biased = run_loop(base, longer, LoopSettings(law="stiff_pi", measure=high))
    drop = plain.series["top_drive_speed_rad_s"][-100:] - biased.series[
        "top_drive_speed_rad_s"][-100:]
    assert drop.mean() == pytest.approx(0.5, rel=0.1)


def test_a_held_torque_is_sent_once_and_the_window_may_start_at_the_first_tick(base, tmp_path):
    """``off`` holds the drive's torque: its one value is in the bag once. A window from 0 s
    covers every step: from the first tick on (the sample at 0 is the start, before any)."""
    scenario = Scenario.steady(60.0, 100.0, duration_s=0.2, window_start_s=0.0)
    r = run_loop(base, scenario, LoopSettings(law="off"), record=tmp_path / "off")
    assert len(_commands_in_bag(tmp_path / "off", ("top_drive_torque",))[
        "top_drive_torque"]) == 1
    assert r.window_s == pytest.approx(0.199, abs=1e-9)


def test_before_the_switch_the_drives_loop_has_the_drives_limits(base):
    """Until the switch the drive's own stiff loop runs under the drive's torque limits: a
    5 kN·m motor under a rising weight is held at 5 kN·m, not at the law's default 100."""
    from dataclasses import replace
    weak = replace(base.top_drive, motor_torque_max_nm=5000.0, motor_torque_min_nm=-5000.0)
    heavier = Scenario.of_points("heavier", ((0.0, 60.0),), ((0.0, 80.0), (0.2, 160.0)),
                                 duration_s=1.0, window_start_s=0.5, switch_on_s=0.9)
    r = run_loop(base, heavier, LoopSettings(law="z_torque", top_drive=weak))
    before = r.series["law_output"][:900]
    assert before.max() == pytest.approx(5000.0, rel=1e-12)
