"""Repairing a bag: every damaged file rewritten whole from what can be read (summary, indexes,
statistics) and ``metadata.yaml`` written, so seeking readers (``ros2 bag play``, Foxglove)
open it again. Nothing is ever lost by repairing:

- input that is not an MCAP bag is refused before anything is touched, and so is a bag with
  nothing to repair (every file sound, metadata.yaml listing them);
- free space is checked first, and each file is written to a temporary file, synced and read
  back (every chunk's CRC, the summary, the count) before anything is renamed;
- an original is kept byte for byte under a fresh name (``X.mcap.damaged``, else
  ``X.mcap.damaged.1``, ...), linked there before the repaired file takes its place, so the
  bag never lacks a file and no earlier original is overwritten;
- the walk skips damaged chunks and goes on with the intact ones (``mcap_scan``), and what was
  lost is said, per file, and recorded in the file as a ``repair`` metadata record.
"""

from __future__ import annotations

import datetime as dt
import os
import shutil
from dataclasses import dataclass, field
from pathlib import Path

from .bag import Bag, BagInfo
from .errors import BagError
from .mcap_scan import MappedFile, McapScan, what_it_is
from .metadata import FILE_NAME, write_metadata_yaml
from .repair_files import bag_metadata, rewrite
from .verify import damage

SPACE_MARGIN = 1.05            # the rewrite compresses as the node does; a little to spare
SPACE_SPARE_BYTES = 1 << 20


@dataclass
class FileRepair:
    """One rewritten file: its name, the name its original is kept under, the messages kept,
    what was lost, and whether it lost anything with intact data after it (a gap)."""

    name: str
    kept_as: str
    messages: int
    lost: list[str] = field(default_factory=list)
    gaps: int = 0


@dataclass
class RepairResult:
    """What ``repair`` did; ``info``: the repaired bag's."""

    bag: Path
    files: list[FileRepair]
    metadata_kept_as: str | None
    info: BagInfo


def repair(path: str | Path) -> RepairResult:
    """Rewrite every damaged file of the bag directory ``path`` from what can be read and
    write ``metadata.yaml``, keeping every original (see the module's docstring). BagError,
    with nothing changed, for input that is not an MCAP bag, a sound bag, too little free
    space or a rewrite that fails or does not read back."""
    bag = Path(path)
    if not bag.is_dir():
        raise BagError(f"bag {bag}: repair works on a bag directory")
    with Bag.open(bag) as listed:
        files, meta, notes = listed.files, listed.metadata_yaml, listed.notes
    storage = (meta or {}).get("storage_identifier", "mcap")
    if storage != "mcap":
        raise BagError(f"bag {bag}: storage '{storage}', not MCAP: these tools read and repair "
                       "MCAP bags only; nothing was changed")
    damaged: dict[Path, list[str]] = {}
    for file in files:
        mapped = MappedFile(file)
        try:
            if not mapped.is_mcap:
                earlier = _earliest_kept(file)
                raise BagError(f"{file}: not an MCAP file ({what_it_is(mapped.view)}); nothing "
                               "was changed" + (f" (an earlier repair kept the original as "
                                                f"{earlier.name})" if earlier else ""))
            found = damage(mapped)
            if found or mapped.summary is None:
                damaged[file] = found or [f"{file.name}: no sound summary"]
        finally:
            mapped.close()
    names = [f.name for f in files]
    metadata_sound = meta is not None and not notes and \
        list(meta.get("relative_file_paths", [])) == names
    if not damaged and metadata_sound:
        raise BagError(f"bag {bag}: nothing to repair: every file is sound and metadata.yaml "
                       "lists them; nothing was changed")
    _check_space(bag, damaged)
    repaired = _rewrite_all(bag, damaged)
    try:
        metadata_kept = _keep(bag / FILE_NAME) if (bag / FILE_NAME).exists() else None
        write_metadata_yaml(bag, bag_metadata(files, meta))
        _sync_dir(bag)
    except OSError as exc:
        raise BagError(f"bag {bag}: the files are repaired (originals kept as *.damaged) but "
                       f"metadata.yaml could not be written: {exc.strerror or exc}; run repair "
                       "again once that is fixed") from None
    with Bag.open(bag) as done:
        return RepairResult(bag, repaired, metadata_kept and metadata_kept.name, done.info())


def _check_space(bag: Path, damaged: dict[Path, list[str]]) -> None:
    need = int(sum(f.stat().st_size for f in damaged) * SPACE_MARGIN) + SPACE_SPARE_BYTES
    free = shutil.disk_usage(bag).free
    if free < need:
        raise BagError(f"bag {bag}: not enough free space to repair it: about "
                       f"{need / 1e6:.1f} MB needed, {free / 1e6:.1f} MB free; nothing was "
                       "changed")


def _rewrite_all(bag: Path, damaged: dict[Path, list[str]]) -> list[FileRepair]:
    """Each damaged file rewritten to a temporary file and read back; only then are the
    originals kept aside and the repaired files put in their place."""
    done: list[tuple[Path, Path, FileRepair]] = []
    try:
        for file in damaged:
            tmp = file.with_name(file.name + ".repair.tmp")
            done.append((file, tmp, FileRepair(file.name, "", 0)))
            problems: list[str] = []
            with McapScan(file, problems) as scan:
                count = rewrite(scan, tmp, {"original": _fresh_name(file).name,
                                            "date": _now()})
            result = done[-1][2]
            result.messages, result.lost, result.gaps = count, problems, scan.gaps
            _read_back(tmp, count)
    except OSError as exc:
        for _, tmp, _ in done:
            tmp.unlink(missing_ok=True)
        raise BagError(f"bag {bag}: cannot write the repaired files: "
                       f"{exc.strerror or exc}; nothing was changed") from None
    except BagError:
        for _, tmp, _ in done:
            tmp.unlink(missing_ok=True)
        raise
    for file, tmp, result in done:
        result.kept_as = _keep(file).name
        os.replace(tmp, file)
    return [r for _, _, r in done]


def _read_back(tmp: Path, count: int) -> None:
    """The rewritten file must be sound: every chunk, the summary, the message count."""
    mapped = MappedFile(tmp)
    try:
        problems = damage(mapped)
        stats = None if mapped.summary is None else mapped.summary.statistics
        if problems or stats is None or stats.message_count != count:
            raise BagError(f"{tmp.name}: the rewritten file does not read back whole ("
                           + ("; ".join(problems) or "summary or count differs")
                           + "); nothing was changed")
    finally:
        mapped.close()


def _fresh_name(file: Path) -> Path:
    """``X.damaged``, else ``X.damaged.1``, ``X.damaged.2``, ...: the first that is free."""
    k = 0
    while True:
        name = file.with_name(file.name + ".damaged" + (f".{k}" if k else ""))
        if not name.exists() and not name.is_symlink():
            return name
        k += 1


def _earliest_kept(file: Path) -> Path | None:
    first = file.with_name(file.name + ".damaged")
    return first if first.exists() else None


def _keep(file: Path) -> Path:
    """Give ``file`` a second name, fresh (never replacing one), so it survives being
    replaced: a hard link where the file system has them, else a rename."""
    while True:
        kept = _fresh_name(file)
        try:
            os.link(file, kept)
            return kept
        except FileExistsError:
            continue
        except OSError:
            if kept.exists():
                continue
            os.rename(file, kept)
            return kept


def _sync_dir(path: Path) -> None:
    fd = os.open(path, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


def _now() -> str:
    return dt.datetime.now(dt.timezone.utc).isoformat(timespec="seconds")
