"""The Foxglove and PlotJuggler layouts shipped in drill_sim/config parse, plot the quantities
the rig is watched by, and name only topics and fields the rig publishes (from the topics
table), so a renamed topic or field breaks this test rather than a user's plot."""

from __future__ import annotations

import json
import xml.etree.ElementTree as ET
from importlib.resources import files

from drill_sim.wire import rig_topics

NODE = "/" + rig_topics.NODE_NAME                      # the layouts' rig: root namespace
# what the layouts must show: RigSample fields
WATCHED = {"bit_speed_rad_s", "top_drive_speed_rad_s", "wob_n", "tob_nm",
           "surface_torque_nm", "motor_torque_nm", "stick_slip"}


def _published() -> dict[str, dict[str, str]]:
    """Full topic name -> {message field path: RigSample field} of every output."""
    return {t.under(NODE): {f.message: f.sample for f in t.fields}
            for t in rig_topics.OUTPUTS}


def _sample_of(topic: str, field: str) -> str:
    fields = _published().get(topic)
    assert fields is not None, f"{topic} is not a topic the rig publishes"
    assert field in fields, f"{topic} has no field {field} the rig fills ({sorted(fields)})"
    return fields[field]


def test_foxglove_layout_plots_only_published_fields():
    layout = json.loads((files("drill_sim") / "config" / "foxglove_layout.json").read_text())
    panels = layout["configById"]
    shown = set()
    for panel_id, config in panels.items():
        assert panel_id.startswith("Plot!"), panel_id
        for path in config["paths"]:
            topic, _, field = path["value"].partition(".")
            shown.add(_sample_of(topic, field))

    def leaves(node) -> set[str]:
        return leaves(node["first"]) | leaves(node["second"]) if isinstance(node, dict) \
            else {node}
    assert leaves(layout["layout"]) == set(panels)     # every panel placed, none missing
    assert shown == WATCHED


def test_plotjuggler_layout_plots_only_published_fields():
    root = ET.fromstring((files("drill_sim") / "config" / "plotjuggler_layout.xml").read_text())
    topics = _published()
    shown = set()
    for curve in root.iter("curve"):
        name = curve.get("name")
        topic = max((t for t in topics if name.startswith(t + "/")), key=len, default=None)
        assert topic is not None, f"{name} is on no topic the rig publishes"
        shown.add(_sample_of(topic, name[len(topic) + 1:].replace("/", ".")))
    assert shown == WATCHED
    plotted = {t for t in topics if any(c.get("name").startswith(t + "/")
                                        for c in root.iter("curve"))}
    for plugin in root.iter("plugin"):
        for selected in plugin.iter("selected_topics"):
            assert set(selected.get("value").split(";")) == plotted, plugin.get("ID")
