"""Every command the README and docs/ show runs as written, from any folder.

Each ``python -m mitsuba_brdfs ...`` (or ``mitsuba-brdfs ...``) line of the README and of
docs/*.md is parsed by the command line's own parser (its options exist and take the
values shown), and what it names is there for a user of the installed package, who works
in an empty folder: a scene or plugin file is one that comes with the package
(``paths.installed_copy``) or one that an earlier line of the same page writes (``> nickel.xml``),
and a BSDF named by ``check`` or ``explore`` is a plugin Mitsuba, this package or the line's
``--load`` file registers. Lines with placeholders (``SCENE.xml``, ``[--out DIR]``) are
synopses, and measured files (``.binary``) and a scene the page asks the user to save
(``scene.xml``) are the user's: neither is run. The README's measured recipe, which makes
its files itself, is run from an empty folder.
"""
import glob
import os
import re
import shlex

import mitsuba as mi
import pytest

from cmdline import run_many
from mitsuba_brdfs.__main__ import parser
from mitsuba_brdfs.messages import note_registered, plugin_names
from mitsuba_brdfs.paths import installed_copy

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
PAGES = ["README.md"] + sorted(os.path.relpath(p, ROOT) for p in
                               glob.glob(os.path.join(ROOT, "docs", "**", "*.md"),
                                         recursive=True))
#: a command, up to the end of its code span, line, comment, pipe or redirection
COMMAND = re.compile(r"(?:python -m mitsuba_brdfs|mitsuba-brdfs)(?![\w.-])"
                     r"((?:[^`\n#|&>;]|>(?!\s))*)"
                     r"(?:>\s*(\S+))?")
#: files that are the user's own: measurements (MERL, RGL), the scene a plugin page asks to
#: save, the material file of a user's
USERS = re.compile(r"(\.binary$|\.bsdf$|^(my_)?scene\.xml$|^material\.xml$)")


def _commands():
    """(page, argv, file it redirects to) of every command line of the pages."""
    out = []
    for page in PAGES:
        with open(os.path.join(ROOT, page)) as f:
            text = f.read()
        for m in COMMAND.finditer(text):
            words = shlex.split(m.group(1))
            if not words or "[" in m.group(1) or "..." in m.group(1) \
                    or any(re.search(r"[A-Z]{2,}|^[A-Z]$", w) for w in words):
                continue  # the bare command named in prose, or a synopsis with placeholders
            out.append((page, words, m.group(2)))
    return out


COMMANDS = _commands()


def test_the_pages_show_commands():
    pages = {page for page, _, _ in COMMANDS}
    assert {"README.md", "docs/check.md", "docs/explore.md", "docs/presets.md"} <= pages
    assert len(COMMANDS) > 40


@pytest.mark.parametrize("page, argv, redirect", COMMANDS,
                         ids=[f"{p}: {' '.join(a)}" for p, a, _ in COMMANDS])
def test_a_documented_command_runs_as_written(page, argv, redirect, tmp_path, monkeypatch):
    if argv[-1] == "--help" or argv == ["examples"]:
        pytest.skip("nothing named")
    try:
        args = parser(argv).parse_args(argv)
    except SystemExit as e:
        if len(argv) == 1:  # the command named in prose ("`python -m mitsuba_brdfs check`")
            pytest.skip("a command named, not shown")
        pytest.fail(f"{page}: `{' '.join(argv)}` is refused by the parser (exit {e.code})")
    monkeypatch.chdir(tmp_path)  # an empty folder, as a user's
    written = {r for p, _, r in COMMANDS if p == page and r}

    def there(path):
        return (os.path.isfile(path) or installed_copy(path) is not None or path in written
                or USERS.search(os.path.basename(path)))

    registered = []
    for path in getattr(args, "load", None) or []:
        assert there(path), f"{page}: `{' '.join(argv)}`: --load {path} is not there"
        copy = installed_copy(path)
        registered += note_registered(copy) if copy else []
    specs = (getattr(args, "scenes", None) or getattr(args, "spec", None)
             or getattr(args, "file", None) or getattr(args, "source", None) or [])
    for spec in [specs] if isinstance(specs, str) else specs:
        if spec.lower().endswith((".xml", ".binary", ".bsdf")) or os.sep in spec:
            assert there(spec), f"{page}: `{' '.join(argv)}`: {spec} is not there"
        elif args.command in ("check", "explore", "to-rgl", "to-merl"):
            mi.set_variant("llvm_ad_rgb")
            assert spec in set(plugin_names("bsdf")) | set(registered), \
                f"{page}: `{' '.join(argv)}`: no BSDF plugin {spec!r}"


#: options that make each command of the README's measured recipe cheap (its lines run as
#: written otherwise): coarse files, few evaluations, the page served on any free port
CHEAP = {"to-rgl": ["--grid", "16", "--theta-i", "6", "--vndf", "16", "--ndf", "32",
                    "--no-compare"],
         "to-merl": ["--dims", "30,30,60"],
         "fit-measured": ["--evaluations", "15", "--samples", "1500"],
         "explore": ["--port", "0", "--no-browser"]}
#: explore serves until stopped: once its BSDFs are loaded and its port bound, say so, stop
_SERVED = """
from mitsuba_brdfs.explore import command as _command
def _serve(application, sock, args, count):
    print(f"served {count} BSDF(s) on port {sock.getsockname()[1]}")
    return 0
_command._serve = _serve
"""


def test_the_readme_measured_recipe_runs_from_an_empty_folder(tmp_path):
    """The README's "Measured materials, from an empty folder": each line in an empty
    folder, in order (each makes what the next reads); the file the text says fit-measured
    writes is there."""
    with open(os.path.join(ROOT, "README.md")) as f:
        text = f.read()
    section = text.split("### Measured materials, from an empty folder", 1)[1]
    block = section.split("```sh\n", 1)[1].split("```", 1)[0]
    argvs = [shlex.split(line.split("#")[0])[3:] for line in block.splitlines()
             if line.startswith("python -m mitsuba_brdfs ")]
    assert [a[0] for a in argvs] == ["to-rgl", "to-merl", "fit-measured", "explore"], argvs
    cases = [argv + CHEAP[argv[0]] for argv in argvs]
    results = run_many(cases, cwd=tmp_path, prelude=_SERVED,
                       env={"MITSUBA_BRDFS_CACHE": str(tmp_path / "cache")})
    for argv, (code, out, err) in zip(cases, results):
        assert code == 0, (argv, out[-1500:], err[-1500:])
    rgl, merl, fit, explore = results
    assert "blue-plastic.bsdf: roughplastic alpha=0.2" in rgl[1]
    assert "blue-plastic.binary: roughplastic alpha=0.2" in merl[1]
    assert "| cook_torrance |" in fit[1] and "| ward |" in fit[1], fit[1]
    assert explore[1].startswith("served 2 BSDF(s) on port "), explore
    folder = re.findall(r"`(mitsuba_brdfs-out/fit-measured/)`", section.split("Real ")[0])
    said = re.findall(r"`(blue-plastic\.bsdf_[^`]+)`", section.split("Real ")[0])
    assert folder and said and all((tmp_path / folder[0] / f).is_file() for f in said), \
        (said, fit[1])
    assert {"blue-plastic.bsdf", "blue-plastic.binary"} <= set(os.listdir(tmp_path))
