"""The topics table (drill_sim.wire.rig_topics) is the rig's interface: the running node offers
exactly its topics and services with their types and QoS, the encoders put each sample field
where the table says, and msg_docs/node.md documents every entry."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from drill_sim.core import RPM, Rig, RigSample, load_preset
from drill_sim.core.rig_sample import REGIME_NAMES
from drill_sim.core.sensors import Measured, exact_measured
from drill_sim.session import rules
from drill_sim.session.rig_messages import RigEncoders
from drill_sim.wire import rig_topics
from drill_sim.wire.cdr import VECTOR_FIELDS
from drill_sim.wire.qos import BEST_EFFORT
from drill_sim.wire.rig_topics import COMMAND, OUTPUT, SERVICE, TOPICS

ROOT = Path(__file__).resolve().parents[2]
NS = "/wire_graph"
# what every rclpy node offers besides its own interface
STANDARD_TOPICS = {"/rosout", "/parameter_events"}
STANDARD_SERVICES = {"describe_parameters", "get_parameter_types", "get_parameters",
                     "list_parameters", "set_parameters", "set_parameters_atomically",
                     "get_type_description"}


def test_table_entries_are_complete_and_consistent():
    assert len({t.name for t in TOPICS}) == len(TOPICS)
    for t in TOPICS:
        assert t.name.startswith(("~/", "/")), t.name
        kind = "srv" if t.direction == SERVICE else "msg"
        assert re.fullmatch(rf"\w+/{kind}/\w+", t.type_name), t.name
        assert (t.qos is None) == (t.direction == SERVICE), t.name
        if t.direction == OUTPUT:
            assert t.fields, f"{t.name}: an output without fields"
        source = Measured if t.source == rig_topics.MEASURED else RigSample
        assert (t.source == rig_topics.MEASURED) == t.name.startswith("~/measured/"), t.name
        for f in t.fields:
            assert f.sample in source._fields, f"{t.name}: {f.sample} is not a {source} field"
        if t.direction == COMMAND and t.command != rules.JOINT_COMMANDS:
            rule = rules.COMMANDS[t.command]   # the session's rule reads the field it names
            assert VECTOR_FIELDS[t.type_name][rule.index] == rule.field, t.name
    assert set(rig_topics.COMMAND_BY_RULE) == set(rules.COMMANDS) | {rules.JOINT_COMMANDS}


def test_joint_fields_of_the_bag_series_agree_with_the_table():
    from drill_sim.bag.series import JOINT_FIELDS
    table = {(f.message, f.sample) for f in rig_topics.JOINT_STATES.fields}
    for name, (array, j) in JOINT_FIELDS.items():
        assert (f"{array}[{j}]", name) in table, name


def _samples() -> list[RigSample]:
    """The base rig off bottom, drilling and stuck: every regime."""
    preset = load_preset("base")
    rig = Rig(preset.rig)
    rig.start_at_rest(0.05)
    rig.command(60 * RPM, preset.rig.submerged_weight_n - 100e3)
    found: dict[int, RigSample] = {}
    for k in range(1, 40_000):
        rig.advance_to(k * 1e-3)
        s = rig.sample()
        found.setdefault(s.regime, s)
    assert set(found) == set(REGIME_NAMES)
    return list(found.values())


def _field(msg, path: str):
    for part in path.split("."):
        name, _, index = part.partition("[")
        msg = getattr(msg, name)
        if index:
            msg = msg[int(index[:-1])]
    return msg


@pytest.mark.parametrize("with_clock", [False, True])
def test_encoded_outputs_carry_the_sample_fields_the_table_names(with_clock):
    from rclpy.serialization import deserialize_message

    from drill_sim.ros.topics import message_class

    enc = RigEncoders(with_clock)
    assert enc.topics == rig_topics.published(with_clock)
    stamp_ns = 1_700_000_123_456_789_012
    for s in _samples():
        for t, data in zip(enc.topics, enc.sample(stamp_ns, s), strict=True):
            msg = deserialize_message(data, message_class(t.type_name))
            stamp = msg.clock if t.direction == rig_topics.CLOCK else getattr(
                getattr(msg, "header", None), "stamp", None)
            if stamp is not None:
                assert stamp.sec * 1_000_000_000 + stamp.nanosec == stamp_ns, t.name
                if hasattr(msg, "header"):
                    assert msg.header.frame_id == t.frame_id, t.name
            if t.joints:
                assert tuple(msg.name) == t.joints
            source = exact_measured(s) if t.source == rig_topics.MEASURED else s
            for f in t.fields:
                assert _field(msg, f.message) == getattr(source, f.sample), (t.name, f)


def test_node_md_documents_every_entry_with_its_type():
    """Each entry has a line in msg_docs/node.md naming it and its type (as pkg/Type)."""
    lines = (ROOT / "msg_docs" / "node.md").read_text(encoding="utf-8").splitlines()
    for t in TOPICS:
        short = t.type_name.replace("/msg/", "/").replace("/srv/", "/")
        assert any(f"`{t.name}`" in line and f"`{short}`" in line for line in lines), \
            f"msg_docs/node.md: no line documents `{t.name}` with its type `{short}`"


def _offered(ros, namespace: str, name: str) -> dict[tuple[str, str], tuple]:
    """What the graph shows of node ``namespace/name``: (kind, topic) -> type and QoS."""
    from drill_sim.ros.topics import wire_qos

    found: dict[tuple[str, str], tuple] = {}
    for topic, _ in ros.get_topic_names_and_types():
        for kind, infos in (("publisher", ros.get_publishers_info_by_topic(topic)),
                            ("subscription", ros.get_subscriptions_info_by_topic(topic))):
            for info in infos:
                if (info.node_name, info.node_namespace) == (name, namespace) \
                        and topic not in STANDARD_TOPICS:
                    q = wire_qos(info.qos_profile)
                    found[(kind, topic)] = (info.topic_type, q.reliability, q.durability)
    if (name, namespace) not in ros.get_node_names_and_namespaces():
        return found
    for service, types in ros.get_service_names_and_types_by_node(name, namespace):
        if service.rsplit("/", 1)[-1] not in STANDARD_SERVICES:
            found[("service", service)] = tuple(types)
    return found


def _expected(node: str, reliability: str) -> dict[tuple[str, str], tuple]:
    kinds = {rig_topics.OUTPUT: "publisher", rig_topics.CLOCK: "publisher",
             rig_topics.DIAGNOSTICS: "publisher", rig_topics.COMMAND: "subscription"}
    expected: dict[tuple[str, str], tuple] = {}
    for t in TOPICS:
        if t.direction == SERVICE:
            expected[("service", t.under(node))] = (t.type_name,)
        elif t.direction in kinds:
            q = t.qos_for(reliability)
            expected[(kinds[t.direction], t.under(node))] = (t.type_name, q.reliability,
                                                             q.durability)
    return expected


def test_the_running_node_offers_exactly_the_table(ros):
    """The installed node, with /clock and best-effort topics: every table entry is offered
    with its type and QoS (/clock and /diagnostics stay reliable), and nothing else."""
    from rosutil import NodeProcess, wait_for

    expected = _expected(f"{NS}/{rig_topics.NODE_NAME}", BEST_EFFORT)
    seen: dict[tuple[str, str], tuple] = {}

    def discovered() -> bool:
        seen.clear()
        seen.update(_offered(ros, NS, rig_topics.NODE_NAME))
        return seen == expected

    with NodeProcess("drill_sim_node", "--ros-args", "-r", f"__ns:={NS}", "-p",
                     "publish_clock:=true", "-p", f"qos_reliability:={BEST_EFFORT}"):
        try:
            wait_for(discovered, ros, 30.0, "the node's topics and services in the graph")
        except AssertionError:
            assert seen == expected          # shows what differs
