"""Every input form Mitsuba's own plugins take, on every texture parameter of every plugin.

A colour or float parameter takes a float, an ``<rgb>``, a ``<spectrum>`` constant
(``value="0.5"``), a ``<spectrum>`` of wavelength-value pairs (``value="400:0.2, 700:0.8"``)
and a texture (bitmaps: ``test_textures.py``), from XML and from a dict, in RGB, mono and
spectral variants, scalar and LLVM. Each one becomes what Mitsuba's own plugins make of it
(``props.get_texture``): the plugin evaluates as with the texture Mitsuba builds from the
same input, a constant as the plain float, ``lambert`` as Mitsuba's ``diffuse``; a float
parameter reads a colour as Mitsuba's plugins do (``eval_1``: its luminance). The one form
refused is a spectrum of pairs on a float parameter in a spectral variant, which Mitsuba's
``roughconductor`` loads and then cannot evaluate (``eval_1(): not implemented``): it is
refused at load, naming the plugin and the parameter.

The full matrix runs in the scalar variants (no kernels to compile); the LLVM variants load
every case (the range checks) and compare ``lambert`` with ``diffuse``.
"""
import drjit as dr
import mitsuba as mi
import pytest

import mitsuba_brdfs
from checks import FACTS

#: every plugin as loaded by default, and with the parameters it reads only on request
#: (``FACTS.on_request``)
CONFIGS = [{"type": p} for p in sorted(mitsuba_brdfs.plugin_models())] + [
    {"type": p, **settings} for p in sorted(mitsuba_brdfs.plugin_models())
    for settings in FACTS[p].on_request]
FORMS = ("float", "rgb", "constant", "pairs")
#: (wi, wo) pairs (local frame) at which plugins are compared
PAIRS = [((0.0, 0.0, 1.0), (0.0, 0.0, 1.0)), ((0.6, 0.0, 0.8), (-0.48, 0.0, 0.877))]


def parameters(config):
    """parameter name -> Range of the config's checked texture parameters."""
    return mi.load_dict(config)._ranges


def inside(rng, t):
    """A value a fraction t into the range (into [lo, lo + 1] for an unbounded one)."""
    return rng.lo + t * (min(rng.hi, rng.lo + 1.0) - rng.lo)


def form(kind, rng):
    """A load_dict entry of the given kind holding values inside the range."""
    a, b, c = inside(rng, 0.3), inside(rng, 0.5), inside(rng, 0.7)
    return {"float": b,
            "rgb": {"type": "rgb", "value": [a, b, c]},
            "constant": {"type": "spectrum", "value": b},
            "pairs": {"type": "spectrum", "value": [(400.0, c), (700.0, a)]}}[kind]


def mitsuba_texture(entry, scalar):
    """The texture Mitsuba builds from a property, as Mitsuba's own plugins read a colour
    (``props.get_texture``) or a float (``props.get_unbounded_texture``)."""
    captured = []

    class Capture(mi.BSDF):  # defined here: a class is bound to the variant it is made in
        def __init__(self, props):
            mi.BSDF.__init__(self, props)
            get = props.get_unbounded_texture if scalar else props.get_texture
            captured.append(get("x"))

    mi.register_bsdf("_capture_input", lambda props: Capture(props))
    mi.load_dict({"type": "_capture_input", "x": entry})
    return captured[0]


def interaction(wi):
    si = dr.zeros(mi.SurfaceInteraction3f)
    si.wi = dr.normalize(mi.Vector3f(*wi))
    si.uv = mi.Point2f(0.3, 0.6)
    if mi.is_spectral:
        si.wavelengths = mi.Spectrum(450.0, 520.0, 600.0, 680.0)
    return si


def evals(bsdf):
    """eval at PAIRS, as a flat list of floats (a scalar variant)."""
    out = []
    for wi, wo in PAIRS:
        v = bsdf.eval(mi.BSDFContext(), interaction(wi), dr.normalize(mi.Vector3f(*wo)))
        out += [float(x) for x in v] if dr.depth_v(v) else [float(v)]
    return out


def close(a, b, rtol=1e-5):
    return all(abs(x - y) <= rtol * max(abs(x), abs(y), 1e-6) for x, y in zip(a, b))


def refused_in_variant(kind, rng):
    """The one combination refused: pairs on a float parameter in a spectral variant."""
    return kind == "pairs" and rng.scalar and mi.is_spectral


