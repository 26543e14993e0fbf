"""Checking a figure scene's integrator: is ``direct`` (or a shallow ``path``) enough?

``check_integrator`` renders a scene with its own integrator and with a deeper path tracer
and reports how far apart they are: the numbers quoted in the scenes' comments
(``python -m mitsuba_brdfs figures --check``).
"""
import os

import numpy as np

from .. import output, passes, variant
from ..paths import SCENES
from ..scene_xml import defaults, scene_integrator

__all__ = ["check_integrator"]


def _block_means(img, k=8):
    h, w, c = img.shape
    return img[:h // k * k, :w // k * k].reshape(h // k, k, w // k, k, c).mean(axis=(1, 3))


def _scene_size_defines(path, res):
    """The size overrides a scene accepts: ``res`` or ``width`` / ``height`` (aspect kept)."""
    values = defaults(path)
    if "res" in values:
        return {"res": res}
    w, h = float(values["width"]), float(values["height"])
    return {"width": max(1, round(res * w / h)), "height": res}


def check_integrator(scene, defines=None, res=128, spp=1024, reference_depth=16):
    """Compare a scene's integrator with a deeper path tracer; returns report lines.

    ``res`` is the image height (a wide scene keeps its aspect).

    ``direct``: direct renders with seeds 0 and 1 against ``path`` (``reference_depth``)
    with seed 2; the difference is compared with the noise (the two direct seeds), per
    pixel and on 8x8-pixel block means (which average the noise down). Then ``path`` with
    ``max_depth = 2`` (direct light only) against ``reference_depth`` with the same seed:
    the first bounces then take the same random numbers, so the difference is exactly what
    the deeper bounces add. ``path`` with ``max_depth = d``: that same-seed comparison for
    ``d - 1`` and ``d``, and the noise (the scene's integrator with seeds 0 and 1). "8-bit"
    differences are between the tone-mapped sRGB images of the block means, in levels of
    255.
    """
    import mitsuba as mi
    path = os.path.join(SCENES, scene) if not os.path.isabs(scene) else scene
    defines = dict(defines or {})
    props = scene_integrator(path, defines)
    loaded = variant.load_scene(path, {**defines, **_scene_size_defines(path, res)})

    def render(seed, **change):
        integrator = mi.load_dict({**props, **change})
        return passes.render_passes(loaded, spp, seed=seed, progress=False,
                               integrator=integrator)[0].astype(np.float64)

    def mad(a, b):
        return float(np.abs(a - b).mean())

    def levels(a, b):
        return float(np.abs(output.tonemap(_block_means(a)).astype(float)
                            - output.tonemap(_block_means(b)).astype(float)).max())

    name = os.path.basename(path) + "".join(f" {k}={v}" for k, v in defines.items())
    lines = [f"{name}: {res} px high, {spp} spp, integrator {props}"]
    ref = dict(type="path", max_depth=reference_depth)
    if props["type"] == "direct":
        d0, d1, p = render(0), render(1), render(2, **ref)
        lines.append(
            f"  direct vs path max_depth={reference_depth} (independent seeds): pixel MAD "
            f"{mad(d0, p):.5f} vs noise {mad(d0, d1):.5f}; 8x8 blocks "
            f"{mad(_block_means(d0), _block_means(p)):.5f} vs noise "
            f"{mad(_block_means(d0), _block_means(d1)):.5f}; means {d0.mean():.4f} vs {p.mean():.4f}")
        depths = [2]
    else:
        s0, s1 = render(0), render(1)
        lines.append(f"  noise ({props['type']} max_depth={props['max_depth']}, seeds 0 and 1): "
                     f"pixel MAD {mad(s0, s1):.5f}")
        depths = [props["max_depth"] - 1, props["max_depth"]]
    full = render(0, **ref)
    for d in depths:
        img = render(0, type="path", max_depth=d)
        lines.append(
            f"  path max_depth={d} vs {reference_depth} (same seed): deeper bounces add "
            f"{(full.mean() - img.mean()) / full.mean():.2%} of the mean, pixel MAD "
            f"{mad(img, full):.5f}, 8-bit 8x8-block max {levels(img, full):.0f}")
    return lines
