"""First-order discrete filters for the control laws: bilinear (Tustin) sections, prewarped.

Prewarping puts each section's -3 dB corner exactly at the requested frequency whatever the
sample period, so one set of documented corners behaves the same in a 10 ms and a 1 ms loop.
The filtered derivative is the corner times a high-pass section, i.e. s·ωc/(s + ωc): its gain
above the corner is bounded by ωc instead of growing like 2/h as a raw difference does, which
is what keeps sensor noise on the speed from dominating an inertia-torque estimate at 1 kHz.
"""

from __future__ import annotations

import math

from ..core.parameters import ParameterError, check_number


def check_corner(name: str, corner_hz: object, h_s: float) -> float:
    """A corner frequency [Hz] must be positive and below the Nyquist frequency 1/(2h)."""
    value = check_number(name, corner_hz)
    nyquist_hz = 0.5 / h_s
    if value >= nyquist_hz:
        raise ParameterError(f"{name} = {value!r} is out of range: expected a finite number > 0 "
                             f"and < the Nyquist frequency {nyquist_hz:g} Hz (h_s = {h_s:g} s)")
    return value


class FirstOrderSection:
    """y = H(z) x for H(s) = ωc/(s + ωc) (``lowpass``) or s/(s + ωc) (``highpass``).

    Difference equation y_k = b0 x_k + b1 x_{k-1} - a1 y_{k-1}; no allocation per step.
    """

    __slots__ = ("a1", "b0", "b1", "corner_hz", "highpass", "x1", "y1")

    def __init__(self, corner_hz: float, h_s: float, *, highpass: bool = False,
                 name: str = "corner_hz") -> None:
        h_s = check_number("h_s", h_s)
        self.corner_hz = check_corner(name, corner_hz, h_s)
        self.highpass = highpass
        wc = 2.0 * math.pi * self.corner_hz
        k = wc / math.tan(0.5 * wc * h_s)        # prewarped bilinear constant (2/h at low wc h)
        den = k + wc
        self.a1 = (wc - k) / den
        if highpass:
            self.b0, self.b1 = k / den, -k / den
        else:
            self.b0 = self.b1 = wc / den
        self.x1 = 0.0
        self.y1 = 0.0

    def settle(self, x: float) -> None:
        """Set the state to the steady response to a constant input ``x`` (no transient)."""
        self.x1 = x
        self.y1 = 0.0 if self.highpass else x

    def step(self, x: float) -> float:
        y = self.b0 * x + self.b1 * self.x1 - self.a1 * self.y1
        self.x1 = x
        self.y1 = y
        return y


class FilteredDerivative:
    """dx/dt seen through a first-order low-pass at ``corner_hz``: s·ωc/(s + ωc).

    Discretely ωc times the prewarped high-pass, which equals the low-pass section (same
    corner) applied to the prewarped bilinear derivative (SoftSpeed's inertia compensation).
    Not for an estimate that must cancel a torque applied over the sample: the bilinear
    derivative is half a sample off that (``z_torque`` takes a backward difference).
    """

    __slots__ = ("_hpf", "_wc")

    def __init__(self, corner_hz: float, h_s: float, *, name: str = "corner_hz") -> None:
        self._hpf = FirstOrderSection(corner_hz, h_s, highpass=True, name=name)
        self._wc = 2.0 * math.pi * self._hpf.corner_hz

    @property
    def corner_hz(self) -> float:
        return self._hpf.corner_hz

    @property
    def section(self) -> FirstOrderSection:
        """The high-pass section the derivative is ωc times."""
        return self._hpf

    def settle(self, x: float) -> None:
        """Steady state at a constant ``x``: derivative zero."""
        self._hpf.settle(x)

    def step(self, x: float) -> float:
        return self._wc * self._hpf.step(x)


class HeldLag:
    """A first-order lag of time constant ``tau_s`` for an input held between samples, exact:
    y_k = x_{k-1} + (y_{k-1} - x_{k-1}) exp(-h/τ) -- the filter the rig's sensor model
    applies (``core.sensors``), so a law can pass one signal through another's filter.
    τ = 0: the identity."""

    __slots__ = ("decay", "tau_s", "x1", "y1")

    def __init__(self, tau_s: float, h_s: float, *, name: str = "tau_s") -> None:
        self.tau_s = check_number(name, tau_s, low_inclusive=True, high=10.0)
        self.decay = math.exp(-h_s / self.tau_s) if self.tau_s > 0.0 else 0.0
        self.x1 = self.y1 = 0.0

    def settle(self, x: float) -> None:
        self.x1 = self.y1 = x

    def step(self, x: float) -> float:
        if self.tau_s == 0.0:
            return x
        y = self.x1 + (self.y1 - self.x1) * self.decay
        self.x1, self.y1 = x, y
        return y


class SampleWindow:
    """The last ``n`` samples of a signal, in a fixed ring: their mean and the change over them.

    A signal that updates every n law samples (a 100 Hz drive signal read at 1 kHz) is a
    staircase: its mean over n samples is its linear interpolation, and its change over n
    samples (what ``push`` returns, subtracted from the newest) divided by n h is the slope of
    that interpolation, so a torque and a speed that both come as such staircases stay aligned
    in time as a window's mean and the other window's slope."""

    __slots__ = ("i", "n", "ring", "total")

    def __init__(self, n: int) -> None:
        self.n = n
        self.ring = [0.0] * n
        self.i = 0
        self.total = 0.0

    def settle(self, x: float) -> None:
        self.ring[:] = [x] * self.n
        self.i = 0
        self.total = x * self.n

    def push(self, x: float) -> float:
        """Add ``x``; return the value it replaces (the one n samples ago)."""
        old = self.ring[self.i]
        self.ring[self.i] = x
        self.i += 1
        if self.i == self.n:               # once a round: the sum afresh (no drift)
            self.i = 0
            self.total = math.fsum(self.ring)
        else:
            self.total += x - old
        return old

    def mean(self) -> float:
        return self.total / self.n