@pytest.mark.parametrize("variant", ["scalar_rgb", "scalar_spectral"])
def test_every_form_on_every_parameter_evaluates_as_mitsuba_reads_it(variant):
    """Each parameter alone in each form: the plugin loads and evaluates as with the
    texture Mitsuba builds from that input (and as the plain float for a constant); a float
    parameter given a colour evaluates as with the float Mitsuba's texture returns for it
    (``eval_1``). Pairs on a float parameter in a spectral variant are refused by name."""
    mi.set_variant(variant)
    failures = []
    for config in CONFIGS:
        for name, rng in parameters(config).items():
            for kind in FORMS:
                entry = form(kind, rng)
                tag = f"{config} {name}={kind}"
                if refused_in_variant(kind, rng):
                    with pytest.raises(RuntimeError, match=rf"{config['type']}: parameter "
                                       rf"'{name}' must be .* wavelength-value pairs"):
                        mi.load_dict({**config, name: entry})
                    continue
                try:
                    got = evals(mi.load_dict({**config, name: entry}))
                except Exception as e:  # noqa: BLE001  (collected, reported below)
                    failures.append(f"{tag}: {str(e).splitlines()[-1]}")
                    continue
                tex = mitsuba_texture(entry, rng.scalar)
                if rng.scalar:  # Mitsuba's plugins read it with eval_1
                    want = evals(mi.load_dict({**config, name: tex.eval_1(interaction((0, 0, 1)))}))
                else:
                    want = evals(mi.load_dict({**config, name: tex}))
                if kind in ("float", "constant"):
                    plain = evals(mi.load_dict({**config, name: form("float", rng)}))
                    if not close(got, plain):
                        failures.append(f"{tag}: {got} vs the float: {plain}")
                if not all(v == v and v >= 0 for v in got) or not close(got, want):
                    failures.append(f"{tag}: {got} vs Mitsuba's texture: {want}")
    assert not failures, f"{variant}:\n" + "\n".join(failures)


@pytest.mark.parametrize("variant", ["llvm_ad_rgb", "llvm_ad_mono", "llvm_ad_spectral",
                                     "llvm_ad_spectral_polarized"])
def test_every_form_on_every_parameter_loads_in_llvm_variants(variant):
    """The range checks of the LLVM variants take every form too (pairs on a float
    parameter of a spectral variant refused by name, as in the scalar one)."""
    mi.set_variant(variant)
    failures = []
    for config in CONFIGS:
        for name, rng in parameters(config).items():
            for kind in FORMS:
                try:
                    mi.load_dict({**config, name: form(kind, rng)})
                    ok = not refused_in_variant(kind, rng)
                except RuntimeError as e:
                    ok = refused_in_variant(kind, rng) and f"parameter '{name}'" in str(e)
                if not ok:
                    failures.append(f"{config} {name}={kind}")
    assert not failures, f"{variant}:\n" + "\n".join(failures)


@pytest.mark.parametrize("variant", ["scalar_rgb", "scalar_spectral", "llvm_ad_mono"])
@pytest.mark.parametrize("value", ["0.5", "400:0.2, 700:0.8", "400:0.2, 500:0.9, 700:0.4"])
def test_xml_spectrum_lambert_is_diffuse(variant, value):
    """``<spectrum name="reflectance" value="..."/>`` in a scene file: ``lambert`` gives what
    Mitsuba's ``diffuse`` gives with the same element (a constant stays a constant; pairs
    become a colour in RGB variants, their luminance in mono, a spectrum in spectral)."""
    mi.set_variant(variant)
    inner = f'<spectrum name="reflectance" value="{value}"/>'
    bsdfs = [mi.load_string(f'<bsdf version="3.0.0" type="{p}">{inner}</bsdf>')
             for p in ("lambert", "diffuse")]
    si = dr.zeros(mi.SurfaceInteraction3f)
    si.wi = dr.normalize(mi.Vector3f(0.3, 0.1, 0.9))
    if mi.is_spectral:
        si.wavelengths = mi.Spectrum(420.0, 500.0, 610.0, 690.0)
    wo = dr.normalize(mi.Vector3f(-0.2, 0.4, 0.8))
    ours, theirs = (b.eval(mi.BSDFContext(), si, wo) for b in bsdfs)
    assert dr.all(dr.abs(ours - theirs) <= 1e-6 * dr.abs(theirs) + 1e-9, axis=None), (ours, theirs)
    assert dr.all(ours > 0, axis=None)


def test_reflectance_spectrum_values_outside_0_1_refused_in_every_variant():
    """A reflectance spectrum with a value above 1 is refused in RGB variants too, where
    Mitsuba would clamp the colour it becomes (and the spectral variant would see 3)."""
    for variant in ("scalar_rgb", "scalar_spectral"):
        mi.set_variant(variant)
        with pytest.raises(RuntimeError, match=r"lambert: parameter 'reflectance' must be a "
                           r"reflectance in \[0, 1\].*\(got values in \[0.2, 3\]\)"):
            mi.load_dict({"type": "lambert", "reflectance":
                          {"type": "spectrum", "value": [(400.0, 0.2), (550.0, 3.0), (700.0, 0.8)]}})
