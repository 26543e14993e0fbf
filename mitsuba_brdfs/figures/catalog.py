"""The model catalog: every model and form on the same sphere under the same light.

One tile per configuration, labelled, composed into ``catalog.png`` (rendered by
``python -m mitsuba_brdfs figures``, figure ``catalog``). The scene is the sphere of
``scenes/as_sphere.xml`` (``sphere.sphere_scene``): a small area light up-left and a dim
environment, ``direct`` integrator (nothing else in the scene to reflect). Every model
gets the same red diffuse colour (``RED``) and a white specular layer where it has one; the
entries are the models' own (``catalog`` of their ``FACTS``).

Entries whose plugin is not registered (a model not written yet) are left out with a
printed note, so the catalog always renders what exists::

    python -m mitsuba_brdfs figures --only catalog
"""
from ..core.facts import RED
from ..passes import DEFAULT_PASS_SAMPLES
from ..sphere import sphere_scene
from .panels import Figure, Panel, render_figure

__all__ = ["RED", "CATALOG", "catalog_entries", "available", "catalog_figure", "render_catalog"]


def catalog_entries():
    """(label, bsdf dict) of every model's ``catalog`` (``core.facts``), model by model."""
    from ..core.facts import in_folder, label
    from ..models import facts
    from ..paths import SCENES
    return [(label(plugin, suffix), {"type": plugin, **in_folder(params, SCENES)})
            for plugin, f in facts().items() for suffix, params in f.catalog]


#: (label, bsdf dict) in reading order
CATALOG = catalog_entries()


def available(entries=None, note=print):
    """The entries whose BSDF loads in the active variant; a note for each one left out.

    A plugin that is not registered (yet) or does not accept the entry's parameters is
    skipped, never an error: the catalog shows what exists.
    """
    import mitsuba as mi
    kept = []
    for label, bsdf in (CATALOG if entries is None else entries):
        try:
            mi.load_dict(bsdf)
        except RuntimeError as e:
            reason = (f"plugin {bsdf['type']!r} is not registered" if "not found" in str(e)
                      else f"{bsdf['type']!r} did not load: {str(e).splitlines()[0]}")
            note(f"catalog: skipping {label!r}: {reason}")
            continue
        kept.append((label, bsdf))
    return kept


def catalog_figure(entries=None, columns=5, note=print):
    """The catalog as a ``panels.Figure``: one panel per available entry."""
    def loader(bsdf):
        return lambda defines: sphere_scene(bsdf, res=defines["res"])

    panels = [Panel(loader(bsdf), label) for label, bsdf in available(entries, note)]
    return Figure("catalog", "Every model on the same sphere, light and diffuse colour",
                  panels, spp={"preview": 64, "final": 256},
                  res={"preview": 160, "final": 320}, columns=columns)


def render_catalog(quality="preview", out_dir=None, pass_samples=DEFAULT_PASS_SAMPLES,
                   spp=None, res=None, entries=None, columns=5):
    """Render every available catalog entry and write the labelled grid ``catalog.png``
    (and one EXR per tile, ``catalog_<k>.exr``); returns the timings dict."""
    fig = catalog_figure(entries, columns)
    if not fig.panels:
        print("catalog: no model available, nothing rendered")
        return {"panels": 0, "quality": quality}
    t = render_figure(fig, quality, out_dir, pass_samples, spp, res)
    return {**t, "shown": [p.label for p in fig.panels]}
