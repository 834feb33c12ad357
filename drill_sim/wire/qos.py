"""QoS as plain data, stated once: the rig's topics carry a ``Qos``; ``ros.topics.rclpy_qos``
turns it into an rclpy profile and ``qos_profile`` into rosbag2's ``offered_qos_profiles`` entry.

Spellings are rosbag2's (metadata version 9). History is always KEEP_LAST ``depth``.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

from . import WireError

RELIABLE, BEST_EFFORT = "reliable", "best_effort"
RELIABILITIES = (RELIABLE, BEST_EFFORT)
VOLATILE, TRANSIENT_LOCAL = "volatile", "transient_local"
DURABILITIES = (VOLATILE, TRANSIENT_LOCAL)
INFINITE = {"sec": 9223372036, "nsec": 854775807}   # rmw's "unspecified" duration

# how rosbag2 bags spell the policies: strings in Jazzy, the rmw enum values in older bags
_RELIABILITY_OF = {RELIABLE: RELIABLE, 1: RELIABLE, BEST_EFFORT: BEST_EFFORT, 2: BEST_EFFORT}
_DURABILITY_OF = {TRANSIENT_LOCAL: TRANSIENT_LOCAL, 1: TRANSIENT_LOCAL,
                  VOLATILE: VOLATILE, 2: VOLATILE}


@dataclass(frozen=True)
class Qos:
    """KEEP_LAST ``depth`` [messages] with this reliability and durability; depth 0 stands for
    unknown, as discovery reports other processes' publishers and rosbag2 records them."""

    reliability: str = RELIABLE
    durability: str = VOLATILE
    depth: int = 10

    def __post_init__(self) -> None:
        if self.reliability not in RELIABILITIES or self.durability not in DURABILITIES \
                or self.depth < 0:
            raise WireError(f"QoS {self}: expected reliability in {RELIABILITIES}, durability "
                            f"in {DURABILITIES} and depth >= 0")

    def with_reliability(self, reliability: str) -> Qos:
        return replace(self, reliability=reliability)

    def with_depth(self, depth: int) -> Qos:
        return replace(self, depth=depth)

    def as_dict(self) -> dict:
        """This profile as rosbag2 writes it in ``offered_qos_profiles``."""
        return qos_profile(self.reliability, self.depth, self.durability)


def qos_profile(reliability: str = RELIABLE, depth: int = 10, durability: str = VOLATILE) -> dict:
    """One offered QoS profile in rosbag2's metadata-version-9 form."""
    return {"history": "keep_last", "depth": depth, "reliability": reliability,
            "durability": durability, "deadline": dict(INFINITE), "lifespan": dict(INFINITE),
            "liveliness": "automatic", "liveliness_lease_duration": dict(INFINITE),
            "avoid_ros_namespace_conventions": False}


def player_qos(profiles: list[dict] | None, depth: int) -> Qos:
    """The profile to publish recorded messages with, as rosbag2's player chooses it from the
    recorded publishers' profiles: reliable unless one of them was best effort (or unknown
    spellings: reliable), transient-local only if every one was; KEEP_LAST ``depth``."""
    profiles = [p for p in profiles or [] if isinstance(p, dict)]
    reliable = all(_RELIABILITY_OF.get(p.get("reliability"), RELIABLE) == RELIABLE
                   for p in profiles)
    latched = bool(profiles) and all(
        _DURABILITY_OF.get(p.get("durability")) == TRANSIENT_LOCAL for p in profiles)
    return Qos(RELIABLE if reliable else BEST_EFFORT, TRANSIENT_LOCAL if latched else VOLATILE,
               depth)
