"""What the Phong and Blinn-Phong models share: parameters, the three forms, the diffuse term.

Both models (Akyuz, "BRDF Summary", sec. 2-7) are a diffuse term plus a cosine-power
specular lobe cos^p(angle), written in three forms. With l the light direction
(Mitsuba's ``wo`` in radiance transport) and v the viewer (``si.wi``):

    original     f = kd / pi + ks cos^p / cos(theta_l)        (Akyuz eq. 2, 7)
    modified     f = kd / pi + ks cos^p                       (Akyuz eq. 3, 8)
    normalized   f = kd / pi + ks N(p) cos^p                  (Akyuz eq. 5, 9)

``eval`` returns f cos(theta_l): ``ks cos^p`` for the original form (the classic shading
formula kd cos(theta_l) + ks cos^p, with the diffuse term as below), ``ks cos^p
cos(theta_l)`` for the modified one. The models supply the angle (Phong: between the mirror
direction of l and v; Blinn-Phong: between n and the half vector) and N(p), the factor that
makes the specular albedo exactly ks at normal incidence, where it is largest (Phong:
(p + 2) / (2 pi), eq. 5; Blinn-Phong: the exact value that eq. 9 approximates).

The diffuse term is kd / pi in every form: Akyuz writes kd without 1/pi in eq. 2, 3, 7 and 8,
the scan-line convention in which kd is the colour seen under a unit light at normal
incidence (the lecture writes its Lambert term the same way and the package restores 1/pi
there). With 1/pi, ``diffuse_reflectance`` is the diffuse albedo in all three forms, so
switching the form changes the highlight and not the body colour; the non-conservation of
the original and modified forms is then entirely their specular term's, as Akyuz says
("impossible to normalize the Phong BRDF in its original form").

The original form is not reciprocal (1 / cos(theta_l) singles out the light): the model
sets ``RECIPROCAL = False`` and the two-lobe base swaps the roles of wi and wo under
``TransportMode.Importance``. The modified and normalized forms are reciprocal.

The form is chosen at load time: a factor function and an albedo estimate are selected in
the constructor, so the traced kernel holds the chosen form only.
"""

from ..core.frame import cos_theta
from ..core.lobes import LambertDiffuseModel, Point
from ..core.numerics import channel_mean
from ..core.roughness import read_roughness, roughness_relations
from ..core.warp import MAX_EXPONENT

__all__ = ["FORMS", "PhongFamily", "generic_facts"]

FORMS = ("original", "modified", "normalized")


# -- the forms: factor multiplying ks cos^p in f cos(theta_l) ------------------------------------

def _factor_original(norm, p, cos_l):
    return 1.0  # ks cos^p / cos(theta_l), times cos(theta_l)


def _factor_modified(norm, p, cos_l):
    return cos_l


def _factor_normalized(norm, p, cos_l):
    return norm(p) * cos_l


# -- the forms: estimate of the specular albedo per unit ks (lobe selection only) ----------------
# ``integrals(p)`` = (integral of cos^p, integral of cos^p cos(theta_l)) over the hemisphere
# at normal incidence. Away from it the cos(theta_l) weighting moves with the mirror
# direction: its mean over the lobe is about ((p + 1) cos(theta_v) + 1) / (p + 2), which is
# right at normal incidence and for sharp lobes and stays > 0 at grazing incidence (where
# wide lobes keep part of their albedo).

def _cos_mean(p, cos_v):
    return ((p + 1) * cos_v + 1) / (p + 2)


def _albedo_original(norm, integrals, p, cos_v):
    return integrals(p)[0]


def _albedo_modified(norm, integrals, p, cos_v):
    return integrals(p)[1] * _cos_mean(p, cos_v)


def _albedo_normalized(norm, integrals, p, cos_v):
    return norm(p) * integrals(p)[1] * _cos_mean(p, cos_v)


_FACTORS = {"original": _factor_original, "modified": _factor_modified,
            "normalized": _factor_normalized}
_ALBEDOS = {"original": _albedo_original, "modified": _albedo_modified,
            "normalized": _albedo_normalized}


class _At(Point):
    """Parameter values at one shading point: kd, ks and the exponent p."""
    __slots__ = ("kd", "ks", "exponent")


