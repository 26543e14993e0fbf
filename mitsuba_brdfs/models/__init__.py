"""The reflectance models; importing this package declares every plugin.

Every module of this package is one model; each is imported here, so a new model file
is picked up without editing this list.
"""
import importlib
import pkgutil

__all__ = sorted(m.name for m in pkgutil.iter_modules(__path__) if not m.name.startswith("_"))

for _name in __all__:
    importlib.import_module(f"{__name__}.{_name}")
