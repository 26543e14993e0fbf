"""What the microfacet models share: Lambertian diffuse plus a microfacet specular lobe.

``cook_torrance`` (the lecture's Cook-Torrance, Cook & Torrance 1982) and
``torrance_sparrow`` (Akyuz sec. 8) are both

    f(l, v) = kd / pi + ks D(h) F(v.h) G(l, v) / (4 cos(theta_l) cos(theta_v))

with F Schlick's approximation from the reflectance f0 at normal incidence. They differ in
their parameters, their distribution D and their shadowing G, which they choose at load
time from ``core.microfacet`` (where the distributions, G and the specular term are).

Both take ``energy_compensation`` (``core.energy``): ``none`` (the model as written; none
of what follows is traced), ``kulla_conty`` (a multiple-scattering lobe ks f_ms added to
the specular one, part of the glossy component, sampled cosine-weighted, chosen within the
glossy lobe in proportion to its albedo ks F_ms (1 - E_i) against the single-scattering
albedo's estimate ks F(cos_i) E_i) or ``turquin`` (the specular lobe scaled by
1 + f0 (1 - E_v) / E_v, E_v at the viewer: not reciprocal).
"""
import drjit as dr
import mitsuba as mi

from ..core.energy import (COMPENSATIONS, EnergyTable, kulla_conty_f,
                           multiple_scattering_fresnel, turquin_scale)
from ..core.frame import cos_theta, half_vector, reflect
from ..core.fresnel import schlick
from ..core.lobes import LambertDiffuseModel, Point
from ..core.microfacet import microfacet_specular, reflection_jacobian
from ..core.numerics import channel_mean, safe_div
from ..core.texture_ranges import texture_range

__all__ = ["MicrofacetModel", "MicrofacetPoint"]

#: largest float32 below 1: a rescaled sample stays in [0, 1)
_ONE_MINUS_EPS = 1 - 2.0 ** -24


class MicrofacetPoint(Point):
    """Values at one shading point: kd, ks (lobe weights), f0, rho and the distribution;
    with energy compensation, the table lookups made at it (``MicrofacetModel._loss``)."""
    __slots__ = ("kd", "ks", "f0", "rho", "dist", "looked_up")