class PhongFamily(LambertDiffuseModel):
    """Base of ``phong`` and ``blinn_phong`` (see the module docstring).

    A subclass defines ``_cos_power(exponent, wi, wo)`` (the lobe cos^p of its angle),
    ``_normalization(p)`` (N(p) of the normalized form), ``_lobe_integrals(p)`` (see
    ``_albedo_*``), ``_exponent_from_alpha(alpha)`` (the exponent of the Beckmann-equivalent
    lobe, see ``core.roughness``) and the glossy sampler ``_glossy_sample`` /
    ``_glossy_pdf``; it may read
    options of its own in ``_read_model_options(r)`` (and show them in ``_options``).
    """

    OPTIONS = {"form": FORMS}
    RELATIONS = roughness_relations(("exponent",), anisotropic=False)

    def _read_parameters(self, r):
        self.kd = r.reflectance("diffuse_reflectance", 0.5)
        self.ks = r.reflectance("specular_reflectance", 0.2)
        # the exponent, or a Beckmann roughness that sets it (a load-time choice)
        alpha = read_roughness(r)
        self.alpha = None if alpha is None else alpha[0]
        if self.alpha is None:
            self.exponent = r.scalar("exponent", 30.0, hi=MAX_EXPONENT, what="a Phong exponent")
        self.form = r.enum("form", "normalized", self.OPTIONS["form"])
        # load-time choice: the kernel traces only this form's factor and albedo estimate
        self._factor = _FACTORS[self.form]
        self._albedo = _ALBEDOS[self.form]
        self.RECIPROCAL = self.form != "original"
        self._read_model_options(r)

    def _read_model_options(self, r):
        """Options of one model of the family (none by default)."""

    def _textures(self):
        shape = {"exponent": self.exponent} if self.alpha is None else {"alpha": self.alpha}
        return {"diffuse_reflectance": self.kd, "specular_reflectance": self.ks, **shape}

    def _options(self):
        return {"form": self.form}

    def _lobes_present(self):
        return not self._is_constant(self.ks, 0.0), not self._is_constant(self.kd, 0.0)

    def _at(self, si, active):
        if self.alpha is None:
            exponent = self.exponent.eval_1(si, active)
        else:
            exponent = self._exponent_from_alpha(self.alpha.eval_1(si, active))
        return _At(kd=self.kd.eval(si, active), ks=self.ks.eval(si, active), exponent=exponent)

    # -- specular lobe ---------------------------------------------------------------------

    def _glossy_f(self, p, wi, wo):
        scale = self._factor(self._normalization, p.exponent, cos_theta(wo))
        return p.ks * (scale * self._cos_power(p.exponent, wi, wo))

    def _glossy_albedo(self, p, wi):
        return channel_mean(p.ks) * self._albedo(self._normalization, self._lobe_integrals,
                                                 p.exponent, cos_theta(wi))

    # the diffuse lobe kd / pi in every form, and the albedo AOV (kd, or ks where kd is
    # black): LambertDiffuseModel


def generic_facts():
    """The generic tests' settings of a Phong-family model (``core.facts``: ``cases``,
    ``not_reciprocal``, ``chi2``, ``stability``, ``renders``): each setting in two of the three
    forms, each chi-square case in one (the forms share the sampler and the pdf)."""
    from ..core.facts import rgb
    settings = [(0.5, 0.2, 30.0), (rgb(0.7, 0.1, 0.3), rgb(0.2, 0.4, 0.1), 1.0),
                (0.0, rgb(0.9, 0.6, 0.3), 1000.0), (0.3, 1.0, 0.0), (1.0, 0.0, 5.0)]
    chi2 = [("mixed_0", dict(specular_reflectance=0.5, exponent=30.0), 0, 16),
            ("mixed_45", dict(specular_reflectance=0.5, diffuse_reflectance=0.3, exponent=10.0),
             45, 16),
            ("glossy_80", dict(specular_reflectance=0.8, diffuse_reflectance=0.0, exponent=100.0),
             80, 32),
            ("mixed_89", dict(specular_reflectance=0.5, exponent=20.0), 89, 32),
            ("sharp_30", dict(specular_reflectance=1.0, diffuse_reflectance=0.0, exponent=1000.0),
             30, 64),
            ("flat_60", dict(specular_reflectance=0.6, diffuse_reflectance=0.2, exponent=0.0),
             60, 8)]
    return dict(
        cases=tuple((dict(diffuse_reflectance=kd, specular_reflectance=ks, exponent=p,
                          form=FORMS[(i + j) % 3]), 5e-4)
                    for i, (kd, ks, p) in enumerate(settings) for j in (0, 1)),
        not_reciprocal=({"form": "original"},),
        chi2=tuple((f"{label}-{FORMS[i % 3]}", {**s, "form": FORMS[i % 3]}, theta, ires)
                   for i, (label, s, theta, ires) in enumerate(chi2))
        + (("diffuse_component", dict(component=1, specular_reflectance=0.5, exponent=10.0), 60,
            8),),
        stability={"form": FORMS, "specular_reflectance": (0.0, 1.0),
                   "diffuse_reflectance": (0.0, 1.0), "exponent": (0.0, 1e-3, 1.0, 1e4, 1e6)},
        renders=(("mixed-original", dict(specular_reflectance=0.3, exponent=60.0,
                                         form="original")),
                 ("sharp-modified", dict(specular_reflectance=1.0, diffuse_reflectance=0.2,
                                         exponent=1e6, form="modified")),
                 ("flat-normalized", dict(specular_reflectance=0.2, diffuse_reflectance=0.3,
                                          exponent=0.0))))
