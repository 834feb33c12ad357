"""drill_sim: a real-time simulator of a rotary drilling rig's drill string and drag bit."""

__version__ = "0.1.0"
