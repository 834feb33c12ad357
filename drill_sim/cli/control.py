"""``drill_sim control``: score the reference stick-slip controllers on a named scenario set.

Offline through the core (``drill_sim.control.evaluation``); one table (SSI, stick fraction,
mean ROP, surface-torque oscillation, saturation, MSE), optionally written as CSV or JSON and
plotted (bit speed and surface torque of every law: the kinematic drive is the "before").
"""

from __future__ import annotations

import argparse
import csv
import sys
from dataclasses import replace
from pathlib import Path

from ..control import LAWS
from ..control.closed_loop import run_loop
from ..control.evaluation import (
    DEFAULT_PERTURBATION,
    DEFAULT_SAMPLE_PERIOD_S,
    LoopResult,
    LoopSettings,
    Scenario,
    build_law,
    law_top_drive,
    sensor_profiles,
)
from ..control.reference import reference_gains
from ..control.scenarios import SETS, named
from ..core import NoSteadyDrilling, load_preset
from ..core.distributed import STRING_MODELS
from ..session.parameter_table import PERTURBATION_RANGE
from ..terminal import Progress
from .case import RPM_MAX
from .checks import (
    in_range,
    json_line,
    number,
    output_file,
    plot_file,
    sample_period,
    sensor_seed,
)
from .errors import UsageError

DEFAULT_LAWS = ("kinematic", "stiff_pi", "soft_speed", "z_torque")
# (JSON/CSV key, table heading, format, unit)
COLUMNS = (
    ("ssi", "SSI", "{:6.3f}", "-"),
    ("stick_fraction", "stick", "{:6.3f}", "-"),
    ("mean_rop_m_h", "ROP m/h", "{:8.2f}", "m/h"),
    ("mean_bit_speed_rpm", "bit rpm", "{:8.1f}", "rpm"),
    ("max_bit_speed_rpm", "max rpm", "{:8.1f}", "rpm"),
    ("surface_torque_p2p_nm", "Ts p2p kN·m", "{:11.2f}", "N·m"),
    ("surface_torque_rms_nm", "Ts rms kN·m", "{:11.3f}", "N·m"),
    ("saturation_fraction", "sat", "{:5.2f}", "-"),
    ("mse_pa", "MSE MPa", "{:8.1f}", "Pa"),
    ("motor_torque_rms_nm", "Tm rms kN·m", "{:11.3f}", "N·m"),
    ("torque_rate_rms_nm_s", "dTm/dt kN·m/s", "{:13.1f}", "N·m/s"),
    ("drive_energy_j", "E MJ", "{:6.2f}", "J"),
    ("settling_time_s", "settle s", "{:8.2f}", "s"),
)
TABLE_SCALE = {"surface_torque_p2p_nm": 1e-3, "surface_torque_rms_nm": 1e-3, "mse_pa": 1e-6,
               "motor_torque_rms_nm": 1e-3, "torque_rate_rms_nm_s": 1e-3,
               "drive_energy_j": 1e-6}
UNITS = {"ssi": "-", "stick_fraction": "-", "mean_rop_m_h": "m/h", "mean_rop": "m/h",
         "mean_bit_speed_rpm": "rpm", "min_bit_speed_rpm": "rpm", "max_bit_speed_rpm": "rpm",
         "surface_torque_p2p_nm": "N·m", "surface_torque_rms_nm": "N·m",
         "mean_surface_torque_nm": "N·m", "saturation_fraction": "-", "saturation_time_s": "s",
         "mse_pa": "Pa", "mse_mpa": "MPa", "window_s": "s",
         "motor_torque_rms_nm": "N·m", "motor_torque_p2p_nm": "N·m",
         "torque_rate_rms_nm_s": "N·m/s", "time_at_torque_limit_fraction": "-",
         "drive_energy_j": "J", "settling_time_s": "s"}


