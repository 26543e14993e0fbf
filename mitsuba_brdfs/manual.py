"""The plugin reference: one Markdown page per plugin, generated from its model's docstring.

The docstring is the one source of the text: its title, its parameter table (an RST simple
table: name, type, description ending in "(Default: ...)", the range written "in [lo, hi]"
or ">= lo"), the prose and equations, and its XML and Python examples. What the page adds
comes from the plugin itself, loaded with its defaults: the keys ``mi.traverse`` exposes and
their flags, a render of the sphere of ``scenes/as_sphere.xml`` and a lobe/albedo plot
measured with the plugin's own ``eval`` and ``sample`` (``validate.properties``). Writes
``<plugin>.md``, ``img/`` (not with ``--text-only``, whose pages show only the images an
earlier run left there) and the index ``README.md`` into ``--out`` (default
``mitsuba_brdfs-out/manual/``), and, when ``--out`` is the repository's ``docs/plugins``
(``make docs``), the plugin table of the top-level README (between its ``plugins``
markers)::

    python -m mitsuba_brdfs manual [--out DIR] [--only PLUGIN ...] [--text-only]

The docstring is read by ``docstrings`` and its RST turned into Markdown by
``rst_markdown``; this module lays out the pages and writes them.

``tests/test_manual.py`` fails when a committed page and its docstring disagree.
"""
import os
import re

from .core.registry import models as plugin_models
from .output import write_text

from .core.relations import describe
from .docstrings import ROOT, Parameter, model_doc, parameters, parse_table, split_doc, summary
from .rst_markdown import inline, rst_to_markdown

__all__ = ["ROOT", "Parameter", "parse_table", "parameters", "summary", "page", "index",
           "overview", "update_readme", "scene_xml", "complete_scene", "add_arguments", "run"]

#: the repository's reference pages and README, relative to the current directory (its root
#: when run from there, as ``make docs`` does): the README's plugin table is updated only
#: when the pages are written there
DOCS = os.path.join("docs", "plugins")
README = "README.md"
VARIANT = "llvm_ad_rgb"  # the keys, types and flags shown are this variant's
BEGIN, END = "<!-- plugins:begin -->", "<!-- plugins:end -->"


# -- what the plugin says about itself ---------------------------------------------------

def _traverse(plugin):
    """[(key, value type, parent class, flags text)] of the plugin loaded with its defaults."""
    import mitsuba as mi
    params = mi.traverse(mi.load_dict({"type": plugin}))
    rows = []
    for key in params.keys():
        _, _, parent, flags = params.properties[key]
        rows.append((key, type(params[key]).__name__, parent.class_name(), _flags(flags)))
    return rows


def _flags(flags):
    import mitsuba as mi
    out = ["exposed"]
    if not int(flags) & int(mi.ParamFlags.NonDifferentiable):
        out.append("differentiable")
    if int(flags) & int(mi.ParamFlags.Discontinuous):
        out.append("discontinuous")
    return ", ".join(out)


# -- the pages ---------------------------------------------------------------------------

def _value(text):
    """A default as written: numbers plain, words as code."""
    try:
        float(text)
        return text
    except ValueError:
        return f"`{text}`" if text and "`" not in text else inline(text)


#: a whole scene around a page's ``<bsdf>`` example: the sphere of the plugin images, lit by
#: a small area light and a dim environment, rendered with ``direct`` (nothing reflects onto
#: the sphere); ``res`` and ``spp`` are -D defines
_SCENE = """<scene version="3.0.0">
    <default name="res" value="256"/>
    <default name="spp" value="64"/>
    <integrator type="direct"/>
    <sensor type="perspective">
        <float name="fov" value="24"/>
        <transform name="to_world">
            <lookat origin="0, 0, 6" target="0, 0, 0" up="0, 1, 0"/>
        </transform>
        <sampler type="independent">
            <integer name="sample_count" value="$spp"/>
        </sampler>
        <film type="hdrfilm">
            <integer name="width" value="$res"/>
            <integer name="height" value="$res"/>
        </film>
    </sensor>
    <shape type="sphere">
        <transform name="to_world">
            <rotate x="1" angle="-90"/>
        </transform>
{bsdf}
    </shape>
    <shape type="sphere">
        <point name="center" x="-4" y="4" z="6"/>
        <float name="radius" value="0.5"/>
        <emitter type="area">
            <rgb name="radiance" value="40"/>
        </emitter>
    </shape>
    <emitter type="constant">
        <rgb name="radiance" value="0.08"/>
    </emitter>
</scene>"""


def scene_xml(fragment):
    """A complete scene (a sphere under a light) around an XML ``<bsdf>`` fragment."""
    bsdf = "\n".join("        " + ln if ln.strip() else "" for ln in fragment.splitlines())
    return _SCENE.replace("{bsdf}", bsdf)


