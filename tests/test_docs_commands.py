"""Every command the README and docs/ show runs as written, from any folder.

Each ``python -m mitsuba_brdfs ...`` (or ``mitsuba-brdfs ...``) line of the README and of
docs/*.md is parsed by the command line's own parser (its options exist and take the
values shown), and what it names is there for a user of the installed package, who works
in an empty folder: a scene or plugin file is one that comes with the package
(``paths.installed_copy``) or one that an earlier line of the same page writes (``> nickel.xml``),
and a BSDF named by ``check`` or ``explore`` is a plugin Mitsuba, this package or the line's
``--load`` file registers. Lines with placeholders (``SCENE.xml``, ``[--out DIR]``) are
synopses, and measured files (``.binary``) and a scene the page asks the user to save
(``scene.xml``) are the user's: neither is run.
"""
import glob
import os
import re
import shlex

import mitsuba as mi
import pytest

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
        elif args.command in ("check", "explore", "to-rgl"):
            mi.set_variant("llvm_ad_rgb")
            assert spec in set(plugin_names("bsdf")) | set(registered), \
                f"{page}: `{' '.join(argv)}`: no BSDF plugin {spec!r}"
