"""``python -m mitsuba_brdfs explore``: a BRDF explorer in the browser over the real plugins.

The plugins of this package, Mitsuba's built-in BSDFs, a plugin registered by a user's
``--load FILE.py``, the ``<bsdf>`` of an XML file and measured files (RGL, MERL) are
evaluated by Mitsuba itself on the server (Dr.Jit, one JIT variant) and drawn in the page
with Plotly, which the ``plotly`` package ships (no CDN: the page works offline).

- ``controls``: what can be set of a BSDF (from the docstring's parameter table, or from
  ``mi.traverse`` for other plugins), partners and alternatives, how a value is checked;
- ``entries``: the BSDFs shown: loading, their state for the page, changes;
- ``measurement``: measured files (RGL, MERL through ``to-rgl``, cached) as entries;
- ``fitting``: a model of this package fitted to a measured entry as ``fit-measured`` fits it
  (``measured.data.prepare``, ``measured.report.fit_file``), at the page's budget;
- ``xmldict``: scene XML <-> ``load_dict`` dictionaries (the exports);
- ``evaluate``: the plots' data, one vectorized ``eval`` and one ``sample`` per BSDF;
- ``sphere``: a sphere rendered by Mitsuba under a movable light, in passes, on a dark grey;
- ``session``: the entries of a run and what the API does with them (one lock, bounds);
- ``api``: the requests' bodies and queries, read and checked;
- ``guard``: who may use the server (Host, token, origin, body size);
- ``server``: the web application (Starlette) and the page in ``static/``;
- ``messages``: the one-line errors the page shows;
- ``command``: the command line.

Needs the ``explore`` extra: ``pip install 'mitsuba_brdfs[explore]'``.
"""
__all__ = ["REQUIRES"]

#: module -> the package pip installs it from, for the message when one is missing
REQUIRES = {"starlette": "starlette", "uvicorn": "uvicorn", "plotly": "plotly",
            "PIL": "Pillow", "threadpoolctl": "threadpoolctl"}
