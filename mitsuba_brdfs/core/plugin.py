"""Binding the package's model classes to Mitsuba variants and registering them.

A Python ``mi.BSDF`` subclass belongs to the variant that was active when the class was
created, and nanobind accepts a single base class. So each model is written as a plain
class (with a plain base, ``TwoLobeModel``), and for every variant a ``mi.BSDF`` subclass
is built from the methods of the model's MRO. That class is registered under the model's
plugin name; registering again (same or other variant) is harmless.

A plugin may build another model for one value of a load-time parameter (``oren_nayar``
with ``form = energy_preserving`` is EON): that model is declared with
``bsdf_plugin(name, form=(parameter, value))``, and the plugin's constructor picks it when
the scene gives that value.
"""
import mitsuba as mi

from .llvm import check_llvm

__all__ = ["bsdf_plugin", "models", "bind", "register"]

_MODELS = {}
#: plugin name -> {(parameter, value): the model built when the parameter has that value}
_FORMS = {}
_BOUND = {}


def bsdf_plugin(name, form=None):
    """Class decorator: make ``cls`` the model behind plugin ``name``; with ``form`` =
    (parameter, value), the model that plugin builds instead when its load-time string
    ``parameter`` is ``value``."""
    def deco(cls):
        cls.NAME = name
        if form is None:
            _MODELS[name] = cls
        else:
            _FORMS.setdefault(name, {})[form] = cls
        return cls
    return deco


def models():
    """Plugin name -> model class, for every model of the package."""
    return dict(_MODELS)


def bind(name, variant=None, model=None):
    """The ``mi.BSDF`` subclass of plugin ``name`` (or of its form ``model``) for ``variant``
    (default: the active one)."""
    variant = variant or mi.variant()
    if variant is None:
        raise RuntimeError("mitsuba_brdfs: no Mitsuba variant is set; call mi.set_variant() first")
    model = model or _MODELS[name]
    key = (variant, model)
    if key not in _BOUND:
        if mi.variant() != variant:
            raise RuntimeError(f"mitsuba_brdfs: cannot bind to {variant!r} while "
                               f"{mi.variant()!r} is active")
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
        forms = {form: bind(name, variant, model) for form, model in _FORMS.get(name, {}).items()}
        mi.register_bsdf(name, lambda props, cls=cls, forms=forms: _chosen(props, cls, forms)(props))
    return sorted(_MODELS)


def _chosen(props, cls, forms):
    """The class whose form ``props`` asks for, else the plugin's own (which reads, and
    refuses, any other value)."""
    for (parameter, value), form_cls in forms.items():
        if parameter in props and props.get(parameter) == value:
            return form_cls
    return cls
