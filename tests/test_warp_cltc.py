"""The clipped linearly transformed cosine warp (EON's sampler): density against a float64
transcription, chi-square, every sample above the surface, corner samples."""
import mitsuba as mi
import numpy as np
import pytest

from mitsuba_brdfs.core import warp
from checks import random_upper, sph, to_np, vec, warp_chi2

#: (a, b, c, d) of the matrix M = [[a, 0, b], [0, c, 0], [d, 0, 1]]: the identity (the
#: cosine), EON-like lobes and stretched, tilted ones of both signs of d
MATRICES = {
    "identity": (1.0, 0.0, 1.0, 0.0),
    "eon_grazing": (1.06, 0.82, 1.15, -0.51),
    "eon_normal": (1.02, -0.01, 0.98, 0.0),
    "stretched": (1.3, -0.4, 0.8, -1.5),
    "tilted_forward": (0.7, 0.3, 1.2, 1.2),
}
WI = sph(np.radians(60), 0.7)[0]


def ref_clipped_ltc_pdf(w, wi, a, b, c, d):
    """float64: D(w) = D_o(M^-1 w / |M^-1 w|) / (|M| |M^-1 w|^3), D_o the cosine lobe
    restricted to the wh that M maps above the surface, renormalised by its area pi s."""
    w = np.asarray(w, float)
    x = np.array([wi[0], wi[1], 0.0])
    x = x / np.linalg.norm(x) if np.linalg.norm(x) > 0 else np.array([1.0, 0, 0])
    y = np.array([-x[1], x[0], 0.0])
    local = np.stack([w @ x, w @ y, w[:, 2]], axis=1)
    m = np.array([[a, 0, b], [0, c, 0], [d, 0, 1]], float)
    h = local @ np.linalg.inv(m).T
    norm = np.linalg.norm(h, axis=1)
    hz = h[:, 2] / norm
    s = 0.5 * (1 + 1 / np.sqrt(1 + d * d))
    return np.where((hz > 0) & (w[:, 2] > 0), hz / (np.pi * s) / (np.linalg.det(m) * norm ** 3), 0.0)


@pytest.mark.parametrize("name", list(MATRICES))
def test_pdf_matches_reference(name):
    w = random_upper(np.random.default_rng(3), 5000)
    w[:500, 2] *= -1  # below the surface: 0
    got = to_np(warp.clipped_ltc_pdf(vec(w), vec(WI), *MATRICES[name]))
    want = ref_clipped_ltc_pdf(w.astype(np.float32).astype(float), WI, *MATRICES[name])
    np.testing.assert_allclose(got, want, rtol=2e-4, atol=1e-6)


@pytest.mark.parametrize("name", list(MATRICES))
def test_chi2(name):
    m = MATRICES[name]
    wi = vec(WI)
    ok, messages = warp_chi2(lambda u: warp.square_to_clipped_ltc(u, wi, *m),
                             lambda w: warp.clipped_ltc_pdf(w, wi, *m), ires=8, res=101)
    assert ok, messages


def test_chi2_detects_a_wrong_matrix():
    wi = vec(WI)
    ok, _ = warp_chi2(lambda u: warp.square_to_clipped_ltc(u, wi, 1.3, -0.4, 0.8, -1.5),
                      lambda w: warp.clipped_ltc_pdf(w, wi, 1.3, -0.4, 0.8, -1.2), ires=8, res=101)
    assert not ok


@pytest.mark.parametrize("name", list(MATRICES))
@pytest.mark.parametrize("wi", [[0, 0, 1], WI.tolist(), [0.999999, 0, 1e-6]])
def test_samples_above_surface_and_finite(name, wi):
    """Every sample (corners included) is a finite unit vector on or above the surface with
    a finite pdf; the clipping leaves none below."""
    u = np.array([0, 1e-7, 0.25, 0.5, 0.75, 1 - 2**-24, 1.0], np.float32)
    g1, g2 = np.meshgrid(u, u)
    rng = np.random.default_rng(1).random((2, 20000)).astype(np.float32)
    for u1, u2 in ((g1.ravel(), g2.ravel()), rng):
        w = warp.square_to_clipped_ltc(mi.Point2f(u1, u2), vec(wi), *MATRICES[name])
        wn = to_np(w)
        assert np.isfinite(wn).all()
        np.testing.assert_allclose(np.linalg.norm(wn, axis=1), 1, atol=2e-6)
        assert (wn[:, 2] >= -1e-6).all()
        pdf = to_np(warp.clipped_ltc_pdf(w, vec(wi), *MATRICES[name]))
        assert np.isfinite(pdf).all() and (pdf >= 0).all()
