"""The rig's metrics over a time window, summed a chunk at a time, and the window itself.

Every metric is a sum, a count, a minimum or a maximum over the samples, so ``RigStats`` takes
the samples a chunk at a time and keeps a few numbers: memory does not grow with the bag.
Samples holding NaN or infinite values are left out and counted, and header stamps that go
backwards are counted: both are problems of the bag, reported with the metrics.
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Iterable, Iterator
from dataclasses import dataclass

import numpy as np

from ..core.stick_slip import severity_index, stuck
from .errors import BagError

# the quantities the metrics read (SI, named as in ``series.JOINT_FIELDS``)
QUANTITIES = ("bit_speed_rad_s", "wob_n", "tob_nm", "surface_torque_nm", "rop_m_s")


@dataclass(frozen=True)
class Window:
    """Which samples: ``start_s``..``end_s`` seconds after the first sample, or the last
    ``last_s`` seconds up to the latest stamp; all of them when none is given."""

    start_s: float | None = None
    end_s: float | None = None
    last_s: float | None = None


class Windowed:
    """Chunks of (stamps [ns], values) cut to a ``Window``. ``origin_ns``: the first sample's
    stamp, once met. For ``last_s`` the chunks that may fall in the window are held until the
    end (memory grows with ``last_s``, not with the bag)."""

    def __init__(self, chunks: Iterable[tuple[np.ndarray, np.ndarray]], window: Window) -> None:
        self.chunks, self.window = chunks, window
        self.origin_ns: int | None = None
        self.latest_ns: int | None = None           # the latest stamp met, in or out

    def span(self) -> str:
        """The stamps met, in the window's words (after the first sample), for a window
        that came out empty."""
        if self.origin_ns is None or self.latest_ns is None:
            return "the topic has no samples"
        return (f"its samples span 0 to {(self.latest_ns - self.origin_ns) * 1e-9:.3f} s "
                "after the first")

    def __iter__(self) -> Iterator[tuple[np.ndarray, np.ndarray]]:
        w = self.window
        held: deque[tuple[np.ndarray, np.ndarray]] = deque()
        latest: int | None = None
        for ns, values in self.chunks:
            if not ns.size:
                continue
            if self.origin_ns is None:
                self.origin_ns = int(ns[0])
            top = int(ns.max())
            self.latest_ns = top if self.latest_ns is None else max(self.latest_ns, top)
            if w.last_s is None:
                t = (ns - self.origin_ns) * 1e-9
                keep = np.ones(ns.size, bool)
                if w.start_s is not None:
                    keep &= t >= w.start_s
                if w.end_s is not None:
                    keep &= t <= w.end_s
                yield (ns, values) if keep.all() else (ns[keep], values[keep])
                continue
            latest = top if latest is None else max(latest, top)
            held.append((ns, values))
            span = round(w.last_s * 1e9)
            while held and int(held[0][0].max()) < latest - span:
                held.popleft()
        if w.last_s is not None and latest is not None:
            cutoff = latest - round(w.last_s * 1e9)
            for ns, values in held:
                keep = ns >= cutoff
                yield ns[keep], values[keep]


class RigStats:
    """Metrics (MODEL.md section 7) summed over samples added a chunk at a time: each sample
    weighs the same (a fixed tick)."""

    def __init__(self, topic: str) -> None:
        self.topic = topic
        self.n = self.stuck = self.bounce = self.nonfinite = self.backwards = 0
        self.sums = dict.fromkeys(QUANTITIES, 0.0)
        self.w_min, self.w_max = math.inf, -math.inf
        self.t_min, self.t_max = math.inf, -math.inf
        self.last_t: float | None = None
        self.first_bad_t: float | None = None
        self.first_back_t: float | None = None

    def add(self, time_s: np.ndarray, columns: dict[str, np.ndarray]) -> None:
        """Samples at ``time_s`` (seconds after the first sample), ``columns`` by quantity."""
        if not time_s.size:
            return
        steps = np.diff(time_s, prepend=time_s[0] if self.last_t is None else self.last_t)
        back = steps < 0
        if back.any():
            self.backwards += int(back.sum())
            if self.first_back_t is None:
                self.first_back_t = float(time_s[np.argmax(back)])
        self.last_t = float(time_s[-1])
        cols = [np.asarray(columns[q]) for q in QUANTITIES]
        finite = np.isfinite(time_s) & np.logical_and.reduce([np.isfinite(c) for c in cols])
        if not finite.all():
            self.nonfinite += int((~finite).sum())
            if self.first_bad_t is None:
                self.first_bad_t = float(time_s[np.argmin(finite)])
            time_s, cols = time_s[finite], [c[finite] for c in cols]
            if not time_s.size:
                return
        w, wob = cols[0], cols[1]
        self.n += w.size
        for q, c in zip(QUANTITIES, cols, strict=True):
            self.sums[q] += float(np.sum(c))
        self.w_min, self.w_max = min(self.w_min, float(w.min())), max(self.w_max, float(w.max()))
        self.t_min = min(self.t_min, float(time_s.min()))
        self.t_max = max(self.t_max, float(time_s.max()))
        self.stuck += int(np.count_nonzero(stuck(w, wob)))
        self.bounce += int(np.count_nonzero(wob == 0.0))

    def problems(self) -> list[str]:
        """What the samples themselves got wrong, in words."""
        found = []
        if self.nonfinite:
            found.append(f"{self.topic}: {self.nonfinite} samples hold NaN or infinite values "
                         f"(the first at {self.first_bad_t:.3f} s) and are left out of the "
                         "metrics")
        if self.backwards:
            found.append(f"{self.topic}: the header stamps go backwards {self.backwards} times "
                         f"(the first at {self.first_back_t:.3f} s); duration_s is the span "
                         "from the earliest stamp to the latest")
        return found

    def result(self) -> dict[str, float]:
        """The metrics, SI; BagError if no sample was added."""
        if self.n == 0:
            raise BagError(f"{self.topic}: no samples in the window")
        mean = self.sums["bit_speed_rad_s"] / self.n
        return {
            "duration_s": self.t_max - self.t_min,
            "samples": self.n,
            "ssi": severity_index(self.w_max, self.w_min, mean),
            "stick_fraction": self.stuck / self.n,
            "bounce_fraction": self.bounce / self.n,
            "mean_bit_speed_rad_s": mean,
            "mean_wob_n": self.sums["wob_n"] / self.n,
            "mean_tob_nm": self.sums["tob_nm"] / self.n,
            "mean_surface_torque_nm": self.sums["surface_torque_nm"] / self.n,
            "mean_rop_m_s": self.sums["rop_m_s"] / self.n,
        }