def add_loop_arguments(parser: argparse.ArgumentParser) -> None:
    """How the loop is closed, as drill_sim control and drill_sim tune take it: the law's
    sample period, what it measures, the string."""
    parser.add_argument("--sample-period", type=number, default=DEFAULT_SAMPLE_PERIOD_S,
                        help="the controller's sample period h [s], 1e-4 to 0.1; default "
                             f"{DEFAULT_SAMPLE_PERIOD_S:g} (the rig node's 1 kHz)")
    parser.add_argument("--sensor-profile", choices=sensor_profiles(), default="ideal",
                        help="what the controller measures (msg_docs/sensors.md); default ideal")
    parser.add_argument("--sensor-seed", type=int, default=0,
                        help="seed of the sensors' noise, >= 0; default 0")
    parser.add_argument("--string-model", choices=STRING_MODELS, default="lumped",
                        help="the string model; default lumped")


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--preset", default="base", help="shipped preset or preset YAML; base")
    parser.add_argument("--rpm", type=number, help="one steady point instead of the set: "
                        f"top-drive speed set-point [rpm], > 0 to {RPM_MAX:g} (with --wob-kn)")
    parser.add_argument("--wob-kn", type=number, help="its available weight on bit W0 [kN]")
    parser.add_argument("--scenarios", default=None,
                        help=f"comma-separated scenario sets: standard (all, the default), "
                             f"{', '.join(SETS)}; or a rig scenario (shipped name or YAML, "
                             "msg_docs/driver.md); not with --rpm/--wob-kn")
    parser.add_argument("--laws", default=",".join(DEFAULT_LAWS),
                        help=f"comma-separated laws ({', '.join(LAWS)}); default "
                             f"{','.join(DEFAULT_LAWS)}")
    parser.add_argument("--gain", action="append", default=[], metavar="LAW.NAME=VALUE",
                        help="override one gain, e.g. z_torque.alpha=0.25 (repeatable; units "
                             "as in msg_docs/control.md)")
    parser.add_argument("--published-gains", action="store_true",
                        help="the laws' published defaults instead of the reference tuning "
                             "from the string")
    parser.add_argument("--duration", type=number, default=None,
                        help="for --rpm/--wob-kn: run length [s], 2 to 3600; default 60")
    parser.add_argument("--window-start", type=number, default=None,
                        help="for --rpm/--wob-kn: metrics from this time [s] to the end; "
                             "default half the duration")
    parser.add_argument("--switch-on", type=number, default=0.0,
                        help="for --rpm/--wob-kn: the drive's stiff loop until this time [s], "
                             "then the law (bumpless); default 0, the law from the start")
    parser.add_argument("--top-drive-inertia", type=number, default=None,
                        help="J_TD [kg m^2], 1 to 1e5; default the preset's (base 2900)")
    parser.add_argument("--motor-torque-max-knm", type=number, default=None,
                        help="the drive's largest motor torque [kN m], > 0 to 1000; default "
                             "the preset's (base 60)")
    parser.add_argument("--motor-torque-min-knm", type=number, default=None,
                        help="its smallest [kN m], -1000 to 0 (0: cannot brake); default the "
                             "preset's (base -60)")
    add_loop_arguments(parser)
    parser.add_argument("--out", type=Path, help="the table as .csv or .json")
    parser.add_argument("--plot", type=Path, help="bit speed and surface torque of every law "
                        "against time (.png, .pdf...); one file per scenario, suffixed with its "
                        "name, when there are several")
    parser.add_argument("--ros", action="store_true",
                        help="run each law through the installed nodes in lockstep (the rig node "
                             "and drill_sim_controller) and score the rig's samples; every "
                             "scenario (changing set-points and a switch-on are played in the "
                             "lockstep)")
    parser.add_argument("--ros-controller", metavar="COMMAND", default=None,
                        help="with --ros: score this controller command line instead (it must "
                             "answer each tick on the rig's ~/cmd/top_drive_torque with the "
                             "tick's stamp; run under the namespace the rig gets); one row, "
                             "named by the first law of --laws")
    parser.add_argument("--perturbation", type=number, default=DEFAULT_PERTURBATION,
                        help="relative perturbation of the steady start's bit speed, "
                             f"{PERTURBATION_RANGE[0]:g} to {PERTURBATION_RANGE[1]:g}; default "
                             f"{DEFAULT_PERTURBATION:g} (lets stick-slip grow from the start; "
                             "with --ros the rig node's initial_perturbation)")
    parser.add_argument("--record", type=Path, default=None, metavar="DIR",
                        help="record each run as the rig node would, a bag per row "
                             "DIR/<scenario>-<law>, which drill_sim bag resim re-runs exactly "
                             "(offline only)")
    parser.add_argument("--json", action="store_true",
                        help="print the table as one JSON object (strict: null, never NaN)")


