"""Rendering the figures of ``scenes/`` (and the model catalog) into ``renders/``.

A figure is one or more panels; each panel renders a scene XML with some ``<default>``
overrides (or a scene built in Python, as the catalog's). Panels are rendered in passes
(bounded memory) with a progress bar, written as EXR, and composed on a grid, labelled,
into ``renders/<figure>.png``. Seconds and spp per figure go to ``renders/timings.json``.

    python -m mitsuba_brdfs figures [--quality preview|final] [--only NAME ...]
    python -m mitsuba_brdfs figures --check [--only NAME ...]

The ``fig*`` figures reproduce Figures 1-4 and 6 of Ashikhmin & Shirley 2000; each scene
says in its comment block what it shows, why its light and camera, and how its integrator
was chosen. ``--check`` renders the checked panels of each figure with the scene's own
integrator and with a deeper path tracer and prints how far apart they are
(``check_integrator``): the numbers quoted in the scenes' comments. ``catalog`` is the
model catalog of ``catalog.py``: every model on the same sphere (models whose plugin is
not registered yet are left out with a note).
"""
import dataclasses
import json
import os
import re
import time

import numpy as np

from . import render as R

__all__ = ["Panel", "Figure", "FIGURES", "NAMES", "figure", "size_defines", "render_figure",
           "compose", "wrap_text", "scene_integrator", "check_integrator", "add_arguments",
           "run"]

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SCENES = os.path.join(ROOT, "scenes")


@dataclasses.dataclass
class Panel:
    #: file name in scenes/, or a callable(defines) -> mi.Scene (defines hold the size)
    scene: object
    label: str = ""
    defines: dict = dataclasses.field(default_factory=dict)
    spp: int = 0               # samples per pixel of this panel at every quality (0: the figure's)


@dataclasses.dataclass
class Figure:
    name: str
    title: str
    panels: list
    spp: dict                  # quality -> spp
    res: dict                  # quality -> n (the scene's `res`) or (width, height)
    columns: int = 0           # 0: all panels in one row
    check: tuple = (0,)        # panels compared with a deeper path tracer by --check


EXPONENTS = (10, 100, 1000, 10000)
VIEWS = ((10, "near-normal"), (60, "oblique"), (84, "grazing"))

FIGURES = {f.name: f for f in [
    Figure("as_sphere", "Ashikhmin-Shirley sphere: nu = 20, nv = 1000, Rs = 0.05, red Rd",
           [Panel("as_sphere.xml")], spp={"preview": 64, "final": 256},
           res={"preview": 256, "final": 512}),
    # Fig. 1: nu grows along a row, nv down a column; u is horizontal on screen
    Figure("fig1_exponents",
           "Fig. 1: metal spheres (Rd = 0). nu (exponent along u, horizontal on screen) "
           "grows to the right, nv (along v, vertical) downward",
           [Panel("fig1_exponents.xml", f"nu = {nu}, nv = {nv}", {"nu": nu, "nv": nv})
            for nv in EXPONENTS for nu in EXPONENTS],
           spp={"preview": 256, "final": 1024}, res={"preview": 160, "final": 320}, columns=4,
           check=(0, 8)),  # nu = nv = 10 and nu = 10, nv = 1000
    # Fig. 2: the exponents are given per direction on the cylinder (see the scene)
    Figure("fig2_brushed_cylinder",
           "Fig. 2: brushed metal cylinder, Rd = 0, Rs = 0.9, nu = 10, nv = 100",
           [Panel("fig2_brushed_cylinder.xml",
                  "u along the axis (nu = 10), v around (nv = 100): brushed around the "
                  "cylinder, the highlight streaks along it",
                  {"n_axis": 10, "n_around": 100}),
            Panel("fig2_brushed_cylinder.xml",
                  "u and v swapped (Mitsuba's own mapping, u around): brushed along the "
                  "axis, the highlight spreads around",
                  {"n_axis": 100, "n_around": 10})],
           spp={"preview": 256, "final": 1024}, res={"preview": 320, "final": 640},
           check=(0, 1)),
    Figure("fig3_polished",
           "Fig. 3: polished red floor, nu = nv = 400, Rs = 0.05, from near-normal to grazing",
           [Panel("fig3_polished.xml", f"{a} deg from the normal ({name})", {"view": a})
            for a, name in VIEWS],
           spp={"preview": 256, "final": 1024}, res={"preview": 288, "final": 576},
           check=(0, 2)),
    Figure("fig4_lambert_vs_as",
           "Fig. 4: a Lambertian sphere and an ashikhmin_shirley sphere with nu = nv = 5",
           [Panel("fig4_lambert_vs_as.xml",
                  "left: Lambert (Mitsuba's diffuse); right: ashikhmin_shirley nu = nv = 5, "
                  "Rs = 0.05; the same diffuse colour")],
           spp={"preview": 256, "final": 1024},
           res={"preview": (480, 240), "final": (960, 480)}),
    # Fig. 6 is about the sample counts: they stay 9, 26, 100 at every quality
    Figure("fig6_sampling", "Fig. 6: path tracer with the paper's sampling at 9, 26, 100 spp",
           [Panel("fig6_sampling.xml", f"{n} spp", spp=n) for n in (9, 26, 100)],
           spp={"preview": 100, "final": 100}, res={"preview": 288, "final": 576}),
]}

