"""The image judge of a fit: the measurement and the fit rendered alike, compared as people
see colours.

A number in BRDF space (the held-out loss) ranks fits by what they get wrong where the
BRDF is large, the highlight's peak; what people see is the whole sphere: the base
colour, the highlight's size and the rim at grazing angles. Bieron & Peers (2020) choose
among fitted candidates by their image error, and Kavoosighafi et al. (2025) find a colour
difference of renders the best judge of a fit. So:

- **The renders.** One sphere under the ``ngan2005`` figure's environment (a sky gradient,
  a bright band at the horizon, a dark ground, four dark meridians: its reflection shows a
  lobe's sharpness) and one round area lamp 35 deg above the horizon, seen from three
  sides (``VIEWS``): from beside the lamp (the highlight near the sphere's centre, light
  and view near the normal), from 90 deg away (the highlight half way to the rim), and
  from opposite it (the lamp behind the sphere: the rim lit at grazing angles, where
  Fresnel and the lobes' shapes differ most). ``RES`` x ``RES`` pixels each, ``SPP``
  samples per pixel, Mitsuba's ``direct`` integrator (the lamp and the environment, by
  light and BSDF sampling), the same seed for every BSDF.
- **The measurement** renders as itself: an RGL file through Mitsuba's ``measured`` (a
  spectral one through its linear sRGB twin, as ``data`` reads it), a MERL file through
  its RGL conversion (``to-rgl``, which Mitsuba renders), a ``--target`` BSDF directly
  (``reference``).
- **The difference**: Delta E ITP (ITU-R BT.2124; colour-science's ``delta_E(...,
  method="ITP")``) of each pixel on the sphere (its edge left out), the images' linear
  sRGB taken into ITU-R BT.2020 and to absolute luminance with 1 = ``WHITE`` cd/m^2
  (BT.2408's reference white), then ICtCp with the PQ curve. ITP rather than CIEDE2000:
  it is made for high dynamic range (a highlight is many times the white, where CIELAB's
  lightness has no meaning) and for colours outside sRGB (the RGL films'), and it is the
  judge Kavoosighafi et al. find closest to people's. Delta E ITP 1 is about a just
  noticeable difference. Both images are first blurred by a Gaussian of ``BLUR`` pixels,
  so that Monte Carlo noise (which two BSDFs' importance sampling make differently) does
  not count as a colour difference: at the defaults the noise of two renders of the same
  BSDF with different seeds reads about 1.6 (mean) and 4 (95th percentile). A fit's
  mean moves by 0.1-0.2 with the seed, the difference between two fits (rendered with the
  same seed) by 0.05 or less: the ranking holds, though below 1 two fits look alike.
- The result: ``{"metric": "delta_e_itp", "mean", "p95"}`` (the mean and 95th percentile
  over the pixels), and the seconds.

References: A. Ngan, F. Durand, W. Matusik, "Experimental Analysis of BRDF Models", EGSR
2005 (the figure's lighting); J. Bieron, P. Peers, "An Adaptive BRDF Fitting Metric",
EGSR 2020; B. Kavoosighafi et al., "A Survey on Measured BRDF Models and Fitting
Metrics", CGF 2025; ITU-R BT.2124 (Delta E ITP), BT.2100 (ICtCp), BT.2408 (reference
white).
"""
import math
import os
import tempfile
import time

import numpy as np

__all__ = ["METRIC", "RES", "SPP", "BLUR", "WHITE", "VIEWS", "LAMP", "Judge", "reference",
           "delta_e_itp", "figure"]

METRIC = "delta_e_itp"
#: pixels per side of each view, samples per pixel, the blur (pixels) before comparing
RES, SPP, BLUR = 64, 128, 1.0
#: the luminance (cd/m^2) of a linear sRGB white 1
WHITE = 203.0
#: the views: (label, azimuth of the camera from the lamp's, degrees)
VIEWS = (("lamp behind the camera", 15.0), ("lamp to the side", 90.0),
         ("lamp behind the sphere", 165.0))
