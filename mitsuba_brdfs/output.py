"""Writing files whole, and images: the outputs of every command.

Every file a command writes goes through ``atomic``: it is written to a temporary file
beside the target and renamed over it, so an interrupted command never leaves a
half-written file, and ``written()`` can say which files were finished. ``write_text``
and ``save_figure`` are the two usual cases. ``check_target`` and ``check_folder`` refuse,
before any work, a target that cannot be written: a read-only or immutable file, a folder
where no file can be created.

Images: ``write_exr`` (OpenEXR, float32 or float16), ``write_hdr`` (PFM, RGBE),
``write_png`` / ``write_jpeg`` (8-bit sRGB through ``tonemap``), ``read_exr``.
"""
import contextlib
import errno
import json
import math
import os
import stat
import tempfile

import numpy as np

from .arguments import UsageError

__all__ = ["atomic", "written", "write_text", "write_json", "jsonable", "save_figure",
           "check_target", "check_folder", "write_exr", "read_exr", "write_hdr", "write_png", "write_jpeg",
           "tonemap", "color", "default_channels"]

_WRITTEN = []


def written(clear=False):
    """The files written whole (through ``atomic``) since the last ``written(clear=True)``."""
    files = list(_WRITTEN)
    if clear:
        _WRITTEN.clear()
    return files


def _new_file_mode():
    """The mode of a new file: 0o666 less the umask."""
    umask = os.umask(0)
    os.umask(umask)
    return 0o666 & ~umask


@contextlib.contextmanager
def atomic(path):
    """Yield a temporary path in the target's folder (with the target's extension); rename
    it over ``path`` on success. A file replaced keeps its mode; a read-only or immutable
    one is refused (``check_target``) before anything is written.

    The temporary file is removed whatever stops the write, a signal included (the command
    line turns SIGINT and SIGTERM into exceptions, so this ``finally`` runs)."""
    path = os.fspath(path)
    check_target(path, error=OSError)
    directory = os.path.dirname(os.path.abspath(path))
    os.makedirs(directory, exist_ok=True)
    try:
        mode = stat.S_IMODE(os.stat(path).st_mode)
    except OSError:
        mode = _new_file_mode()
    tmp = None
    try:
        fd, tmp = tempfile.mkstemp(prefix=".partial-", suffix=os.path.splitext(path)[1],
                                   dir=directory)
        os.close(fd)
        yield tmp
        os.chmod(tmp, mode)  # mkstemp makes it readable by its owner only
        os.replace(tmp, path)
        _WRITTEN.append(path)
    finally:
        if tmp is not None and os.path.exists(tmp):
            os.remove(tmp)


def write_text(path, text):
    """Write ``text`` to ``path``, atomically."""
    with atomic(path) as tmp, open(tmp, "w") as f:
        f.write(text)


def write_json(path, data, **kwargs):
    """Write ``data`` as JSON (``json.dump``'s ``kwargs``) and a final newline, atomically."""
    write_text(path, json.dumps(data, **kwargs) + "\n")


def jsonable(x):
    """``x`` as JSON holds it, the one way the package writes JSON (``check --json``, the
    explorer's answers, the performance study's results): NumPy scalars and arrays as
    Python numbers and lists, tuples as lists, keys as strings, and the non-finite floats
    JSON lacks as the strings "inf", "-inf", "nan"; anything else as it is."""
    if isinstance(x, dict):
        return {str(k): jsonable(v) for k, v in x.items()}
    if isinstance(x, np.ndarray):
        x = x.tolist()
    if isinstance(x, (list, tuple)):
        # the explorer's plots send ~1e5 numbers an answer: a list of finite floats as it is
        if all(type(v) is float for v in x) and all(map(math.isfinite, x)):
            return list(x)
        return [jsonable(v) for v in x]
    if isinstance(x, (bool, np.bool_)):
        return bool(x)
    if isinstance(x, (int, np.integer)):
        return int(x)
    if isinstance(x, (float, np.floating)):
        return float(x) if math.isfinite(x) else str(float(x))
    return x


def save_figure(fig, path, **kwargs):
    """``fig.savefig(path, **kwargs)`` (a Matplotlib figure), atomically."""
    with atomic(path) as tmp:
        fig.savefig(tmp, **kwargs)


# -- refusing what cannot be written ---------------------------------------------------------

