"""Rendering the figure scenes of ``scenes/`` into ``renders/``.

A figure is one or more panels; each panel renders a scene XML with some ``<default>``
overrides. Panels are rendered in passes (bounded memory) with a progress bar, written as
EXR + PNG, and composed side by side, labelled, into ``renders/<figure>.png``.
Seconds and spp per figure go to ``renders/timings.json``.

    python -m mitsuba_brdfs figures [--quality preview|final] [--only NAME ...]
"""
import dataclasses
import json
import os
import time

import numpy as np

from . import render as R

__all__ = ["Panel", "Figure", "FIGURES", "render_figure", "compose", "add_arguments", "run"]

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SCENES = os.path.join(ROOT, "scenes")


@dataclasses.dataclass
class Panel:
    scene: str                 # file name in scenes/
    label: str = ""
    defines: dict = dataclasses.field(default_factory=dict)


@dataclasses.dataclass
class Figure:
    name: str
    title: str
    panels: list
    spp: dict                  # quality -> spp
    res: dict                  # quality -> resolution (the scene's `res` default)
    columns: int = 0           # 0: all panels in one row


FIGURES = {f.name: f for f in [
    Figure("as_sphere", "Ashikhmin-Shirley sphere: nu = 20, nv = 1000, Rs = 0.05, red Rd",
           [Panel("as_sphere.xml")], spp={"preview": 64, "final": 256},
           res={"preview": 256, "final": 512}),
]}


def _font(size):
    from PIL import ImageFont
    try:
        return ImageFont.load_default(size=size)
    except TypeError:  # Pillow < 10.1
        return ImageFont.load_default()


def compose(tiles, labels, columns=0, title="", pad=6):
    """Place tone-mapped (H, W, 3) uint8 tiles on a grid with a label under each."""
    from PIL import Image, ImageDraw
    n = len(tiles)
    cols = columns or n
    rows = (n + cols - 1) // cols
    th = max(t.shape[0] for t in tiles)
    tw = max(t.shape[1] for t in tiles)
    fsize = max(11, min(18, tw // 14))
    label_h = fsize + 2 * pad if any(labels) else 0
    title_h = fsize + 2 * pad if title else 0
    W = cols * tw + (cols + 1) * pad
    H = title_h + rows * (th + label_h) + (rows + 1) * pad
    canvas = Image.new("RGB", (W, H), (255, 255, 255))
    draw = ImageDraw.Draw(canvas)
    font = _font(fsize)
    if title:
        draw.text((pad, pad), title, fill=(0, 0, 0), font=font)
    for i, (tile, label) in enumerate(zip(tiles, labels)):
        r, c = divmod(i, cols)
        x = pad + c * (tw + pad)
        y = title_h + pad + r * (th + label_h + pad)
        canvas.paste(Image.fromarray(tile), (x, y))
        if label:
            draw.text((x + 2, y + th + pad // 2), label, fill=(0, 0, 0), font=font)
    return np.array(canvas)


def render_figure(fig, quality="preview", out_dir=None, pass_samples=R.DEFAULT_PASS_SAMPLES,
                  spp=None, res=None):
    """Render every panel of ``fig``; write EXRs, panel PNGs and the composed PNG.

    Returns a dict of timings (seconds, spp, resolution, panels).
    """
    out_dir = out_dir or os.path.join(ROOT, "renders")
    spp = spp or fig.spp[quality]
    res = res or fig.res[quality]
    tiles, labels, seconds = [], [], 0.0
    t0 = time.perf_counter()
    for k, panel in enumerate(fig.panels):
        defines = {"res": res, **panel.defines}
        scene = R.load_scene(os.path.join(SCENES, panel.scene), defines)
        label = f"{fig.name} {k + 1}/{len(fig.panels)}"
        image, sec = R.render_passes(scene, spp, pass_samples, label=label)
        seconds += sec
        stem = fig.name if len(fig.panels) == 1 else f"{fig.name}_{k + 1}"
        R.write_exr(os.path.join(out_dir, stem + ".exr"), image)
        tiles.append(R.tonemap(image))
        labels.append(panel.label)
    if len(tiles) == 1 and not labels[0]:
        R.write_png(os.path.join(out_dir, fig.name + ".png"), tiles[0], already_tonemapped=True)
    else:
        R.write_png(os.path.join(out_dir, fig.name + ".png"),
                    compose(tiles, labels, fig.columns, fig.title), already_tonemapped=True)
    return {"seconds_render": round(seconds, 3),
            "seconds_total": round(time.perf_counter() - t0, 3),
            "spp": spp, "resolution": res, "panels": len(fig.panels), "quality": quality}


def add_arguments(p):
    p.add_argument("--quality", choices=("preview", "final"), default="preview",
                   help="sample count and resolution (default: %(default)s)")
    p.add_argument("--only", nargs="+", metavar="NAME", choices=sorted(FIGURES),
                   help="render only these figures: " + ", ".join(sorted(FIGURES)))
    p.add_argument("--out", default=os.path.join(ROOT, "renders"), help="output directory")
    p.add_argument("--variant", default="llvm_ad_rgb")
    p.add_argument("--pass-samples", type=int, default=R.DEFAULT_PASS_SAMPLES)


def run(args):
    R.set_variant(args.variant)
    names = args.only or list(FIGURES)
    timings_path = os.path.join(args.out, "timings.json")
    timings = {}
    if os.path.exists(timings_path):
        with open(timings_path) as f:
            timings = json.load(f)
    for name in names:
        t = render_figure(FIGURES[name], args.quality, args.out, args.pass_samples)
        timings[name] = t
        print(f"{name}: {t['seconds_total']:.1f} s ({t['panels']} panel(s), {t['spp']} spp, "
              f"{t['resolution']} px)")
    os.makedirs(args.out, exist_ok=True)
    with open(timings_path, "w") as f:
        json.dump(timings, f, indent=2, sort_keys=True)
        f.write("\n")
    return 0
