"""The survivors of the last ``mutmut run``, grouped by what their mutation does, with the
reason each group is equivalent or what is left to do (msg_docs/testing.md, "Mutation
testing"). Run after ``mutmut run`` from the repository's root:

    .venv/bin/python tests/breaks/mutants.py [--list GROUP]
"""

from __future__ import annotations

import argparse
import re
import subprocess
import sys
from collections import defaultdict
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
MUTMUT = str(Path(sys.executable).with_name("mutmut"))

# (group, reason, test of the diff's two lines -> bool); the first that matches names it
GROUPS: list[tuple[str, str, object]] = [
    ("zip strictness", "equivalent: both sides have the same length by construction, so "
     "strict=True, False or left out zip the same pairs",
     lambda old, new: "zip(" in old and "strict" in old),
    ("flag None for False", "equivalent: the flag is only ever read for its truth",
     lambda old, new: re.search(r"= False\b", old) and re.search(r"= None\b", new)),
    ("clamped-limit tolerance", "equivalent: the law clamps its output and integral to "
     "exactly the limit, so any tolerance from 0 to the distance of the nearest unclamped "
     "value counts the same samples",
     lambda old, new: ("tol" in old and ("high" in old or "low" in old or "span" in old
                                         or "torque_m" in old))
     or "span = drive.motor_torque_max_nm" in old),
    ("PI limit boundary", "equivalent: at p + q exactly on a limit, or a zero error, the "
     "conditional integration gives the q the plain one does (q = max(q_nm, limit - p) is q "
     "there)",
     lambda old, new: "p + q" in old and "error_rad_s" in old and "self.torque_m" in old),
    ("a field no law reads", "equivalent: no law reads a measurement's time or surface torque "
     "(they act on the top-drive speed and the motor torque; the sampled loop stamps its own "
     "time before the law)",
     lambda old, new: ("SurfaceMeasurement(None" in new)
     or ("surface_torque_nm)" in old and new.endswith("None)"))),
    ("value held before the first point", "equivalent: a scenario holds its first point's "
     "value before it, so a first point at 1 s with the value it had at 0 s is the same "
     "scenario",
     lambda old, new: "((0.0," in old and "((1.0," in new
     and old.replace("((0.0,", "((1.0,", 1) == new),
    ("a default restated", "equivalent: the argument left out or None falls back on the same "
     "value (window_start_s None: half the duration, 20 of 40 s and 25 of 50 s; duration_s: "
     "60 s, Scenario.steady's default; the base settings' law: each law replaces it)",
     lambda old, new: "window_start_s=None" in new or 'LoopSettings(law="kinematic")' in old
     or ("duration_s=60.0" in old and "duration_s" not in new)),
    ("window start tolerance", "equivalent: samples sit at k h; none lies exactly 1 ns before "
     "the window's start",
     lambda old, new: "window_start_s - 1e-9" in old),
    ("an empty window's ROP", "equivalent: a window of one sample has span 0 and drilled 0, "
     "0/0 is NaN in floating point as the guard gives it",
     lambda old, new: "span > 0" in old),
    ("one start value taken twice", "equivalent: the scenario at t = 0 evaluated at two "
     "points, the first taken",
     lambda old, new: "np.zeros(1)" in old),
    ("nobody to send to", "equivalent: offline there is no publisher; None and () both send "
     "nothing",
     lambda old, new: "session.emit(())" in old),
    ("the first row's index", "equivalent: series[key][None] = x writes every sample, and "
     "every later one is written again",
     lambda old, new: "_record(series, 0" in old),
    ("a lag that is not there", "equivalent: with tau 0 the lag returns its input and never "
     "reads its decay",
     lambda old, new: "self.decay" in old and "else 1.0" in new),
    ("first root only", "equivalent: the first torsional root is the same however many roots "
     "are sought, and psi (the axial coupling) does not enter it",
     lambda old, new: "natural_frequencies(waves" in old),
    ("floating point anyway", "equivalent: the detrend's least squares turns the samples into "
     "floats whatever their type",
     lambda old, new: "np.asarray(series" in old),
    ("below the estimator's resolution", "equivalent to within the documented accuracy: the "
     "default band's top is capped at the last bin below Nyquist (0.5/h or 1.5/h alike); more "
     "zero padding is a finer grid under the same peak; a first bin that is a quarter period "
     "per record; the band's edges moved by one padded bin, inside the Hann main lobe (±8 "
     "padded bins); an exact zero beside the peak; a peak rising out of the band's edge, "
     "refined or not, stays within a bin of the edge",
     lambda old, new: any(k in old for k in (
         "0.5 / h_s if f_max_hz is None", "n_fft = 1 <<", "max(1, math.ceil(f_min / df))",
         "magnitude[lo:hi + 1]", "+ 1e-300", "curvature >= 0.0", "1e-12 * scale"))),
    ("a detrend of higher order", "not equivalent, not killed: a quadratic fit also removes "
     "the linear trend the estimator is specified for, and moves a tone's estimate by less "
     "than the 2e-3 of a bin the tests hold; only a curved trend tells them apart",
     lambda old, new: "np.polyfit(t, x, 1)" in old),
    ("a completed tick kept", "equivalent: a completed tick left pending returns its readings "
     "again if one of them comes again, and the loop answers a tick seen again with its "
     "command; the pending table stays bounded (KEEP_PENDING)",
     lambda old, new: "s <= stamp_ns" in old),
    ("words of a message", "not equivalent (a user reads other words): tests match the "
     "message's key words (the parameter's name, the range), not every word",
     lambda old, new: ("XX" in new or _only_case_differs(old, new)) and ("f\"" in old or "\""
                                                                         in old)),
    ("name in a refusal", "not equivalent: the refusal would not name the parameter",
     lambda old, new: "check_number(" in old and ("check_number(None" in new)),
]


def _only_case_differs(old: str, new: str) -> bool:
    return old != new and old.lower() == new.lower()


def survivors() -> list[str]:
    out = subprocess.run([MUTMUT, "results"], cwd=ROOT, capture_output=True, text=True,
                         check=True).stdout
    return [line.split(":")[0].strip() for line in out.splitlines() if line.endswith("survived")]


def diff(name: str) -> tuple[str, str]:
    out = subprocess.run([MUTMUT, "show", name], cwd=ROOT, capture_output=True, text=True,
                         check=True).stdout
    minus = [ln[1:] for ln in out.splitlines() if ln.startswith("-") and not ln.startswith("---")]
    plus = [ln[1:] for ln in out.splitlines() if ln.startswith("+") and not ln.startswith("+++")]
    return " ".join(minus).strip(), " ".join(plus).strip()


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--list", metavar="GROUP", help="print each survivor of GROUP "
                        "('unexplained' for those no group takes) with its diff")
    args = parser.parse_args(argv)
    groups: dict[str, list[tuple[str, str, str]]] = defaultdict(list)
    for name in survivors():
        old, new = diff(name)
        group = next((g for g, _, test in GROUPS if test(old, new)), "unexplained")
        groups[group].append((name, old, new))
    reasons = {g: r for g, r, _ in GROUPS}
    for group, members in sorted(groups.items(), key=lambda kv: -len(kv[1])):
        print(f"{len(members):5d}  {group}: {reasons.get(group, 'to be killed or explained')}")
    if args.list:
        for name, old, new in groups.get(args.list, []):
            print(f"\n{name}\n  - {old}\n  + {new}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