def check_target(path, what=None, error=UsageError):
    """Refuse (``error``, by default ``UsageError``) a file that exists and may not be
    replaced: a folder, a file whose mode grants no write permission (root included,
    although the system would let root write it: ``mitsuba`` writes into the file
    itself, which a user's 0444 forbids), or an immutable or append-only file
    (``chattr +i`` / ``+a``: opening it for writing fails, even for root). Opening
    without truncating changes nothing in the file."""
    path = os.fspath(path)
    what = what or f"cannot write {path}"
    try:
        st = os.stat(path)
    except (FileNotFoundError, NotADirectoryError):
        return  # a new file (its folder is checked by ``check_folder``)
    except OSError as e:
        raise error(f"{what}: {e.strerror}") from None
    if stat.S_ISDIR(st.st_mode):
        raise error(f"{what}: is a folder")
    if not stat.S_ISREG(st.st_mode):
        return
    if not st.st_mode & 0o222:  # by the mode bits alone: os.access is False for an
        # immutable file too, even for root
        raise error(f"{what}: the file is read-only (mode {stat.S_IMODE(st.st_mode):04o}); "
                    f"refusing to replace it (make it writable, or choose another name)")
    try:
        os.close(os.open(path, os.O_WRONLY | os.O_NONBLOCK))
    except OSError as e:
        kind = ("is immutable or append-only (chattr +i / +a)" if e.errno == errno.EPERM
                else f"cannot be opened for writing ({e.strerror})")
        raise error(f"{what}: the file {kind}; refusing to replace it") from None


def check_folder(folder, what=None):
    """Refuse (``UsageError``) a folder that cannot be created or written into: its
    nearest existing ancestor must be a folder where a file can be created (the only
    reliable test: root passes ``os.access``). Creates nothing that stays."""
    what = what or f"cannot write into {folder}"
    existing = os.path.abspath(folder)
    while not os.path.exists(existing):
        existing = os.path.dirname(existing)
    if not os.path.isdir(existing):
        raise UsageError(f"{what}: {existing} is not a folder")
    try:
        fd, probe = tempfile.mkstemp(prefix=".partial-", dir=existing)
        os.close(fd)
        os.remove(probe)
    except OSError as e:
        raise UsageError(f"{what}: {existing}: {e.strerror}") from None


# -- images ----------------------------------------------------------------------------------

def default_channels(c):
    """Channel names of a ``c``-channel image: Y, YA, RGB, RGBA, or C0, C1, ..."""
    return {1: ["Y"], 2: ["Y", "A"], 3: ["R", "G", "B"], 4: ["R", "G", "B", "A"]}.get(
        c, [f"C{i}" for i in range(c)])


def _as_hwc(image, dtype=np.float32):
    img = np.asarray(image, dtype=dtype)
    return img[..., None] if img.ndim == 2 else img


def _write_bitmap(bmp, path, file_format):
    bmp.write(path, file_format)


def write_exr(path, image, channels=None, component_format="float32"):
    """Write an (H, W, C) image as a ZIP-compressed OpenEXR file, atomically, with
    ``component_format`` ``float32`` or ``float16`` (half, as Mitsuba's ``hdrfilm``
    writes by default) or ``uint32``.

    ``channels`` names the channels (default: Y, YA, RGB or RGBA by their count); X, Y, Z
    images carry the XYZ chromaticities, as Mitsuba's films write them. (The OpenEXR
    module, not ``mi.Bitmap.write``: Mitsuba's EXR writer hangs with a thread pool of one.)
    """
    import OpenEXR
    dtype = {"float32": np.float32, "float16": np.float16, "uint32": np.uint32}
    if component_format not in dtype:
        raise ValueError(f"EXR component_format {component_format!r}: use "
                         f"{', '.join(dtype)}")
    img = _as_hwc(image)
    if component_format == "uint32":
        img = np.clip(np.nan_to_num(img), 0, 2 ** 32 - 1).round()
    img = img.astype(dtype[component_format])
    names = list(channels or default_channels(img.shape[2]))
    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
    if names[:3] == ["X", "Y", "Z"]:
        header["chromaticities"] = (1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1 / 3, 1 / 3)
    pixels = {n: np.ascontiguousarray(img[..., i]) for i, n in enumerate(names)}
    with atomic(path) as tmp:
        _write_openexr(header, pixels, tmp)


def _write_openexr(header, pixels, path):
    import OpenEXR
    with OpenEXR.File(header, pixels) as f:
        f.write(path)


#: channel orders of the usual images (OpenEXR stores channels sorted by name)
_ORDERS = (["R", "G", "B", "A"], ["X", "Y", "Z", "A"], ["Y", "A"])