#: every figure name, in the order the command renders them; `catalog` is built when
#: rendered (it depends on which plugins are registered)
NAMES = list(FIGURES) + ["catalog"]


def figure(name):
    """The Figure called ``name`` (the catalog is built now, from the registered plugins)."""
    if name == "catalog":
        from .catalog import catalog_figure
        return catalog_figure()
    return FIGURES[name]


def size_defines(size):
    """Scene ``<default>`` overrides for an image size: ``res`` (square) or width, height."""
    if isinstance(size, (tuple, list)):
        return {"width": int(size[0]), "height": int(size[1])}
    return {"res": int(size)}


def _font(size):
    from PIL import ImageFont
    try:
        return ImageFont.load_default(size=size)
    except TypeError:  # Pillow < 10.1
        return ImageFont.load_default()


def wrap_text(draw, text, font, width):
    """Split ``text`` into lines at most ``width`` pixels wide.

    Explicit newlines are kept; lines break at spaces, except around "=" (so that
    "nu = 10" stays on one line), and a word wider than ``width`` on its own is cut
    between characters.
    """
    def fits(s):
        return draw.textlength(s, font=font) <= width

    lines = []
    for paragraph in text.split("\n"):
        start = len(lines)
        for word in (w for w in re.split(r"(?<![= ]) +(?![= ])", paragraph.strip()) if w):
            if len(lines) > start and fits(lines[-1] + " " + word):
                lines[-1] += " " + word
                continue
            while not fits(word) and len(word) > 1:
                cut = max(k for k in range(1, len(word) + 1) if k == 1 or fits(word[:k]))
                lines.append(word[:cut])
                word = word[cut:]
            lines.append(word)
        if len(lines) == start:  # an empty paragraph is an empty line
            lines.append("")
    return lines


