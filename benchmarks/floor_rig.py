"""A rig that does nothing but the lockstep's middleware work, for ``bench_lockstep.py --rig
floor``: it publishes a TwistStamped sample on ``<rig>/bit/twist`` (raw bytes, straight to the
publisher's handle), waits on an rcl wait set for the command on ``<rig>/cmd/top_drive`` stamped
with that sample's stamp, and publishes the next; no model, no sensors, no encoding. Its wall
time per tick is the floor any lockstep rig on this middleware and machine stands on.

    python floor_rig.py --rig /bench_lockstep/drill_sim [--best-effort]

Waits for ``<rig>/pause`` false (the lean controller's ``--resume``) before the first sample;
stops on SIGINT.
"""

from __future__ import annotations

import argparse
import signal
import struct
import sys

import rclpy
from geometry_msgs.msg import TwistStamped
from lean_controller import command_template
from rclpy.executors import SingleThreadedExecutor
from rclpy.impl.implementation_singleton import rclpy_implementation as _rclpy
from rclpy.qos import QoSProfile, ReliabilityPolicy
from rclpy.type_support import check_is_valid_msg_type
from std_srvs.srv import SetBool


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--rig", default="/drill_sim", help="the name the rig takes")
    parser.add_argument("--best-effort", action="store_true", help="best-effort QoS")
    args = parser.parse_args()
    qos = QoSProfile(depth=10, reliability=ReliabilityPolicy.BEST_EFFORT if args.best_effort
                     else ReliabilityPolicy.RELIABLE)
    stop = []
    signal.signal(signal.SIGINT, lambda *_: stop.append(True))
    rclpy.init(signal_handler_options=rclpy.signals.SignalHandlerOptions.NO)
    node = rclpy.create_node("floor_rig")
    send = node.create_publisher(TwistStamped, f"{args.rig}/bit/twist", qos).handle.publish_raw
    check_is_valid_msg_type(TwistStamped)
    with node.handle:
        sub = _rclpy.Subscription(node.handle, TwistStamped, f"{args.rig}/cmd/top_drive",
                                  qos.get_c_qos_profile())
    resumed = []

    def on_pause(request, response):
        resumed.append(not request.data)
        response.success = True
        return response
    node.create_service(SetBool, f"{args.rig}/pause", on_pause)
    setup = SingleThreadedExecutor()
    setup.add_node(node)
    while not (resumed and resumed[-1]) and not stop:
        setup.spin_once(timeout_sec=0.01)
    setup.remove_node(node)
    sample, _ = command_template()
    context = node.context.handle
    ws = _rclpy.WaitSet(1, 0, 0, 0, 0, 0, context)
    k = 0
    while not stop:
        k += 1
        struct.pack_into("<iI", sample, 4, k // 1000, (k % 1000) * 1_000_000)
        stamp = bytes(sample[4:12])
        send(bytes(sample))
        while not stop:
            taken = sub.take_message(TwistStamped, True)
            if taken is not None:
                if taken[0][4:12] == stamp:
                    break
                continue
            with context:
                ws.clear_entities()
                ws.add_subscription(sub)
                ws.wait(100_000_000)
    setup.shutdown()
    node.destroy_node()
    rclpy.try_shutdown()
    return 0


if __name__ == "__main__":
    sys.exit(main())
