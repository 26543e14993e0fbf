"""The plugin reference (``docs/plugins/``) against the docstrings it is generated from.

- Every committed page, the index and the README's plugin table equal what
  ``python -m mitsuba_brdfs manual`` writes today (text only, no renders): a docstring
  changed without regenerating the pages fails here, and so does a page edited by hand.
- Each docstring's parameter table lists exactly what its plugin reads: loaded with every
  documented parameter at its documented default (Mitsuba refuses properties a plugin does
  not read) it is the plugin loaded with no parameters at all, and every key of
  ``mi.traverse`` and every load-time option is documented.
- The documented ranges and choices are the plugin's: the bounds load, values just beyond
  them and unknown choices are refused with an error naming plugin and parameter.
- The examples of each page load, and the README's traverse-key example runs.
"""
import os
import re
import subprocess
import sys

import mitsuba as mi
import pytest

import mitsuba_brdfs
from checks import FACTS
from mitsuba_brdfs import manual

PLUGINS = sorted(mitsuba_brdfs.plugin_models())
REGENERATE = ("run `python -m mitsuba_brdfs manual --out docs/plugins` (--text-only if only the "
              "text changed), or `make docs`")


def read(path):
    with open(path) as f:
        return f.read()


def documented_value(p):
    """The documented default of ``p`` as a load_dict value (None if it is not a value)."""
    text = p.default.strip("`")
    try:
        if p.type.startswith(("float", "spectrum")):
            return float(text)
        if p.type == "integer":
            return int(text)
    except ValueError:
        return None
    if p.type == "boolean":
        return {"true": True, "false": False}.get(text.lower())
    return text if p.type == "string" and text else None


def load(plugin, **params):
    return mi.load_dict({"type": plugin, **params})


# -- the pages are the docstrings --------------------------------------------------------

@pytest.mark.parametrize("plugin", PLUGINS)
def test_page_matches_docstring(plugin):
    path = os.path.join(manual.ROOT, manual.DOCS, f"{plugin}.md")
    assert os.path.exists(path), f"docs/plugins/{plugin}.md is missing: {REGENERATE}"
    assert read(path) == manual.page(plugin), \
        f"docs/plugins/{plugin}.md and its docstring disagree: {REGENERATE}"
    for image in (f"{plugin}.png", f"{plugin}_lobe.png"):
        assert os.path.exists(os.path.join(manual.ROOT, manual.DOCS, "img", image)), f"{image}: {REGENERATE}"


def test_index_and_readme_table():
    assert read(os.path.join(manual.ROOT, manual.DOCS, "README.md")) == manual.index(), REGENERATE
    pages = {f[:-3] for f in os.listdir(os.path.join(manual.ROOT, manual.DOCS)) if f.endswith(".md")} - {"README"}
    assert pages == set(PLUGINS), f"pages without a plugin or plugins without a page: {REGENERATE}"
    readme = read(os.path.join(manual.ROOT, manual.README))
    table = readme.split(manual.BEGIN)[1].split(manual.END)[0]
    assert table == "\n" + manual.overview("docs/plugins/"), REGENERATE
    assert "../shared" not in readme  # the repository documents itself


