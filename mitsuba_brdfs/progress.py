"""Progress bars of the long commands: tqdm on stderr, with the time spent and the time left
as h:mm:ss."""
import functools
import sys

__all__ = ["progress_bar", "advance", "hms", "request_stop", "stop_requested"]

#: stop signals received (the command line's handler adds them): loops that run for long
#: look here between steps, so that a stop is honoured even when the exception the handler
#: raised was swallowed where it landed (inside a native call or a callback)
_STOP_REQUESTS = []


def request_stop(signum=None):
    """Record a stop request (``signum``: the signal); ``None`` clears them all."""
    if signum is None:
        _STOP_REQUESTS.clear()
    else:
        _STOP_REQUESTS.append(signum)


def stop_requested():
    """Whether a stop was requested since the command started."""
    return bool(_STOP_REQUESTS)


def hms(seconds):
    """Seconds as h:mm:ss."""
    s = int(round(seconds))
    return f"{s // 3600}:{s // 60 % 60:02d}:{s % 60:02d}"


@functools.lru_cache(maxsize=None)
def _bar_class():
    from tqdm import tqdm

    class Bar(tqdm):
        """tqdm with the elapsed time and the time left (ETA) as h:mm:ss."""

        @property
        def format_dict(self):
            d = super().format_dict
            elapsed, done = d["elapsed"], d["n"] - d.get("initial", 0)
            rate = d["rate"] or (done / elapsed if elapsed and done else None)
            left = (d["total"] - d["n"]) / rate if rate and d["total"] else None
            d["elapsed_hms"] = hms(elapsed)
            d["eta"] = hms(left) if left is not None else "?"
            return d
    return Bar


def progress_bar(total, label, unit="it", enabled=True):
    """A tqdm progress bar on stderr, with the time spent and the time left as h:mm:ss.
    Where stderr is not a terminal (a CI log) it is redrawn at most every 5 seconds, so
    logs stay short."""
    bar_format = ("{desc}: {percentage:3.0f}%|{bar}| {n_fmt}/{total_fmt} {unit} "
                  "[{elapsed_hms} spent, ETA {eta}{postfix}]")
    return _bar_class()(total=total, desc=label, unit=unit, file=sys.stderr,
                        disable=not enabled, bar_format=bar_format,
                        unit_scale=bool(total and total >= 100_000),
                        mininterval=0.1 if sys.stderr.isatty() else 5.0, dynamic_ncols=True)


def advance(bar, n=1, note=""):
    """Count ``n`` more steps done on ``bar`` (a ``progress_bar``, or None) and show ``note``
    beside it."""
    if bar is not None:
        bar.set_postfix_str(note, refresh=False)
        bar.update(n)