def run(args: argparse.Namespace) -> int:
    preset = load_preset(args.preset)
    scenarios = _scenarios(args)
    laws = _laws(args.laws)
    gains = _gains(args.gain, laws)
    h = sample_period(args.sample_period)
    drive = _drive(args, preset)
    if args.out is not None:
        if args.out.suffix.lower() not in (".csv", ".json"):
            raise UsageError(f"--out {args.out}: expected a .csv or .json file")
        output_file("--out", args.out)
    if args.plot is not None:
        plot_file("--plot", args.plot)
    settings = []
    for law in laws:
        law_gains = {} if args.published_gains else reference_gains(
            law, preset, drive.top_drive_inertia_kg_m2, string_model=args.string_model,
            sensor_profile=args.sensor_profile, sample_period_s=h)
        law_gains.update(gains.get(law, {}))
        one = LoopSettings(law=law, gains=law_gains, sample_period_s=h, top_drive=drive,
                           string_model=args.string_model, sensor_profile=args.sensor_profile,
                           sensor_seed=sensor_seed(args.sensor_seed),
                           perturbation=in_range("--perturbation", args.perturbation,
                                                 *PERTURBATION_RANGE,
                                                 what="a relative perturbation of the bit speed"))
        build_law(preset, one, law_top_drive(preset, law, drive))   # bad gains: before any run
        settings.append(one)
    if args.record is not None:
        if args.ros:
            raise UsageError("--record with --ros: the rig node records its own session "
                             "(-p record:=BAG); expected --record for offline runs")
        if args.record.exists():
            raise UsageError(f"--record {args.record}: it exists; expected a new directory "
                             "(a bag per row goes into it)")
        try:
            args.record.mkdir()
        except OSError as exc:
            raise UsageError(f"--record {args.record}: cannot create it ({exc.strerror}); "
                             "expected a new directory in an existing folder") from None
    if args.ros_controller is not None and not args.ros:
        raise UsageError("--ros-controller needs --ros")
    if args.ros_controller is not None:
        settings = settings[:1]
        if settings[0].law == "kinematic":
            raise UsageError("--ros-controller: the row's law must be a torque law (the rig "
                             "runs in torque mode); expected e.g. --laws z_torque")
    progress = Progress("drill_sim control")
    results: list[LoopResult] = []
    total = len(scenarios) * len(settings)
    try:
        for i, scenario in enumerate(scenarios):
            for j, one in enumerate(settings):
                done = i * len(settings) + j
                def report(f: float, d: int = done) -> None:
                    progress((d + f) / total)
                if args.ros:
                    results.append(_ros_row(preset, scenario, one, args.ros_controller, report))
                else:
                    bag = (None if args.record is None
                           else args.record / f"{scenario.name}-{one.law}")
                    try:
                        results.append(run_loop(preset, scenario, one, progress=report,
                                                record=bag))
                    except NoSteadyDrilling as exc:     # the steady start: not a bug
                        least_kn = preset.rig.friction_weight_n / 1e3
                        raise UsageError(f"scenario {scenario.name}, its steady start: {exc}; "
                                         f"expected a weight on bit above {least_kn:.4g} kN "
                                         "on this preset") from None
    finally:
        progress.close()
    document = _document(args, preset.name, drive, h, results, settings)
    if args.out is not None:
        _write(args.out, document)
    if args.plot is not None:
        _plot(args.plot, scenarios, results)
    if args.record is not None:
        print(f"drill_sim control: {len(results)} sessions recorded in {args.record} "
              "(<scenario>-<law>; drill_sim bag resim re-runs each)", file=sys.stderr)
    if args.json:
        print(json_line(document))
    else:
        _print_table(document, args)
    return 0


