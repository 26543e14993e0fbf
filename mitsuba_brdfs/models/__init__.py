"""The reflectance models; importing this package declares every plugin.

Every module of this package is one model; each is imported here, so a new model file
is picked up without editing this list. A plugin's module declares ``FACTS``
(``core.facts.Facts``): what the generic tests, the property table, the catalog and the
performance study run of it; ``facts()`` collects them.
"""
import importlib
import os
import pkgutil
import sys

__all__ = sorted(m.name for m in pkgutil.iter_modules(__path__) if not m.name.startswith("_"))

for _name in __all__:
    importlib.import_module(f"{__name__}.{_name}")


def facts():
    """Plugin name -> the ``Facts`` its module declares (``FACTS``), for every plugin of the
    package, in name order; an empty ``Facts()`` where a module declares none (which
    ``tests/test_layout.py`` refuses, naming the module)."""
    from ..core.facts import Facts
    from ..core.plugin import models
    return {name: getattr(sys.modules[cls.__module__], "FACTS", None) or Facts()
            for name, cls in sorted(models().items())}


def module_of(plugin):
    """The file of the module that declares ``plugin``, as ``mitsuba_brdfs/models/<name>.py``
    (for messages)."""
    from ..core.plugin import models
    path = sys.modules[models()[plugin].__module__].__file__
    return os.path.relpath(path, os.path.dirname(os.path.dirname(os.path.dirname(path))))
