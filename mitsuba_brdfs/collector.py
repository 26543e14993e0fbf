"""Python's cycle collector paused around Dr.Jit work that must not see it run.

``paused()`` turns the collector off for the time of a ``with`` block and back on after
(if it was on), whichever thread ends last when several hold it at once, also when the
block raises. Two uses:

- a fit (``measured.fitting.fit``, ``image_fit.fit``; ``collect=True``): the garbage is
  collected first and none while the fit runs, so that its result depends on its inputs
  alone. When the collector runs changes the state in which Dr.Jit computes the loss and
  its gradient, and with it their float32 rounding in the last bits, which an optimiser
  can follow elsewhere: the same fits of measured data of the same files in one process
  ended at other minima in two runs of four before, and the render fit's values moved in
  their 7th digit;
- a step recorded by ``@dr.freeze`` (``bench.optimisation``; ``image_fit`` within the
  fit's pause): a scene the collector frees while Dr.Jit records aborts the process in
  Dr.Jit 1.5 (``RecordThreadState::enqueue_host_func(): this function cannot be
  recorded!``).
"""
import contextlib
import gc
import threading

__all__ = ["paused"]

#: the blocks inside ``paused`` now (in any thread), and whether the collector was on
#: before the first of them
_STATE = {"holders": 0, "was_on": True}
#: re-entrant: a finalizer that the collection runs may enter ``paused`` itself
_LOCK = threading.RLock()


@contextlib.contextmanager
def paused(collect=False):
    """The collector off inside the block. ``collect``: collect the garbage first, where no
    other block holds the collector off (a collection then would come at a moment set by
    the other threads)."""
    with _LOCK:
        if _STATE["holders"] == 0:
            if collect:
                gc.collect()
            _STATE["was_on"] = gc.isenabled()
            gc.disable()
        _STATE["holders"] += 1
    try:
        yield
    finally:
        with _LOCK:
            _STATE["holders"] -= 1
            if _STATE["holders"] == 0 and _STATE["was_on"]:
                gc.enable()
