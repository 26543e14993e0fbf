"""Toon (cel) shading (``toon``): flat colour bands chosen by thresholds.

Reference: the lecture "BRDF models" (Politecnico di Milano), section Toon shading.

Parameters
----------
========================  ================  =============================================
``diffuse_reflectance``   spectrum/texture  m_D1, colour of the lit diffuse band, in
                                            [0, 1]. (Default: 0.5)
``diffuse_shade``         spectrum/texture  m_D2, colour of the dark diffuse band, in
                                            [0, 1]. (Default: 0.1)
``diffuse_threshold``     float/texture     t_D, in [0, 1]: the lit band is where
                                            cos(theta_light) >= t_D. (Default: 0.5)
``specular_reflectance``  spectrum/texture  m_S1, colour of the highlight band, in [0, 1].
                                            (Default: 0.3)
``specular_shade``        spectrum/texture  m_S2, specular colour outside the highlight,
                                            in [0, 1]. (Default: 0)
``specular_threshold``    float/texture     t_S, in [0, 1]: the highlight is where the
                                            specular cosine is >= t_S. (Default: 0.95)
``specular_model``        string            ``phong``: the cosine is viewer . r, r the
                                            light mirrored about n; ``blinn``: n . h.
                                            (Default: ``phong``)
``smoothing``             float/texture     width w in [0, 1] of the gradient between two
                                            bands (a smooth step over [t - w/2, t + w/2]);
                                            0 gives the hard two-band switch; not with
                                            both ramps. (Default: 0.05)
``diffuse_ramp``          texture           the lecture's f_mD: a 1D colour texture in
                                            [0, 1] (a bitmap N pixels wide), looked up at
                                            u = cos(theta_light); replaces the diffuse
                                            bands (``diffuse_reflectance``,
                                            ``diffuse_shade``, ``diffuse_threshold``, which
                                            must then be absent). (Default: unused)
``specular_ramp``         texture           the lecture's f_mS: a 1D colour texture in
                                            [0, 1], looked up at u = the specular cosine;
                                            replaces the specular bands
                                            (``specular_reflectance``, ``specular_shade``,
                                            ``specular_threshold``, which must then be
                                            absent). (Default: unused)
========================  ================  =============================================

Values outside the ranges above (NaN included) are refused with an error naming the
plugin, the parameter and its range, at load and when ``params.update()`` sets them.

All colours, thresholds, ramps and the smoothing are exposed by ``traverse`` and differentiable
(thresholds only through the gradient between bands: with w = 0 the switch is a step).

The lecture's formula, with d the light (Mitsuba's ``wo``), omega_r the viewer (``si.wi``)
and r = 2 n (d.n) - d:

    f_diffuse  = m_D1 if d.n >= t_D else m_D2
    f_specular = m_S1 if omega_r.r >= t_S else m_S2    (Phong version; Blinn: n.h)

"starting from a Lambert diffuse and a Phong or Blinn specular with gamma = 1", plus the
remark that small gradients between the bands give better results (``smoothing``), and that
"more than two colors are used", "implemented as 1D textures": f_diffuse = f_mD(d.n),
f_specular = f_mS(omega_r.r) (``diffuse_ramp``, ``specular_ramp``).

Our reading. The lecture's "BRDFs" are the factors of its rendering equation for a single
light, L = l * (f_diffuse + f_specular): its Lambert term is m_D clamp(d.n), the cosine
included. The toon bands replace that whole factor, so inside a band the colour is flat: the
cosine is not applied again. Mitsuba's ``eval`` is that factor (f cos(theta_light)), and
The package maps the lecture's diffuse colours to eval by 1/pi (Lambert: eval =
rho/pi cos(theta_light)). So

    eval = ( band(d.n; t_D, w; m_D1, m_D2) + band(c_s; t_S, w; m_S1, m_S2) ) / pi,

band(x; t, w; a, b) = b + (a - b) smoothstep(t - w/2, t + w/2, x), c_s = omega_r.r or n.h.
The lit band of a white ``diffuse_reflectance`` gives eval = 1/pi, exactly what a white
``lambert`` gives at normal incidence: swapping ``lambert`` for ``toon`` keeps the
brightness of the lit parts (and with t_D = 0.5 and a black shade even the albedo: both 1).
Light from below the surface gives 0 (one-sided, as every plugin of the package), where the
lecture's formula would still show m_D2.

Ramps. A ramp replaces its lobe's two bands: eval = (ramp_D(d.n) + ramp_S(c_s)) / pi, the
ramp's colour taken where it is looked up (a ramp and bands may be mixed: one lobe each).
The lookup is at u = the lobe's cosine clamped to [0, 1], v = 1/2, by evaluating the texture
at a copy of the shading point with that uv (the ramp is a function of the cosine, not of
the surface position). For a bitmap N pixels wide (any height; rows are expected alike), u
is further clamped to the centres of its first and last pixel, [1/(2N), 1 - 1/(2N)], so
neither the filter nor the wrap mode ever blends the two ends (a repeating bitmap would mix
the darkest and the brightest colour at u = 0 and 1). Then ``filter_type = nearest`` gives
N flat bands of equal width 1/N in the cosine (pixel k for cos in [k/N, (k+1)/N)), and
``bilinear`` (Mitsuba's default) a piecewise linear gradient through the pixel colours at
the cosines (k + 1/2)/N, flat below the first and above the last centre. Bitmap values are
checked to lie in [0, 1] (8-bit images as fractions of 255; an sRGB PNG is decoded to linear
colours unless ``raw`` is set). A constant ``<rgb>`` ramp is a flat colour. ``smoothing``
shapes the transitions of bands only; with both ramps it is refused. A white ramp value
gives what the white lit band gives (eval = 1/pi). A diffuse ramp's albedo is
2 int_0^1 ramp_D(mu) dmu for any viewer (twice the mean pixel of a nearest bitmap).
The ramps of the example below, ``toon_ramp_diffuse.png`` and ``toon_ramp_specular.png``,
and ``toon_ramp.xml``, a scene that shows both filters, are in the repository's top-level
``scenes/`` folder; a wheel installs them with the package as ``mitsuba_brdfs/scenes``, the
folder ``mitsuba_brdfs.paths.SCENES`` names (printed by
``python -c "import mitsuba_brdfs.paths as p; print(p.SCENES)"``). A scene kept elsewhere
finds them once that folder is on its search path:
``python -m mitsuba_brdfs render my_scene.xml -a FOLDER`` (or copy them beside the scene).

Not physically based: the BRDF f = eval / cos(theta_light) is not reciprocal
(``RECIPROCAL = False``: the roles of wi and wo are swapped under importance transport), and
energy is not conserved in general. The diffuse albedo is
2 (m_D1 (1 - t_D) + m_D2 t_D) for any viewer (if the gradient window lies inside [0, 1]),
e.g. 2 m_D1 at t_D = 0; the Phong highlight band adds 2 m_S1 (1 - t_S) where its cone
around the mirror direction lies above the horizon (Blinn's n.h band is about four times
wider in light directions). The values are finite and >= 0 everywhere; below the lit threshold a flat
non-zero shade makes the sample weights eval/pdf = m_D2 / cos(theta) grow at grazing
angles (finite, but noisy under environment light).

Sampling: cosine-weighted for both lobes (``cosine_only``): pdf = cos(theta)/pi,
weight = eval / pdf.

Lobes: a glossy component (index 0, the specular bands or ramp) and a diffuse one (index 1);
a lobe whose two colours (or its ramp) are a constant zero is left out of the kernel (the
component stays declared).

Albedo AOV (``eval_diffuse_reflectance``, the ``aov`` integrator's ``albedo``): m_D1,
the lit band's colour (a white lit band is as bright as a white ``lambert`` head-on);
where m_D1 is black, m_S1, the highlight's colour. A ramp gives its colour at cosine 1
(its lit end) instead. Never above 1.

XML::

    <bsdf type="toon">
        <rgb name="diffuse_reflectance" value="0.9, 0.3, 0.2"/>
        <rgb name="diffuse_shade" value="0.3, 0.1, 0.1"/>
        <float name="diffuse_threshold" value="0.4"/>
        <float name="specular_reflectance" value="0.5"/>
        <string name="specular_model" value="blinn"/>
        <float name="smoothing" value="0"/>
    </bsdf>

Python: ``mi.load_dict({'type': 'toon', 'diffuse_reflectance': {'type': 'rgb', 'value': [0.9, 0.3, 0.2]}})``

With ramps::

    <bsdf type="toon">
        <texture type="bitmap" name="diffuse_ramp">
            <string name="filename" value="toon_ramp_diffuse.png"/>
            <string name="filter_type" value="nearest"/>
        </texture>
        <texture type="bitmap" name="specular_ramp">
            <string name="filename" value="toon_ramp_specular.png"/>
        </texture>
    </bsdf>
"""
import drjit as dr
import mitsuba as mi

