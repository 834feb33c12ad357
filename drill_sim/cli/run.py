"""``drill_sim run``: the main job. The rig node playing a driller scenario on its own clock
(``-p scenario:=``) in a subprocess, a live status line, and at the end a summary and a plot. A
scenario with a ``controller`` section also starts ``drill_sim_controller`` (disabled, the rig's
drive on its own speed loop), which the rig switches on at its time; the summary and the plot
compare before and after."""

from __future__ import annotations

import argparse
import sys
from datetime import datetime
from pathlib import Path

import numpy as np

from ..bag.errors import BagError
from ..bag.series import RigSeries
from ..bag.session_events import BagSession, read_session
from ..core import RPM, load_preset
from ..core.distributed import STRING_MODELS
from ..core.effort import SETTLING_SSI, SETTLING_WINDOW_S, Figures, effort_figures
from ..core.stick_slip import severity_index
from ..programs import program
from ..session.diagnostics import drilling_regime
from ..session.pacing import CATCH_UP_TICKS
from ..session.scenario import load_scenario
from .checks import in_range, new_bag, number, plot_file
from .errors import UsageError
from .plot import plot_rig_series

STATUS_WINDOW_S = 1.0          # the stretch of samples the status line names the regime of
STUCK_AT_ALL = 0.01            # a bit stuck less than this share of the time has no stick-slip
COMPARE_WINDOW_S = 10.0        # before/after a controller is switched on: the last ... of each

MAX_DURATION_S = 1e6     # --duration [s] (documented in msg_docs/cli.md, "Limits")


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--scenario", default="controller_on",
                        help="shipped scenario or YAML file (default controller_on: the driller "
                             "drills into stick-slip, Z-Torque is switched on and clears it)")
    parser.add_argument("--preset", default="base",
                        help="rig preset or preset YAML file (default base)")
    parser.add_argument("--duration", type=number, default=None,
                        help=f"wall seconds to run, up to {MAX_DURATION_S:g}; default: the "
                             "scenario's duration (the rig runs in real time: about as many "
                             "simulated seconds, a little more as it ticks while the "
                             "programs start)")
    parser.add_argument("--plot", type=Path, default=Path("drill_sim.png"),
                        help="figure written at the end (.png, .pdf, .svg...; default "
                             "drill_sim.png)")
    parser.add_argument("--record", type=Path, default=None, metavar="BAG",
                        help="bag directory to record the session into (default: "
                             "drill_sim_session_<date>-<time> here)")
    parser.add_argument("--no-record", action="store_true", help="do not record the session")
    parser.add_argument("--string-model", choices=STRING_MODELS, default=None,
                        help="the drill string's model on the rig, and the controller's tuning "
                             "for it: lumped (one torsional spring) or distributed (the pipe's "
                             "torsional and axial waves, damped); default: the preset's "
                             "(base: lumped)")
    parser.add_argument("--no-controller", action="store_true",
                        help="ignore the scenario's controller section (the driller alone)")
    parser.add_argument("--ros-args", dest="ros_args", nargs=argparse.REMAINDER, default=[],
                        help="passed on to drill_sim_node (e.g. -p rate_hz:=500.0)")


