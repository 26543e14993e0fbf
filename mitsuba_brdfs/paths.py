"""Where the package finds its data: the figure scenes.

The scenes (plain Mitsuba XML, and the bitmaps they use) live in the top-level ``scenes/``
folder of the source tree, beside ``mitsuba_brdfs/``; a wheel installs them inside the
package as ``mitsuba_brdfs/scenes/`` (``pyproject.toml`` maps that package to the folder).
``SCENES`` is whichever of the two holds them: the installed copy, else the source tree's
(a checkout, or an editable install of it).
"""
import os

__all__ = ["SCENES"]

_PACKAGE = os.path.dirname(os.path.abspath(__file__))


def _scenes_folder():
    """The installed scenes if there are any, else the source tree's."""
    installed = os.path.join(_PACKAGE, "scenes")
    # a file, not the folder: a checkout may keep an empty mitsuba_brdfs/scenes/__pycache__
    if os.path.isfile(os.path.join(installed, "as_sphere.xml")):
        return installed
    return os.path.join(os.path.dirname(_PACKAGE), "scenes")


#: the folder of the figure scenes
SCENES = _scenes_folder()