from ..core.facts import RED, Facts, rgb, white
from ..core.frame import cos_theta, half_vector, mirror
from ..core.lobes import Point, TwoLobeModel
from ..core.registry import bsdf_plugin
from ..core.relations import Excludes
from ..core.shading import band

__all__ = ["Toon"]

#: the parameters each ramp replaces
_BANDS = {"diffuse_ramp": ("diffuse_reflectance", "diffuse_shade", "diffuse_threshold"),
          "specular_ramp": ("specular_reflectance", "specular_shade", "specular_threshold")}


def phong_cosine(wi, wo):
    """viewer . r, r = the light direction mirrored about n (the lecture's Phong, gamma = 1)."""
    return dr.dot(wi, mirror(wo))


def blinn_cosine(wi, wo):
    """n . h (the lecture's Blinn, gamma = 1)."""
    h, _ = half_vector(wi, wo)
    return cos_theta(h)


def ramp_u_range(tex):
    """(lo, hi) of the lookup coordinate u: the centres of the first and last pixel of a
    bitmap (so that neither filtering nor the wrap mode blends its two ends), [0, 1] for
    any other texture."""
    for key, value in mi.traverse(tex).items():
        if key.endswith("data") and hasattr(value, "shape") and len(value.shape) == 3:
            width = value.shape[1]
            return 0.5 / width, 1 - 0.5 / width
    return 0.0, 1.0


