"""A dependency-free progress bar for long commands (renders, figures, studies).

On a terminal it redraws one line; when stderr is a file or pipe (CI logs) it prints a
line at most every few seconds and at the end, so logs stay short.
"""
import sys
import time

__all__ = ["Progress"]


class Progress:
    """``Progress(total, label)``; call ``advance(n)`` as work is done, ``close()`` at the end."""

    def __init__(self, total, label="", unit="", stream=None, width=28, interval=5.0):
        self.total = max(total, 1)
        self.label = label
        self.unit = unit
        self.stream = stream or sys.stderr
        self.width = width
        self.interval = interval
        self.done = 0
        self.note = ""
        self.start = time.perf_counter()
        self._last = -1e30
        self._tty = hasattr(self.stream, "isatty") and self.stream.isatty()
        self._draw(force=True)

    def advance(self, n=1, note=""):
        self.done = min(self.done + n, self.total)
        self.note = note
        self._draw(note=note)

    def close(self, note=None):
        self._draw(force=True, note=self.note if note is None else note, end=True)

    def _draw(self, force=False, note="", end=False):
        now = time.perf_counter()
        if not (force or self._tty or now - self._last >= self.interval):
            return
        state = (self.done, note)
        if end and not self._tty and state == getattr(self, "_drawn", None):
            return  # the final state is already in the log
        self._last, self._drawn = now, state
        frac = self.done / self.total
        filled = int(round(frac * self.width))
        elapsed = now - self.start
        eta = elapsed / frac - elapsed if 0 < frac < 1 else 0.0
        line = (f"{self.label} [{'#' * filled}{'.' * (self.width - filled)}] {100 * frac:5.1f}% "
                f"{self.done}/{self.total}{self.unit} {elapsed:6.1f}s"
                + (f" eta {eta:5.1f}s" if 0 < frac < 1 else "") + (f" {note}" if note else ""))
        if self._tty:
            self.stream.write("\r" + line + ("\n" if end else "\x1b[K"))
        else:
            self.stream.write(line + "\n")
        self.stream.flush()
