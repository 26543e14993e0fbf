"""Plugins that exist only for the performance study (``python -m mitsuba_brdfs bench``).

They are registered under ``bench_*`` names in the active variant by ``register()`` and are
not part of ``mitsuba_brdfs.plugin_models()``:

- ``bench_cosine``: any BSDF (nested as ``bsdf``) sampled by cosine-weighted directions
  instead of its own sampler, with its own ``eval``. The baseline that prices a model's
  importance sampling, for models that have no ``sampling = cosine`` option.
- ``bench_as_naive``: ``ashikhmin_shirley`` with the paper's formulas written literally
  in float32, as the stable forms of ``core.warp`` replace them: eq. 4's exponent
  (nu h_u^2 + nv h_v^2) / (1 - (h.n)^2) and h_n to that power, eq. 6 likewise, eq. 9
  with tan/atan and eq. 10 as cos = (1 - xi)^(1 / (E + 1)), sin = sqrt(1 - cos^2).

The naive formulas live here and nowhere else: they are what the study compares the
package's forms against.
"""
import drjit as dr
import mitsuba as mi

from ..core.frame import cos_theta, half_vector, reflect
from ..core.fresnel import schlick
from ..core.numerics import safe_div
from ..models.ashikhmin_shirley import AshikhminShirley

__all__ = ["naive_aniso_phong_cos_power", "naive_aniso_phong_half_vector", "naive_phong_lobe_cos_power",
           "naive_sample_cos_sin", "register"]

_BOUND = {}


# -- naive forms ---------------------------------------------------------------------------

def naive_aniso_phong_cos_power(h, nu, nv):
    """AS eq. 4 as printed: (n.h)^((nu h_u^2 + nv h_v^2) / (1 - (n.h)^2))."""
    e = (nu * h.x * h.x + nv * h.y * h.y) / (1 - h.z * h.z)
    return dr.power(dr.maximum(h.z, 0), e)


def naive_phong_lobe_cos_power(w, axis, p):
    """max(w.axis, 0)^p with the dot product (cos rounds to 1 near the axis)."""
    return dr.power(dr.maximum(dr.dot(w, axis), 0), p)


def naive_sample_cos_sin(u2, e):
    """AS eq. 10 as printed: cos = (1 - xi)^(1 / (E + 1)), sin = sqrt(1 - cos^2)."""
    cos_t = dr.power(1 - u2, 1 / (e + 1))
    return cos_t, dr.safe_sqrt(1 - cos_t * cos_t)


def naive_aniso_phong_half_vector(u, nu, nv):
    """AS eq. 9-10 literally: phi = atan(sqrt((nu+1)/(nv+1)) tan(pi xi / 2)) per quadrant."""
    x1 = 4 * u.x
    q = dr.minimum(dr.floor(x1), 3)
    t = x1 - q
    odd = (q == 1) | (q == 3)
    t = dr.select(odd, 1 - t, t)
    phi = dr.atan(dr.sqrt((nu + 1) / (nv + 1)) * dr.tan(dr.pi * 0.5 * t))
    sin_phi, cos_phi = dr.sincos(phi)
    e = nu * cos_phi * cos_phi + nv * sin_phi * sin_phi
    cos_t, sin_t = naive_sample_cos_sin(u.y, e)
    sx = dr.select((q == 1) | (q == 2), -1.0, 1.0)
    sy = dr.select(q >= 2, -1.0, 1.0)
    return mi.Vector3f(sx * sin_t * cos_phi, sy * sin_t * sin_phi, cos_t)


def _naive_half_vector_pdf(h, nu, nv):
    """AS eq. 6 as printed."""
    p = dr.sqrt((nu + 1) * (nv + 1)) * dr.inv_two_pi * naive_aniso_phong_cos_power(h, nu, nv)
    return dr.select(h.z > 0, p, 0)