def test_command_writes_the_committed_page(tmp_path):
    """Through the command line, as a user runs it (a folder of its own: README untouched)."""
    before = read(os.path.join(manual.ROOT, manual.README))
    out = subprocess.run([sys.executable, "-m", "mitsuba_brdfs", "manual", "--text-only",
                          "--only", "lambert", "--out", str(tmp_path)],
                         capture_output=True, text=True, cwd=manual.ROOT, timeout=300)
    assert out.returncode == 0, out.stderr
    # --text-only renders nothing, so its pages link no image (the committed ones do)
    assert read(tmp_path / "lambert.md") == manual.page("lambert", images=False)
    assert read(tmp_path / "README.md") == manual.index(images=False)
    assert "img/" not in read(tmp_path / "lambert.md") + read(tmp_path / "README.md")
    assert "a render and its lobes" not in read(tmp_path / "README.md")  # nor says it does
    assert not (tmp_path / "img").exists()
    assert read(os.path.join(manual.ROOT, manual.README)) == before
    # where an earlier run wrote the images, --text-only links them: the committed page
    (tmp_path / "img").mkdir()
    for image in ("lambert.png", "lambert_lobe.png"):
        (tmp_path / "img" / image).write_bytes(b"")
    again = subprocess.run([sys.executable, "-m", "mitsuba_brdfs", "manual", "--text-only",
                            "--only", "lambert", "--out", str(tmp_path)],
                           capture_output=True, text=True, cwd=manual.ROOT, timeout=300)
    assert again.returncode == 0, again.stderr
    assert read(tmp_path / "lambert.md") == read(os.path.join(manual.ROOT, manual.DOCS, "lambert.md"))
    bad = subprocess.run([sys.executable, "-m", "mitsuba_brdfs", "manual", "--text-only",
                          "--only", "bogus", "--out", str(tmp_path)],
                         capture_output=True, text=True, cwd=manual.ROOT, timeout=300)
    assert bad.returncode == 2 and "bogus" in bad.stderr and "Traceback" not in bad.stderr


# -- the parameter tables are the plugins' -------------------------------------------------

@pytest.mark.parametrize("plugin", PLUGINS)
def test_table_lists_what_the_plugin_reads(plugin):
    params = manual.parameters(plugin)
    assert params, f"{plugin}: no parameter table found in its docstring"
    names = [p.name for p in params]
    assert len(set(names)) == len(names), f"{plugin}: a parameter is documented twice"
    values = {p.name: documented_value(p) for p in params}
    # parameters of another form (EON's) are checked with their form in the ranges test
    given = {k: v for k, v in values.items()
             if v is not None and "form" not in COMPANIONS.get((plugin, k), {})}
    optional = set(values) - set(given)  # no default value (e.g. a texture that is off)
    # Mitsuba refuses a property the plugin does not read; the documented defaults are the
    # plugin's own when loading with all of them gives the same object as loading with none
    explicit, default = load(plugin, **given), load(plugin)
    assert str(explicit) == str(default), f"{plugin}: documented defaults {given}"
    read_names = {k.split(".")[0] for k in mi.traverse(default).keys()} | set(default._options())
    missing = set(names) - read_names - optional
    assert read_names <= set(names) and not missing, (
        f"{plugin}: undocumented {sorted(read_names - set(names))}, "
        f"documented but neither traversed nor a load-time option {sorted(missing)}")


def _refused(plugin, name, value, **extra):
    with pytest.raises(Exception) as e:
        load(plugin, **{name: value}, **extra)
    message = str(e.value)
    assert plugin in message and name in message, message
    return message.splitlines()[-1]


def _companions(plugin):
    """{parameter: the settings it loads with}: its partners and the form it needs, from
    the relations the model declares (``core.relations``; a partner at its documented
    default, or the middle of its range), and the model's ``FACTS.companions`` (rules on
    values the relations do not state)."""
    from mitsuba_brdfs.core.registry import models
    from mitsuba_brdfs.core.relations import companions
    params = manual.parameters(plugin)
    values = {p.name: documented_value(p) for p in params}
    for p in params:
        if values[p.name] is None and p.bounds():
            values[p.name] = (p.bounds()[0] + p.bounds()[1]) / 2
    out = {p.name: companions(models()[plugin].RELATIONS, p.name, values) for p in params}
    for name, settings in FACTS[plugin].companions.items():
        out[name] = {**out.get(name, {}), **settings}
    return {name: settings for name, settings in out.items() if settings}


#: parameters that only load together with others (a pair, or an option of one form)
COMPANIONS = {(p, name): settings for p in PLUGINS for name, settings in _companions(p).items()}


