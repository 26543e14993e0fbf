"""The model of a fit: which plugin, loaded how, written back how.

``model_spec`` builds the dict of a ``--model`` (a preset model, ``--init MATERIAL``, ``-p``
values), ``load_model`` loads it with its colours as RGB (``colour_spec``, so that a fit
finds a colour: ``variables.colour_spec``) or refuses it in one line, ``bsdf_xml`` writes the fitted ``<bsdf>`` under
the names the plugin reads (Mitsuba's dielectric interfaces get ``int_ior``, ``ext_ior``).
"""
__all__ = ["MITSUBA_PLUGINS", "BUILTIN_EVALUATIONS", "model_spec", "load_model",
           "bsdf_xml"]

#: default budget for Mitsuba's own plugins (their parameter updates are slow)
BUILTIN_EVALUATIONS = 300
#: Mitsuba's BSDFs with a lobe ``eval`` sees, and whose parameters ``mi.traverse`` exposes
MITSUBA_PLUGINS = ("diffuse", "plastic", "roughplastic", "roughconductor", "roughdielectric",
                   "principled", "principledthin")
#: Mitsuba's plugins that take a dielectric interface as int_ior / ext_ior (their traverse
#: exposes the relative index as ``eta``)
_IOR_PLUGINS = ("plastic", "roughplastic", "dielectric", "roughdielectric", "thindielectric")


def model_spec(model, init=None, options=()):
    """The dict to load: a preset model's plugin (``ward_duer``: ``ward``, form duer), the
    material's preset with ``init``, the ``-p`` options on top."""
    from .. import presets
    from ..spec import parse_params, parse_value
    if init is not None:
        if model not in presets.MODELS:
            raise ValueError(f"fit-measured: --init needs a preset model "
                             f"({', '.join(presets.MODELS)}), got --model {model}")
        spec = presets.ngan2005(model, init)
    elif model == "ward_duer":
        spec = {"type": "ward", "form": "duer"}
    else:
        spec = {"type": model}
    spec.update({k: parse_value(v) for k, v in parse_params(options).items()})
    return spec


def load_model(spec, model):
    """The BSDF of ``spec`` (its colours as RGB), or ValueError in one line: an unknown
    plugin (with a suggestion), not a BSDF, a Mitsuba plugin without a lobe to fit."""
    import mitsuba as mi
    from ..core.registry import models
    try:
        bsdf = mi.load_dict(spec)
    except Exception as e:
        from ..presets import suggest
        from ..messages import last_line
        if "not found" in str(e):
            hint = suggest(model, list(models()) + list(MITSUBA_PLUGINS) + ["ward_duer"])
            raise ValueError(f"fit-measured: --model {model}: no such plugin{hint}") from None
        raise ValueError(f"fit-measured: --model {model}: {last_line(e)}") from None
    if not isinstance(bsdf, mi.BSDF):
        raise ValueError(f"fit-measured: --model {model} is not a BSDF plugin")
    if spec["type"] not in models() and spec["type"] not in MITSUBA_PLUGINS:
        flags = bsdf.flags()
        smooth = flags & (mi.BSDFFlags.DiffuseReflection | mi.BSDFFlags.GlossyReflection)
        why = ("it has no reflection that eval sees (none, or a delta lobe: a mirror)"
               if not smooth else "a plugin fit-measured does not know how to write back")
        raise ValueError(f"fit-measured: --model {spec['type']}: {why}; Mitsuba's plugins "
                         f"it fits: {', '.join(MITSUBA_PLUGINS)}")
    from .variables import colour_spec
    spec = colour_spec(spec, bsdf)
    return spec, mi.load_dict(spec)


def bsdf_xml(spec, values):
    """The fitted ``<bsdf version="3.0.0">`` (a file's root element): the model's options
    from ``spec`` (the dict it was loaded from), the fitted values of ``values`` ({traverse
    key: list}), under the names the plugin reads (``eta`` of Mitsuba's dielectric
    interfaces as ``int_ior`` over ``ext_ior``)."""
    from ..bsdf_xml import dict_to_xml
    out = {k: v for k, v in spec.items() if k != "type"}
    for key, v in values.items():
        name = key[:-len(".value")] if key.endswith(".value") else key
        out[name] = float(v[0]) if len(v) == 1 else {"type": "rgb",
                                                      "value": [float(x) for x in v[:3]]}
    if spec["type"] in _IOR_PLUGINS and "eta" in out:
        ext = _ext_ior(spec)
        out.pop("int_ior", None)
        out["int_ior"] = float(out.pop("eta")) * ext
        out["ext_ior"] = ext
    # 9 significant digits give back each fitted float32
    return dict_to_xml({"type": spec["type"], **out}, version=True, digits=9)


def _ext_ior(spec):
    """The exterior index of a dielectric interface as ``spec`` gives it (a number or one
    of Mitsuba's material names), 1 where it gives none."""
    ext = spec.get("ext_ior", 1.0)
    if isinstance(ext, str):  # a material name: Mitsuba's table, through a probe
        import mitsuba as mi
        probe = mi.traverse(mi.load_dict({"type": "roughplastic", "int_ior": 1.0,
                                          "ext_ior": ext}))
        ext = 1 / float(probe["eta"][0])
    return float(ext)
