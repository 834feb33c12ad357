"""YAML files shipped in a package folder (presets, scenarios, sensor profiles), or given by
path: one loader for all of them."""

from __future__ import annotations

import re
from importlib import resources
from pathlib import Path

import yaml

from .parameters import ParameterError


class NumberLoader(yaml.SafeLoader):
    """The safe loader, with numbers as YAML 1.2 reads them: ``1e9`` and ``6e7`` are floats
    (YAML 1.1 wants a dot, ``1.0e9``, and reads ``1e9`` as the string '1e9'), so a preset, a
    scenario and a sensor profile take the same numbers."""


NumberLoader.add_implicit_resolver(
    "tag:yaml.org,2002:float",
    re.compile(r"^[-+]?[0-9][0-9_]*(?:\.[0-9_]*)?[eE][-+]?[0-9]+$"), list("-+0123456789"))


def load_yaml(text: str) -> object:
    """``text`` parsed by ``NumberLoader`` (yaml.YAMLError if it is not YAML)."""
    return yaml.load(text, Loader=NumberLoader)     # a SafeLoader: no arbitrary objects


def shipped_names(folder: str) -> list[str]:
    """Names (without .yaml) of the files shipped in ``drill_sim/<folder>/``."""
    root = resources.files("drill_sim") / folder
    return sorted(p.name[:-5] for p in root.iterdir() if p.name.endswith(".yaml"))


def read_yaml(kind: str, folder: str, name_or_path: str | Path) -> tuple[str, object]:
    """(name, parsed YAML) of a shipped file by name or of any YAML file; ParameterError if
    neither exists, the file cannot be read, is not UTF-8 text or is not YAML."""
    text_name = str(name_or_path)
    if text_name in shipped_names(folder):
        source = resources.files("drill_sim") / folder / f"{text_name}.yaml"
        text, name = source.read_text(encoding="utf-8"), text_name
    else:
        path = Path(text_name)
        if not path.is_file():
            raise ParameterError(f"{kind} {text_name!r} is neither a shipped {kind} "
                                 f"({', '.join(shipped_names(folder))}) nor a readable YAML file")
        try:
            text, name = path.read_text(encoding="utf-8"), path.stem
        except UnicodeDecodeError as exc:
            raise ParameterError(f"{kind} {text_name!r} is not a text file: byte "
                                 f"{exc.object[exc.start]:#04x} at offset {exc.start} is not "
                                 "UTF-8; expected a YAML text file") from None
        except OSError as exc:
            raise ParameterError(f"{kind} {text_name!r} cannot be read: {exc.strerror}; "
                                 "expected a readable YAML file") from None
    try:
        return name, load_yaml(text)
    except yaml.YAMLError as exc:
        raise ParameterError(f"{kind} {text_name!r} is not valid YAML: {exc}") from None
