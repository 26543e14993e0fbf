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
import time

import numpy as np

from .arguments import UINT32_MAX
from .progress import advance, progress_bar

__all__ = ["DEFAULT_PASS_SAMPLES", "passes", "pass_sizes", "pass_seed", "Rendered",
           "render_image", "render_passes"]

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
    records Dr.Jit's kernel history to tell JIT compilation apart.
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
    with progress_bar(total, label, "spp", enabled=progress) as bar, flag:
        if measure_compile:
            dr.kernel_history_clear()
        for i, n in enumerate(passes(total, w * h, pass_samples, count)):
            mi.render(scene, spp=n, seed=pass_seed(seed, i), sensor=sensor, integrator=integrator)
            img, names = _film_image(film)
            acc = img.astype(np.float64) * n if acc is None else acc + img * n
            done += n
            n_passes = i + 1
            dr.flush_malloc_cache()
            if measure_compile:
                compile_ms += sum(k.get("codegen_time", 0) + k.get("backend_time", 0)
                                  for k in dr.kernel_history())
            if bar.total is not None and done > bar.total:
                bar.total = done  # the sampler's rounding of the last pass
            advance(bar, n, f"pass {n_passes}")
    seconds = time.perf_counter() - t0
    return Rendered((acc / done).astype(np.float32), names, done, n_passes, compile_ms / 1e3,
                    seconds)


def render_passes(scene, spp=None, pass_samples=DEFAULT_PASS_SAMPLES, seed=0, sensor=0,
                  label="render", progress=True, integrator=None):
    """``render_image``'s image and seconds: (float32 (H, W, C), seconds)."""
    r = render_image(scene, spp, pass_samples, seed, sensor, label, progress, integrator)
    return r.image, r.seconds
