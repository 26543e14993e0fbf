"""The machine's load around a measurement: the study runs on machines shared with other
work, so a section's numbers come with the 1-minute load average before and after it and
the number of cores (``under_load``)."""
import os

__all__ = ["under_load"]


def under_load(measure):
    """``measure()`` (a dict), with ``load_average`` (before, after) and ``cores``."""
    before = os.getloadavg()[0]
    out = measure()
    out.update(load_average=[before, os.getloadavg()[0]], cores=os.cpu_count())
    return out