def complete_scene(plugin, fragment):
    """The page's lines that show the example in a whole scene, and how to render it."""
    files = re.findall(r'name="filename" value="([^"]+)"', fragment)
    md = ["The same material in a complete scene: save it as `scene.xml` and render it with "
          "`python -m mitsuba_brdfs render scene.xml` (scene.exr and scene.png; `-D res=64` "
          "for a quick look). Mitsuba's own `mitsuba` command cannot load it: the plugins "
          "are registered when `mitsuba_brdfs` is imported."]
    if files:
        names = ", ".join(f"`{f}`" for f in files)
        md[-1] += (f" The example reads {names}: they are in the `scenes/` folder of the "
                   "repository and installed with the package as `mitsuba_brdfs/scenes` "
                   "(`mitsuba_brdfs.paths.SCENES`; `python -c \"import mitsuba_brdfs.paths "
                   "as p; print(p.SCENES)\"` prints the folder); copy them beside the scene "
                   "or add the folder with `-a FOLDER`.")
    return md + ["", "```xml", scene_xml(fragment), "```", ""]


def page(plugin, images=True):
    """The Markdown page of ``plugin`` (text only: the images are written by ``run``); with
    ``images`` False, without the table that shows them."""
    doc, source = model_doc(plugin)
    title, line = summary(plugin)
    prose, examples = rst_to_markdown(split_doc(doc)[2])
    keys = _traverse(plugin)
    flags = {k.split(".")[0]: f for k, _, _, f in keys}
    md = [f"<!-- Generated by `python -m mitsuba_brdfs manual` from the docstring of "
          f"{source}: edit that docstring and rerun. -->", "", f"# {title}", ""]
    if line.rstrip(".") != title.rsplit(" (`", 1)[0]:  # the first line says more than the title
        md += [inline(line), ""]
    md += ["| Parameter | Type | Default | Range | Description | Flags |",
           "|---|---|---|---|---|---|"]
    for p in parameters(plugin):
        rng = ", ".join(f"`{c}`" for c in p.choices()) if p.type == "string" else p.range
        if p.range and not p.contains(p.default):  # e.g. "0 (off) or N in [2, 4096]"
            rng = f"{p.default} or {rng}"
        md.append(f"| `{p.name}` | {p.type} | {_value(p.default)} | {inline(rng)} | "
                  f"{inline(p.description)} | {flags.get(p.name, 'load time')} |")
    md += [""]
    rules = describe(plugin_models()[plugin].RELATIONS)
    if rules:  # the relations the model declares: what its reader refuses
        md += ["Parameters that depend on each other (anything else is refused at load):", ""]
        md += [f"- {inline(rule)}" for rule in rules] + [""]
    if images:
        md += [f"| ![{plugin} at its defaults](img/{plugin}.png) | "
               f"![lobe and albedo of {plugin}](img/{plugin}_lobe.png) |", "|---|---|",
               "| at its defaults, the sphere of `scenes/as_sphere.xml` | eval in the plane of "
               "incidence at 0, 30 and 60 deg (light dashed), and the albedo |", ""]
    md += [f"To change its parameters and watch its lobes, albedo and a lit sphere follow: "
           f"`python -m mitsuba_brdfs explore {plugin}` "
           f"([the explorer](../../README.md#exploring-a-bsdf-in-the-browser)).", ""]
    md += prose
    md += ["## Examples", ""]
    if "XML" in examples:
        md += ["```xml", examples["XML"], "```", ""]
        md += complete_scene(plugin, examples["XML"])
    if "Python" in examples:
        code = examples["Python"]
        md += ["```python", "import mitsuba as mi", f"mi.set_variant('{VARIANT}')",
               "import mitsuba_brdfs  # registers the plugins", "",
               f"bsdf = {code}" if code.startswith("mi.load_dict(") else code, "```", ""]
    md += ["## Traverse keys", "",
           f"`mi.traverse(bsdf)` of `{plugin}` loaded with its defaults ({VARIANT}). In a scene "
           "every key starts with the BSDF's path: `<bsdf id>.` for a BSDF declared at the top "
           "level with an id, `<shape id>.bsdf.` for one nested in a shape (see the "
           "[README](../../README.md#traverse-keys-in-a-scene)). A bitmap texture exposes "
           "`<name>.data` instead of `<name>.value`.", "",
           "| Key | Type | Parent | Flags |", "|---|---|---|---|"]
    md += [f"| `{k}` | {t} | {p} | {f} |" for k, t, p, f in keys]
    return "\n".join(md).rstrip() + "\n"


def overview(prefix="", images=False):
    """The plugin table (links relative to ``prefix``): plugin, model, parameters, render."""
    md = ["| Plugin | Model | Parameters |" + (" At its defaults |" if images else ""),
          "|---|---|---|" + ("---|" if images else "")]
    for plugin in sorted(plugin_models()):
        names = ", ".join(f"`{p.name}`" for p in parameters(plugin))
        md.append(f"| [`{plugin}`]({prefix}{plugin}.md) | {inline(summary(plugin)[1])} | {names} |"
                  + (f" ![{plugin}]({prefix}img/{plugin}.png) |" if images else ""))
    return "\n".join(md) + "\n"