def read_exr(path, names=False):
    """Read an OpenEXR file as float32 (H, W, C) (and its channel names if ``names``):
    colour channels first (R, G, B, A or X, Y, Z, A or Y, A), the others by name."""
    import OpenEXR
    with OpenEXR.File(os.fspath(path), separate_channels=True) as f:
        chans = {k: v.pixels for k, v in f.channels().items()}
    order = []
    for colour in _ORDERS:
        if colour[0] in chans and (colour[0] != "Y" or "X" not in chans):
            order = [c for c in colour if c in chans]
            break
    order += sorted(set(chans) - set(order))
    img = np.stack([np.asarray(chans[n], dtype=np.float32) for n in order], axis=-1)
    return (img, order) if names else img


def color(image, channels):
    """The colour of a film image as linear sRGB (H, W, 3), or its luminance (H, W, 1)."""
    import mitsuba as mi
    image = _as_hwc(image)
    names = list(channels or default_channels(image.shape[2]))
    if names[:3] == ["R", "G", "B"]:
        return image[..., :3]
    if names[:3] == ["X", "Y", "Z"]:
        xyz = mi.Bitmap(np.ascontiguousarray(image[..., :3]), pixel_format=mi.Bitmap.PixelFormat.XYZ)
        return np.array(xyz.convert(mi.Bitmap.PixelFormat.RGB, mi.Struct.Type.Float32, False))
    if names[:1] == ["Y"]:
        return image[..., :1]
    raise ValueError(f"no colour channels (RGB, XYZ or Y) among {', '.join(names)}")


def write_hdr(path, image, channels=None, file_format="pfm"):
    """Write the colour of an image (linear sRGB, or luminance; alpha and AOVs left out,
    as Mitsuba's film does for these formats) as ``pfm`` (float32) or ``rgbe`` (Radiance
    .hdr; RGB), atomically."""
    import mitsuba as mi
    img = np.ascontiguousarray(color(image, channels), dtype=np.float32)
    if file_format == "rgbe" and img.shape[2] == 1:
        img = np.ascontiguousarray(np.repeat(img, 3, axis=2))
    fmt = mi.Bitmap.PixelFormat.Y if img.shape[2] == 1 else mi.Bitmap.PixelFormat.RGB
    kind = {"pfm": mi.Bitmap.FileFormat.PFM, "rgbe": mi.Bitmap.FileFormat.RGBE}[file_format]
    with atomic(path) as tmp:
        _write_bitmap(mi.Bitmap(img, pixel_format=fmt), tmp, kind)


def tonemap(image, exposure=0.0):
    """Linear RGB (or luminance) -> 8-bit sRGB (clamped): (H, W, 3) (or (H, W, 1)) uint8."""
    x = np.asarray(image, dtype=np.float64)[..., :3] * 2.0 ** exposure
    x = np.clip(np.nan_to_num(x, nan=0.0, posinf=1.0), 0.0, 1.0)
    srgb = np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1 / 2.4) - 0.055)
    return np.round(srgb * 255).astype(np.uint8)


def _write_ldr(path, image, exposure, already_tonemapped, file_format, channels=None):
    import mitsuba as mi
    img = np.asarray(image)
    if img.ndim == 2:
        img = img[..., None]
    if not already_tonemapped:
        img = tonemap(color(img, channels), exposure)
    img = np.array(img, dtype=np.uint8, order="C")
    fmt = mi.Bitmap.PixelFormat.Y if img.shape[2] == 1 else mi.Bitmap.PixelFormat.RGB
    bmp = mi.Bitmap(img, pixel_format=fmt)
    with atomic(path) as tmp:
        _write_bitmap(bmp, tmp, file_format)


def write_png(path, image, exposure=0.0, already_tonemapped=False, channels=None):
    """Write an 8-bit sRGB PNG, atomically: the colour of ``image`` (RGB, XYZ or luminance
    by ``channels``; alpha and AOVs are left out) tone-mapped from linear with
    ``exposure`` stops, unless ``already_tonemapped`` (uint8 RGB or grey)."""
    import mitsuba as mi
    _write_ldr(path, image, exposure, already_tonemapped, mi.Bitmap.FileFormat.PNG, channels)


def write_jpeg(path, image, exposure=0.0, already_tonemapped=False, channels=None):
    """``write_png`` as a JPEG (quality 100)."""
    import mitsuba as mi
    _write_ldr(path, image, exposure, already_tonemapped, mi.Bitmap.FileFormat.JPEG, channels)