@pytest.mark.parametrize("plugin", PLUGINS)
def test_documented_ranges_and_choices(plugin):
    for p in manual.parameters(plugin):
        extra = COMPANIONS.get((plugin, p.name), {})
        if p.type == "string":
            for choice in p.choices():
                load(plugin, **{p.name: choice}, **extra)
            message = _refused(plugin, p.name, "__bogus__", **extra)
            accepted = re.findall(r"'(\w+)'", message.split("one of")[-1].split("(got")[0])
            if "one of" in message:
                assert set(accepted) == set(p.choices()), f"{plugin}.{p.name}: {message}"
            continue
        if p.bounds() is None:
            continue
        lo, hi, lo_in, hi_in = p.bounds()
        cast = int if p.type == "integer" else float
        for bound, outward, included in ((lo, -1, lo_in), (hi, 1, hi_in)):
            if abs(bound) == float("inf"):
                continue
            step = 1 if p.type == "integer" else max(abs(bound) * 1e-2, 1e-6)
            inside, outside = (bound, bound + outward * step) if included else \
                (bound - outward * step, bound)
            load(plugin, **{p.name: cast(inside)}, **extra)
            _refused(plugin, p.name, cast(outside), **extra)


@pytest.mark.parametrize("plugin", PLUGINS)
def test_page_examples_load(plugin):
    # the page as the manual writes it (test_page_matches_docstring: the committed one)
    text = manual.page(plugin)
    xml = re.findall(r"```xml\n(.*?)```", text, re.S)
    python = re.findall(r"```python\n(.*?)```", text, re.S)
    assert xml and python, f"{plugin}: the docstring has no XML or Python example"
    from mitsuba_brdfs.paths import SCENES
    resolver = mi.file_resolver()
    resolver.append(SCENES)  # examples may name the scenes' bitmaps (toon's ramps)
    for snippet in xml:
        assert f'type="{plugin}"' in snippet
        if not snippet.startswith("<scene"):  # the complete scene renders below
            mi.load_string(snippet.replace("<bsdf ", '<bsdf version="3.0.0" ', 1))
    for snippet in python:
        scope = {}
        exec(snippet, scope)
        assert any(isinstance(v, mi.BSDF) for v in scope.values()), snippet


@pytest.mark.parametrize("plugin", PLUGINS)
def test_page_scene_renders_as_pasted(plugin, tmp_path):
    """The page's complete scene, saved as a file, renders with the render command's loader
    (scalar_rgb: no kernel to compile) to a finite, lit image."""
    text = manual.page(plugin)
    scenes = [x for x in re.findall(r"```xml\n(.*?)```", text, re.S) if x.startswith("<scene")]
    assert len(scenes) == 1, f"{plugin}: the page has no complete scene"
    path = tmp_path / "scene.xml"
    path.write_text(scenes[0])
    mi.set_variant("scalar_rgb")
    scene = mi.load_file(str(path), res=6, spp=2)
    image = mi.TensorXf(mi.render(scene)).numpy()
    assert image.shape[:2] == (6, 6) and (image >= 0).all() and image.max() > 0.01


def test_readme_traverse_example(capsys):
    readme = read(os.path.join(manual.ROOT, manual.README))
    section = readme.split("## Traverse keys in a scene", 1)[1].split("\n## ", 1)[0]
    code = re.search(r"```python\n(.*?)```", section, re.S).group(1)
    scope = {}
    exec(code, scope)  # a wrong key raises KeyError
    printed = capsys.readouterr().out
    assert "ball.bsdf.nu.value" in printed and "steel.alpha_u.value" in printed
    params = scope["params"]
    assert params["ball.bsdf.nu.value"] == 10.0 and params["steel.alpha_u.value"] == 0.05
    bsdfs = {s.id(): s.bsdf() for s in scope["scene"].shapes()}
    assert "nu = UniformSpectrum[value=[10]]" in str(bsdfs["ball"])


def test_the_parameter_table_of_using_md_is_its_plugins():
    """docs/using.md shows the lead model's parameters in a table that names the plugin in
    its header; it lists every parameter the plugin's docstring does, and no other."""
    text = read(os.path.join(manual.ROOT, "docs", "using.md"))
    tables = re.findall(r"^\| `(\w+)` parameter \|.*\n\|[-|]+\|\n((?:\|.*\n)+)", text, re.M)
    assert tables, "docs/using.md: no table headed by a plugin's parameters"
    for plugin, rows in tables:
        listed = set(re.findall(r"`(\w+)`", "".join(r.split("|")[1] for r in rows.splitlines())))
        assert listed == {p.name for p in manual.parameters(plugin)}, (plugin, sorted(listed))
