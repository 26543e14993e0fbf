"""The validation suite: the checks of this package, run on any BSDF.

``run(bsdf, settings)`` runs every check of ``CHECKS`` on a loaded BSDF (a plugin of this
package, one of Mitsuba's, or one the user wrote, in Python or C++) and returns one
``Result`` per check: its name, its status, the numbers it measured and a line saying
what they mean. ``python -m mitsuba_brdfs check`` prints them; the package's tests run the
same suite on every model.

Statuses: ``PASS``; ``FAIL``, a defect that changes an image or breaks an integrator;
``WARN``, a departure from the plugin contract that Mitsuba's integrators mask (each
warning with its count and an example); ``NOTE``, a property the BSDF lacks that was not
asked for (reciprocity without ``reciprocal``, an albedo above 1 with ``allow_gain``);
``SKIP``, what could not be checked and why. A BSDF passes when no check fails
(``summary(results, strict=True)``: and none warns).

What the integrators mask, read in Mitsuba 3.9.1's ``src/integrators/path.cpp`` (``direct``,
``volpath`` and the Python ``prb*`` integrators, ``ad/integrators/common.py``, do the
same):

- a sample of weight 0 ends the path: ``throughput *= bsdf_weight``, then ``active``
  requires ``throughput_max != 0``, so its ``wo`` (the next ray) and its ``pdf`` (the next
  vertex's MIS weight, ``prev_bsdf_pdf``) are never read (``direct.cpp`` traces a BSDF
  sample only where ``any(bsdf_val != 0)``). A NaN or negative ``wo`` or ``pdf`` there is a
  WARN; with a non-zero weight it is a FAIL;
- ``pdf()`` (through ``eval_pdf``) enters only ``mis_weight(ds.pdf, bsdf_pdf)``, which squares
  both pdfs and returns 0 for a non-finite weight (``dr::select(dr::isfinite(w), w, 0)``),
  and that weight multiplies ``bsdf_val``. Where eval is 0 in every channel a NaN, negative
  or non-zero pdf (across the surface of a reflection-only BSDF, below a one-sided one, a
  side where ``sample()`` draws nothing) contributes nothing: a WARN. Where eval is not 0 a
  wrong pdf biases the MIS weights: a FAIL (``chi2``, ``weight``, ``hard_cases``);
- no integrator sets ``ctx.component`` or ``ctx.type_mask`` or reads
  ``bs.sampled_component``: what ``components`` finds, and a component index outside
  ``0 .. component_count() - 1``, are WARNs. The flags are read: ``flags()`` decides
  emitter sampling (``Smooth``) and ``sampled_type`` the MIS of the next hit (``Delta``),
  so wrong flags where something scatters, and eval not 0 where the flags say nothing
  scatters, are FAILs.

Everything else is a FAIL: a chi-square rejection, a weight that is not eval / pdf, a NaN,
infinite or negative eval or weight, an albedo above 1, a sampled direction of non-zero
weight that is not a finite unit vector.

The checks (each on the incidences of ``Settings``, theta_i in degrees, phi = 0.3):

- ``chi2``: Mitsuba's chi-square test of the sampled directions against pdf();
- ``weight``: each sample's weight is eval / pdf at its direction, its pdf is pdf(), and a
  sample that failed (pdf 0) weighs 0;
- ``eval_pdf``: eval_pdf() gives eval() and pdf();
- ``pdf``: pdf() integrates to at most 1 over the sphere;
- ``furnace``: the mean sample weight (the Monte Carlo albedo) equals a quadrature of eval()
  over the sphere: nothing eval() reflects is missed by the sampler, nothing is counted twice;
- ``energy``: the albedo (what the BSDF reflects of the light it receives) is at most 1
  by both of its estimates, the mean sample weight (delta lobes included) and the
  quadrature of eval(): a BSDF whose eval() reflects more than it receives fails it even
  where its sampler's weights stay below 1 (``furnace`` says that they disagree);
- ``reciprocity``: f(a, b) = f(b, a); across the surface of a transmissive BSDF
  f(a, b) / eta_a^2 = f(b, a) / eta_b^2 (radiance transport), and the same for the energy
  of a delta transmission (``validate.reciprocity`` derives it);
- ``hard_cases``: finite values >= 0 at the normal, at grazing and horizon directions, with
  h = n, nearly opposite grazing pairs, below the horizon, and at corner sample values;
- ``flags``: the declared flags agree with the sampled types and components, and with what
  the BSDF does (nothing on a side or in a direction that the flags exclude);
- ``components``: ``ctx.component`` selects one lobe: samples come from it, its weight is its
  eval / pdf and its mean weight its quadrature, and the lobes add up to the whole.

Two-sided BSDFs (a ``BackSide`` flag) are checked from both sides (incidences theta_i
above 90 degrees come from below); for one-sided ones a ``SKIP`` line, ``sides``, says so.
A BSDF without a transmission flag is checked on wi's side of the surface (and ``flags``
checks that nothing goes across); the energy of a transmissive one is measured in
importance transport (radiance is scaled by eta^2 across an interface). Delta lobes
(smooth mirrors and glass) and the null lobe of ``mask`` have no density: their samples
are left out of the checks that compare with eval and pdf, and ``chi2`` tests the other
lobes (its line says so), under the default context as integrators call the BSDF.

Mitsuba's conventions are followed: a sample of weight 0 is discarded whatever its pdf
(as ``mitsuba.chi2.BSDFAdapter`` does), and eval includes the cosine. The BSDF is called as
integrators call it (``probe.call_sample`` and the others): through Mitsuba's own entry
points with ``active`` given, so a Python plugin gets what a render gives it (``active``
may be a required argument) and what it returns is converted as in a render (an ``eval``
returning the Python float 0.0 is a black ``Spectrum``).
"""
import dataclasses
import re
import time

