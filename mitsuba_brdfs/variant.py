"""Setting Mitsuba up for a command: the variant, a user's plugin files, scenes.

``set_variant`` is the one way the commands activate a variant: it checks that the variant
can run here (``check_variant``), activates it and registers this package's plugins in it.
``run_file`` runs a user's Python file (``--load FILE.py``), which registers its own plugins
once the variant is set.
"""
import os
import re
import runpy

from .arguments import UsageError

__all__ = ["check_variant", "last_line", "set_variant", "run_file", "load_scene", "scene_spp"]

#: Mitsuba's variant names: backend, AD, colour, polarization, precision
_VARIANT = re.compile(r"(scalar|llvm|cuda|metal)(_ad)?_(rgb|mono|spectral)(_polarized)?(_double)?$")


def check_variant(variant):
    """Raise ``UsageError`` (or ``LLVMVersionError``) unless ``variant`` can run here.

    Checked before ``mi.set_variant``: it must be built into this Mitsuba, and its JIT
    backend must be present (a CUDA GPU, or a libLLVM of a release Dr.Jit can use).
    """
    import mitsuba as mi
    built = mi.variants()
    if variant not in built:
        what = (f"variant {variant!r} is not built into this Mitsuba" if _VARIANT.match(variant)
                else f"unknown variant {variant!r}")
        raise UsageError(f"{what} (it has {', '.join(built)})")
    if variant.startswith("llvm_"):
        from .core.llvm import check_llvm
        check_llvm(variant)
    elif variant.startswith("cuda_"):
        import drjit as dr
        if not dr.has_backend(dr.JitBackend.CUDA):
            raise UsageError(f"variant {variant!r} needs an NVIDIA GPU and its CUDA driver; "
                             f"Dr.Jit found none (the llvm_* variants run on the CPU)")


def set_variant(variant):
    """Activate ``variant`` (and register the plugins in it), after ``check_variant``."""
    import mitsuba as mi
    if mi.variant() != variant:
        check_variant(variant)
        mi.set_variant(variant)
    import mitsuba_brdfs
    mitsuba_brdfs.register()


def last_line(e):
    """The last non-blank line of an error's message (Mitsuba's put the cause last)."""
    lines = [ln.strip() for ln in str(e).splitlines() if ln.strip()]
    return lines[-1] if lines else ""


def run_file(path):
    """Run a user's Python file (``--load FILE.py``: it registers its plugins with
    ``mi.register_bsdf``), once the variant is set. A missing file is a
    ``FileNotFoundError``, a file that fails a ``ValueError`` naming it and the cause."""
    if not os.path.isfile(path):
        raise FileNotFoundError(f"--load {path}: no such file")
    try:
        runpy.run_path(path, run_name="__mitsuba_brdfs_load__")
    except (Exception, SystemExit) as e:
        raise ValueError(f"--load {path}: {type(e).__name__}: {last_line(e)}") from None


def load_scene(path, defines=None):
    """``mi.load_file`` with ``<default>`` overrides (strings, as ``-D key=value`` gives)."""
    import mitsuba as mi
    return mi.load_file(str(path), **{k: str(v) for k, v in (defines or {}).items()})


def scene_spp(scene, sensor=0):
    """The samples per pixel of the sensor's sampler."""
    return scene.sensors()[sensor].sampler().sample_count()