def run(args: argparse.Namespace) -> int:
    from ..ros.session_watch import watch_session

    if args.no_record and args.record is not None:
        raise UsageError(f"--no-record with --record {args.record}: they contradict each other; "
                         "expected one of them")
    scenario = load_scenario(args.scenario)
    preset = load_preset(args.preset)
    string_model = args.string_model or preset.string_model
    duration = scenario.duration_s if args.duration is None else in_range(
        "--duration", args.duration, 0.0, MAX_DURATION_S, unit="s", low_open=True,
        what="a wall time")
    plot_file("--plot", args.plot)
    if args.no_record:
        bag = None
    elif args.record is not None:
        bag = new_bag("--record", args.record)
    else:
        bag = new_bag("--record", Path(datetime.now().strftime(
            "drill_sim_session_%Y_%m_%d-%H_%M_%S")))
    # the rig plays the scenario itself, on its simulated clock (every event on its tick)
    played = Path(args.scenario)
    node_cmd = [program("drill_sim_node"), "--ros-args", "-p", f"preset:={args.preset}",
                "-p", f"string_model:={string_model}",
                "-p", f"initial_state:={scenario.initial_state}",
                "-p", f"scenario:={played.absolute() if played.is_file() else args.scenario}",
                *(("-p", f"record:={bag.absolute()}") if bag is not None else ()),
                *args.ros_args]
    switch = None if args.no_controller else scenario.controller
    clients: list[list[str]] = []
    if switch is not None:
        node_cmd[2:2] = ["-p", "top_drive_mode:=speed"]     # the user's -p come later, and win
        clients.append(controller_command(preset, switch.law, string_model))
    else:
        node_cmd[2:2] = ["-p", "scenario_controller:=''"]   # a switch is only recorded
    watched = watch_session(node_cmd, clients, duration, sys.stdout.isatty(), _status_line)
    others, node_exit, received = watched.others, watched.node_exit, watched.received
    if others:
        print(f"drill_sim run: another rig publishes on {watched.topic} ({', '.join(others)}): "
              "the session would mix both rigs' samples and send the driller's commands to "
              "both, so it stopped; stop that rig, or run this session on another "
              "ROS_DOMAIN_ID (ROS_DOMAIN_ID=7 drill_sim run)", file=sys.stderr)
        return 1
    if node_exit == 2 and received.time_s.size == 0:
        return 2                   # a bad start-up parameter: the node said which, in one line
    if node_exit is not None:
        print(f"drill_sim run: drill_sim_node stopped early with status {node_exit} "
              "(its message is above)", file=sys.stderr)
        return 1
    read = _read_bag(bag, scenario)
    series, whence = (received, "as received here: the node's first samples, before this "
                      "monitor matched it, are not counted") if read is None else \
        (read.series, "every sample the node published, read from its bag")
    if series.time_s.size < 2:
        print("drill_sim run: no samples received from the rig", file=sys.stderr)
        return 1
    _summary(series, whence, scenario.name, f"'{preset.name}' ({string_model} string)")
    _effort(read, series, scenario)
    marks = {}
    if switch is not None:
        compared = _before_after(series, switch.law, switch.on_at_s)
        if compared:
            marks[switch.on_at_s] = f"{switch.law} on: SSI {compared}"
    drive = preset.top_drive
    plot_rig_series(args.plot, series, title=f"drill_sim run: {scenario.name} on {preset.name}, "
                                             f"{string_model} string",
                    marks=marks,
                    motor_torque_nm=None if read is None else read.motor_torque_nm,
                    speed_set_rad_s=scenario.speed_set_rad_s(series.time_s - series.time_s[0]),
                    torque_limits_nm=(drive.motor_torque_min_nm, drive.motor_torque_max_nm))
    print(f"plot written to {args.plot}")
    if bag is not None and bag.is_dir():
        print(f"session recorded to {bag}: replay it with drill_sim_replay, re-run it with "
              f"drill_sim bag resim, or see drill_sim bag info|metrics|plot")
    return 0


def controller_command(preset, law: str, string_model: str = "lumped") -> list[str]:
    """``drill_sim_controller``, disabled, for this preset's string (on ``string_model``) and
    drive: the reference gains (``control.reference``), the drive's limits, and the rig's
    drive mode managed (torque when on, speed when off)."""
    from ..control.reference import reference_gains
    from ..control.tuning import pipe_impedance
    drive = preset.top_drive
    from ..wire import rig_topics
    names = {t.name for t in rig_topics.TOPICS}
    params = {"law": law, "enabled": False, "manage_drive_mode": True,
              "inputs": "measured" if "~/measured/top_drive/twist" in names else "exact",
              "impedance_nm_s_rad": pipe_impedance(preset),
              "top_drive_inertia_kg_m2": drive.top_drive_inertia_kg_m2,
              f"{law}.torque_min_nm": drive.motor_torque_min_nm,
              f"{law}.torque_max_nm": drive.motor_torque_max_nm}
    params.update({f"{law}.{k}": v for k, v in reference_gains(
        law, preset, drive.top_drive_inertia_kg_m2, string_model=string_model).items()})
    cmd = [program("drill_sim_controller"), "--ros-args"]
    for name, value in params.items():
        text = str(value).lower() if isinstance(value, bool) else (
            repr(float(value)) if isinstance(value, (int, float)) else value)
        cmd += ["-p", f"{name}:={text}"]
    return cmd


