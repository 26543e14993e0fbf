"""Rendering a scene in passes of bounded memory, and averaging them.

Mitsuba renders all samples of a call at once, so the memory of a call can grow with
width x height x spp (how much depends on the integrator; ``docs/performance.md``
measures it). ``render_image`` splits the samples into passes of bounded size, made one
at a time (a huge spp costs nothing before the first pixel), and averages the film's
images (each pass weighted by the samples the sampler really took: ``stratified`` and
other samplers round a count up).
"""
import collections
import contextlib
import math
import os
import time

import numpy as np

from .arguments import UINT32_MAX
from .progress import advance, progress_bar, stop_requested

__all__ = ["DEFAULT_PASS_SAMPLES", "passes", "pass_sizes", "pass_seed", "Rendered",
           "Interrupted", "render_image", "render_passes", "film_channels", "memory_estimate",
           "memory_limit"]

#: samples (pixels x spp) traced at once; bounds the memory of one pass (~1-2 GiB)
DEFAULT_PASS_SAMPLES = 1 << 22


# -- passes -------------------------------------------------------------------------------

def _sample_counter(sampler):
    """``count(n)``: the samples per pixel ``sampler`` really takes when asked for ``n``
    (``stratified``, ``ldsampler``, ... round up to their grids). Probing is silent and
    leaves the sampler's own count as it was."""
    import mitsuba as mi
    cache = {}

    def count(n):
        if n not in cache:
            old, level = sampler.sample_count(), mi.log_level()
            mi.set_log_level(mi.LogLevel.Error)  # the rounding warning of each probe
            try:
                sampler.set_sample_count(n)
                cache[n] = sampler.sample_count()
                sampler.set_sample_count(old)
            finally:
                mi.set_log_level(level)
        return cache[n]
    return count


def _largest_valid(count, want):
    """The largest count the sampler takes that is <= ``want`` (``count`` rounds up and
    grows with its argument), or its smallest one if all are larger."""
    if count(want) <= want:
        return count(want)
    lo, hi = 1, want  # count(hi) > want
    if count(lo) > want:
        return count(lo)
    # count(lo) <= want < count(hi): bisect
    while hi - lo > 1:
        mid = (lo + hi) // 2
        lo, hi = (mid, hi) if count(mid) <= want else (lo, mid)
    return count(lo)


