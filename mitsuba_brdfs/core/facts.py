"""What a model declares about itself for the generic tests, tables, figures and benchmarks.

Each model module ends with ``FACTS = Facts(...)``: the settings of its plugin that the
package's generic code runs, so that a new model is one file. ``mitsuba_brdfs.models.facts()``
collects them (plugin name -> ``Facts``); nothing keeps a list of models of its own.

Who reads what:

- ``tests/test_models.py`` (the generic model tests): ``cases``, ``not_reciprocal``,
  ``chi2``, ``stability``, ``renders``, ``colour``; ``tests/test_hard_cases.py``:
  ``colour``, ``edges``, ``float64`` (the float64 formula itself is the model's entry in
  ``tests/reference.py``, the one thing a new model adds outside its file; the tests say
  so when it is missing);
- ``tests/test_traverse.py``: ``differentiable``; ``tests/test_scenes.py``: ``non_default``,
  ``colour``; ``tests/test_scenes_lobes.py``: ``zero_lobes``; ``tests/test_aov.py``:
  ``albedo``; ``tests/test_gradients.py``: ``finite_difference``, ``gradient_edges``;
  ``tests/test_inputs.py`` and ``tests/test_params.py``: ``on_request``;
  ``tests/test_variants.py``: ``traced_options``; ``tests/test_manual.py``: ``companions``;
  ``tests/test_check.py``: ``check_notes``;
- ``properties`` (the property table): ``properties``; the ``catalog`` figure: ``catalog``;
  the performance study (``bench.speed``): ``cpp`` (the Python plugin against Mitsuba's
  closest C++ one) and ``dropped_lobes`` (a lobe of zero weight against a tiny one).

Settings are plain ``load_dict`` parameters without ``type`` (the plugin is the module's);
a ``filename`` in them names a file of the package's ``scenes/`` folder (toon's colour
ramps), whose path the readers put in front (``in_folder``). Labels and keys are given
without the plugin name, which the readers put in front too: ``("sigma=0.3", {...})`` of
``oren_nayar`` is the row ``oren_nayar sigma=0.3``, and an empty label is the plugin alone.
A model declares only what fits it; ``tests/test_layout.py`` says which fields every model
fills.
"""
import dataclasses
import os

__all__ = ["Facts", "RED", "rgb", "white", "label", "in_folder"]


def rgb(r, g, b):
    """An ``rgb`` colour property."""
    return {"type": "rgb", "value": [r, g, b]}


def white(v):
    """A grey ``rgb`` of value ``v`` (the catalog's specular colours)."""
    return rgb(v, v, v)


#: the catalog's diffuse colour: every model shows the same red
RED = rgb(0.5, 0.1, 0.08)


def label(plugin, suffix, sep=" "):
    """``plugin`` followed by ``suffix`` (nothing when the suffix is empty)."""
    return f"{plugin}{sep}{suffix}" if suffix else plugin


def in_folder(settings, folder):
    """``settings`` with each ``filename`` in it, at any depth, taken in ``folder``."""
    if isinstance(settings, dict):
        return {k: os.path.join(folder, v) if k == "filename" else in_folder(v, folder)
                for k, v in settings.items()}
    return settings


@dataclasses.dataclass(frozen=True)
class Facts:
    #: the parameter of the model's main (diffuse) colour, a reflectance in [0, 1]
    colour: str = None
    #: the continuous parameters of the plugin contract (MODELS.md), which ``mi.traverse``
    #: exposes as differentiable at the defaults
    differentiable: tuple = ()
    #: a value other than the default for parameters of each kind the model has (float,
    #: colour as an (r, g, b) tuple, integer, string): a scene written in XML renders as the
    #: same scene as a dict
    non_default: dict = dataclasses.field(default_factory=dict)
    #: settings at the edges of the documented ranges: eval, pdf and samples stay finite
    #: at nearly opposite grazing directions
    edges: tuple = ()
    #: (settings, relative tolerance): eval against the float64 formula of
    #: ``tests/reference.py`` at nearly opposite grazing directions
    float64: tuple = ()
    #: (settings, relative tolerance): the model's representative settings, every form:
    #: eval against the float64 formula of ``tests/reference.py`` at random pairs and mirror
    #: pairs (h = n), sample weights = eval / pdf from four incidences, and reciprocity
    #: (unless ``not_reciprocal`` says otherwise)
    cases: tuple = ()
    #: settings (parts of them) whose model is not reciprocal by design (``{}``: every
    #: setting): a case that includes one must show it (f(a, b) != f(b, a))
    not_reciprocal: tuple = ()
    #: (label, settings, theta_i in degrees, ires): Mitsuba's chi-square test of ``sample``
    #: against ``pdf`` (a ``component`` entry selects that lobe through the context)
    chi2: tuple = ()
    #: {parameter: values}: the stability grid, every combination: eval, pdf and samples
    #: finite and >= 0 at the hard directions and corner samples, sampled directions unit
    stability: dict = dataclasses.field(default_factory=dict)
    #: (label, settings): rendered in llvm_ad_rgb with ``path`` and ``direct`` (lit, finite);
    #: the first one in scalar_rgb too
    renders: tuple = ()
    #: settings at the edges of the ranges where gradients (every parameter, both
    #: directions) stay finite at the hard directions
    gradient_edges: tuple = ({},)
    #: (settings, parameters): reverse- and forward-mode gradients of a render agree with
    #: finite differences for these parameters, or None
    finite_difference: tuple = None
    #: (parameter, value that removes a lobe, value that gives it back, other settings):
    #: one per lobe a value can remove; an update brings the lobe back in every wrapper
    zero_lobes: tuple = ()
    #: (settings, expected albedo AOV as [r, g, b])
    albedo: tuple = ()
    #: settings with the parameters the model reads only when they are given (another
    #: parameterisation, an optional texture): loaded in every input form and variant
    on_request: tuple = ()
    #: settings whose load-time choices trace other code than the defaults: rendered in
    #: the other CPU variants
    traced_options: tuple = ()
    #: parameter -> the settings it only loads with, where the model's ``RELATIONS``
    #: (``core.relations``) do not say it (a rule on values)
    companions: dict = dataclasses.field(default_factory=dict)
    #: what ``check`` reports as a note, not a failure, at the defaults (a property the
    #: model lacks by design, e.g. reciprocity)
    check_notes: frozenset = frozenset()
    #: (label, settings) rows of the property table: 2-3 per form, white colours
    properties: tuple = ()
    #: (label, settings) tiles of the catalog figure, with the same ``RED`` diffuse colour
    catalog: tuple = ()
    #: (key, settings, Mitsuba's C++ BSDF dict, why that neighbour): timed side by side
    cpp: tuple = ()
    #: (key, settings without the lobe, settings with a tiny one, what): a lobe of zero
    #: weight must be dropped from the kernel (fewer instructions, less time)
    dropped_lobes: tuple = ()
