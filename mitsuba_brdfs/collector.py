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
import weakref

__all__ = ["paused"]


class _Token:
    """A block inside ``paused``: alive as long as the block's frame."""
    __slots__ = ("__weakref__",)


#: the blocks inside ``paused`` now (in any thread): weak, so that a block that an
#: interrupt (Ctrl-C) stopped on its way out does not hold the collector off for good;
#: whether the collector was on before the first of them, and whether it is off because
#: of them
_HOLDERS = weakref.WeakSet()
_STATE = {"was_on": True, "off_by_us": False}
#: re-entrant: a finalizer that the collection runs may enter ``paused`` itself
_LOCK = threading.RLock()


def _enter(token, collect):
    with _LOCK:
        if not _HOLDERS:
            if collect:
                gc.collect()
            # (off_by_us still set: an interrupt stopped the last block on its way out,
            # before it put the collector back as it was, which was_on still says)
            if not _STATE["off_by_us"]:
                _STATE["was_on"] = gc.isenabled()
            _STATE["off_by_us"] = True
        _HOLDERS.add(token)
        gc.disable()


def _leave(token):
    with _LOCK:
        _HOLDERS.discard(token)
        if not _HOLDERS and _STATE["off_by_us"]:
            if _STATE["was_on"]:
                gc.enable()
            _STATE["off_by_us"] = False


@contextlib.contextmanager
def paused(collect=False):
    """The collector off inside the block. ``collect``: collect the garbage first, where no
    other block holds the collector off (a collection then would come at a moment set by
    the other threads). A block that an interrupt (Ctrl-C) stops on its way in or out
    may leave the collector off until the next block ends."""
    token = _Token()
    try:
        _enter(token, collect)
        yield
    finally:
        _leave(token)
