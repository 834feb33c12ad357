"""Message definitions (``ros2msg`` schema text) and type hashes of installed ROS types.

rosbag2 stores a type as its ``.msg`` text followed, for each nested type (sorted, depth first,
no repeats), by a line of 80 ``=``, ``MSG: pkg/Type`` and that type's ``.msg`` text. The texts and
the RIHS01 hashes come from the ``share/<pkg>/msg/`` folders the message packages install.
"""

from __future__ import annotations

import json
import os
import re
import sys
from functools import cache
from pathlib import Path

SEPARATOR = "=" * 80
_PRIMITIVES = {"bool", "byte", "char", "float32", "float64", "int8", "uint8", "int16", "uint16",
               "int32", "uint32", "int64", "uint64", "string", "wstring"}
_FIELD = re.compile(r"^\s*([A-Za-z0-9_/]+)(?:<=\d+)?(\[[^\]]*\])?\s+([A-Za-z0-9_]+)")


def _share_dirs() -> list[Path]:
    roots = [Path(p) for p in os.environ.get("AMENT_PREFIX_PATH", "").split(os.pathsep) if p]
    roots.append(Path(sys.prefix))
    return [r / "share" for r in roots]


@cache
def _msg_file(type_name: str, suffix: str) -> Path:
    pkg, _, name = _split(type_name)
    for share in _share_dirs():
        path = share / pkg / "msg" / f"{name}{suffix}"
        if path.is_file():
            return path
    raise LookupError(f"no definition of {type_name} ({name}{suffix}) under "
                      f"{', '.join(str(s) for s in _share_dirs())}")


def _split(type_name: str) -> tuple[str, str, str]:
    parts = type_name.split("/")
    if len(parts) == 3 and parts[1] == "msg":
        return parts[0], "msg", parts[2]
    if len(parts) == 2:
        return parts[0], "msg", parts[1]
    raise ValueError(f"type name {type_name!r}: expected pkg/msg/Type")


def _dependencies(pkg: str, text: str) -> list[str]:
    deps = []
    for line in text.splitlines():
        line = line.split("#", 1)[0]
        m = _FIELD.match(line)
        if not m or "=" in line.split(m.group(3), 1)[1][:3]:
            continue                                # constants are not fields
        base = m.group(1)
        if base in _PRIMITIVES:
            continue
        if base == "Header":
            base = "std_msgs/Header"
        deps.append(base if "/" in base else f"{pkg}/{base}")
    return deps


@cache
def message_definition(type_name: str) -> str:
    """The ros2msg schema text of ``type_name`` (``pkg/msg/Type``) with its nested types."""
    pkg, _, _ = _split(type_name)
    text = _msg_file(type_name, ".msg").read_text(encoding="utf-8")
    seen: list[str] = []

    def visit(p: str, t: str) -> None:
        for dep in sorted(set(_dependencies(p, t))):
            short = dep.replace("/msg/", "/")
            if short in seen:
                continue
            seen.append(short)
            dep_text = _msg_file(short, ".msg").read_text(encoding="utf-8")
            visit(short.split("/")[0], dep_text)

    visit(pkg, text)
    parts = [text]
    for short in seen:
        parts.append(f"{SEPARATOR}\nMSG: {short}\n"
                     + _msg_file(short, ".msg").read_text(encoding="utf-8"))
    return "\n".join(p.rstrip("\n") for p in parts) + "\n"


@cache
def type_hash(type_name: str) -> str:
    """The RIHS01 type-description hash of ``type_name``."""
    pkg, _, name = _split(type_name)
    data = json.loads(_msg_file(type_name, ".json").read_text(encoding="utf-8"))
    full = f"{pkg}/msg/{name}"
    for entry in data.get("type_hashes", []):
        if entry.get("type_name") == full:
            return entry["hash_string"]
    raise LookupError(f"no type hash for {full}")
