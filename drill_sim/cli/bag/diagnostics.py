"""``drill_sim bag diagnostics``: the ``/diagnostics`` a bag recorded, as a table or JSON lines.

The node's bag records its own ``/diagnostics`` (a status a diagnostics period: tick rate,
stalls, lockstep waits, commands, the drilling regime), and without the ``ros2`` command line
this is how to read them back: one row per status, its level, name and message, and the values
asked for with ``--keys``; at the end every key of the last status, so the names to ask for are
in view.
"""

from __future__ import annotations

import argparse
import difflib
import json
import sys
from pathlib import Path

from ...bag.bag import Bag
from ...session.diagnostics import ERROR, OK, WARN
from ...wire import WireError, rig_topics
from ...wire.cdr_decode import decode_diagnostic_array
from ..errors import UsageError

HELP = "the /diagnostics a bag recorded: level, message and chosen values over time"
TOPIC = rig_topics.DIAGNOSTICS_TOPIC
TYPE = TOPIC.type_name
LEVELS = {OK: "OK", WARN: "WARN", ERROR: "ERROR", 3: "STALE"}   # DiagnosticStatus's levels


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("bag", type=Path, help="bag directory or .mcap file")
    parser.add_argument("--topic", default=TOPIC.name,
                        help=f"a DiagnosticArray topic of the bag (default: {TOPIC.name})")
    parser.add_argument("--name", default="",
                        help="only the statuses whose name contains this (e.g. 'rig')")
    parser.add_argument("--keys", default="",
                        help="comma-separated value keys to show as columns, e.g. "
                        "overruns,longest_stall_ms,tick_rate_hz")
    parser.add_argument("--json", action="store_true",
                        help="one JSON object a status on stdout (every value)")


def run(args: argparse.Namespace) -> int:
    keys = [k.strip() for k in args.keys.split(",") if k.strip()]
    problems: list[str] = []
    with Bag.open(args.bag) as bag:
        types = bag.topic_types(problems)
        if args.topic not in types:
            found = sorted(t for t, ty in types.items() if ty == TYPE)
            raise UsageError(f"{args.bag} has no topic {args.topic}: expected one of its "
                             f"{TYPE} topics ({', '.join(found) or 'it has none'})")
        if types[args.topic] != TYPE:
            raise UsageError(f"{args.topic} in {args.bag} is {types[args.topic]}: expected "
                             f"a {TYPE} topic")
        rows, last, t0 = 0, None, None
        seen: set[str] = set()                 # every value key of the statuses shown
        if not args.json:
            print("\t".join(["t_s", "level", "name", "message", *keys]))
        for m in bag.messages({args.topic}, problems):
            try:
                sec, nanosec, statuses = decode_diagnostic_array(m.data)
            except WireError as exc:
                problems.append(f"a message at log time {m.log_time_ns} ns: {exc}")
                continue
            t0 = m.log_time_ns if t0 is None else t0
            t_s = (m.log_time_ns - t0) * 1e-9
            for st in statuses:
                if args.name not in st.name:
                    continue
                rows, last, values = rows + 1, st, dict(st.values)
                seen.update(values)
                level = LEVELS.get(st.level, str(st.level))
                if args.json:
                    print(json.dumps({"t_s": round(t_s, 6), "stamp_s": sec + nanosec * 1e-9,
                                      "level": level, "name": st.name, "message": st.message,
                                      "hardware_id": st.hardware_id, "values": values}))
                else:
                    print("\t".join([f"{t_s:.3f}", level, st.name, st.message,
                                     *(values.get(k, "-") for k in keys)]))
    if not args.json:
        if last is None:
            print(f"(no status{f' named *{args.name}*' if args.name else ''} on {args.topic})")
        else:
            print(f"\n{rows} statuses; t_s: seconds of log time since the first. Keys of the "
                  f"last ({last.name}):")
            for k, v in last.values:
                print(f"  {k:<28} {v}")
    for p in dict.fromkeys(problems):
        print(f"problem: {p}", file=sys.stderr)
    unknown = [k for k in keys if k not in seen] if rows else []
    for k in unknown:
        near = difflib.get_close_matches(k, sorted(seen), n=1)
        print(f"--keys: no status shown has a value '{k}'"
              f"{f' (did you mean {near[0]!r}?)' if near else ''}; its keys: "
              f"{', '.join(sorted(seen))}", file=sys.stderr)
    return 2 if unknown else 1 if problems else 0