def _read_bag(bag: Path | None, scenario) -> BagSession | None:
    """The session from its bag (every sample the node published, the motor torque, the
    effort with the settling after the scenario's switch or set-point steps), read once;
    None without a bag or when it cannot be read (said)."""
    if bag is None or not bag.is_dir():
        return None
    try:
        return read_session(bag, scenario.settling_events_s)
    except BagError as exc:
        print(f"drill_sim run: reading {bag}: {exc}; summing up what was received",
              file=sys.stderr)
        return None


def _effort(read: BagSession | None, series: RigSeries, scenario) -> Figures:
    """Print the drive's effort over the run and the settling after the scenario's switch or
    set-point steps (``core.effort``), from the bag when there is one (it has the motor
    torque), else from the samples received (no motor torque: those figures are missing)."""
    events = scenario.settling_events_s
    if read is not None:
        figures = read.effort
    else:
        figures = effort_figures(series.time_s - series.time_s[0], series.bit_speed_rad_s,
                                 events_s=events)

    def shown(key: str, scale: float, unit: str, fmt: str = ".2f") -> str:
        value = figures[key]
        return "-" if value is None else f"{format(value * scale, fmt)} {unit}"

    print(f"  drive effort (whole run): motor torque rms about its mean "
          f"{shown('motor_torque_rms_nm', 1e-3, 'kN m')}, p2p "
          f"{shown('motor_torque_p2p_nm', 1e-3, 'kN m')}, rate rms "
          f"{shown('torque_rate_rms_nm_s', 1e-3, 'kN m/s', '.1f')}, at its limit "
          f"{shown('time_at_torque_limit_fraction', 100.0, '%', '.1f')} of the time, energy "
          f"{shown('drive_energy_j', 1e-6, 'MJ')}")
    if events:
        settle = figures["settling_time_s"]
        print(f"  settling after {events[-1]:g} s: " + (
            "not settled by the end of the run" if settle is None else
            f"{settle:.2f} s (bit-speed SSI at most {SETTLING_SSI:g} over every "
            f"{SETTLING_WINDOW_S:g} s window from then on)"))
    return figures


def _before_after(series: RigSeries, law: str, on_s: float) -> str:
    """Print SSI and stick fraction over the last COMPARE_WINDOW_S before the switch and at the
    end; return "before → after" of the SSI ("" when the run did not reach the switch)."""
    end = series.time_s[-1] - series.time_s[0]
    if end < on_s + 2.0 or on_s < 2.0:
        print(f"  controller {law}: the run ended before it was on long enough to compare")
        return ""
    before = series.window(max(0.0, on_s - COMPARE_WINDOW_S), on_s).metrics()
    after = series.window(max(on_s, end - COMPARE_WINDOW_S), None).metrics()
    print(f"  controller {law} switched on at {on_s:g} s: SSI {before['ssi']:.2f} -> "
          f"{after['ssi']:.2f}, stick fraction {before['stick_fraction']:.2f} -> "
          f"{after['stick_fraction']:.2f}, ROP {before['mean_rop_m_s'] * 3600:.1f} -> "
          f"{after['mean_rop_m_s'] * 3600:.1f} m/h (the {before['duration_s']:.0f} s before, "
          f"the last {after['duration_s']:.0f} s)")
    stuck_before, stuck_after = before["stick_fraction"], after["stick_fraction"]
    if stuck_before < STUCK_AT_ALL:
        verdict = (f"no stick-slip before the switch (stuck {100 * stuck_before:.1f} % of the "
                   "time)")
    elif stuck_after < STUCK_AT_ALL:
        verdict = f"cleared (stuck {100 * stuck_after:.1f} % of the time after)"
    else:
        verdict = f"not cleared (stuck {100 * stuck_after:.1f} % of the time after)"
    print(f"  stick-slip: {verdict}")
    return f"{before['ssi']:.2f} → {after['ssi']:.2f}"


