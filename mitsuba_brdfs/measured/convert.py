"""Writing a source (``sources.Source``: a BSDF, a MERL or an RGL file) as an RGL file:
``preflight`` refuses a source with nothing to measure, ``convert`` measures it
(``acquire``), writes the file (``tensor``) and compares it with the source
(``roundtrip``). The ``to-rgl`` command (``to_rgl``) runs them.
"""
import math
import os
import time

__all__ = ["preflight", "convert"]


def preflight(source):
    """Refuse (``ValueError``, one line) a source that reflects nothing back (no NDF to
    measure); return whether it is isotropic."""
    from . import acquire, sources
    isotropic = (source.isotropic if source.isotropic is not None
                 else sources.is_isotropic(source.evaluate))
    theta, _ = acquire._theta_nodes(64)
    d = acquire._retro_directions(theta)
    if not (acquire.luminance(source.evaluate(d, d)) > 0).any():
        raise ValueError(f"{source.name}: reflects nothing back towards the light (its "
                         f"retro-reflection is 0 everywhere: a delta or transmissive BSDF?), "
                         f"so there is no NDF to measure")
    return isotropic


def convert(source, path, res, description=None, compare=True, progress=None,
            isotropic=None):
    """Measure ``source`` (a ``sources.Source``) at resolution ``res`` and write the RGL
    file ``path`` (anisotropic when the source is: ``isotropic`` None finds out); returns
    the summary (what was written, the comparison)."""
    from . import acquire, roundtrip, sources, tensor
    from ..progress import advance
    t0 = time.perf_counter()
    if isotropic is None:   # the command checks before its progress bar starts
        isotropic = preflight(source)
    fields, info = acquire.acquire(source.evaluate, res,
                                   description=description or f"to-rgl: {source.description}",
                                   progress=lambda note: advance(progress, 1, note),
                                   incidences=source.incidences, isotropic=isotropic)
    size = tensor.write(path, fields)
    seconds = time.perf_counter() - t0
    summary = {"source": source.name, "kind": source.kind, "output": path, "bytes": size,
               "resolution": {"ndf": res.ndf, "theta_i": res.theta_i, "vndf": res.vndf,
                              "grid": res.grid,
                              **({} if isotropic else {"phi_i": res.phi_i,
                                                       "azimuths": len(fields["phi_i"]),
                                                       "ndf_phi": res.ndf_phi,
                                                       "ndf_aniso": res.ndf_aniso})},
               "theta_i_deg": [round(math.degrees(t), 3) for t in fields["theta_i"]],
               "seconds": round(seconds, 3), "notes": list(source.notes),
               "options": dict(source.options), "defaults": list(source.defaults), **info}
    if compare:
        import mitsuba as mi
        written = sources.bsdf_evaluator(mi.load_dict({"type": "measured",
                                                       "filename": os.path.abspath(path)}))
        c = roundtrip.compare(source.evaluate, written,
                              phis=(0.0,) if isotropic else roundtrip.ALBEDO_PHIS)
        summary["compare"] = {
            "albedo": {str(t): {"source": [round(float(x), 5) for x in a],
                                "file": [round(float(x), 5) for x in b], "error": round(e, 5)}
                       for t, (a, b, e) in c["albedo"].items()},
            "eval_median_error": round(c["eval_median"], 5),
            "eval_within_10_percent": round(c["eval_within_10"], 4), "pairs": c["pairs"]}
        summary["seconds_compare"] = round(time.perf_counter() - t0 - seconds, 3)
        advance(progress, 1, "compared")
    return summary