#: the lamp: elevation (degrees), distance, radius, radiance (the ngan2005 figure's
#: irradiance: radius 0.5 and radiance 60 at about the same distance)
LAMP = {"elevation": 35.0, "distance": 8.0, "radius": 1.0, "radiance": 15.0}
#: the cameras: distance and elevation (degrees), the ngan2005 figure's
_CAMERA = (6.12, 11.3)


def _point(azimuth, elevation, distance):
    a, e = math.radians(azimuth), math.radians(elevation)
    return [distance * math.sin(a) * math.cos(e), distance * math.sin(e),
            distance * math.cos(a) * math.cos(e)]


def _scene(bsdf, res, spp):
    """The judge's scene holding ``bsdf`` (a dict or a loaded BSDF), a sensor per view."""
    import mitsuba as mi
    from ..figures.ngan2005 import environment
    T = mi.ScalarTransform4f()
    scene = {"type": "scene", "integrator": {"type": "direct"},
             "ball": {"type": "sphere", "bsdf": bsdf},
             "lamp": {"type": "sphere", "radius": LAMP["radius"],
                      "center": _point(0, LAMP["elevation"], LAMP["distance"]),
                      "emitter": {"type": "area", "radiance": {"type": "rgb",
                                                               "value": LAMP["radiance"]}}},
             "env": {"type": "envmap", "bitmap": mi.Bitmap(environment()),
                     "to_world": T.rotate([0, 1, 0], 30)}}
    for i, (_, azimuth) in enumerate(VIEWS):
        scene[f"view{i}"] = {
            "type": "perspective", "fov": 24,
            "to_world": T.look_at(origin=_point(azimuth, _CAMERA[1], _CAMERA[0]),
                                  target=[0, 0, 0], up=[0, 1, 0]),
            "film": {"type": "hdrfilm", "width": res, "height": res,
                     "rfilter": {"type": "box"}},
            "sampler": {"type": "independent", "sample_count": spp}}
    return mi.load_dict(scene)


def _masks(scene, res, blur, k=4):
    """Per view, the pixels wholly on the sphere, ``blur`` pixels (rounded up, and one
    more) away from its edge: k x k rays per pixel, each intersected with the unit sphere."""
    import mitsuba as mi
    out = []
    t = (np.arange(res * k) + 0.5) / (res * k)
    x, y = np.meshgrid(t, t)
    for sensor in scene.sensors():
        rays, _ = sensor.sample_ray(0.0, 0.5, mi.Point2f(x.ravel(), y.ravel()),
                                    mi.Point2f(0.5, 0.5))
        o = np.array(rays.o, dtype=np.float64).reshape(3, -1).T
        d = np.array(rays.d, dtype=np.float64).reshape(3, -1).T
        b = np.sum(o * d, 1)
        hit = b * b - (np.sum(o * o, 1) - 1) > 0
        cover = hit.reshape(res, k, res, k).all(axis=(1, 3))
        from scipy.ndimage import binary_erosion
        out.append(binary_erosion(cover, iterations=int(math.ceil(blur)) + 1))
    return np.stack(out)


def _itp(rgb):
    """ICtCp of linear sRGB pixels (..., 3), 1 = ``WHITE`` cd/m^2."""
    import colour
    wide = colour.RGB_to_RGB(np.nan_to_num(np.asarray(rgb, float)), "sRGB", "ITU-R BT.2020")
    return colour.RGB_to_ICtCp(np.maximum(wide, 0) * WHITE)


def delta_e_itp(a, b):
    """Delta E ITP of linear sRGB pixels (..., 3) a against b."""
    import colour
    return colour.delta_E(_itp(a), _itp(b), method="ITP")


