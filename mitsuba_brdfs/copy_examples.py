"""``python -m mitsuba_brdfs examples [--out DIR]``: the examples, copied where pytest finds them.

The README's testing example (``pytest examples/mydiffuse``) runs on two files: a user's
plugin (``mydiffuse.py``) and its pytest file. A checkout holds them in ``examples/``;
``pip install`` installs them inside the package (``paths.EXAMPLES``), where they are read
but not run. This command copies them into ``examples/`` of the current directory (``--out
DIR``: into DIR), so that, with pytest installed (``pip install pytest``: not a dependency
of the package), the README's ``pytest examples/mydiffuse`` runs as written, from any folder.

A file already there with the same contents is left as it is; one with other contents (your
edits) is not overwritten: the command stops before copying anything, exit status 2.
"""
import filecmp
import os

from .arguments import UsageError
from .output import check_folder, check_target, write_text
from .paths import EXAMPLES

__all__ = ["WRITES_ATOMICALLY", "example_files", "add_arguments", "run"]

#: every file goes through ``output.atomic``: an interruption can say what was written
WRITES_ATOMICALLY = True


def example_files():
    """The examples' files, as paths relative to ``EXAMPLES`` (``mydiffuse/mydiffuse.py``,
    ...), sorted."""
    out = []
    for folder, dirs, files in os.walk(EXAMPLES):
        dirs[:] = sorted(d for d in dirs if d != "__pycache__")
        out += [os.path.relpath(os.path.join(folder, f), EXAMPLES) for f in files
                if f.endswith(".py")]
    return sorted(out)


def add_arguments(p):
    p.add_argument("--out", default="examples", metavar="DIR",
                   help="the folder to copy them into (default: examples/ in the current "
                        "directory, as the README's `pytest examples/mydiffuse` expects)")


def run(args):
    files = example_files()
    if not files:
        raise UsageError(f"no examples found in {EXAMPLES}")
    check_folder(args.out)
    todo = []
    for rel in files:
        source, target = os.path.join(EXAMPLES, rel), os.path.join(args.out, rel)
        if os.path.isfile(target) and filecmp.cmp(source, target, shallow=False):
            continue
        if os.path.exists(target):
            raise UsageError(f"{target}: exists with other contents; refusing to overwrite "
                             f"it (move it away, or choose another --out)")
        check_target(target)
        todo.append((source, target))
    for source, target in todo:
        os.makedirs(os.path.dirname(target), exist_ok=True)
        with open(source) as f:
            write_text(target, f.read())
    folders = sorted({os.path.dirname(os.path.join(args.out, rel)) for rel in files})
    if todo:
        print(f"copied {', '.join(t for _, t in todo)}")
    else:
        print(f"{', '.join(folders)}: already there, unchanged")
    print(f"run them with: pytest {' '.join(folders)}   (pytest: pip install pytest)")
    return 0