def index(images=True):
    """``docs/plugins/README.md`` (with ``images`` False, without the renders' column)."""
    return "\n".join([
        "<!-- Generated by `python -m mitsuba_brdfs manual`: edit the model docstrings and rerun. -->",
        "", "# Plugin reference", "",
        "Every BSDF of the package, one page each: its parameters (type, default, range, "
        "whether `mi.traverse` exposes it and it is differentiable), the model's equations and "
        "choices, XML and Python examples, its traverse keys"
        + (", a render and its lobes." if images else " (no images: `--text-only` renders none)."),
        "",
        overview(images=images),
        "What all plugins share: the local frame has the shading normal as z and the surface's "
        "u and v tangents as x and y (anisotropic models orient their lobe with them); `eval` "
        "returns f cos(theta) of the light direction, as every Mitsuba BSDF does; the plugins "
        "are one-sided (`twosided` wraps them); colours are textures (`<rgb>`, `<float>`, "
        "bitmaps) and work in RGB and spectral variants; a bad parameter is a load-time error "
        "naming the plugin, the parameter and its range; a lobe whose weight is a constant "
        "zero (a metal's diffuse lobe) stays declared, as the flags wrappers copy must hold "
        "every lobe an update could switch on, but it is neither sampled nor traced into "
        "the kernel.", ""])


def update_readme(path=README):
    """Replace the table between the README's ``plugins`` markers; False if it has none."""
    with open(path) as f:
        text = f.read()
    if BEGIN not in text or END not in text:
        return False
    head, rest = text.split(BEGIN, 1)
    new = head + BEGIN + "\n" + overview("docs/plugins/") + END + rest.split(END, 1)[1]
    if new != text:
        write_text(path, new)
    return True


# -- images ------------------------------------------------------------------------------

def _images(plugin, img_dir, res=128, spp=128, samples=1 << 16):
    """The render and the lobe/albedo plot of ``plugin`` at its defaults."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import mitsuba as mi

    from .validate import properties
    from .output import save_figure, write_png
    from .sphere import sphere_scene
    bsdf = {"type": plugin}
    write_png(os.path.join(img_dir, f"{plugin}.png"),
              mi.render(sphere_scene(bsdf, res=res, spp=spp), seed=0))
    fig = plt.figure(figsize=(6.4, 2.7), layout="constrained")
    lobe, albedo = fig.add_subplot(1, 2, 1, projection="polar"), fig.add_subplot(1, 2, 2)
    properties.draw_lobes(lobe, mi.load_dict(bsdf), "eval in the plane of incidence")
    lobe.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, 0.08), ncol=3,
                frameon=False)
    rows = properties.measure(samples, [(plugin, "", {})], progress=False)
    properties.draw_albedo(albedo, rows, "")
    albedo.get_legend().remove()
    albedo.set_title("directional albedo", fontsize=8)
    save_figure(fig, os.path.join(img_dir, f"{plugin}_lobe.png"), dpi=96)
    plt.close(fig)


# -- the command -------------------------------------------------------------------------

def add_arguments(p):
    from .arguments import default_out
    p.add_argument("--out", default=default_out("manual"),
                   help="folder of the pages (default: %(default)s/ in the current directory; "
                        "docs/plugins updates the README's plugin table too)")
    p.add_argument("--only", nargs="+", metavar="PLUGIN", help="only these plugins' pages")
    p.add_argument("--text-only", action="store_true",
                   help="write the pages without rendering their images (seconds); a page "
                        "shows its images only if an earlier run left them in OUT/img")


def _write(path, text):
    write_text(path, text)


def run(args):
    from .progress import advance, progress_bar
    from .variant import set_variant
    set_variant(VARIANT)
    from .messages import suggest
    from .output import check_folder
    plugins = sorted(plugin_models())
    unknown = sorted(set(args.only or []) - set(plugins))
    if unknown:
        raise ValueError(f"manual: unknown plugin '{unknown[0]}'{suggest(unknown[0], plugins)} "
                         f"(plugins: {', '.join(plugins)})")
    check_folder(args.out)
    img = os.path.join(args.out, "img")
    if not args.text_only:
        os.makedirs(img, exist_ok=True)
    todo = args.only or plugins

    def has_images(plugin):  # --text-only links the images an earlier run wrote, if any
        return not args.text_only or all(
            os.path.isfile(os.path.join(img, f"{plugin}{end}.png")) for end in ("", "_lobe"))

    bar = progress_bar(len(todo), "manual", unit="page")
    for plugin in todo:
        if not args.text_only:
            _images(plugin, img)
        _write(os.path.join(args.out, f"{plugin}.md"), page(plugin, has_images(plugin)))
        advance(bar, note=plugin)
    bar.close()
    _write(os.path.join(args.out, "README.md"), index(all(map(has_images, plugins))))
    if (os.path.abspath(args.out) == os.path.abspath(DOCS) and os.path.exists(README)
            and update_readme()):
        print(f"updated the plugin table of {os.path.relpath(README)}")
    print(f"wrote {len(args.only or plugins)} pages and the index into {args.out}")
    return 0