class NaiveAshikhminShirley(AshikhminShirley):
    """``ashikhmin_shirley`` with eq. 4, 6, 9 and 10 evaluated as printed (see module)."""

    def _glossy_f(self, p, wi, wo):
        """The specular lobe with eq. 4 as printed."""
        h, _ = half_vector(wi, wo)
        k_h = dr.dot(wi, h)
        cos_i, cos_o = cos_theta(wi), cos_theta(wo)
        lobe = dr.sqrt((p.nu + 1) * (p.nv + 1)) / (8 * dr.pi) \
            * naive_aniso_phong_cos_power(h, p.nu, p.nv)
        return schlick(p.rs, k_h) * safe_div(lobe * cos_o, k_h * dr.maximum(cos_i, cos_o))

    def _glossy_pdf(self, p, wi, wo):
        """Its pdf with eq. 6 as printed."""
        h, _ = half_vector(wi, wo)
        return safe_div(_naive_half_vector_pdf(h, p.nu, p.nv), 4 * dr.dot(wi, h))

    def _glossy_sample(self, p, wi, u):
        """A half vector from eq. 9-10 as printed, reflected."""
        return reflect(wi, naive_aniso_phong_half_vector(u, p.nu, p.nv))


# -- cosine-weighted sampling of any BSDF --------------------------------------------------------

class CosineSampled:
    """Cosine-weighted sampling around any BSDF's ``eval`` (parameter ``bsdf``: nested BSDF)."""

    def __init__(self, props):
        """Wrap the nested ``bsdf``, with its components."""
        mi.BSDF.__init__(self, props)
        self.inner = props.get("bsdf")
        if self.inner is None:
            raise ValueError("bench_cosine: a nested 'bsdf' is required")
        n = self.inner.component_count()
        self.m_components = [self.inner.flags(i) for i in range(n)]
        self.m_flags = self.inner.flags()

    def _ok(self, si, wo, active):
        """Both directions above the surface."""
        return mi.Bool(active) & (cos_theta(si.wi) > 0) & (cos_theta(wo) > 0)

    def sample(self, ctx, si, sample1, sample2, active=True):
        """A cosine-weighted direction, weighted by the nested BSDF."""
        wo = mi.warp.square_to_cosine_hemisphere(sample2)
        pdf = mi.warp.square_to_cosine_hemisphere_pdf(wo)
        ok = self._ok(si, wo, active) & (pdf > 0)
        f = self.inner.eval(ctx, si, wo, ok)
        bs = dr.zeros(mi.BSDFSample3f, dr.width(wo))
        bs.wo = wo
        bs.pdf = dr.select(ok, pdf, 0)
        bs.eta = 1.0
        bs.sampled_type = mi.UInt32(+self.m_components[0])
        bs.sampled_component = mi.UInt32(0)
        return bs, dr.select(ok, f / dr.select(ok, pdf, 1), 0)

    def eval(self, ctx, si, wo, active=True):
        """The nested BSDF's eval."""
        return self.inner.eval(ctx, si, wo, active)

    def pdf(self, ctx, si, wo, active=True):
        """The cosine-weighted density."""
        ok = self._ok(si, wo, active)
        return dr.select(ok, mi.warp.square_to_cosine_hemisphere_pdf(wo), 0)

    def eval_pdf(self, ctx, si, wo, active=True):
        """eval and pdf."""
        return self.eval(ctx, si, wo, active), self.pdf(ctx, si, wo, active)

    def traverse(self, callback):
        """Nothing to expose."""
        pass

    def to_string(self):
        """The wrapper and its nested BSDF."""
        return "CosineSampled[\n  bsdf = " + str(self.inner).replace("\n", "\n  ") + "\n]"


def _bind(model):
    """A ``mi.BSDF`` subclass for the active variant from a plain class and its bases."""
    key = (mi.variant(), model.__name__)
    if key not in _BOUND:
        ns = {}
        for klass in reversed(model.__mro__[:-1]):
            ns.update({k: v for k, v in vars(klass).items() if k not in ("__dict__", "__weakref__")})
        _BOUND[key] = type(model.__name__, (mi.BSDF,), ns)
    return _BOUND[key]


def register():
    """Register ``bench_cosine`` and ``bench_as_naive`` in the active variant."""
    for name, model in (("bench_cosine", CosineSampled), ("bench_as_naive", NaiveAshikhminShirley)):
        cls = _bind(model)
        mi.register_bsdf(name, lambda props, cls=cls: cls(props))
    return ["bench_cosine", "bench_as_naive"]