class MicrofacetModel(LambertDiffuseModel):
    """Lambertian diffuse kd / pi plus microfacet specular ks D F G / (4 cos_i cos_o).

    F is Schlick's with reflectance f0 at normal incidence, evaluated at wi.h. Subclasses
    read their parameters and set, in ``_read_parameters``, ``self._geometry`` (a function
    of ``core.microfacet.GEOMETRIES``) and ``self._visible`` (sample GGX's visible
    normals), call ``_read_compensation`` with their table, and build the
    ``MicrofacetPoint`` in ``_at``. The specular lobe samples h from D cos (or the visible
    normals) and reflects wi; the diffuse lobe is cosine-weighted (base class). The lobes
    are chosen in proportion to mean(ks F(cos_i)) and mean(kd).
    """

    # -- energy compensation (``core.energy``): load-time choice ------------------------------

    def _read_compensation(self, r, table):
        """Read ``energy_compensation``; with one, the lobe's table (``core.energy`` key)."""
        self.energy_compensation = r.enum("energy_compensation", "none", COMPENSATIONS)
        self._energy = None if self.energy_compensation == "none" else EnergyTable(table)
        self.RECIPROCAL = self.energy_compensation != "turquin"

    def _table_roughness(self, p):
        """Where the model's lobe enters its table (the roughness rho by default)."""
        return p.rho

    def _table_texture(self):
        """The parameter the table coordinate comes from, and that coordinate as a function
        of its value (the roughness itself by default)."""
        return self.roughness, lambda v: v

    def _update(self):
        """Per-scene work: with a roughness that is one number, the table's row at it."""
        self._fixed = False
        if self._energy is None:
            return
        tex, coordinate = self._table_texture()
        if tex.is_spatially_varying():
            return
        lo, hi = self._known.get(id(tex)) or texture_range(tex, scalar=True)
        if lo == hi:
            self._energy.fix_roughness(coordinate(lo))
            self._fixed = True

    def _loss(self, p, w, average=True):
        """(1 - E(cos theta_w), 1 - E_avg) of the white lobe at p (without ``average``:
        1 - E alone), looked up once per direction and call (a direction object is the key;
        it is kept alive with it). A roughness that is one number and not differentiated
        reads the table's row at it (``EnergyTable.lookup_row``); a differentiated one goes
        through the whole table, so that its derivative does."""
        cache = getattr(p, "looked_up", None)
        if cache is None:
            tex = self._table_texture()[0]
            params = mi.traverse(tex)
            row = self._fixed and not any(dr.grad_enabled(params[k]) for k in params.keys())
            cache = p.looked_up = {"row": row, "r": None if row else self._table_roughness(p)}
        key = (id(w), average)
        if key not in cache:
            loss = (self._energy.lookup_row(w, average) if cache["row"]
                    else self._energy.lookup(w, cache["r"], average))
            cache[key] = (w, loss)
        return cache[key][1]

    def _multiple_scattering(self, p, wi, wo):
        """Kulla & Conty's lobe ks F_ms f_ms cos(theta_o)."""
        loss_i, loss_avg = self._loss(p, wi)
        loss_o = self._loss(p, wo, average=False)
        return (p.ks * multiple_scattering_fresnel(p.f0, loss_avg)
                * kulla_conty_f(loss_i, loss_o, loss_avg, wo))

    def _albedos(self, p, wi):
        """Estimates of the single- and multiple-scattering albedos at wi (Kulla-Conty)."""
        loss_i, loss_avg = self._loss(p, wi)
        single = channel_mean(p.ks * schlick(p.f0, cos_theta(wi))) * (1 - loss_i)
        multiple = channel_mean(p.ks * multiple_scattering_fresnel(p.f0, loss_avg)) * loss_i
        return single, multiple

    def _multiple_probability(self, p, wi):
        """Probability of sampling the multiple-scattering lobe within the glossy one."""
        single, multiple = self._albedos(p, wi)
        return safe_div(multiple, single + multiple)

    # -- the specular lobe -------------------------------------------------------------------

    def _glossy_f(self, p, wi, wo):
        h, cos_ih = half_vector(wi, wo)
        cos_i, cos_o = cos_theta(wi), cos_theta(wo)
        g = self._geometry(p.rho, cos_i, cos_o, cos_theta(h), cos_ih)
        f = p.ks * microfacet_specular(p.dist.eval(h), schlick(p.f0, cos_ih), g, cos_i)
        if self._energy is None:
            return f
        if self.energy_compensation == "turquin":  # wi is the viewer (see lobes._f)
            return f * turquin_scale(p.f0, self._loss(p, wi)[0])
        return f + self._multiple_scattering(p, wi, wo)

    def _single_pdf(self, p, wi, wo):
        h, cos_ih = half_vector(wi, wo)
        pdf_h = p.dist.pdf_visible(wi, h, cos_ih) if self._visible else p.dist.pdf(h)
        return pdf_h * reflection_jacobian(cos_ih)

    def _single_sample(self, p, wi, u):
        h = p.dist.sample_visible(wi, u) if self._visible else p.dist.sample(u)
        return reflect(wi, h)

    def _glossy_pdf(self, p, wi, wo):
        if self._energy is None or self.energy_compensation != "kulla_conty":
            return self._single_pdf(p, wi, wo)
        q = self._multiple_probability(p, wi)
        return ((1 - q) * self._single_pdf(p, wi, wo)
                + q * mi.warp.square_to_cosine_hemisphere_pdf(wo))

    def _glossy_sample(self, p, wi, u):
        if self._energy is None or self.energy_compensation != "kulla_conty":
            return self._single_sample(p, wi, u)
        # u.x picks the lobe and, rescaled to [0, 1), samples it
        q = self._multiple_probability(p, wi)
        multiple = u.x < q
        x = dr.select(multiple, safe_div(u.x, q), safe_div(u.x - q, 1 - q))
        u = mi.Point2f(dr.minimum(x, _ONE_MINUS_EPS), u.y)
        return dr.select(multiple, mi.warp.square_to_cosine_hemisphere(u),
                         self._single_sample(p, wi, u))

    def _glossy_albedo(self, p, wi):
        if self._energy is None:
            return channel_mean(p.ks * schlick(p.f0, cos_theta(wi)))
        if self.energy_compensation == "turquin":
            loss_i = self._loss(p, wi)[0]
            return channel_mean(p.ks * schlick(p.f0, cos_theta(wi))
                                * ((1 - loss_i) + p.f0 * loss_i))
        single, multiple = self._albedos(p, wi)
        return single + multiple

    # -- the diffuse lobe kd / pi: LambertDiffuseModel; the albedo AOV: kd, or the specular
    # colour at normal incidence where kd is black

    def _specular_colour(self, p):
        return p.ks * p.f0
