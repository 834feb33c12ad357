"""Lines rewritten in place on stderr (status, progress bar), shown only on a terminal.

Top level, with nothing but the standard library, so that the ROS programs and the command
line both draw their status lines without importing each other."""

from __future__ import annotations

import sys
import time


class StatusLine:
    """A line rewritten in place on a terminal (silent elsewhere), at most every
    ``interval_s``: ``due()`` says whether to compose one, ``show`` draws it."""

    def __init__(self, interval_s: float, stream=None) -> None:
        self.stream = sys.stderr if stream is None else stream
        self.enabled = bool(getattr(self.stream, "isatty", lambda: False)())
        self.interval_s = interval_s
        self.next = 0.0
        self.drawn = False

    def due(self) -> bool:
        if not self.enabled or time.monotonic() < self.next:
            return False
        self.next = time.monotonic() + self.interval_s
        return True

    def show(self, text: str) -> None:
        self.stream.write("\r" + text)
        self.stream.flush()
        self.drawn = True

    def close(self) -> None:
        if self.drawn:
            self.stream.write("\n")
            self.stream.flush()


class Progress:
    """Call with a fraction in [0, 1]; draws after ``delay_s`` so short runs stay quiet."""

    def __init__(self, label: str, *, delay_s: float = 1.0, stream=None) -> None:
        self.label = label
        self.line = StatusLine(0.1, stream)
        self.start = time.monotonic()
        self.delay_s = delay_s

    def __call__(self, fraction: float) -> None:
        elapsed = time.monotonic() - self.start
        if fraction < 1.0 and (elapsed < self.delay_s or not self.line.due()):
            return
        if not self.line.enabled:
            return
        width = 30
        filled = int(width * min(max(fraction, 0.0), 1.0))
        eta = elapsed * (1.0 - fraction) / fraction if fraction > 0 else 0.0
        self.line.show(f"{self.label} [{'#' * filled}{'.' * (width - filled)}] "
                       f"{100 * fraction:5.1f}%  {elapsed:5.1f} s elapsed, {eta:5.1f} s left")

    def close(self) -> None:
        self.line.close()
