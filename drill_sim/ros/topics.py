"""What the recorder and the player share: message classes from type names, and QoS profiles
to and from rosbag2's ``offered_qos_profiles`` (strings in Jazzy, integers in older bags)."""

from __future__ import annotations

import importlib

from rclpy.qos import (
    DurabilityPolicy,
    HistoryPolicy,
    QoSProfile,
    ReliabilityPolicy,
)
from rclpy.topic_endpoint_info import TopicEndpointInfo

from ..bag.writer import qos_profile

_RELIABILITY = {"reliable": ReliabilityPolicy.RELIABLE, 1: ReliabilityPolicy.RELIABLE,
                "best_effort": ReliabilityPolicy.BEST_EFFORT, 2: ReliabilityPolicy.BEST_EFFORT}
_DURABILITY = {"transient_local": DurabilityPolicy.TRANSIENT_LOCAL,
               1: DurabilityPolicy.TRANSIENT_LOCAL,
               "volatile": DurabilityPolicy.VOLATILE, 2: DurabilityPolicy.VOLATILE}


class UnknownType(LookupError):
    """A message type that is not installed here (or not a ``pkg/msg/Type`` name)."""


def message_class(type_name: str) -> type:
    """The Python class of ``pkg/msg/Type``, imported from the installed interfaces."""
    parts = type_name.split("/")
    if len(parts) != 3 or parts[1] != "msg" or not all(parts):
        raise UnknownType(f"'{type_name}' is not a message type name (pkg/msg/Type)")
    try:
        return getattr(importlib.import_module(f"{parts[0]}.msg"), parts[2])
    except (ImportError, AttributeError):
        raise UnknownType(f"message type '{type_name}' is not installed here") from None


def profile_dict(qos: QoSProfile) -> dict:
    """One rclpy profile as a rosbag2 metadata (version 9) QoS entry."""
    return qos_profile(
        reliability="best_effort" if qos.reliability == ReliabilityPolicy.BEST_EFFORT
        else "reliable",
        depth=int(qos.depth),
        durability="transient_local" if qos.durability == DurabilityPolicy.TRANSIENT_LOCAL
        else "volatile")


def profile_from_dicts(profiles: list[dict] | None, depth: int) -> QoSProfile:
    """The profile to publish recorded messages with, as rosbag2's player chooses it: reliable
    and transient-local only if every recorded publisher offered them; keep-last ``depth``."""
    profiles = [p for p in profiles or [] if isinstance(p, dict)]
    reliable = all(_RELIABILITY.get(p.get("reliability"), ReliabilityPolicy.RELIABLE)
                   == ReliabilityPolicy.RELIABLE for p in profiles)
    latched = bool(profiles) and all(
        _DURABILITY.get(p.get("durability")) == DurabilityPolicy.TRANSIENT_LOCAL
        for p in profiles)
    return QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=depth,
                      reliability=ReliabilityPolicy.RELIABLE if reliable
                      else ReliabilityPolicy.BEST_EFFORT,
                      durability=DurabilityPolicy.TRANSIENT_LOCAL if latched
                      else DurabilityPolicy.VOLATILE)


def subscription_qos(publishers: list[TopicEndpointInfo], depth: int) -> QoSProfile:
    """A subscription that matches every publisher, as rosbag2's recorder adapts it: reliable
    only if all publishers are, transient-local only if all are."""
    return profile_from_dicts([profile_dict(p.qos_profile) for p in publishers], depth)
