"""Binding the package's model classes to Mitsuba variants and registering them.

A Python ``mi.BSDF`` subclass belongs to the variant that was active when the class was
created, and nanobind accepts a single base class. So each model is written as a plain
class (with a plain base, ``TwoLobeModel``), and for every variant a ``mi.BSDF`` subclass
is built from the methods of the model's MRO. That class is registered under the model's
plugin name; registering again (same or other variant) is harmless.
"""
import mitsuba as mi

from .llvm import check_llvm

__all__ = ["bsdf_plugin", "models", "bind", "register"]

_MODELS = {}
_BOUND = {}


def bsdf_plugin(name):
    """Class decorator: make ``cls`` the model behind plugin ``name``."""
    def deco(cls):
        cls.NAME = name
        _MODELS[name] = cls
        return cls
    return deco


def models():
    """Plugin name -> model class, for every model of the package."""
    return dict(_MODELS)


def bind(name, variant=None):
    """The ``mi.BSDF`` subclass of plugin ``name`` for ``variant`` (default: the active one)."""
    variant = variant or mi.variant()
    if variant is None:
        raise RuntimeError("mitsuba_brdfs: no Mitsuba variant is set; call mi.set_variant() first")
    key = (variant, name)
    if key not in _BOUND:
        if mi.variant() != variant:
            raise RuntimeError(f"mitsuba_brdfs: cannot bind to {variant!r} while "
                               f"{mi.variant()!r} is active")
        model = _MODELS[name]
        ns = {}
        for klass in reversed(model.__mro__[:-1]):  # without `object`
            ns.update({k: v for k, v in vars(klass).items()
                       if k not in ("__dict__", "__weakref__")})
        _BOUND[key] = type(model.__name__, (mi.BSDF,), ns)
    return _BOUND[key]


def register():
    """Register every plugin of the package in the active Mitsuba variant."""
    variant = mi.variant()
    if variant is None:
        raise RuntimeError("mitsuba_brdfs: no Mitsuba variant is set; call mi.set_variant() first")
    check_llvm(variant)
    for name in _MODELS:
        cls = bind(name, variant)
        mi.register_bsdf(name, lambda props, cls=cls: cls(props))
    return sorted(_MODELS)
