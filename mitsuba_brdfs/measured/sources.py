"""What ``to-rgl`` converts, as an evaluator: a function eval(wi, wo) -> (n, C) NumPy array
(f cos theta_o, as a BSDF's eval returns it) on local directions (n, 3).

- an RGL file (recognised by its ``tensor_file`` header): Mitsuba's ``measured`` plugin
  (RGB files in RGB variants, spectral files in spectral variants, as ``measured`` needs);
- a MERL file (``.binary``, recognised by its size, ``merl.check_file``): the table
  looked up as MERL's ``BRDFRead.cpp`` does (the bin of the half and difference angles,
  ``merl.lookup``), unmeasured bins (negative in the file) as 0;
- anything else names a BSDF as ``check`` does (``spec.load_bsdfs``): a plugin of
  Mitsuba's, of this package or of a ``--load`` file with ``-p`` parameters, or an XML
  file holding one ``<bsdf>``.

``is_isotropic`` says whether eval is unchanged when both directions turn about the
normal (measured on 2000 random pairs, 4 turns); ``options`` lists every option of a loaded
BSDF as the plugin holds it, defaults included (``distribution = beckmann`` for Mitsuba's
``roughconductor`` given only ``alpha``).
"""
import dataclasses
import os
import re

import numpy as np

from .evaluators import bsdf_evaluator, is_isotropic
from .tensor import FormatError, is_tensor_file

__all__ = ["Source", "open_source", "bsdf_evaluator", "rgl_evaluator",
           "is_isotropic", "options"]


@dataclasses.dataclass
class Source:
    """A source: its evaluator, a name, its kind ("bsdf", "merl", "rgl"), notes (one line
    each) about what the conversion leaves out, the incidences it was measured at (an
    RGL file's, else None), whether it is isotropic when its format says so (a MERL
    file, an RGL file; None: ``is_isotropic`` finds out), and a BSDF's options ({name:
    value}, every one the plugin holds, ``options``) with those not given (``defaults``,
    the plugin's defaults)."""
    evaluate: object
    name: str
    kind: str
    description: str
    notes: list
    incidences: object = None
    isotropic: object = None
    options: dict = dataclasses.field(default_factory=dict)
    defaults: list = dataclasses.field(default_factory=list)


def rgl_evaluator(path):
    """(evaluate, Material) of an RGL file through Mitsuba's ``measured`` plugin, in the
    active variant (which must be of the file's kind: RGB or spectral)."""
    import mitsuba as mi
    from . import rgl
    material = rgl.load_for_variant(path)
    bsdf = mi.load_dict({"type": "measured", "filename": os.path.abspath(path)})
    return bsdf_evaluator(bsdf), material


def open_source(spec, params=None):
    """The ``Source`` that ``spec`` names (with ``-p`` params, raw strings, for a BSDF)."""
    params = params or {}
    if os.path.isfile(spec) and is_tensor_file(spec):
        if params:
            raise ValueError(f"{spec}: an RGL file takes no -p parameters")
        evaluate, material = rgl_evaluator(spec)
        return Source(evaluate, os.path.basename(spec), "rgl",
                      material.description or os.path.basename(spec), [],
                      incidences=material.theta_i, isotropic=material.isotropic)
    if os.path.isfile(spec) and not spec.lower().endswith(".xml") and not _is_xml(spec):
        from . import merl
        try:
            merl.check_file(spec)
        except ValueError as e:
            raise FormatError(f"{e} (to-rgl reads RGL files, MERL files and XML files "
                              f"holding a <bsdf>)") from None
        if params:
            raise ValueError(f"{spec}: a MERL file takes no -p parameters")
        evaluate, dims, unmeasured = merl.evaluator(spec)
        notes = [f"{unmeasured} of {int(np.prod(dims))} MERL bins unmeasured: read as 0"] \
            if unmeasured else []
        return Source(evaluate, os.path.basename(spec), "merl",
                      f"MERL {os.path.basename(spec)}", notes, isotropic=True)
    from ..spec import load_bsdfs
    bsdfs = load_bsdfs(spec, params)
    if len(bsdfs) != 1:
        raise ValueError(f"{spec} holds {len(bsdfs)} BSDFs ({', '.join(n for n, _ in bsdfs)}); "
                         f"to-rgl converts one: give an XML file with a single <bsdf>")
    name, bsdf = bsdfs[0]
    held = options(bsdf)
    named = set(params) | ({"eta", "k"} if "material" in params else set())
    given = lambda key: any(key == k or key.startswith(k + "_") or key.startswith(k + ".")
                            for k in named)
    return Source(bsdf_evaluator(bsdf), name, "bsdf", _describe(spec, params), _notes(bsdf),
                  options=held, defaults=[k for k in held if not given(k)])


def _split_top(text, separators):
    """``text`` cut at the ``separators`` that stand outside brackets."""
    parts, depth, start = [], 0, 0
    for i, ch in enumerate(text):
        depth += (ch in "[(") - (ch in "])")
        if depth == 0 and ch in separators:
            parts.append(text[start:i])
            start = i + 1
    return parts + [text[start:]]


def options(bsdf):
    """{option: value} of a loaded BSDF, every option its plugin prints (``to_string``),
    defaults included, values on one line (a uniform or RGB spectrum as its numbers)."""
    text = str(bsdf)
    body = text[text.index("\n") + 1:] if "\n" in text else ""
    body = body.strip()
    if body.endswith("]") and text.split("\n", 1)[0].rstrip().endswith("["):
        body = body[:-1]
    out = {}
    for item in _split_top(body, ","):
        pair = next(((item[:i], item[i + 1:]) for i, ch in enumerate(item)
                     if ch in "=:" and item[:i].count("[") == item[:i].count("]")), None)
        if pair is None or not pair[0].strip():
            continue
        value = " ".join(pair[1].split())
        inner = re.fullmatch(r"\w+\[ ?value ?= ?\[\[?(.*?)\]?\] ?\]", value)
        value = inner.group(1) if inner else re.sub(r"^\[([^\[\]]*)\]$", r"\1", value)
        out[pair[0].strip()] = value
    return out


def _is_xml(path):
    with open(path, "rb") as f:
        head = f.read(256).lstrip()
    return head.startswith(b"<")


def _describe(spec, params):
    extra = " ".join(f"{k}={v}" for k, v in params.items())
    return f"{spec} {extra}".strip()


def _notes(bsdf):
    """What an RGL file (one-sided glossy reflection) cannot hold of ``bsdf``."""
    import mitsuba as mi
    flags, notes = bsdf.flags(), []
    if flags & (mi.BSDFFlags.DeltaReflection | mi.BSDFFlags.DeltaTransmission):
        notes.append("its delta (perfectly specular) lobes have no eval: they are left out")
    if flags & (mi.BSDFFlags.GlossyTransmission | mi.BSDFFlags.DiffuseTransmission):
        notes.append("its transmission is left out (measured reflects only)")
    if flags & mi.BSDFFlags.BackSide:
        notes.append("its back side is left out (measured is one-sided; wrap the file's "
                     "<bsdf> in a twosided to show it from both sides)")
    return notes

