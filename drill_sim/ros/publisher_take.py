"""A take that says which publisher sent the message, for the rig's exclusive command mode.

rclpy's ``take_message`` hands out a message's sequence numbers and timestamps but not the
publisher's GID that rcl's ``rmw_message_info_t`` carries, so a subscriber cannot tell two
publishers apart. This calls rcl's own ``rcl_take_serialized_message`` on the raw
subscription rclpy made (its ``pointer``), through ctypes, and reads the GID from the message
info; the graph (``get_publishers_info_by_topic``'s ``endpoint_gid``) names the node behind it.
Only the rig's ``command_owner: first`` uses it; the ordinary take stays rclpy's.

The structures below are rcl/rmw Jazzy's (``rmw/types.h``, ``rcutils/allocator.h``); a take
costs about what rclpy's raw take costs (~12 us with Fast DDS).
"""

from __future__ import annotations

import ctypes
from typing import NamedTuple

RMW_GID_STORAGE_SIZE = 16           # rmw/types.h, Jazzy
RCL_RET_OK = 0
RCL_RET_SUBSCRIPTION_TAKE_FAILED = 401   # nothing to take
FIRST_CAPACITY_BYTES = 256          # the buffer grows (rcl reallocates) for bigger messages


class _Allocator(ctypes.Structure):
    _fields_ = [("allocate", ctypes.c_void_p), ("deallocate", ctypes.c_void_p),
                ("reallocate", ctypes.c_void_p), ("zero_allocate", ctypes.c_void_p),
                ("state", ctypes.c_void_p)]


class _Uint8Array(ctypes.Structure):      # rcl_serialized_message_t
    _fields_ = [("buffer", ctypes.POINTER(ctypes.c_uint8)), ("buffer_length", ctypes.c_size_t),
                ("buffer_capacity", ctypes.c_size_t), ("allocator", _Allocator)]


class _Gid(ctypes.Structure):
    _fields_ = [("implementation_identifier", ctypes.c_char_p),
                ("data", ctypes.c_uint8 * RMW_GID_STORAGE_SIZE)]


class _MessageInfo(ctypes.Structure):
    _fields_ = [("source_timestamp", ctypes.c_int64), ("received_timestamp", ctypes.c_int64),
                ("publication_sequence_number", ctypes.c_uint64),
                ("reception_sequence_number", ctypes.c_uint64),
                ("publisher_gid", _Gid), ("from_intra_process", ctypes.c_bool)]


class PublisherTakeUnavailable(RuntimeError):
    """rcl's take could not be bound (another ROS distribution's libraries)."""


class Taken(NamedTuple):
    data: bytes             # the CDR bytes, as rclpy's raw take gives them
    sequence: int           # the publisher's sequence number (0: the middleware numbers none)
    publisher: bytes        # the publisher's GID, as ``endpoint_gid`` in the graph


class PublisherTake:
    """``take(handle)``: the next message of a raw rclpy subscription with its publisher, or
    None. One buffer, grown by rcl as needed, serves every take."""

    def __init__(self) -> None:
        try:
            rcl = ctypes.CDLL("librcl.so")            # already loaded by rclpy: found by name
            rcutils = ctypes.CDLL("librcutils.so")
            take = rcl.rcl_take_serialized_message
            rcutils.rcutils_get_default_allocator.restype = _Allocator
            init = rcutils.rcutils_uint8_array_init
            self._fini = rcutils.rcutils_uint8_array_fini
        except (OSError, AttributeError) as exc:
            raise PublisherTakeUnavailable(f"rcl's take is not reachable ({exc})") from None
        take.argtypes = [ctypes.c_void_p, ctypes.POINTER(_Uint8Array),
                         ctypes.POINTER(_MessageInfo), ctypes.c_void_p]
        take.restype = ctypes.c_int
        init.argtypes = [ctypes.POINTER(_Uint8Array), ctypes.c_size_t,
                         ctypes.POINTER(_Allocator)]
        self._fini.argtypes = [ctypes.POINTER(_Uint8Array)]
        self._allocator = rcutils.rcutils_get_default_allocator()
        self._buffer = _Uint8Array()
        if init(ctypes.byref(self._buffer), FIRST_CAPACITY_BYTES,
                ctypes.byref(self._allocator)) != RCL_RET_OK:
            raise PublisherTakeUnavailable("could not allocate the take's buffer")
        self._info = _MessageInfo()
        self._take = take
        self._args = (ctypes.byref(self._buffer), ctypes.byref(self._info), None)

    def take(self, handle) -> Taken | None:
        """The next message on ``handle`` (an ``_rclpy.Subscription``), None if there is none."""
        ret = self._take(handle.pointer, *self._args)
        if ret == RCL_RET_SUBSCRIPTION_TAKE_FAILED:
            return None
        if ret != RCL_RET_OK:
            raise RuntimeError(f"rcl_take_serialized_message failed with code {ret}")
        info = self._info
        sequence = info.publication_sequence_number
        return Taken(ctypes.string_at(self._buffer.buffer, self._buffer.buffer_length),
                     0 if sequence == 2**64 - 1 else sequence,
                     bytes(info.publisher_gid.data))

    def close(self) -> None:
        if self._buffer.buffer:
            self._fini(ctypes.byref(self._buffer))
            self._buffer = _Uint8Array()


def endpoint_gid(info) -> bytes:
    """A graph entry's GID in the form ``Taken.publisher`` has."""
    return bytes(info.endpoint_gid)[:RMW_GID_STORAGE_SIZE]
