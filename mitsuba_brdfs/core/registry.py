"""Which models the package has: ``bsdf_plugin`` declares a model class as the plugin of a
name, or as the model that plugin builds for one value of a load-time parameter (a form);
``models()`` and ``forms(name)`` list them. Nothing here needs Mitsuba: ``core.plugin``
binds the declared models to Mitsuba's variants and registers them.
"""

__all__ = ["bsdf_plugin", "models", "forms"]

_MODELS = {}
#: plugin name -> {(parameter, value): the model built when the parameter has that value}
_FORMS = {}


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


def forms(name):
    """{(parameter, value): model class} of the forms of plugin ``name`` (often none)."""
    return dict(_FORMS.get(name, {}))