def ramp_lookup(tex, u_range, c, si, active):
    """The ramp's colour at u = c clamped to [0, 1] (and to ``u_range``), v = 1/2: the
    texture evaluated at a copy of the shading point with that uv."""
    si2 = mi.SurfaceInteraction3f(si)
    si2.uv = mi.Point2f(dr.clip(c, *u_range), 0.5)
    return tex.eval(si2, active)


class _At(Point):
    """Parameter values at one shading point (and the point itself, for ramp lookups)."""
    __slots__ = ("d1", "d2", "td", "s1", "s2", "ts", "w", "si", "active")


@bsdf_plugin("toon")
class Toon(TwoLobeModel):
    cosine_only = True
    RECIPROCAL = False
    OPTIONS = {"specular_model": ("phong", "blinn")}
    RELATIONS = tuple(Excludes(bands, (ramp,), why="the ramp replaces the lobe's two bands")
                      for ramp, bands in _BANDS.items()) + (
        Excludes(("smoothing",), tuple(_BANDS), every=True,
                 why="it shapes the bands between two colours, which the ramps replace"),)

    def _read_parameters(self, r):
        #: ramp name -> texture (None: the lobe has its two bands)
        self.ramps = {name: self._read_ramp(r, name) for name in _BANDS}
        if self.ramps["diffuse_ramp"] is None:
            self.d1 = r.reflectance("diffuse_reflectance", 0.5)
            self.d2 = r.reflectance("diffuse_shade", 0.1)
            self.td = r.scalar("diffuse_threshold", 0.5, 0.0, 1.0, what="a cosine threshold")
        if self.ramps["specular_ramp"] is None:
            self.s1 = r.reflectance("specular_reflectance", 0.3)
            self.s2 = r.reflectance("specular_shade", 0.0)
            self.ts = r.scalar("specular_threshold", 0.95, 0.0, 1.0, what="a cosine threshold")
        self.specular_model = r.enum("specular_model", "phong", self.OPTIONS["specular_model"])
        self.smoothing = None
        if None in self.ramps.values():
            self.smoothing = r.scalar("smoothing", 0.05, 0.0, 1.0, what="a band gradient width")
        # a load-time choice: the kernel holds one of the two cosines
        self._specular_cosine = {"phong": phong_cosine, "blinn": blinn_cosine}[self.specular_model]

    @staticmethod
    def _read_ramp(r, name):
        """The ramp texture (colours in [0, 1]), or None if not given."""
        if name not in r.props:
            return None
        return r.reflectance(name, 0.0)

    def _textures(self):
        textures = {}
        d_ramp, s_ramp = self.ramps["diffuse_ramp"], self.ramps["specular_ramp"]
        if d_ramp is None:
            textures.update(diffuse_reflectance=self.d1, diffuse_shade=self.d2,
                            diffuse_threshold=self.td)
        else:
            textures["diffuse_ramp"] = d_ramp
        if s_ramp is None:
            textures.update(specular_reflectance=self.s1, specular_shade=self.s2,
                            specular_threshold=self.ts)
        else:
            textures["specular_ramp"] = s_ramp
        if self.smoothing is not None:
            textures["smoothing"] = self.smoothing
        return textures

    def _options(self):
        return {"specular_model": self.specular_model}

    def _lobes_present(self):
        def present(ramp, colours):
            if ramp is not None:
                return not self._is_constant(ramp, 0.0)
            return not all(self._is_constant(c, 0.0) for c in colours)
        d_ramp, s_ramp = self.ramps["diffuse_ramp"], self.ramps["specular_ramp"]
        glossy = present(s_ramp, () if s_ramp else (self.s1, self.s2))
        diffuse = present(d_ramp, () if d_ramp else (self.d1, self.d2))
        return glossy, diffuse

    def _update(self):
        # the u range of each ramp follows its current width (an update may change it)
        self._ramp_range = {name: ramp_u_range(tex) for name, tex in self.ramps.items()
                            if tex is not None}

    def _ramp(self, name, c, p):
        """The ramp ``name`` at the cosine c (see ``ramp_lookup``)."""
        return ramp_lookup(self.ramps[name], self._ramp_range[name], c, p.si, p.active)

    def _at(self, si, active):
        p = _At(si=si, active=active)
        if self.ramps["diffuse_ramp"] is None:
            p.d1, p.d2 = self.d1.eval(si, active), self.d2.eval(si, active)
            p.td = self.td.eval_1(si, active)
        if self.ramps["specular_ramp"] is None:
            p.s1, p.s2 = self.s1.eval(si, active), self.s2.eval(si, active)
            p.ts = self.ts.eval_1(si, active)
        if self.smoothing is not None:
            p.w = self.smoothing.eval_1(si, active)
        return p

    # -- specular bands or ramp (glossy component) -----------------------------------------------

    def _glossy_f(self, p, wi, wo):
        c = self._specular_cosine(wi, wo)
        if self.ramps["specular_ramp"] is None:
            return band(c, p.ts, p.w, p.s1, p.s2) * dr.inv_pi
        return self._ramp("specular_ramp", c, p) * dr.inv_pi

    # -- diffuse bands or ramp ---------------------------------------------------------------

    def _diffuse_f(self, p, wi, wo):
        if self.ramps["diffuse_ramp"] is None:
            return band(cos_theta(wo), p.td, p.w, p.d1, p.d2) * dr.inv_pi
        return self._ramp("diffuse_ramp", cos_theta(wo), p) * dr.inv_pi

    # -- albedo AOV: the lit bands' colours ------------------------------------------------

    def _diffuse_colour(self, p):
        if self.ramps["diffuse_ramp"] is None:
            return p.d1
        return self._ramp("diffuse_ramp", 1.0, p)  # the lit end: light along the normal

    def _specular_colour(self, p):
        if self.ramps["specular_ramp"] is None:
            return p.s1
        return self._ramp("specular_ramp", 1.0, p)


