"""A one-line progress bar on stderr, shown only on a terminal and only for long work."""

from __future__ import annotations

import sys
import time


class Progress:
    """Call with a fraction in [0, 1]; draws after ``delay_s`` so short runs stay quiet."""

    def __init__(self, label: str, *, delay_s: float = 1.0, stream=None) -> None:
        self.label = label
        self.stream = sys.stderr if stream is None else stream
        self.enabled = bool(getattr(self.stream, "isatty", lambda: False)())
        self.start = time.monotonic()
        self.delay_s = delay_s
        self.drawn = False

    def __call__(self, fraction: float) -> None:
        if not self.enabled:
            return
        elapsed = time.monotonic() - self.start
        if elapsed < self.delay_s and fraction < 1.0:
            return
        width = 30
        filled = int(width * min(max(fraction, 0.0), 1.0))
        eta = elapsed * (1.0 - fraction) / fraction if fraction > 0 else 0.0
        self.stream.write(f"\r{self.label} [{'#' * filled}{'.' * (width - filled)}] "
                          f"{100 * fraction:5.1f}%  {elapsed:5.1f} s elapsed, {eta:5.1f} s left")
        self.stream.flush()
        self.drawn = True

    def close(self) -> None:
        if self.drawn:
            self.stream.write("\n")
            self.stream.flush()
