"""The CPU latency request (no ROS): what it writes where, and how it refuses."""

from __future__ import annotations

import struct

from drill_sim.ros.wakeups import CpuLatencyRequest, cpu_latency_now_us


def test_the_request_writes_the_latency_as_the_kernel_reads_it(tmp_path):
    """The kernel takes a native 32-bit integer of microseconds (any other write is read as
    hexadecimal text: "25" would be 37 us); the request stays open until closed."""
    device = tmp_path / "cpu_dma_latency"
    device.write_bytes(b"")
    request = CpuLatencyRequest(25, str(device))
    assert request.held and request.refused is None
    assert struct.unpack("=i", device.read_bytes()) == (25,)
    assert cpu_latency_now_us(str(device)) == 25
    request.close()
    request.close()                                  # idempotent
    assert not request.held


def test_a_system_without_the_device_refuses_with_a_reason(tmp_path):
    request = CpuLatencyRequest(0, str(tmp_path / "none"))
    assert not request.held and "no " in request.refused and "CPU latency QoS" in request.refused
    assert cpu_latency_now_us(str(tmp_path / "none")) is None


def test_a_device_that_refuses_the_write_is_named_with_the_latency(tmp_path):
    request = CpuLatencyRequest(3, str(tmp_path))            # a directory: no such device
    assert not request.held and request.refused.startswith(f"{tmp_path} refused 3 us: ")
