"""The Phong lobe warp and Walter's Ward half-vector warp: densities, chi-square, limits."""
import mitsuba as mi
import numpy as np
import pytest

from mitsuba_brdfs.core import warp
from checks import sph, to_np, unit, vec, warp_chi2


def corner_samples():
    u = np.array([0, 1e-7, 0.25, 0.5, 0.75, 0.999999, 1 - 2**-24, 1.0])
    g1, g2 = np.meshgrid(u, u)
    return mi.Point2f(g1.ravel().astype(np.float32), g2.ravel().astype(np.float32))


def uniform_samples(n, seed=0):
    rng = np.random.default_rng(seed)
    return mi.Point2f(*rng.random((2, n)).astype(np.float32))


# -- independent float64 transcriptions ---------------------------------------------------------

def ref_phong_pdf(w, axis, p):
    """(p + 1) / (2 pi) cos^p(alpha), zero for alpha >= 90 deg."""
    c = np.asarray(w, float) @ np.asarray(axis, float)
    with np.errstate(divide="ignore"):
        return np.where(c > 0, (p + 1) / (2 * np.pi) * np.abs(c) ** p, 0.0)


def ref_ward_pdf(h, au, av):
    """Walter 2005: exp(-tan^2 th (cos^2 ph / au^2 + sin^2 ph / av^2)) / (pi au av cos^3 th)."""
    h = np.asarray(h, float)
    th = np.arccos(np.clip(h[:, 2], -1, 1))
    ph = np.arctan2(h[:, 1], h[:, 0])
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
        e = np.exp(-np.tan(th) ** 2 * (np.cos(ph) ** 2 / au ** 2 + np.sin(ph) ** 2 / av ** 2))
        v = e / (np.pi * au * av * np.cos(th) ** 3)
    return np.where(h[:, 2] > 0, np.nan_to_num(v), 0.0)


# -- Phong lobe ------------------------------------------------------------------------------

AXES = {
    "normal": [0, 0, 1],
    "tilted": unit([0.6, 0.2, 0.77]),
    "near_horizon": sph(np.radians(88), 2.0)[0],
}


@pytest.mark.parametrize("p", [0.0, 1.0, 30.0, 1000.0])
@pytest.mark.parametrize("axis", list(AXES))
def test_phong_lobe_pdf_matches_reference(axis, p):
    rng = np.random.default_rng(2)
    a = AXES[axis]
    w = unit(rng.normal(size=(3000, 3)))
    # points close to the axis (the peak) as well
    w = np.concatenate([w, unit(a + 0.03 * rng.normal(size=(500, 3)))])
    w32 = unit(w.astype(np.float32).astype(float))
    got = to_np(warp.phong_lobe_pdf(vec(w), vec(a), p))
    want = ref_phong_pdf(w32, np.asarray(a, np.float32).astype(float), p)
    np.testing.assert_allclose(got, want, rtol=2e-3, atol=1e-6 * want.max())


PHONG_CHI2 = [(0.0, 32), (1.0, 8), (10.0, 8), (100.0, 16), (1000.0, 64)]


@pytest.mark.parametrize("p,ires", PHONG_CHI2, ids=[f"p={c[0]:g}" for c in PHONG_CHI2])
@pytest.mark.parametrize("axis", list(AXES))
def test_phong_lobe_chi2(axis, p, ires):
    a = mi.Vector3f(*map(float, AXES[axis]))
    ok, messages = warp_chi2(lambda u: warp.square_to_phong_lobe(u, a, p),
                             lambda w: warp.phong_lobe_pdf(w, a, p), ires)
    assert ok, messages


def test_phong_lobe_chi2_detects_wrong_density():
    """The chi-square set-up can fail: cos^(p+1) samples against the cos^p density."""
    a = mi.Vector3f(0, 0, 1)
    ok, _ = warp_chi2(lambda u: warp.square_to_phong_lobe(u, a, 11.0),
                      lambda w: warp.phong_lobe_pdf(w, a, 10.0), ires=8)
    assert not ok


