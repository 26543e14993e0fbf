"""Where the package finds its data: the figure scenes and the examples.

The scenes (plain Mitsuba XML, and the bitmaps they use) live in the top-level ``scenes/``
folder of the source tree, beside ``mitsuba_brdfs/``, and the examples (a user's plugin with
its pytest file) in ``examples/``; a wheel installs them inside the package as
``mitsuba_brdfs/scenes/`` and ``mitsuba_brdfs/examples/`` (``pyproject.toml`` maps those
packages to the folders). ``SCENES`` and ``EXAMPLES`` are whichever of the two holds them:
the installed copy, else the source tree's (a checkout, or an editable install of it).

``installed_copy`` lets the commands the README shows run from any folder: a relative name
such as ``scenes/as_sphere.xml`` or ``mydiffuse.py`` that is not a file there names the
copy installed with the package; ``copied_example`` first, the copy the ``examples``
command made in the current folder (the one a user edits).
"""
import os

__all__ = ["SCENES", "EXAMPLES", "installed_copy", "copied_example"]

_PACKAGE = os.path.dirname(os.path.abspath(__file__))


def _data_folder(name, probe):
    """The installed folder ``name`` if it holds ``probe``, else the source tree's."""
    installed = os.path.join(_PACKAGE, name)
    # a file, not the folder: a checkout may keep an empty mitsuba_brdfs/scenes/__pycache__
    if os.path.isfile(os.path.join(installed, probe)):
        return installed
    return os.path.join(os.path.dirname(_PACKAGE), name)


#: the folder of the figure scenes
SCENES = _data_folder("scenes", "as_sphere.xml")
#: the folder of the examples (``mydiffuse/``: a user's plugin and its pytest file)
EXAMPLES = _data_folder("examples", os.path.join("mydiffuse", "mydiffuse.py"))


def installed_copy(path):
    """The file of the package's scenes or examples that a relative ``path`` names when it
    is not a file here (``scenes/as_sphere.xml``, ``as_sphere.xml``,
    ``examples/mydiffuse/mydiffuse.py``, ``mydiffuse.py``), or None. A path that exists, an
    absolute one, or one whose folders are not ``scenes/`` or ``examples/...`` names none."""
    path = os.fspath(path)
    if os.path.isabs(path) or os.path.exists(path):
        return None
    parts = os.path.normpath(path).split(os.sep)
    name, folders = parts[-1], parts[:-1]
    candidates = []
    if not folders or folders == ["scenes"]:
        candidates.append(os.path.join(SCENES, name))
    if folders and folders[0] == "examples":
        candidates.append(os.path.join(EXAMPLES, *folders[1:], name))
    elif not folders and os.path.isdir(EXAMPLES):
        candidates += [os.path.join(EXAMPLES, d, name) for d in sorted(os.listdir(EXAMPLES))]
    return next((c for c in candidates if os.path.isfile(c)), None)


def copied_example(path):
    """The file of the examples that ``python -m mitsuba_brdfs examples`` copied into
    ``examples/`` of the current folder that a bare name (``mydiffuse.py``) names, when it
    is not a file here: ``examples/mydiffuse/mydiffuse.py``, the copy a user edits; or
    None."""
    path = os.fspath(path)
    if os.path.isabs(path) or os.path.exists(path) or os.path.dirname(path) \
            or not os.path.isdir(EXAMPLES):
        return None
    found = [(os.path.join("examples", d, path), os.path.join(EXAMPLES, d, path))
             for d in sorted(os.listdir(EXAMPLES))]
    # (in a checkout, examples/ here is the package's own: not a copy)
    return next((f for f, own in found if os.path.isfile(f)
                 and not (os.path.isfile(own) and os.path.samefile(f, own))), None)
