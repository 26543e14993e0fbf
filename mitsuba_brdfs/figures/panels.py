"""Figures made of panels: render each panel in passes, compose them on a labelled grid.

A figure is one or more panels; each panel renders a scene XML of ``scenes/`` with some
``<default>`` overrides (or a scene built in Python, as the catalog's). Panels are
rendered in passes (bounded memory) with a progress bar, written as EXR, and composed on
a grid, labelled, into ``<out>/<figure>.png``. The paper's figures are in ``paper``, the
model catalog in ``catalog``, the ``figures`` command in ``command``.
"""
import dataclasses
import os
import re
import time

import numpy as np

from .. import output, passes, variant
from ..passes import DEFAULT_PASS_SAMPLES
from ..arguments import default_out
from ..paths import SCENES

__all__ = ["Panel", "Figure", "size_defines", "render_figure", "compose", "wrap_text"]


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
    return variant.load_scene(os.path.join(SCENES, panel.scene), defines)


def render_figure(fig, quality="preview", out_dir=None, pass_samples=DEFAULT_PASS_SAMPLES,
                  spp=None, res=None):
    """Render every panel of ``fig``; write one EXR per panel and the composed PNG.

    Samples per pixel: ``spp`` when given (quick test renders), else the panel's own
    ``Panel.spp``, else the figure's spp for ``quality``. ``res`` (n or (width, height))
    overrides the figure's size. Returns a dict of timings (seconds, spp, resolution,
    panels); ``spp`` is a list when the panels differ.
    """
    out_dir = out_dir or default_out("figures")
    size = res or fig.res[quality]
    tiles, labels, seconds, spps = [], [], [], []
    t0 = time.perf_counter()
    for k, panel in enumerate(fig.panels):
        n = spp or panel.spp or fig.spp[quality]
        scene = _load(panel, {**size_defines(size), **panel.defines})
        label = f"{fig.name} {k + 1}/{len(fig.panels)}"
        image, sec = passes.render_passes(scene, n, pass_samples, label=label)
        del scene
        seconds.append(sec)
        spps.append(n)
        stem = fig.name if len(fig.panels) == 1 else f"{fig.name}_{k + 1}"
        output.write_exr(os.path.join(out_dir, stem + ".exr"), image)
        tiles.append(output.tonemap(image))
        labels.append(panel.label)
    if len(tiles) == 1 and not labels[0]:
        output.write_png(os.path.join(out_dir, fig.name + ".png"), tiles[0], already_tonemapped=True)
    else:
        output.write_png(os.path.join(out_dir, fig.name + ".png"),
                    compose(tiles, labels, fig.columns, fig.title), already_tonemapped=True)
    t = {"seconds_render": round(sum(seconds), 3),
         "seconds_total": round(time.perf_counter() - t0, 3),
         "spp": spps[0] if len(set(spps)) == 1 else spps,
         "resolution": list(size) if isinstance(size, (tuple, list)) else size,
         "panels": len(fig.panels), "quality": quality}
    if len(set(spps)) > 1:
        t["seconds_per_panel"] = [round(s, 3) for s in seconds]
    return t