@pytest.mark.parametrize("p", [0.0, 1e-3, 1.0, 1e4, 1e6])
@pytest.mark.parametrize("axis", list(AXES))
def test_phong_lobe_limits(axis, p):
    a = AXES[axis]
    w = warp.square_to_phong_lobe(corner_samples(), vec(a), p)
    wn = to_np(w)
    assert np.isfinite(wn).all()
    np.testing.assert_allclose(np.linalg.norm(wn, axis=1), 1, atol=2e-6)
    assert (wn @ np.asarray(a) >= -1e-6).all()  # on the hemisphere around the axis
    pdf = to_np(warp.phong_lobe_pdf(w, vec(a), p))
    assert np.isfinite(pdf).all() and (pdf >= 0).all()
    # the density at hard points: the axis itself, opposite, orthogonal
    hard = np.stack([a, -np.asarray(a), unit(np.cross(a, [1, 0, 0.1]))])
    ph = to_np(warp.phong_lobe_pdf(vec(hard), vec(np.tile(a, (3, 1))), p))
    assert np.isfinite(ph).all()
    np.testing.assert_allclose(ph[0], (p + 1) / (2 * np.pi), rtol=1e-5)
    assert ph[1] == 0


@pytest.mark.parametrize("p", [1e4, 1e6])
def test_phong_sharp_lobe_keeps_its_width(p):
    """E[1 - cos(alpha)] = 1 / (p + 2): the sharp lobe does not collapse onto the axis."""
    a = AXES["tilted"]
    w = to_np(warp.square_to_phong_lobe(uniform_samples(200_000), vec(a), p)).astype(float)
    omc = 0.5 * np.sum((w - a) ** 2, axis=1)
    np.testing.assert_allclose(omc.mean() * (p + 2), 1, rtol=0.02)
    # and the density agrees with the samples: cos^p at the median sample is 1/2 of the peak
    lobe = to_np(warp.phong_lobe_cos_power(vec(w), vec(np.tile(a, (len(w), 1))), p))
    np.testing.assert_allclose(np.median(lobe), 0.5 ** (p / (p + 1)), rtol=0.02)


# -- Ward half-vector ------------------------------------------------------------------------

ALPHAS = [(0.1, 0.1), (0.05, 0.3), (0.3, 0.05), (0.5, 0.5), (1.0, 1.0), (1e-4, 0.2)]


@pytest.mark.parametrize("au,av", ALPHAS)
def test_ward_pdf_matches_reference(au, av):
    rng = np.random.default_rng(4)
    h = rng.normal(size=(3000, 3))
    h[:, 2] = np.abs(h[:, 2])
    # points near n (where the narrow lobes live)
    near = np.concatenate([rng.normal(scale=[au, av], size=(1000, 2)), np.ones((1000, 1))], axis=1)
    h = unit(np.concatenate([h, near]))
    h32 = unit(h.astype(np.float32).astype(float))
    got = to_np(warp.ward_half_vector_pdf(vec(h), au, av))
    want = ref_ward_pdf(h32, au, av)
    np.testing.assert_allclose(got, want, rtol=2e-3, atol=1e-6 * want.max())


WARD_CHI2 = [(0.1, 0.1, 16), (0.05, 0.3, 32), (0.3, 0.05, 32), (0.5, 0.5, 8), (1.0, 1.0, 8),
             (0.06, 0.06, 64), (0.04, 0.04, 128)]


@pytest.mark.parametrize("au,av,ires", WARD_CHI2, ids=[f"{c[0]:g}-{c[1]:g}" for c in WARD_CHI2])
def test_ward_half_vector_chi2(au, av, ires):
    ok, messages = warp_chi2(lambda u: warp.square_to_ward_half_vector(u, au, av),
                             lambda h: warp.ward_half_vector_pdf(h, au, av), ires)
    assert ok, messages


