"""``python -m mitsuba_brdfs explore``: a BRDF explorer in the browser over the real plugins.

The plugins of this package, Mitsuba's built-in BSDFs, a plugin registered by a user's
``--load FILE.py`` and the ``<bsdf>`` of an XML file are evaluated by Mitsuba itself on
the server (Dr.Jit, one JIT variant) and drawn in the page with Plotly, which the
``plotly`` package ships (no CDN: the page works offline).

- ``entries``: the BSDFs shown, their controls (from the docstring's parameter table, or
  from ``mi.traverse`` for other plugins), updates and exports (XML, ``load_dict``);
- ``evaluate``: the plots' data, one vectorized ``eval`` and one ``sample`` per BSDF;
- ``sphere``: a sphere rendered by Mitsuba under a movable light, in passes;
- ``server``: the web application (Starlette) and the page in ``static/``;
- ``command``: the command line.

Needs the ``explore`` extra: ``pip install 'mitsuba_brdfs[explore]'``.
"""
__all__ = ["REQUIRES"]

#: module -> the package pip installs it from, for the message when one is missing
REQUIRES = {"starlette": "starlette", "uvicorn": "uvicorn", "plotly": "plotly",
            "PIL": "Pillow"}
