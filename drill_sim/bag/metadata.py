"""A bag's ``metadata.yaml`` (rosbag2 version 9): built from topics and file entries, written
atomically, and read back tolerantly (a broken one is ignored: the ``.mcap`` files themselves
say what the bag holds)."""

from __future__ import annotations

from pathlib import Path

import yaml

FILE_NAME = "metadata.yaml"


def file_entry(name: str, start_ns: int | None, end_ns: int, count: int) -> dict:
    """One file's entry in metadata.yaml."""
    start = start_ns or 0
    return {"path": name, "starting_time": {"nanoseconds_since_epoch": start},
            "duration": {"nanoseconds": max(0, end_ns - start)}, "message_count": count}


def bag_information(topics: list[dict], files: list[dict], custom_data: dict | None = None,
                    ros_distro: str = "jazzy") -> dict:
    """metadata.yaml (version 9) from topics {name, type, qos (list), hash, count} and file
    entries."""
    live = [e for e in files if e["message_count"]]
    start = min((e["starting_time"]["nanoseconds_since_epoch"] for e in live), default=0)
    end = max((e["starting_time"]["nanoseconds_since_epoch"] + e["duration"]["nanoseconds"]
               for e in live), default=start)
    return {"rosbag2_bagfile_information": {
        "version": 9,
        "storage_identifier": "mcap",
        "duration": {"nanoseconds": end - start},
        "starting_time": {"nanoseconds_since_epoch": start},
        "message_count": sum(e["message_count"] for e in files),
        "topics_with_message_count": [
            {"topic_metadata": {"name": t["name"], "type": t["type"],
                                "serialization_format": "cdr",
                                "offered_qos_profiles": t["qos"],
                                "type_description_hash": t["hash"]},
             "message_count": t["count"]} for t in topics],
        "compression_format": "",
        "compression_mode": "",
        "relative_file_paths": [e["path"] for e in files],
        "files": files,
        "custom_data": dict(custom_data or {}),
        "ros_distro": ros_distro,
    }}


def write_metadata_yaml(bag_dir: Path, information: dict) -> None:
    """Write ``information`` (from ``bag_information``) beside the files, through a temporary
    file so a crash never leaves half a metadata.yaml."""
    tmp = bag_dir / (FILE_NAME + ".tmp")
    tmp.write_text(yaml.safe_dump(information, sort_keys=False), encoding="utf-8")
    tmp.replace(bag_dir / FILE_NAME)


def read_metadata_yaml(bag_dir: Path) -> dict | None:
    """The ``rosbag2_bagfile_information`` of the bag directory, or None if it has no
    metadata.yaml or an unreadable one."""
    path = bag_dir / FILE_NAME
    if not path.is_file():
        return None
    try:
        info = yaml.safe_load(path.read_text(encoding="utf-8"))["rosbag2_bagfile_information"]
    except (yaml.YAMLError, UnicodeDecodeError, KeyError, TypeError):
        return None
    return info if isinstance(info, dict) else None
