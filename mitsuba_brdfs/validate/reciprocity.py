"""Reciprocity: f(a, b) = f(b, a), the BSDF without the cosine; across an interface, with the
eta^2 factor of radiance transport.

Mitsuba's ``eval(ctx, si, wo)`` with ``si.wi = a``, ``wo = b`` in radiance mode (the
default) is f(b -> a): the radiance scattered towards a (the camera's side) per unit of
irradiance from b, cosine included. Radiance crossing into a denser medium is compressed
into a smaller solid angle, so it grows by (eta_a / eta_b)^2, and the BSDF is not
symmetric; Veach's generalised reciprocity (thesis, 1997, eq. 5.14) says what is:
f(b -> a) / eta_a^2 = f(a -> b) / eta_b^2, that is

    eval(a, b) / |cos b| / eta_a^2 = eval(b, a) / |cos a| / eta_b^2,

with eta_x the refractive index on x's side: 1 above the surface (the exterior), the
relative index eta = int_ior / ext_ior below it, which the BSDF reports as ``bs.eta`` of
its transmitted samples from above. (In importance mode the BSDF is the adjoint:
eval_importance(a, b) / |cos b| = eval(b, a) / |cos a|.) Mitsuba's ``roughdielectric``
satisfies it to float precision.

Delta lobes (``dielectric``, ``thindielectric``) have no eval: for them the energy each
lobe carries is compared. A delta transmission from a to t(a) carries E(a) = T (eta_a /
eta_t(a))^2 in radiance mode, T the Fresnel transmittance, which is the same both ways, so
E(a) (eta_t(a) / eta_a)^2 = E(t(a)) (eta_a / eta_t(a))^2.
"""
import mitsuba as mi
import numpy as np

from .probe import call_sample, close, eval_np, expect, floats, interaction, point2, rows
from .sampling import DIRAC

__all__ = ["eval_both_ways", "reciprocity_error", "check_reciprocal", "interface_eta",
           "transmission_reciprocity", "delta_transmission_reciprocity"]


def eval_both_ways(bsdf, a, b):
    """f(a, b) and f(b, a), the BSDF without the cosine."""
    f_ab = eval_np(bsdf, a, b) / np.abs(b[:, 2:3]).astype(np.float32)
    f_ba = eval_np(bsdf, b, a) / np.abs(a[:, 2:3]).astype(np.float32)
    return f_ab, f_ba


def reciprocity_error(bsdf, a, b, rtol=1e-3, eta_a=1.0, eta_b=1.0):
    """How far f(a, b) / eta_a^2 is from f(b, a) / eta_b^2 (eta 1: plain reciprocity): a
    ``close`` record (to rtol, and to 1e-6 of the largest value) whose ``max_rel`` is the
    largest difference relative to the largest value. eta_a, eta_b: numbers or one per
    pair."""
    f_ab, f_ba = eval_both_ways(bsdf, a, b)
    f_ab = f_ab / np.square(np.reshape(eta_a, (-1, 1)))
    f_ba = f_ba / np.square(np.reshape(eta_b, (-1, 1)))
    scale = float(np.abs(f_ab).max(initial=0.0)) or 1.0
    r = close(f_ab, f_ba, rtol, atol=1e-6 * scale)
    r["max_rel"] = float(np.abs(f_ab - f_ba).max(initial=0.0) / scale)
    return r


def check_reciprocal(bsdf, a, b, rtol=1e-3, err_msg=""):
    """f(a, b) = f(b, a) to rtol, and to 1e-6 of the largest value. Returns the largest
    difference relative to the largest value."""
    r = reciprocity_error(bsdf, a, b, rtol)
    expect(r["ok"], (err_msg, r))
    return r["max_rel"]


def _stratified(bsdf, wi, n, ctx=None):
    """n samples at each direction of wi with sample1 stratified, (k + 0.5) / n, and
    sample2 at the centre: the share of a delta lobe chosen by sample1 to 1 / n."""
    wi = np.repeat(np.reshape(wi, (-1, 3)), n, axis=0)
    u = np.tile((np.arange(n) + 0.5) / n, len(wi) // n)
    bs, w = call_sample(bsdf, ctx or mi.BSDFContext(), interaction(wi), floats(u),
                        point2(np.full(len(u), 0.5), np.full(len(u), 0.5)))
    m = len(u)
    return (rows(w, m, True), rows(bs.wo, m), rows(bs.eta, m),
            rows(bs.sampled_type, m).astype(np.int64))


def interface_eta(bsdf, n=4096):
    """The relative index of refraction below the surface, as the BSDF reports it: the
    median ``bs.eta`` of its transmitted samples of non-zero weight from 40 degrees above
    (None when it transmits nothing there)."""
    wi = [np.sin(0.7), 0.0, np.cos(0.7)]
    w, wo, eta, _ = _stratified(bsdf, wi, 64)
    rng = np.random.default_rng(1)
    wis = np.repeat([wi], n, axis=0)
    bs, weight = call_sample(bsdf, mi.BSDFContext(), interaction(wis), floats(rng.random(n)),
                             point2(rng.random(n), rng.random(n)))
    w = np.concatenate([w, rows(weight, n, True)])
    wo = np.concatenate([wo, rows(bs.wo, n)])
    eta = np.concatenate([eta, rows(bs.eta, n)])
    t = (wo[:, 2] < 0) & (w != 0).any(axis=1)
    return float(np.median(eta[t])) if t.any() else None


def transmission_reciprocity(bsdf, a, b, eta, rtol=1e-3):
    """``reciprocity_error`` of pairs a (above) and b (below the surface), eta the relative
    index below (eta_a = 1, eta_b = eta)."""
    return reciprocity_error(bsdf, a, b, rtol, 1.0, eta)


def delta_transmission_reciprocity(bsdf, wi, eta, n=20000, rtol=2e-3):
    """For each direction a of wi (above the surface): the radiance carried by the delta
    transmission from a to t(a), E(a), and from t(a) back, E(t(a)), from n stratified
    samples each; E(a) (eta_t / eta_a)^2 must equal E(t(a)) (eta_a / eta_t)^2 (both are the
    Fresnel transmittance). Returns a ``close`` record with ``pairs`` (how many directions
    transmit) and ``values`` (the two sides, per direction)."""
    def carried(dirs):
        w, wo, _, typ = _stratified(bsdf, dirs, n)
        t = ((typ & DIRAC) != 0) & (wo[:, 2] * np.repeat(dirs[:, 2], n) < 0)
        e = (w * t[:, None]).reshape(len(dirs), n, -1).mean(axis=1)
        wo_t = np.where(t[:, None], wo, 0).reshape(len(dirs), n, 3).sum(axis=1)
        return e, wo_t

    a = np.reshape(wi, (-1, 3))
    e_a, t_a = carried(a)
    norm = np.linalg.norm(t_a, axis=1, keepdims=True)
    ok = norm[:, 0] > 0
    a, e_a, t_a = a[ok], e_a[ok], t_a[ok] / norm[ok]
    if not len(a):
        return {"ok": True, "max_rel": 0.0, "off": 0, "pairs": 0, "values": []}
    e_t, _ = carried(t_a)
    lhs, rhs = e_a * eta ** 2, e_t / eta ** 2  # eta_a = 1 above, eta_t = eta below
    r = close(lhs, rhs, rtol, atol=2.0 / n)
    r.update(pairs=int(len(a)), values=[[float(x), float(y)] for x, y in
                                        zip(lhs.mean(axis=1), rhs.mean(axis=1))])
    return r
