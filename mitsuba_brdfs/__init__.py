"""mitsuba_brdfs: analytic BRDF models as validated Mitsuba 3 plugins.

Usage::

    import mitsuba as mi
    mi.set_variant('llvm_ad_rgb')
    import mitsuba_brdfs          # registers every plugin in the active variant

    scene = mi.load_file('scenes/as_sphere.xml')

Registration follows the active variant: after a later ``mi.set_variant`` the plugins are
registered again automatically (``mitsuba_brdfs.register()`` does it by hand). In LLVM
variants the import checks first that Dr.Jit loaded LLVM >= 17 and raises
``LLVMVersionError`` saying what to install otherwise.
"""
import mitsuba as mi

from . import models  # noqa: F401  (declares the plugins)
from .core.llvm import LLVMVersionError, check_llvm
from .core.params import ParameterError
from .core.plugin import bind, register
from .core.registry import models as plugin_models

__all__ = ["register", "bind", "plugin_models", "check_llvm", "LLVMVersionError",
           "ParameterError", "__version__"]
__version__ = "0.1.0"


def _on_variant_change(old, new):
    if new is not None:
        register()


if not getattr(mi, "_mitsuba_brdfs_hooked", False):
    mi.detail.add_variant_callback(_on_variant_change)
    mi._mitsuba_brdfs_hooked = True

if mi.variant() is not None:
    register()