def _ramp(name, filter_type="nearest"):
    """One of the PNG colour ramps of ``scenes/toon_ramp.xml`` (a file of ``scenes/``)."""
    return {"type": "bitmap", "filename": name, "filter_type": filter_type}


#: what the generic tests, the property table, the catalog and the benchmarks run of this
#: model (``core.facts``)
FACTS = Facts(
    colour="diffuse_reflectance",
    differentiable=("diffuse_reflectance", "diffuse_shade", "diffuse_threshold",
                    "specular_reflectance", "specular_shade", "specular_threshold", "smoothing"),
    non_default={"smoothing": 0.05, "specular_model": "blinn"},
    edges=(dict(smoothing=0.0, specular_model="blinn"), dict(smoothing=1.0, diffuse_threshold=0.0)),
    float64=((dict(smoothing=0.0), 1e-4),),
    gradient_edges=(dict(smoothing=0.0), dict(smoothing=0.1)),
    zero_lobes=(("diffuse_reflectance", 0, 0.5, {"diffuse_shade": white(0.0)}),
                ("specular_reflectance", 0, 0.5, {"specular_shade": white(0.0)})),
    albedo=(({"diffuse_reflectance": rgb(0.9, 0.3, 0.2)}, [0.9, 0.3, 0.2]),
            ({"diffuse_reflectance": 0.0, "diffuse_shade": 0.0, "specular_reflectance": 0.6},
             [0.6] * 3)),
    on_request=({"diffuse_ramp": 0.5, "specular_ramp": 0.2},),
    traced_options=({"specular_model": "blinn", "smoothing": 0.0},),
    check_notes=frozenset({"reciprocity"}),
    properties=(
        ("phong smoothing=0.05", {}),
        ("blinn hard bands", {"specular_model": "blinn", "smoothing": 0.0}),
        # the colour ramps of scenes/toon_ramp.xml (4 diffuse bands, a two-step highlight)
        ("ramps", {"diffuse_ramp": _ramp("toon_ramp_diffuse.png"),
                   "specular_ramp": _ramp("toon_ramp_specular.png")}),
    ),
    catalog=(
        ("", {"diffuse_reflectance": RED}),
        ("ramps (nearest)", {"diffuse_ramp": _ramp("toon_ramp_diffuse.png"),
                             "specular_ramp": _ramp("toon_ramp_specular.png")}),
    ),
    cpp=(("", {}, {"type": "diffuse", "reflectance": 0.5},
          "Mitsuba has no toon shader; `diffuse` has the same (cosine) sampling"),),
    dropped_lobes=(("specular0_vs_tiny", {"specular_reflectance": 0.0},
                    {"specular_reflectance": 1e-6}, "specular bands 0 (specular dropped) / 1e-6"),),
    # smooth bands (where float32 and float64 may take different sides of a hard edge, the
    # model's own test compares them away from the edge)
    cases=((dict(), 1e-5),
           (dict(smoothing=0.3, specular_model="blinn", diffuse_threshold=0.2,
                 specular_threshold=0.7), 1e-5),
           (dict(smoothing=1.0, diffuse_threshold=0.0, specular_threshold=1.0,
                 diffuse_reflectance=rgb(0.9, 0.3, 0.2), diffuse_shade=rgb(0.3, 0.1, 0.05)), 1e-5)),
    not_reciprocal=({},),
    chi2=(("defaults_0", {}, 0, 8), ("defaults_45", {}, 45, 8),
          ("hard_blinn_80", dict(smoothing=0.0, specular_model="blinn", specular_threshold=0.9,
                                 specular_shade=0.05), 80, 8),
          ("wide_89.5", dict(smoothing=1.0, diffuse_threshold=0.0, specular_threshold=1.0),
           89.5, 8),
          # (the adapter drops zero-weight samples: a non-zero shade keeps every sample)
          ("specular_only", dict(component=0, specular_shade=0.1), 30, 8)),
    stability={"specular_model": ("phong", "blinn"), "smoothing": (0.0, 0.1, 1.0),
               "diffuse_threshold": (0.0, 0.95, 1.0), "specular_threshold": (0.0, 1.0)},
    renders=(("phong", {}), ("blinn", {"specular_model": "blinn"})),
)
