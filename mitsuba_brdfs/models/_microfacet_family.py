"""What the microfacet models share: Lambertian diffuse plus a microfacet specular lobe.

``cook_torrance`` (the lecture's Cook-Torrance, Cook & Torrance 1982) and
``torrance_sparrow`` (Akyuz sec. 8) are both

    f(l, v) = kd / pi + ks D(h) F(v.h) G(l, v) / (4 cos(theta_l) cos(theta_v))

with F Schlick's approximation from the reflectance f0 at normal incidence. They differ in
their parameters, their distribution D and their shadowing G, which they choose at load
time from ``core.microfacet`` (where the distributions, G and the specular term are).
"""
from ..core.frame import cos_theta, half_vector, reflect
from ..core.fresnel import schlick
from ..core.lobes import LambertDiffuseModel, Point
from ..core.microfacet import microfacet_specular, reflection_jacobian
from ..core.numerics import channel_mean

__all__ = ["MicrofacetModel", "MicrofacetPoint"]


class MicrofacetPoint(Point):
    """Values at one shading point: kd, ks (lobe weights), f0, rho and the distribution."""
    __slots__ = ("kd", "ks", "f0", "rho", "dist")


class MicrofacetModel(LambertDiffuseModel):
    """Lambertian diffuse kd / pi plus microfacet specular ks D F G / (4 cos_i cos_o).

    F is Schlick's with reflectance f0 at normal incidence, evaluated at wi.h. Subclasses
    read their parameters and set, in ``_read_parameters``, ``self._geometry`` (a function
    of ``core.microfacet.GEOMETRIES``) and ``self._visible`` (sample GGX's visible
    normals), and build the ``MicrofacetPoint`` in ``_at``. The specular lobe samples h
    from D cos (or the visible normals) and reflects wi; the diffuse lobe is
    cosine-weighted (base class). The lobes are chosen in proportion to mean(ks F(cos_i))
    and mean(kd).
    """

    def _glossy_f(self, p, wi, wo):
        h, cos_ih = half_vector(wi, wo)
        cos_i, cos_o = cos_theta(wi), cos_theta(wo)
        g = self._geometry(p.rho, cos_i, cos_o, cos_theta(h), cos_ih)
        return p.ks * microfacet_specular(p.dist.eval(h), schlick(p.f0, cos_ih), g, cos_i)

    def _glossy_pdf(self, p, wi, wo):
        h, cos_ih = half_vector(wi, wo)
        pdf_h = p.dist.pdf_visible(wi, h, cos_ih) if self._visible else p.dist.pdf(h)
        return pdf_h * reflection_jacobian(cos_ih)

    def _glossy_sample(self, p, wi, u):
        h = p.dist.sample_visible(wi, u) if self._visible else p.dist.sample(u)
        return reflect(wi, h)

    def _glossy_albedo(self, p, wi):
        return channel_mean(p.ks * schlick(p.f0, cos_theta(wi)))

    # -- the diffuse lobe kd / pi: LambertDiffuseModel; the albedo AOV: kd, or the specular
    # colour at normal incidence where kd is black

    def _specular_colour(self, p):
        return p.ks * p.f0
