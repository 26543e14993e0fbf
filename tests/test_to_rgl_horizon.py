"""``to-rgl`` near the horizon: a lobe that is not microfacet-shaped (Ashikhmin-Shirley's,
whose eval over the VNDF's density peaks as 1 / (h . k) at grazing incidence) keeps its
albedo to 88 deg, and measured's own sample weights stay below 1."""
import math

import mitsuba as mi
import numpy as np

from checks import sph
from mitsuba_brdfs.measured import acquire, convert, footprint, roundtrip, sources
from mitsuba_brdfs.validate.energy import albedo_at

QUICK = acquire.Resolution(ndf=64, theta_i=16, vndf=64, grid=64)
SPEC = {"type": "ashikhmin_shirley", "nu": 100.0, "nv": 100.0}


def _write(path):
    source = sources.Source(sources.bsdf_evaluator(mi.load_dict(SPEC)), "as", "bsdf", "as", [])
    return convert.convert(source, str(path), QUICK, compare=True)


def test_albedo_to_the_horizon(tmp_path, monkeypatch):
    """Within 5 % at 80 and 85 deg, 10 % at 88; measured's mean sample weight at 88 and
    89 deg is the source's albedo within 10 %, under 1. Written as before (every node the
    source's eval at its direction, the incidences of the sigma rule alone) the file
    reflects several times more light there."""
    s = _write(tmp_path / "as.bsdf")
    assert 0 < s["nodes_averaged"] < 0.1 * s["nodes"]
    cos = np.cos(np.radians(s["theta_i_deg"]))
    assert (cos[:-1] / cos[1:] <= acquire.GRAZING_RATIO * 1.001).all()   # grazing incidences
    for theta, a in s["compare"]["albedo"].items():
        assert a["error"] < roundtrip.bound(theta), (theta, a)
    written = mi.load_dict({"type": "measured", "filename": str(tmp_path / "as.bsdf")})
    source = mi.load_dict(SPEC)
    for theta in (88, 89):
        wi = sph(math.radians(theta), 0.3)[0]
        mc, err = albedo_at(written, wi, n=100_000)
        ref = roundtrip.quadrature_albedo(sources.bsdf_evaluator(source), theta)
        np.testing.assert_allclose(mc, ref, rtol=0.1)
        assert (mc < 1).all()
    monkeypatch.setattr(footprint, "REFINE_TOL", math.inf)
    monkeypatch.setattr(acquire, "_incidences", acquire._sigma_rule)
    before = _write(tmp_path / "before.bsdf")
    assert before["nodes_averaged"] == 0
    assert before["compare"]["albedo"]["88"]["error"] > 2


def test_footprint_average_keeps_the_integral():
    """A peak at a corner of a 9 x 9 grid (a lobe the nodes do not resolve): the
    trapezoidal rule of the averaged values is the peak's integral, where the point
    values give 5 times too much."""
    n, k = 9, footprint.REFINE
    h = lambda x, y: np.exp(-(x * x + y * y) / 0.03 ** 2)        # integral pi 9e-4 / 4
    g = np.linspace(0, 1, n)
    vn = h(*np.meshgrid(g, g))[..., None]
    cells = np.argwhere(np.ones((n - 1, n - 1), bool))
    t = (np.arange(k) + 0.5) / k
    sx, sy = (a.ravel() for a in np.meshgrid(t, t))
    points = (cells[:, None, ::-1] + np.stack([sx, sy], -1)[None]) / (n - 1)
    f = h(points[..., 0], points[..., 1])
    hats = footprint.hats(np.stack([sx, sy], -1)) / len(sx)
    iv, ir = np.einsum("kq,mk->mq", hats, f)[..., None], np.tile(hats.sum(0), (len(cells), 1))
    out, count = footprint.footprint_average(vn, cells, iv, ir)
    w = np.full(n, 1 / (n - 1))
    w[[0, -1]] /= 2
    exact = math.pi * 9e-4 / 4
    assert count == n * n
    assert w @ vn[..., 0] @ w / exact > 5
    assert abs(w @ out[..., 0] @ w / exact - 1) < 0.02
