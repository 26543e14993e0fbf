"""Measured materials in the explorer: an RGL file through Mitsuba's ``measured`` plugin, a
MERL file through the RGL file ``to-rgl`` makes of it (cached).

``is_measured(spec)`` says whether SPEC names a measured file rather than a plugin or an XML
file: any file that is not XML, then recognised as ``measured.read`` recognises it
(``measured.merl.kind``: an RGL file by its ``tensor_file`` header, a MERL file by its
size), whatever its extension. ``rgl_file(path)`` gives the RGL file to load: the file
itself, or for a MERL file the one ``to-rgl`` writes of it at its default resolution
(``measured.acquire``: ``Resolution``, ``acquire``; MERL's table looked up as its reader
does, ``measured.merl.evaluator``)
kept in ``cache_folder()`` under a name made of the MERL file's SHA-256, the resolution and
a digest of the converter's code (``converter_version``): the second start reads it back,
and a file changed in place or a new converter gives a new name. The folder is
``$MITSUBA_BRDFS_CACHE``, else ``$XDG_CACHE_HOME/mitsuba_brdfs/rgl``, else
``~/.cache/mitsuba_brdfs/rgl`` (a file of 1.25 MiB per MERL file; deleting it is safe);
where it cannot be written, the conversion goes to a temporary folder removed when the
process ends (and the entry says so).

``measured`` is one-sided, exposes nothing to ``mi.traverse`` and reads RGB files in RGB
variants only (spectral ones in spectral variants): a file of the other kind is refused in
one line, as is a MERL file in a spectral variant (``to-rgl`` writes RGB files).
"""
import atexit
import functools
import hashlib
import os
import shutil
import tempfile

__all__ = ["is_measured", "cache_folder", "converter_version", "rgl_file", "describe"]

#: the modules whose code makes a MERL file's RGL file: their digest names the cache's files
_CONVERTER = ("measured/merl.py", "measured/acquire.py", "measured/tensor.py", "measured/warp.py",
              "explore/measurement.py")


def _is_xml(path):
    with open(path, "rb") as f:
        return f.read(256).lstrip().startswith(b"<")


def is_measured(spec):
    """True if ``spec`` is a file that is not XML (an RGL or MERL file, or a file that
    claims to be one: ``rgl_file`` then says what is wrong with it)."""
    if not isinstance(spec, str) or spec.lower().endswith(".xml") or not os.path.isfile(spec):
        return False
    try:
        return not _is_xml(spec)
    except OSError:
        return False


def cache_folder():
    """Where MERL files' RGL files are kept (see the module docstring)."""
    if os.environ.get("MITSUBA_BRDFS_CACHE"):
        return os.environ["MITSUBA_BRDFS_CACHE"]
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return os.path.join(base, "mitsuba_brdfs", "rgl")


@functools.lru_cache(maxsize=1)
def converter_version():
    """A digest of the converter's code (12 hex digits)."""
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    h = hashlib.sha256()
    for name in _CONVERTER:
        with open(os.path.join(root, name), "rb") as f:
            h.update(f.read())
    return h.hexdigest()[:12]


def _digest(path):
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for chunk in iter(lambda: f.read(1 << 20), b""):
            h.update(chunk)
    return h.hexdigest()


_TEMPORARY = []


def _temporary_folder():
    if not _TEMPORARY:
        folder = tempfile.mkdtemp(prefix="mitsuba_brdfs-rgl-")
        atexit.register(shutil.rmtree, folder, True)
        _TEMPORARY.append(folder)
    return _TEMPORARY[0]


def _res_tag(res):
    return f"t{res.theta_i}g{res.grid}v{res.vndf}n{res.ndf}"


def _convert_merl(path, res):
    """(the RGL file of the MERL file ``path``, whether it came from the cache, why it is
    not in the cache or None)."""
    import numpy as np
    from ..measured import acquire, tensor
    from ..measured.merl import evaluator
    stem = os.path.splitext(os.path.basename(path))[0]
    name = f"{stem}-{_digest(path)[:16]}-{_res_tag(res)}-{converter_version()}.bsdf"
    folder = cache_folder()
    target = os.path.join(folder, name)
    if os.path.isfile(target):
        return target, True, None
    evaluate = evaluator(path)[0]
    theta = np.radians(np.linspace(0, 85, 18))
    d = np.stack([np.sin(theta), 0 * theta, np.cos(theta)], -1)
    if not (evaluate(d, d) > 0).any():
        raise ValueError(f"{path}: reflects nothing back towards the light (its "
                         f"retro-reflection is 0 everywhere), so there is no NDF to measure "
                         f"and no RGL file to draw")
    fields, _ = acquire.acquire(evaluate, res, description=f"to-rgl: MERL "
                                f"{os.path.basename(path)}", isotropic=True)

    def write(into):   # whole: a stopped write leaves nothing at ``into``
        tensor.write(into, fields)
        return into
    try:
        os.makedirs(folder, exist_ok=True)
        return write(target), False, None
    except OSError as e:
        reason = f"the cache {folder} cannot be written ({e.strerror or e})"
        return write(os.path.join(_temporary_folder(), name)), False, reason


def rgl_file(path):
    """What the entry of the measured file ``path`` loads: {'kind': 'rgl' or 'merl',
    'file': path, 'rgl': the RGL file (absolute), 'cached': a MERL file's RGL file was
    found in the cache, 'note': a sentence or None}. ``ValueError`` (one line naming the
    file) for a file that is neither, a truncated one, or one of the other variant."""
    import mitsuba as mi
    from ..measured import rgl
    from ..measured.acquire import Resolution
    from ..measured.merl import kind
    path = os.path.abspath(path)
    what = kind(path)   # FormatError (a ValueError) names a file that is neither
    if what == "rgl":
        material = rgl.load_for_variant(path, "explore")
        return {"kind": "rgl", "file": path, "rgl": path, "cached": False, "note": None,
                "description": material.description}
    if not mi.is_rgb:
        raise ValueError(f"{path}: a MERL file is shown through the RGL file to-rgl writes "
                         f"of it, an RGB one, which Mitsuba's measured reads in RGB variants "
                         f"only (explore --variant llvm_ad_rgb)")
    res = Resolution()
    target, cached, why = _convert_merl(path, res)
    note = (f"converted by to-rgl ({res.theta_i} incidences, {res.grid} x {res.grid} grid); "
            + (f"read from the cache {target}" if cached else
               f"kept in {target} for the next start" if why is None else
               f"{why}: kept in {target} until explore stops"))
    return {"kind": "merl", "file": path, "rgl": target, "cached": cached, "note": note,
            "description": f"MERL {os.path.basename(path)}"}


def describe(info):
    """The sentence the page shows under a measured entry's name."""
    what = ("an RGL file, drawn through Mitsuba's measured plugin" if info["kind"] == "rgl"
            else "a MERL file, drawn through Mitsuba's measured plugin from the RGL file "
                 "to-rgl makes of it")
    return f"measured data: {what}. It has no parameters (measured exposes none)."