def _status_line(monitor) -> str | None:
    """The live status line of the latest sample the monitor received (None: none yet)."""
    s = monitor.latest()
    if s is None:
        return None
    name = regime(monitor.recent(STATUS_WINDOW_S), monitor.flag)
    return (f"t {s['elapsed_s']:6.1f} s | bit {s['bit_speed_rad_s'] / RPM:6.1f} rpm (top drive "
            f"{s['top_drive_speed_rad_s'] / RPM:5.1f}) | WOB {s['wob_n'] / 1e3:6.1f} kN | TOB "
            f"{s['tob_nm'] / 1e3:5.2f} kN m | {name:<21}")


def regime(series: RigSeries, stick_flag: bool = False) -> str:
    """The drilling regime of a stretch of samples (``session.diagnostics.drilling_regime``,
    as /diagnostics names it): SSI of the bit speed, stuck samples or the node's stick-slip
    flag, off bottom where the WOB is zero."""
    w = series.bit_speed_rad_s
    if w.size == 0:
        return "no data"
    mean = float(np.mean(w))
    off = series.wob_n == 0.0
    return drilling_regime(
        ssi=severity_index(float(w.max()), float(w.min()), mean),
        stuck=bool(np.any(series.stuck)) or stick_flag,
        off_bottom_fraction=float(np.mean(off)), off_bottom_now=bool(off[-1]),
        top_drive_speed_rad_s=float(series.top_drive_speed_rad_s[-1]))


def _summary(series: RigSeries, whence: str, scenario: str, preset: str) -> None:
    elapsed = series.time_s[-1] - series.time_s[0]
    whole = series.metrics()
    last = series.window(elapsed - min(20.0, elapsed / 2), None).metrics()
    print(f"drill_sim run: scenario '{scenario}' on preset {preset}, {elapsed:.3f} s "
          f"simulated, {whole['samples']} samples ({whence})")
    if elapsed > 0:                       # fewer than rate_hz: ticks the machine delayed
        print(f"  samples a simulated s  {whole['samples'] / elapsed:8.0f} (rate_hz ticks; "
              f"fewer where the machine stalled the rig more than {CATCH_UP_TICKS} ticks: "
              "counted on /diagnostics)")
    print(f"  hole drilled             {series.hole_depth_m[-1]:8.3f} m")
    print(f"  last {last['duration_s']:4.1f} s: mean bit speed "
          f"{last['mean_bit_speed_rad_s'] / RPM:6.1f} rpm, WOB {last['mean_wob_n'] / 1e3:6.1f} kN, "
          f"TOB {last['mean_tob_nm'] / 1e3:5.2f} kN m")
    shares: dict[str, int] = {}
    for k in range(max(1, int(elapsed // STATUS_WINDOW_S))):
        name = regime(series.window(k * STATUS_WINDOW_S, (k + 1) * STATUS_WINDOW_S))
        shares[name] = shares.get(name, 0) + 1
    total = sum(shares.values())
    print(f"  stick fraction (whole run)  {whole['stick_fraction']:.3f}; regimes over "
          f"{STATUS_WINDOW_S:g} s windows: " + ", ".join(
              f"{name} {100 * n / total:.0f} %" for name, n in
              sorted(shares.items(), key=lambda kv: -kv[1])))
