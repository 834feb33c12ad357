"""A map on disk: its CSV (one row per point) and the JSON description beside it.

Each finished point is appended to the CSV at once and flushed, so an interrupted map keeps
every point it finished; running the same study again reads them back and computes only the
rest. The description (``FILE.json`` beside ``FILE.csv``) holds the study's settings, and a
study whose settings differ is refused, naming the difference, instead of mixing two maps in
one file. When every point is done the CSV is rewritten in grid order (atomically), so the file
is the same whatever order the points finished in. Numbers are written as the shortest text that
reads back to the same float, so a resumed map equals an uninterrupted one bit for bit.
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Sequence
from pathlib import Path

FORMAT = "drill_sim map 1"


class StoreError(ValueError):
    """The files at the output path belong to another study or are not a map's."""


def description_path(csv_path: Path) -> Path:
    """``FILE.json`` beside ``FILE.csv`` (``FILE.csv.json`` for a name without ``.csv``)."""
    return csv_path.with_suffix(".json") if csv_path.suffix.lower() == ".csv" \
        else csv_path.with_name(csv_path.name + ".json")


def number_text(value: float) -> str:
    """The shortest text that reads back to ``value`` (``nan``, ``inf`` for non-finite)."""
    return repr(float(value)) if math.isfinite(value) else str(float(value))


class MapStore:
    """The CSV ``path`` with ``columns`` (the first one, ``point``, the point's index in the
    grid) for a study of ``points`` points, described by ``description`` whose ``settings``
    must match to resume."""

    def __init__(self, path: Path, columns: Sequence[str], points: int, description: dict):
        self.path = Path(path)
        self.json_path = description_path(self.path)
        self.columns = list(columns)
        self.points = points
        self.description = json.loads(json.dumps(description))   # as it reads back
        self.rows: dict[int, list[float]] = {}
        self.discarded: list[tuple[int, str]] = []   # lines of a former run left out: why
        self._file = None

    # ---- resuming ------------------------------------------------------------------------
    def open(self) -> dict[int, list[float]]:
        """Keep the points a former run of the same study finished (checked against the
        description); return them, point -> values (without the point column)."""
        if self.path.exists():
            old = self._old_description()
            self._check_settings(old.get("settings"))
            self.rows = self._read_rows()
        self._write_description(complete=False)
        self._rewrite(sorted(self.rows))               # drops a torn last line
        self._file = open(self.path, "a", encoding="utf-8", newline="")
        return dict(self.rows)

    def _old_description(self) -> dict:
        try:
            old = json.loads(self.json_path.read_text(encoding="utf-8"))
        except (OSError, ValueError):
            old = None
        if not isinstance(old, dict) or old.get("format") != FORMAT:
            raise StoreError(f"{self.path} exists but {self.json_path}, the description of the "
                             "map it holds, is missing or unreadable; expected another output "
                             f"file, or remove {self.path} to start again")
        return old

    def _check_settings(self, old: object) -> None:
        new = self.description["settings"]
        if old == new:
            return
        diffs = _differences(old if isinstance(old, dict) else {}, new)
        shown = "; ".join(f"{key} {_show(a)} there, {_show(b)} now" for key, a, b in diffs[:4])
        more = f" (and {len(diffs) - 4} more)" if len(diffs) > 4 else ""
        raise StoreError(f"{self.path} holds a map with other settings ({shown}{more}); expected "
                         f"the same settings to resume it, another output file, or remove "
                         f"{self.path} and {self.json_path} to start again")

    def _read_rows(self) -> dict[int, list[float]]:
        text = self.path.read_text(encoding="utf-8")
        lines = text.split("\n")
        if not lines or lines[0].split(",") != self.columns:
            raise StoreError(f"{self.path}: its header is not this study's columns; expected "
                             "another output file, or remove it to start again")
        rows: dict[int, list[float]] = {}
        self.discarded = []
        for number, line in enumerate(lines[1:-1], start=2):  # the last piece: empty or torn
            fields = line.split(",")
            if len(fields) != len(self.columns):
                self.discarded.append((number, f"{len(fields)} fields, not {len(self.columns)}"))
                continue
            try:
                point = int(fields[0])
                values = [float(f) for f in fields[1:]]
            except ValueError:
                self.discarded.append((number, "a field that is not a number"))
                continue
            if not 0 <= point < self.points:
                self.discarded.append((number, f"point {point} is not on this grid"))
            elif point in rows:
                self.discarded.append((number, f"point {point} again"))
            else:
                rows[point] = values
        if lines[-1]:
            self.discarded.append((len(lines), "cut short (the run was stopped while writing it)"))
        return rows

    # ---- writing -------------------------------------------------------------------------
    def append(self, point: int, values: Sequence[float]) -> None:
        """Store one finished point at once (flushed)."""
        values = [float(v) for v in values]
        self._file.write(",".join([str(point), *map(number_text, values)]) + "\n")
        self._file.flush()
        self.rows[point] = values

    def finish(self) -> None:
        """Close: rewrite the CSV in grid order; the description says how many points are done
        and whether that is all of them (``complete``)."""
        self.close()
        self._rewrite(sorted(self.rows))
        self._write_description(complete=len(self.rows) == self.points)

    def close(self) -> None:
        if self._file is not None:
            self._file.close()
            self._file = None

    def _rewrite(self, order: Sequence[int]) -> None:
        tmp = self.path.with_name(self.path.name + ".tmp")
        with open(tmp, "w", encoding="utf-8", newline="") as fh:
            fh.write(",".join(self.columns) + "\n")
            for point in order:
                fh.write(",".join([str(point), *map(number_text, self.rows[point])]) + "\n")
        os.replace(tmp, self.path)

    def _write_description(self, *, complete: bool) -> None:
        body = {"format": FORMAT, "complete": complete, "points": self.points,
                "points_done": len(self.rows), **self.description}
        tmp = self.json_path.with_name(self.json_path.name + ".tmp")
        tmp.write_text(json.dumps(body, indent=1, allow_nan=False) + "\n", encoding="utf-8")
        os.replace(tmp, self.json_path)


def _differences(old: dict, new: dict, prefix: str = "") -> list[tuple[str, object, object]]:
    """(dotted key, old value, new value) of every setting that differs."""
    out = []
    for key in list(new) + [k for k in old if k not in new]:
        a, b = old.get(key, "(absent)"), new.get(key, "(absent)")
        if isinstance(a, dict) and isinstance(b, dict):
            out += _differences(a, b, f"{prefix}{key}.")
        elif a != b:
            out.append((prefix + key, a, b))
    return out


def _show(value: object) -> str:
    text = json.dumps(value) if not isinstance(value, str) else value
    return text if len(text) <= 60 else text[:57] + "..."