def _ros_row(preset, scenario: Scenario, settings: LoopSettings, user: str | None,
             progress) -> LoopResult:
    """One law through the nodes in lockstep, scored on the rig's samples."""
    from ..control.evaluation import sample_metrics
    from ..ros.evaluation import check_ros, run_ros
    check_ros(scenario, user_command=user)
    series = run_ros(preset, scenario, settings, user_command=user, progress=progress)
    drive = None if settings.law == "kinematic" else law_top_drive(preset, settings.law,
                                                                    settings.top_drive)
    return sample_metrics(preset, series, scenario.metrics_from_s, drive,
                          law="user" if user else settings.law, scenario=scenario.name,
                          sensor_profile=settings.sensor_profile,
                          string_model=settings.string_model,
                          events_s=scenario.settling_events_s)


def _scenarios(args: argparse.Namespace) -> list[Scenario]:
    if (args.rpm is None) != (args.wob_kn is None):
        raise UsageError("--rpm and --wob-kn go together: expected both (one steady point) or "
                         "neither (the scenario sets)")
    if args.rpm is None:
        for option in ("duration", "window_start"):
            if getattr(args, option) is not None:
                raise UsageError(f"--{option.replace('_', '-')} applies to --rpm/--wob-kn only; "
                                 "the scenario sets have their own times")
        text = "standard" if args.scenarios is None else args.scenarios
        return named([s.strip() for s in text.split(",") if s.strip()])
    if args.scenarios is not None:
        raise UsageError(f"--scenarios {args.scenarios} with --rpm/--wob-kn: they contradict each "
                         "other (one steady point, or the scenario sets); expected one of them")
    rpm = in_range("--rpm", args.rpm, 0.0, RPM_MAX, unit="rpm", low_open=True)
    wob = in_range("--wob-kn", args.wob_kn, 0.0, 1e4, unit="kN", low_open=True)
    duration = in_range("--duration", 60.0 if args.duration is None else args.duration,
                        2.0, 3600.0, unit="s")
    start = 0.5 * duration if args.window_start is None else args.window_start
    in_range("--window-start", start, 0.0, 0.99 * duration, unit="s", low_open=True,
             what="a time within --duration")
    switch = in_range("--switch-on", args.switch_on, 0.0, start, unit="s",
                      what="a time before --window-start")
    return [Scenario.steady(rpm, wob, duration_s=duration, window_start_s=start,
                            switch_on_s=switch)]


def _laws(text: str) -> list[str]:
    laws = [s.strip() for s in text.split(",") if s.strip()]
    unknown = [name for name in laws if name not in LAWS]
    if unknown or not laws:
        raise UsageError(f"--laws {text!r}: unknown {unknown or 'none given'}; expected names "
                         f"from {', '.join(LAWS)}")
    return laws


def _gains(items: list[str], laws: list[str]) -> dict[str, dict[str, float]]:
    out: dict[str, dict[str, float]] = {}
    for item in items:
        key, sep, value = item.partition("=")
        law, dot, name = key.partition(".")
        if not sep or not dot or law not in LAWS:
            raise UsageError(f"--gain {item!r}: expected LAW.NAME=VALUE with LAW one of "
                             f"{', '.join(LAWS)}")
        if name not in LAWS[law].GAINS:
            raise UsageError(f"--gain {item!r}: {law} has no gain {name!r}; expected one of "
                             f"{', '.join(LAWS[law].GAINS) or 'none'}")
        out.setdefault(law, {})[name] = number(value)
    return out


def _drive(args: argparse.Namespace, preset):
    drive = preset.top_drive
    changes = {}
    if args.top_drive_inertia is not None:
        changes["top_drive_inertia_kg_m2"] = in_range(
            "--top-drive-inertia", args.top_drive_inertia, 1.0, 1e5, unit="kg m^2")
    if args.motor_torque_max_knm is not None:
        changes["motor_torque_max_nm"] = 1e3 * in_range(
            "--motor-torque-max-knm", args.motor_torque_max_knm, 0.0, 1000.0, unit="kN m",
            low_open=True)
    if args.motor_torque_min_knm is not None:
        changes["motor_torque_min_nm"] = 1e3 * in_range(
            "--motor-torque-min-knm", args.motor_torque_min_knm, -1000.0, 0.0, unit="kN m")
    return replace(drive, **changes)