import mitsuba as mi

from ..messages import one_line
from .checks_sampling import (chi2_result, energy_result, eval_pdf_result, furnace_result,
                              pdf_result, weight_result)
from .checks_structure import (components_result, flags_result, hard_cases_result,
                               reciprocity_result, sides_result)
from .results import Result, summary, verdict, warning
from .subject import SETTINGS, Settings, Subject

__all__ = ["Settings", "SETTINGS", "Result", "warning", "verdict", "summary", "Subject", "CHECKS",
           "run", "assert_valid"]


#: (name, function(Subject) -> Result or None), in the order they run and print
CHECKS = [
    ("chi2", chi2_result),
    ("weight", weight_result),
    ("eval_pdf", eval_pdf_result),
    ("pdf", pdf_result),
    ("furnace", furnace_result),
    ("energy", energy_result),
    ("reciprocity", reciprocity_result),
    ("hard_cases", hard_cases_result),
    ("flags", flags_result),
    ("components", components_result),
    ("sides", sides_result),
]


def run(bsdf, settings=None, name="bsdf", only=None, on_result=None):
    """Every check of CHECKS (or the named ones in ``only``) on a loaded BSDF; a check that
    raises FAILs with the exception as its message (said once: a later check that raises
    the same names the first). ``on_result(result)`` is called as each
    check ends. Returns the list of Results."""
    s = Subject(bsdf, name, settings or SETTINGS["default"])
    results = []
    raised = {}  # what a check raised -> the first check that raised it (said once)
    for check_name, fn in CHECKS:
        if only is not None and check_name not in only:
            continue
        t0 = time.perf_counter()
        try:
            r = fn(s)
        except Exception as e:  # a BSDF that raises has failed the check
            if "KeyboardInterrupt" in str(e):  # Ctrl-C, wrapped by Dr.Jit: stop
                raise KeyboardInterrupt from e
            said = f"{type(e).__name__}: {one_line(e)}"
            if "implicit conversion to 'bool'" in said:  # a plugin written for scalar calls
                said += (" (a Python if, and, or on an array: JIT variants call the plugin "
                         "with arrays, as a render does; use dr.select or masks)")
            # the same error with other array sizes is the same error
            first = raised.setdefault(re.sub(r"\d[\d,]*", "#", said), check_name)
            r = Result(check_name, "FAIL", {}, f"raised {said}" if first == check_name else
                       f"raised the {type(e).__name__} of '{first}' (above)")
        if r is None:
            continue
        r.numbers["seconds"] = round(time.perf_counter() - t0, 3)
        results.append(r)
        if on_result:
            on_result(r)
    return results


def assert_valid(bsdf, settings="quick", strict=False, only=None, **options):
    """Run the suite on ``bsdf`` and raise ``AssertionError`` listing every failed check
    (with ``strict``, every warning too), for a test suite::

        from mitsuba_brdfs.validate import assert_valid

        def test_my_bsdf():
            assert_valid({"type": "my_bsdf", "roughness": 0.3})

    ``bsdf`` is a loaded BSDF, a plugin name or a ``mi.load_dict`` dictionary;
    ``settings`` a preset name (``"quick"``, about a second; ``"default"``; ``"thorough"``)
    or a ``Settings``; ``options`` replace fields of it (``allow_gain=True``,
    ``reciprocal=True``, ``samples=...``); ``only`` names the checks to run. Returns the
    results when nothing failed."""
    __tracebackhide__ = True  # pytest shows the caller's line and the message
    if isinstance(bsdf, str):
        bsdf = {"type": bsdf}
    name = bsdf.get("type", "bsdf") if isinstance(bsdf, dict) else (bsdf.id() or "bsdf")
    if isinstance(bsdf, dict):
        bsdf = mi.load_dict(bsdf)
    if isinstance(settings, str):
        if settings not in SETTINGS:
            raise ValueError(f"assert_valid: settings {settings!r} is not one of "
                             f"{', '.join(SETTINGS)} (or a Settings)")
        settings = SETTINGS[settings]
    settings = dataclasses.replace(settings, **options)
    results = run(bsdf, settings, name, only=only)
    ok, line = summary(results, strict)
    if ok:
        return results
    lines = [f"{name}: {line}"]
    for r in results:
        if r.status == "FAIL" or (strict and r.status == "WARN"):
            lines.append(f"  {r.status} {r.name}: {r.message}")
    raise AssertionError("\n".join(lines))