def compose(tiles, labels, columns=0, title="", pad=6):
    """Place tone-mapped (H, W, 3) uint8 tiles on a grid with a label under each.

    Labels wrap to the width of a tile, the title to the width of the canvas; the label
    band is as tall as the longest label.
    """
    from PIL import Image, ImageDraw
    n = len(tiles)
    cols = min(columns or n, n)
    rows = (n + cols - 1) // cols
    th = max(t.shape[0] for t in tiles)
    tw = max(t.shape[1] for t in tiles)
    W = cols * tw + (cols + 1) * pad
    fsize = max(11, min(18, tw // 14))
    font = _font(fsize)
    measure = ImageDraw.Draw(Image.new("RGB", (1, 1)))
    line_h = fsize + 3
    label_lines = [wrap_text(measure, lb, font, tw - 4) if lb else [] for lb in labels]
    title_lines = wrap_text(measure, title, font, W - 2 * pad) if title else []
    label_h = max(len(ls) for ls in label_lines) * line_h + pad if any(labels) else 0
    title_h = len(title_lines) * line_h + pad if title else 0
    H = title_h + rows * (th + label_h) + (rows + 1) * pad
    canvas = Image.new("RGB", (W, H), (255, 255, 255))
    draw = ImageDraw.Draw(canvas)
    for k, line in enumerate(title_lines):
        draw.text((pad, pad + k * line_h), line, fill=(0, 0, 0), font=font)
    for i, (tile, lines) in enumerate(zip(tiles, label_lines)):
        r, c = divmod(i, cols)
        x = pad + c * (tw + pad)
        y = title_h + pad + r * (th + label_h + pad)
        canvas.paste(Image.fromarray(tile), (x, y))
        for k, line in enumerate(lines):
            draw.text((x + 2, y + th + pad // 2 + k * line_h), line, fill=(0, 0, 0), font=font)
    return np.array(canvas)


def _load(panel, defines):
    if callable(panel.scene):
        return panel.scene(defines)
    return R.load_scene(os.path.join(SCENES, panel.scene), defines)


def render_figure(fig, quality="preview", out_dir=None, pass_samples=R.DEFAULT_PASS_SAMPLES,
                  spp=None, res=None):
    """Render every panel of ``fig``; write one EXR per panel and the composed PNG.

    Samples per pixel: ``spp`` when given (quick test renders), else the panel's own
    ``Panel.spp``, else the figure's spp for ``quality``. ``res`` (n or (width, height))
    overrides the figure's size. Returns a dict of timings (seconds, spp, resolution,
    panels); ``spp`` is a list when the panels differ.
    """
    out_dir = out_dir or os.path.join(ROOT, "renders")
    size = res or fig.res[quality]
    tiles, labels, seconds, spps = [], [], [], []
    t0 = time.perf_counter()
    for k, panel in enumerate(fig.panels):
        n = spp or panel.spp or fig.spp[quality]
        scene = _load(panel, {**size_defines(size), **panel.defines})
        label = f"{fig.name} {k + 1}/{len(fig.panels)}"
        image, sec = R.render_passes(scene, n, pass_samples, label=label)
        del scene
        seconds.append(sec)
        spps.append(n)
        stem = fig.name if len(fig.panels) == 1 else f"{fig.name}_{k + 1}"
        R.write_exr(os.path.join(out_dir, stem + ".exr"), image)
        tiles.append(R.tonemap(image))
        labels.append(panel.label)
    if len(tiles) == 1 and not labels[0]:
        R.write_png(os.path.join(out_dir, fig.name + ".png"), tiles[0], already_tonemapped=True)
    else:
        R.write_png(os.path.join(out_dir, fig.name + ".png"),
                    compose(tiles, labels, fig.columns, fig.title), already_tonemapped=True)
    t = {"seconds_render": round(sum(seconds), 3),
         "seconds_total": round(time.perf_counter() - t0, 3),
         "spp": spps[0] if len(set(spps)) == 1 else spps,
         "resolution": list(size) if isinstance(size, (tuple, list)) else size,
         "panels": len(fig.panels), "quality": quality}
    if len(set(spps)) > 1:
        t["seconds_per_panel"] = [round(s, 3) for s in seconds]
    return t


# -- integrator check ---------------------------------------------------------------------

def scene_integrator(path, defines=None):
    """The integrator of a scene XML as a dict (``type`` and its properties), with the
    ``<default>`` values (overridden by ``defines``) substituted."""
    import xml.etree.ElementTree as ET
    root = ET.parse(path).getroot()
    values = {d.get("name"): d.get("value") for d in root.iter("default")}
    values.update({k: str(v) for k, v in (defines or {}).items()})

    def resolve(text):
        return values[text[1:]] if text.startswith("$") else text

    (elem,) = root.findall("integrator")
    props = {"type": resolve(elem.get("type"))}
    for child in elem:
        value = resolve(child.get("value"))
        props[child.get("name")] = {"integer": int, "float": float,
                                    "boolean": lambda v: v.lower() == "true"}[child.tag](value)
    return props


def _block_means(img, k=8):
    h, w, c = img.shape
    return img[:h // k * k, :w // k * k].reshape(h // k, k, w // k, k, c).mean(axis=(1, 3))


def _scene_size_defines(path, res):
    """The size overrides a scene accepts: ``res`` or ``width`` / ``height`` (aspect kept)."""
    import xml.etree.ElementTree as ET
    values = {d.get("name"): d.get("value") for d in ET.parse(path).getroot().iter("default")}
    if "res" in values:
        return {"res": res}
    w, h = float(values["width"]), float(values["height"])
    return {"width": max(1, round(res * w / h)), "height": res}


def check_integrator(scene, defines=None, res=128, spp=1024, reference_depth=16):
    """Compare a scene's integrator with a deeper path tracer; returns report lines.

    ``res`` is the image height (a wide scene keeps its aspect).

    ``direct``: direct renders with seeds 0 and 1 against ``path`` (``reference_depth``)
    with seed 2; the difference is compared with the noise (the two direct seeds), per
    pixel and on 8x8-pixel block means (which average the noise down). Then ``path`` with
    ``max_depth = 2`` (direct light only) against ``reference_depth`` with the same seed:
    the first bounces then take the same random numbers, so the difference is exactly what
    the deeper bounces add. ``path`` with ``max_depth = d``: that same-seed comparison for
    ``d - 1`` and ``d``, and the noise (the scene's integrator with seeds 0 and 1). "8-bit"
    differences are between the tone-mapped sRGB images of the block means, in levels of
    255.
    """
    import mitsuba as mi
    path = os.path.join(SCENES, scene) if not os.path.isabs(scene) else scene
    defines = dict(defines or {})
    props = scene_integrator(path, defines)
    loaded = R.load_scene(path, {**defines, **_scene_size_defines(path, res)})

    def render(seed, **change):
        integrator = mi.load_dict({**props, **change})
        return R.render_passes(loaded, spp, seed=seed, progress=False,
                               integrator=integrator)[0].astype(np.float64)

    def mad(a, b):
        return float(np.abs(a - b).mean())

    def levels(a, b):
        return float(np.abs(R.tonemap(_block_means(a)).astype(float)
                            - R.tonemap(_block_means(b)).astype(float)).max())

    name = os.path.basename(path) + "".join(f" {k}={v}" for k, v in defines.items())
    lines = [f"{name}: {res} px high, {spp} spp, integrator {props}"]
    ref = dict(type="path", max_depth=reference_depth)
    if props["type"] == "direct":
        d0, d1, p = render(0), render(1), render(2, **ref)
        lines.append(
            f"  direct vs path max_depth={reference_depth} (independent seeds): pixel MAD "
            f"{mad(d0, p):.5f} vs noise {mad(d0, d1):.5f}; 8x8 blocks "
            f"{mad(_block_means(d0), _block_means(p)):.5f} vs noise "
            f"{mad(_block_means(d0), _block_means(d1)):.5f}; means {d0.mean():.4f} vs {p.mean():.4f}")
        depths = [2]
    else:
        s0, s1 = render(0), render(1)
        lines.append(f"  noise ({props['type']} max_depth={props['max_depth']}, seeds 0 and 1): "
                     f"pixel MAD {mad(s0, s1):.5f}")
        depths = [props["max_depth"] - 1, props["max_depth"]]
    full = render(0, **ref)
    for d in depths:
        img = render(0, type="path", max_depth=d)
        lines.append(
            f"  path max_depth={d} vs {reference_depth} (same seed): deeper bounces add "
            f"{(full.mean() - img.mean()) / full.mean():.2%} of the mean, pixel MAD "
            f"{mad(img, full):.5f}, 8-bit 8x8-block max {levels(img, full):.0f}")
    return lines


# -- command line -------------------------------------------------------------------------

def add_arguments(p):
    p.add_argument("--quality", choices=("preview", "final"), default="preview",
                   help="sample count and resolution (default: %(default)s)")
    p.add_argument("--only", nargs="+", metavar="NAME", choices=NAMES,
                   help="render only these figures: " + ", ".join(NAMES))
    p.add_argument("--out", default=os.path.join(ROOT, "renders"), help="output directory")
    p.add_argument("--variant", default="llvm_ad_rgb")
    p.add_argument("--pass-samples", type=int, default=R.DEFAULT_PASS_SAMPLES)
    p.add_argument("--check", action="store_true",
                   help="instead of rendering, compare each figure's integrator with a deeper "
                        "path tracer on its checked panels (128 px, 1024 spp)")


def _check(names):
    for name in names:
        fig = figure(name)
        for k in fig.check:
            panel = fig.panels[k]
            if callable(panel.scene):
                print(f"{name}: built in Python, not checked")
                break
            print("\n".join(check_integrator(panel.scene, panel.defines)), flush=True)
    return 0


def run(args):
    R.set_variant(args.variant)
    names = args.only or NAMES
    if args.check:
        return _check(names)
    timings_path = os.path.join(args.out, "timings.json")
    timings = {}
    if os.path.exists(timings_path):
        with open(timings_path) as f:
            timings = json.load(f)
    t0 = time.perf_counter()
    for name in names:
        fig = figure(name)
        if not fig.panels:
            print(f"{name}: nothing to render")
            continue
        t = render_figure(fig, args.quality, args.out, args.pass_samples)
        timings[name] = t
        spp = t["spp"] if isinstance(t["spp"], int) else "/".join(map(str, t["spp"]))
        res = t["resolution"] if isinstance(t["resolution"], int) else "x".join(
            map(str, t["resolution"]))
        print(f"{name}: {t['seconds_total']:.1f} s ({t['panels']} panel(s), {spp} spp, "
              f"{res} px)", flush=True)
    total = time.perf_counter() - t0
    print(f"{len(names)} figure(s) in {total:.1f} s")
    timings["last_run"] = {"figures": names, "quality": args.quality,
                           "seconds_total": round(total, 3), "cpu_count": os.cpu_count()}
    os.makedirs(args.out, exist_ok=True)
    with open(timings_path, "w") as f:
        json.dump(timings, f, indent=2, sort_keys=True)
        f.write("\n")
    return 0