def _document(args: argparse.Namespace, preset_name: str, drive, h: float,
              results: list[LoopResult], settings: list[LoopSettings]) -> dict:
    rows = [{"name": r.law, **r.row()} for r in results]
    # the gains each law was given (reference tuning and --gain); the others are the law's
    # defaults (msg_docs/control.md)
    gains = {one.law: {k: float(v) for k, v in one.gains.items()} for one in settings}
    if getattr(args, "ros_controller", None) is not None:
        # the row ran the user's controller, with gains of its own: not the reference ones
        gains = {"user": {}}
    return {"preset": preset_name, "sample_period_s": h, "sensor_profile": args.sensor_profile,
            "loop": "ros-lockstep" if args.ros else "offline",
            "sensor_seed": args.sensor_seed,
            "string_model": args.string_model,
            "tuning": "published" if args.published_gains else "reference",
            "top_drive": {"top_drive_inertia_kg_m2": drive.top_drive_inertia_kg_m2,
                          "motor_torque_min_nm": drive.motor_torque_min_nm,
                          "motor_torque_max_nm": drive.motor_torque_max_nm},
            "gains": gains, "units": UNITS, "rows": rows,
            "controller_command": getattr(args, "ros_controller", None)}


def _write(path: Path, document: dict) -> None:
    if path.suffix.lower() == ".json":
        path.write_text(json_line(document) + "\n", encoding="utf-8")
        return
    rows = document["rows"]
    keys = ["scenario", "name", *[k for k in rows[0] if k not in ("scenario", "name", "law")]]
    with open(path, "w", newline="", encoding="utf-8") as fh:
        writer = csv.writer(fh)
        writer.writerow([f"{k} [{UNITS[k]}]" if k in UNITS else k for k in keys])
        for row in rows:
            writer.writerow([f"{row[k]:.6g}" if isinstance(row[k], float) else row[k]
                             for k in keys])


def _print_table(document: dict, args: argparse.Namespace) -> None:
    head = (f"drill_sim control: preset {document['preset']}, h = "
            f"{document['sample_period_s'] * 1e3:g} ms, {document['string_model']} string, "
            f"sensors {document['sensor_profile']}, {document['tuning']} tuning, J_TD "
            f"{document['top_drive']['top_drive_inertia_kg_m2']:g} kg m^2, motor torque "
            f"{document['top_drive']['motor_torque_min_nm'] / 1e3:g}.."
            f"{document['top_drive']['motor_torque_max_nm'] / 1e3:g} kN m")
    widths = [max(len(h), len(f.format(0.0))) for _, h, f, _ in COLUMNS]
    scen_w = max(8, *(len(r["scenario"]) for r in document["rows"]))
    lines = [head, f"{'scenario':<{scen_w}} {'law':<10} " + " ".join(
        f"{h:>{w}}" for (_, h, _, _), w in zip(COLUMNS, widths, strict=True))]
    for row in document["rows"]:
        cells = []
        for (key, _, fmt, _), w in zip(COLUMNS, widths, strict=True):
            value = row[key]
            cells.append(f"{'-':>{w}}" if value is None or value != value else
                         f"{fmt.format(value * TABLE_SCALE.get(key, 1.0)):>{w}}")
        lines.append(f"{row['scenario']:<{scen_w}} {row['name']:<10} " + " ".join(cells))
    for label, path in (("table", args.out), ("plot", args.plot)):
        if path is not None:
            lines.append(f"{label} written to {path}")
    print("\n".join(lines))


def _plot(path: Path, scenarios: list[Scenario], results: list[LoopResult]) -> None:
    from .control_plot import plot_laws
    for scenario in scenarios:
        mine = [r for r in results if r.scenario == scenario.name]
        target = path if len(scenarios) == 1 else path.with_name(
            f"{path.stem}_{scenario.name}{path.suffix}")
        plot_laws(target, scenario, mine)