class Judge:
    """Renders BSDFs under the judge's lighting (``render``) and says how far each looks
    from the reference's render (``error``)."""

    def __init__(self, reference_bsdf, res=RES, spp=SPP, blur=BLUR, seed=0):
        self.res, self.spp, self.blur, self.seed = res, spp, blur, seed
        t0 = time.perf_counter()
        scene = _scene(reference_bsdf, res, spp)
        self.mask = _masks(scene, res, blur)
        self.reference = self._render(scene)
        self._reference = self._blurred(self.reference)
        self.seconds_reference = time.perf_counter() - t0

    def _render(self, scene):
        import mitsuba as mi
        return np.stack([np.array(mi.render(scene, sensor=i, seed=self.seed))[..., :3]
                         for i in range(len(VIEWS))])

    def _blurred(self, img):
        from scipy.ndimage import gaussian_filter
        return gaussian_filter(np.nan_to_num(img), (0, self.blur, self.blur, 0))

    def render(self, bsdf):
        """The views of ``bsdf`` (views, res, res, 3), linear sRGB."""
        return self._render(_scene(bsdf, self.res, self.spp))

    def error(self, bsdf):
        """(``{"metric", "mean", "p95", "seconds"}``, the views) of ``bsdf`` against the
        reference."""
        t0 = time.perf_counter()
        img = self.render(bsdf)
        d = delta_e_itp(self._blurred(img)[self.mask], self._reference[self.mask])
        return ({"metric": METRIC, "mean": float(np.mean(d)),
                 "p95": float(np.percentile(d, 95)),
                 "seconds": time.perf_counter() - t0}, img)


def reference(path=None, bsdf=None, resolution=None):
    """The BSDF a measurement renders as (RGB variant): ``bsdf`` itself, or the file at
    ``path`` through Mitsuba's ``measured``: an RGL file (a spectral one in linear sRGB,
    as ``data`` reads it), a MERL file converted as ``to-rgl`` converts it (at its default
    resolution, or ``resolution``: an ``acquire.Resolution``). Returns (the BSDF, a note
    on how it renders)."""
    import mitsuba as mi
    from . import reader
    if bsdf is not None:
        return bsdf, "the target BSDF itself"
    with tempfile.TemporaryDirectory() as tmp:
        if reader.kind(path) == "rgl":
            from . import rgl
            from .data import rgb_file
            material = rgl.load(path)
            out = mi.load_dict({"type": "measured",
                                "filename": os.path.abspath(rgb_file(material, tmp))})
            how = "Mitsuba's measured" + (" (its linear sRGB twin)" if material.spectral
                                          else "")
            return out, how
        from . import acquire, merl, tensor
        rgl_path = os.path.join(tmp, "merl.bsdf")
        evaluate, _, _ = merl.evaluator(os.fspath(path))
        tensor.write(rgl_path, acquire.acquire(evaluate, resolution or acquire.Resolution())[0])
        return (mi.load_dict({"type": "measured", "filename": rgl_path}),
                "its RGL file (to-rgl) through Mitsuba's measured")


def _tonemap(img):
    """sRGB 8-bit of linear RGB (clipped, NaN as 0)."""
    x = np.clip(np.nan_to_num(img), 0, 1)
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * x ** (1 / 2.4) - 0.055)


def figure(path, rows, title):
    """A PNG of the judge's renders: ``rows`` [(label, views)] (the measurement first),
    each row the three views side by side. Written whole (``output.save_figure``)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from ..output import save_figure
    fig, axes = plt.subplots(len(rows), len(VIEWS), squeeze=False,
                             figsize=(1.6 * len(VIEWS) + 2.6, 1.6 * len(rows) + 0.5))
    for r, (label, views) in enumerate(rows):
        for c, view in enumerate(views):
            ax = axes[r, c]
            ax.imshow(_tonemap(view), interpolation="nearest")
            ax.set_xticks([])
            ax.set_yticks([])
            if r == 0:
                ax.set_title(VIEWS[c][0], fontsize=7)
        axes[r, -1].yaxis.set_label_position("right")
        axes[r, -1].set_ylabel(label, rotation=0, ha="left", va="center", fontsize=7)
    fig.suptitle(title, fontsize=8)
    fig.tight_layout()
    try:
        save_figure(fig, path, dpi=110)
    finally:
        plt.close(fig)
