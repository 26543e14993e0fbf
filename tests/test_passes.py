"""Rendering in passes (``mitsuba_brdfs.passes``) and the progress bars (``progress``)."""
import itertools
import math
import os
import re

import mitsuba as mi
import numpy as np
import pytest

from cmdline import scene_xml
from mitsuba_brdfs import passes as P
from mitsuba_brdfs import progress
from mitsuba_brdfs.variant import load_scene
from mitsuba_brdfs.paths import SCENES

SCENE = os.path.join(SCENES, "as_sphere.xml")

# -- passes -------------------------------------------------------------------------------

@pytest.mark.parametrize("spp, pixels, budget", [(64, 256 * 256, 1 << 22), (100, 10_000, 35_000),
                                                 (7, 1_000_000, 10), (1, 16, 1 << 22)])
def test_pass_sizes_cover_spp_within_budget(spp, pixels, budget):
    sizes = P.pass_sizes(spp, pixels, budget)
    assert sum(sizes) == spp
    assert min(sizes) >= 1 and max(sizes) - min(sizes) <= 1
    assert max(sizes) * pixels <= max(budget, pixels)  # one spp per pass at least


def test_passes_are_made_one_at_a_time():
    """1e11 spp in passes of 1 spp: the first passes come at once, no list is built."""
    for count in (None, lambda n: n):
        gen = P.passes(10 ** 11, 256 * 256, 256 * 256, count)
        assert list(itertools.islice(gen, 3)) == [1, 1, 1]
    # a pass never exceeds Mitsuba's 32-bit sample count
    sizes = list(P.passes(10 ** 11, 1, 10 ** 12))
    assert max(sizes) <= 2 ** 32 - 1 and sum(sizes) == 10 ** 11 and len(sizes) == 24


def _square(n):  # what stratified does with a sample count
    return math.ceil(math.sqrt(n)) ** 2


@pytest.mark.parametrize("spp, per, count, want", [
    (16, 5, _square, [4, 4, 4, 4]),      # the largest square that fits each pass
    (100, 7, _square, None),
    (25, 5, lambda n: max(4, _square(n)), [4] * 7),  # no count fits the last 1: rounded up
])
def test_passes_of_a_rounding_sampler(spp, per, count, want):
    sizes = list(P.passes(spp, 64, 64 * per, count))
    assert all(count(n) == n for n in sizes)  # each pass a count the sampler takes as it is
    assert all(n <= per for n in sizes) or want is not None
    if want is None:
        assert sum(sizes) == spp
    else:
        assert sizes == want


def test_stratified_counts_the_samples_it_takes(tmp_path, monkeypatch):
    """stratified rounds 10 spp up to 16 (as mi.render would); in passes of at most 5 spp,
    it takes 4 passes of 4, and the image is weighted by those."""
    scene = mi.load_file(scene_xml(tmp_path / "s.xml", sampler="stratified", spp=4))
    calls, real = [], mi.render

    def counting(*a, **kw):
        calls.append(kw["spp"])
        return real(*a, **kw)

    monkeypatch.setattr(mi, "render", counting)
    r = P.render_image(scene, 10, pass_samples=64 * 5, progress=False)
    assert calls == [4, 4, 4, 4] and r.spp == 16 and r.passes == 4
    calls.clear()
    r = P.render_image(scene, 10, progress=False)
    assert calls == [16] and r.spp == 16 and r.passes == 1
    assert scene.sensors()[0].sampler().sample_count() == 16  # as Mitsuba leaves it


def test_passes_average_to_one_render(monkeypatch):
    scene = load_scene(SCENE, {"res": 24})
    calls = []
    real = mi.render

    def counting(*a, **kw):
        calls.append(kw["spp"])
        return real(*a, **kw)

    monkeypatch.setattr(mi, "render", counting)
    img_passes, _ = P.render_passes(scene, 64, pass_samples=24 * 24 * 8, progress=False)
    assert calls == [8] * 8
    calls.clear()
    img_one, _ = P.render_passes(scene, 64, pass_samples=1 << 22, progress=False)
    assert calls == [64]
    assert img_passes.shape == img_one.shape == (24, 24, 3)
    assert np.isfinite(img_passes).all() and img_passes.mean() > 0.01
    # different noise, same expectation
    assert abs(img_passes.mean() - img_one.mean()) < 0.03 * img_one.mean()
    assert not np.allclose(img_passes, img_one)


def test_pass_seeds():
    assert P.pass_seed(7, 0) == 7  # one pass: mi.render(scene, seed=7)
    seeds = [P.pass_seed(7, i) for i in range(1, 2000)]
    assert len(set(seeds)) == len(seeds) and all(0 <= s < 2 ** 32 for s in seeds)
    # renders with neighbouring seeds share no pass
    assert not set(seeds) & {P.pass_seed(8, i) for i in range(2000)}
    assert P.pass_seed(2 ** 32 - 1, 5) < 2 ** 32


# -- progress -----------------------------------------------------------------------------

def test_progress_shows_time_as_hms(capsys):
    bar = progress.progress_bar(10 ** 11, "x", "spp")
    bar.update(10 ** 6)
    bar.start_t -= 3600  # an hour spent on 1e6 of 1e11 samples
    text = str(bar)
    bar.close()
    assert "1:00:00 spent" in text
    eta = re.search(r"ETA (\d+):(\d\d):(\d\d)", text)
    hours = int(eta.group(1)) + int(eta.group(2)) / 60
    assert abs(hours - (10 ** 11 - 10 ** 6) / 10 ** 6) < 0.02 * hours
    assert progress.hms(59.6) == "0:01:00" and progress.hms(3 * 3600 + 62) == "3:01:02"
