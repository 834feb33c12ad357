"""rclpy's side of the wire definitions: message and service classes from type names, and
rclpy QoS profiles to and from ``wire.qos`` (the one statement of the rig's QoS and of
rosbag2's ``offered_qos_profiles``, strings in Jazzy, integers in older bags)."""

from __future__ import annotations

import importlib
from collections.abc import Callable

from rclpy.publisher import Publisher
from rclpy.qos import (
    DurabilityPolicy,
    HistoryPolicy,
    QoSProfile,
    ReliabilityPolicy,
)
from rclpy.topic_endpoint_info import TopicEndpointInfo

from ..wire.qos import BEST_EFFORT, RELIABLE, TRANSIENT_LOCAL, VOLATILE, Qos, player_qos

_RELIABILITY = {RELIABLE: ReliabilityPolicy.RELIABLE, BEST_EFFORT: ReliabilityPolicy.BEST_EFFORT}
_DURABILITY = {VOLATILE: DurabilityPolicy.VOLATILE,
               TRANSIENT_LOCAL: DurabilityPolicy.TRANSIENT_LOCAL}


class UnknownType(LookupError):
    """A message type that is not installed here (or not a ``pkg/msg/Type`` name)."""


def message_class(type_name: str) -> type:
    """The Python class of ``pkg/msg/Type``, imported from the installed interfaces."""
    return _interface_class(type_name, "msg")


def service_class(type_name: str) -> type:
    """The Python class of ``pkg/srv/Type``, imported from the installed interfaces."""
    return _interface_class(type_name, "srv")


def _interface_class(type_name: str, kind: str) -> type:
    parts = type_name.split("/")
    if len(parts) != 3 or parts[1] != kind or not all(parts):
        raise UnknownType(f"'{type_name}' is not a {kind} type name (pkg/{kind}/Type)")
    try:
        return getattr(importlib.import_module(f"{parts[0]}.{kind}"), parts[2])
    except (ImportError, AttributeError):
        raise UnknownType(f"{kind} type '{type_name}' is not installed here") from None


def raw_sender(publisher: Publisher) -> Callable[[bytes], None]:
    """Publish CDR bytes on ``publisher`` without ``Publisher.publish``'s wrapper.

    The wrapper enters the handle's use guard and checks the type on every call: ~10 us of a
    ~20 us raw publish here (measured from another process's subscriber), which at 1 kHz and
    16 outputs was a quarter of a core. The guard keeps a publisher from being destroyed
    while another thread publishes; the rig publishes and destroys from one thread."""
    return publisher.handle.publish_raw


def rclpy_qos(qos: Qos) -> QoSProfile:
    """The rclpy profile of a wire ``Qos``: the one conversion for node, driver, monitor and
    player."""
    return QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=qos.depth,
                      reliability=_RELIABILITY[qos.reliability],
                      durability=_DURABILITY[qos.durability])


def wire_qos(qos: QoSProfile) -> Qos:
    """An rclpy profile (a discovered publisher's, say) as a wire ``Qos``."""
    return Qos(BEST_EFFORT if qos.reliability == ReliabilityPolicy.BEST_EFFORT else RELIABLE,
               TRANSIENT_LOCAL if qos.durability == DurabilityPolicy.TRANSIENT_LOCAL
               else VOLATILE, int(qos.depth))


def profile_dict(qos: QoSProfile) -> dict:
    """One rclpy profile as a rosbag2 metadata (version 9) QoS entry."""
    return wire_qos(qos).as_dict()


KEEP_ALL = 0         # a ``depth`` of the player and the recorder: keep every message


def profile_from_dicts(profiles: list[dict] | None, depth: int) -> QoSProfile:
    """The profile to publish recorded messages with, as rosbag2's player chooses it
    (``wire.qos.player_qos``); ``depth`` KEEP_ALL: no message is dropped from the history
    (a reliable publisher then waits for its slowest subscriber: flow control)."""
    profile = rclpy_qos(player_qos(profiles, max(depth, 1)))
    if depth == KEEP_ALL:
        profile.history = HistoryPolicy.KEEP_ALL
    return profile


def subscription_qos(publishers: list[TopicEndpointInfo], depth: int) -> QoSProfile:
    """A subscription that matches every publisher, as rosbag2's recorder adapts it: reliable
    only if all publishers are, transient-local only if all are."""
    return profile_from_dicts([profile_dict(p.qos_profile) for p in publishers], depth)


NOT_YET_NAMED = "(a node not yet named)"


def publisher_names(infos) -> list[str]:
    """Fully qualified node names of ``get_publishers_info_by_topic`` entries; an endpoint
    discovered before its node's name is NOT_YET_NAMED."""
    return [NOT_YET_NAMED if i.node_name == "_NODE_NAME_UNKNOWN_"
            else f"{i.node_namespace.rstrip('/')}/{i.node_name}" for i in infos]
