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
     lambda old, new: "tol" in old and ("high" in old or "low" in old or "span" in old
                                        or "torque_m" in old)),
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