@pytest.mark.parametrize("au,av", ALPHAS)
def test_ward_pdf_is_mitsubas_anisotropic_beckmann(au, av):
    """Walter's density is D(h) cos(theta_h) of the anisotropic Beckmann distribution."""
    rng = np.random.default_rng(9)
    h = unit(np.concatenate([rng.normal(scale=[au, av], size=(2000, 2)), np.ones((2000, 1))], axis=1))
    md = mi.MicrofacetDistribution(mi.MicrofacetType.Beckmann, au, av, False)
    want = to_np(md.pdf(mi.Vector3f(0, 0, 1), vec(h)))
    got = to_np(warp.ward_half_vector_pdf(vec(h), au, av))
    np.testing.assert_allclose(got, want, rtol=1e-4, atol=1e-6 * want.max())


def test_ward_orientation():
    """alpha_u stretches the lobe along u (x), alpha_v along v (y)."""
    h = to_np(warp.square_to_ward_half_vector(uniform_samples(100_000), 0.05, 0.3))
    assert np.std(h[:, 1]) > 4 * np.std(h[:, 0])
    # u_2 = 1/4 is phi = 90 deg exactly (no tan(pi/2)), u_2 = 0 is phi = 0
    q = to_np(warp.square_to_ward_half_vector(mi.Point2f([0.5, 0.5], [0.25, 0.0]), 0.05, 0.3))
    assert abs(q[0, 0]) < 1e-6 and q[0, 1] > 0
    assert abs(q[1, 1]) < 1e-6 and q[1, 0] > 0


@pytest.mark.parametrize("au,av", [(1e-4, 1e-4), (1e-4, 1.0), (1.0, 1e-4), (1.0, 1.0)])
def test_ward_limits(au, av):
    h = warp.square_to_ward_half_vector(corner_samples(), au, av)
    hn = to_np(h)
    assert np.isfinite(hn).all() and (hn[:, 2] >= 0).all()
    np.testing.assert_allclose(np.linalg.norm(hn, axis=1), 1, atol=2e-6)
    pdf = to_np(warp.ward_half_vector_pdf(h, au, av))
    assert np.isfinite(pdf).all() and (pdf >= 0).all()
    hard = vec(unit([[0, 0, 1], [1, 0, 0], [0, 1, 1e-7], [0.3, 0.3, -0.9], [0, 0, -1]]))
    ph = to_np(warp.ward_half_vector_pdf(hard, au, av))
    assert np.isfinite(ph).all() and (ph[1:] == 0).all()
    np.testing.assert_allclose(ph[0], 1 / (np.pi * au * av), rtol=1e-5)
    # the sampled slopes keep their spread: E[(h_u/au)^2 + (h_v/av)^2) / h_n^2] = 1
    s = to_np(warp.square_to_ward_half_vector(uniform_samples(200_000, 1), au, av)).astype(float)
    t = ((s[:, 0] / au) ** 2 + (s[:, 1] / av) ** 2) / s[:, 2] ** 2
    np.testing.assert_allclose(t.mean(), 1, rtol=0.02)


@pytest.mark.parametrize("axis", list(AXES))
def test_phong_sharp_lobe_values_near_the_axis(axis):
    """cos^p at p = 1e6 within the lobe (~1e-3 rad): float32 keeps the float64 values."""
    p = 1e6
    rng = np.random.default_rng(8)
    a = np.asarray(AXES[axis], float)
    w = unit(a + 1.5e-3 * rng.normal(size=(2000, 3)))
    w32 = w.astype(np.float32).astype(float)
    a32 = a.astype(np.float32).astype(float)
    cos = np.sum(unit(w32) * unit(a32[None]), axis=1)
    want = np.exp(p * np.log(cos))
    got = to_np(warp.phong_lobe_cos_power(vec(w), vec(np.tile(a, (len(w), 1))), p))
    assert want.max() > 0.5 and (want < 0.01).any()  # the samples cover the lobe
    np.testing.assert_allclose(got, want, rtol=2e-3, atol=1e-6)