def passes(spp, pixels, pass_samples=DEFAULT_PASS_SAMPLES, count=None):
    """Yield the spp of each pass, lazily: at most ``pass_samples`` samples a pass (and
    at least 1 spp), at most ``UINT32_MAX`` spp (Mitsuba's limit).

    With ``count=None`` every count is valid and the passes are balanced (they differ by
    at most one spp) and add up to ``spp``. Otherwise ``count(n)`` is the count the
    sampler really takes for ``n`` (``_sample_counter``): each pass is the largest valid
    count that fits, and the passes add up to at least ``spp`` (more only when no valid
    count fits the remainder).
    """
    per = max(1, min(spp, pass_samples // max(pixels, 1), UINT32_MAX))
    if count is None:
        n = math.ceil(spp / per)
        base, extra = divmod(spp, n)
        for i in range(n):
            yield base + (i < extra)
        return
    done = 0
    while done < spp:
        n = _largest_valid(count, min(spp - done, per))
        yield n
        done += n


def pass_sizes(spp, pixels, pass_samples=DEFAULT_PASS_SAMPLES):
    """The list of ``passes`` (for small counts; a huge spp makes a huge list)."""
    return list(passes(spp, pixels, pass_samples))


def pass_seed(seed, index):
    """Seed of pass ``index``: ``seed`` itself for the first pass (a one-pass render is
    ``mi.render(scene, seed=seed)``), then a 32-bit hash of (seed, index), so passes and
    renders with other seeds do not share their samples."""
    if index == 0:
        return seed
    return int(np.random.SeedSequence([seed, index]).generate_state(1)[0])


# -- rendering ----------------------------------------------------------------------------

#: a rendered film: image (float32, H x W x C) and its channel names, spp really taken,
#: passes, seconds of JIT compilation and of rendering (the compilation included)
Rendered = collections.namedtuple("Rendered", "image channels spp passes compile_seconds seconds")


class Interrupted(KeyboardInterrupt):
    """A render stopped by a signal (SIGINT, or what the command line turns into
    ``KeyboardInterrupt``); ``rendered`` is the ``Rendered`` average of the passes
    finished before it (None if none was)."""

    def __init__(self, rendered):
        super().__init__()
        self.rendered = rendered


def _stopped(e):
    """Whether ``e`` is a stop (``KeyboardInterrupt``), or an error Dr.Jit raised from
    one (a signal that arrives while a Python plugin is traced is wrapped)."""
    while e is not None:
        if isinstance(e, KeyboardInterrupt):
            return True
        e = e.__cause__ or e.__context__
    return False


def _film_image(film):
    """The film's developed image as Mitsuba's ``mitsuba`` writes it (``film.bitmap()``):
    float32 (H, W, C) and its channel names."""
    bmp = film.bitmap()
    names = [bmp.struct_()[i].name for i in range(bmp.channel_count())]
    img = np.array(bmp, dtype=np.float32, copy=True)
    return img.reshape(img.shape[0], img.shape[1], -1), names


def render_image(scene, spp=None, pass_samples=DEFAULT_PASS_SAMPLES, seed=0, sensor=0,
                 label="render", progress=True, integrator=None, measure_compile=False):
    """Render ``scene`` with ``spp`` samples per pixel (default: its sampler's) in passes.

    Returns a ``Rendered``. The image is the film's (``film.bitmap()``): every channel
    with its name (AOVs included), in the film's pixel format (RGB, luminance or XYZ, with
    or without alpha). Pass ``i`` uses seed ``pass_seed(seed, i)``. ``measure_compile``
    records Dr.Jit's kernel history to tell JIT compilation apart. A stop (Ctrl-C) raises
    ``Interrupted`` holding the average of the passes done.
    """
    import drjit as dr
    import mitsuba as mi

    sensor_obj = scene.sensors()[sensor]
    count = _sample_counter(sensor_obj.sampler())
    spp = spp or sensor_obj.sampler().sample_count()
    total = count(spp) if spp <= UINT32_MAX else spp
    film = sensor_obj.film()
    w, h = film.crop_size()
    acc, done, compile_ms, n_passes = None, 0, 0.0, 0
    flag = (dr.scoped_set_flag(dr.JitFlag.KernelHistory, True) if measure_compile
            else contextlib.nullcontext())
    t0 = time.perf_counter()
    names = None

    def result():
        if not done:
            return None
        np.divide(acc, done, out=acc)  # in place: no second float64 image
        return Rendered(acc.astype(np.float32), names, done, n_passes, compile_ms / 1e3,
                        time.perf_counter() - t0)

    with progress_bar(total, label, "spp", enabled=progress) as bar, flag:
        if measure_compile:
            dr.kernel_history_clear()
        try:
            for i, n in enumerate(passes(total, w * h, pass_samples, count)):
                mi.render(scene, spp=n, seed=pass_seed(seed, i), sensor=sensor,
                          integrator=integrator)
                img, names = _film_image(film)
                if acc is None:
                    acc = np.zeros(img.shape, np.float64)
                acc += img * np.float32(n)
                done += n
                n_passes = i + 1
                dr.flush_malloc_cache()
                if measure_compile:
                    compile_ms += sum(k.get("codegen_time", 0) + k.get("backend_time", 0)
                                      for k in dr.kernel_history())
                if bar.total is not None and done > bar.total:
                    bar.total = done  # the sampler's rounding of the last pass
                advance(bar, n, f"pass {n_passes}")
                if stop_requested():  # the signal's exception was lost in a native call
                    raise KeyboardInterrupt
        except (KeyboardInterrupt, RuntimeError) as e:
            if not _stopped(e):
                raise
            raise Interrupted(result()) from None
    return result()


def film_channels(scene, sensor=0):
    """(channels of the film's storage, channels of its image): Mitsuba's image block holds
    RGB, a weight, alpha if the film has it, and the integrator's AOVs; the image holds the
    film's colour channels (``base_channels_count``: alpha included) and the AOVs."""
    import mitsuba as mi
    film = scene.sensors()[sensor].film()
    integrator = scene.integrator()
    aovs = len(integrator.aov_names()) if integrator is not None else 0
    alpha = bool(film.flags() & int(mi.FilmFlags.Alpha))
    return 4 + alpha + aovs, film.base_channels_count() + aovs


#: bytes per sample of one pass beside the film, by Dr.Jit's loop mode: symbolic loops (one
#: megakernel: the samples' state lives in registers), wavefront loops (``-W``), wavefront
#: loops and calls (``-WW``). Measured with ``dr.detail.malloc_watermark`` (64^2 to 256^2
#: pixels, 4 spp, one pass; a diffuse sphere, ``path`` integrator): 16, 346 and 386 bytes
#: a sample with the film included (as_sphere.xml, ``direct``: 16, 16, 423); rounded up.
BYTES_PER_SAMPLE = (16, 512, 512)

#: bytes per pixel and image channel: while rendering, the film's image as Mitsuba develops
#: it, its copy, the float64 average of the passes and a temporary (4 + 4 + 8 + 4); while
#: writing, the image and the EXR's copies (4 + 8)
_PER_CHANNEL_RENDER, _PER_CHANNEL_WRITE = 20, 12

#: bytes per pixel of tone mapping for the PNG/JPEG (float64 RGB and its temporaries)
_TONEMAP = 100

#: Python, Mitsuba and Dr.Jit before the film
_BASE = 256 << 20


def memory_estimate(scene, spp=None, pass_samples=DEFAULT_PASS_SAMPLES, sensor=0,
                    wavefront=0):
    """(bytes a render of ``scene`` needs at its peak, samples of one pass, storage
    channels): the film's storage (float32, in Dr.Jit), its images in NumPy while rendering
    or while writing (whichever is larger), the state of one pass's samples
    (``BYTES_PER_SAMPLE[wavefront]``) and the process itself."""
    film = scene.sensors()[sensor].film()
    w, h = film.crop_size()
    pixels = w * h
    block, image = film_channels(scene, sensor)
    spp = spp or scene.sensors()[sensor].sampler().sample_count()
    per_pass = max(1, min(spp, pass_samples // max(pixels, 1))) * pixels
    rendering = pixels * (4 * block + _PER_CHANNEL_RENDER * image)
    writing = pixels * (_PER_CHANNEL_WRITE * image + _TONEMAP)
    total = (_BASE + max(rendering, writing)
             + per_pass * BYTES_PER_SAMPLE[min(wavefront, len(BYTES_PER_SAMPLE) - 1)])
    return total, per_pass, block


def memory_limit(fraction=0.75):
    """``fraction`` of the memory this process may use: the machine's physical memory, or
    its control group's limit (a container's) where that is lower."""
    limit = os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")
    for path in ("/sys/fs/cgroup/memory.max", "/sys/fs/cgroup/memory/memory.limit_in_bytes"):
        try:
            with open(path) as f:
                text = f.read().strip()
        except OSError:
            continue
        if text.isdigit():
            limit = min(limit, int(text))
    return int(limit * fraction)


def render_passes(scene, spp=None, pass_samples=DEFAULT_PASS_SAMPLES, seed=0, sensor=0,
                  label="render", progress=True, integrator=None):
    """``render_image``'s image and seconds: (float32 (H, W, C), seconds)."""
    r = render_image(scene, spp, pass_samples, seed, sensor, label, progress, integrator)
    return r.image, r.seconds
