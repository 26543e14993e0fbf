"""The package's command line: ``python -m mitsuba_brdfs COMMAND ...``, or
``mitsuba-brdfs COMMAND ...`` where the package is installed.

This module only parses the arguments and dispatches: each command's module (``COMMANDS``)
has ``add_arguments(parser)`` and ``run(args)``. A bad invocation is refused in one line
with exit status 2 before anything runs (``--debug`` shows the traceback). Ctrl-C (SIGINT)
stops a command with exit status 130, SIGTERM with 143; neither leaves a partial file,
and the message says which files were written before the stop.
"""
import argparse
import importlib
import os
import re
import signal
import sys
import traceback

from .messages import one_line

#: command -> (module, one-line help saying where it writes by default: never the tracked
#: docs/ or renders/ of a checkout, see ``arguments.default_out``); each module has
#: add_arguments(parser) and run(args)
COMMANDS = {
    "render": ("mitsuba_brdfs.render",
               "render scene XMLs in passes to EXR + PNG (default: the scene's name, in "
               "the current directory)"),
    "figures": ("mitsuba_brdfs.figures.command",
                "render the paper's figures and the model catalog (default: into "
                "mitsuba_brdfs-out/figures/)"),
    "properties": ("mitsuba_brdfs.properties",
                   "measure albedo, reciprocity and sampling of every model (default: into "
                   "mitsuba_brdfs-out/properties/)"),
    "fit": ("mitsuba_brdfs.fit",
            "recover nu, nv, Rs of the brushed cylinder by differentiable rendering "
            "(default: into mitsuba_brdfs-out/fit/)"),
    "bench": ("mitsuba_brdfs.bench.command",
              "measure what accuracy costs in time (default: into mitsuba_brdfs-out/bench/; "
              "--quick: a check)"),
    "manual": ("mitsuba_brdfs.manual",
               "write a reference page per plugin from its docstring (default: into "
               "mitsuba_brdfs-out/manual/)"),
    "presets": ("mitsuba_brdfs.presets.command",
                "list the measured-material presets (Ngan et al. 2005 fits to MERL) or show "
                "one as a dict or XML; writes nothing"),
    "fit-measured": ("mitsuba_brdfs.fit_measured",
                     "fit plugins to a measured MERL or RGL file, or to any BSDF (--target), "
                     "by automatic differentiation, and rank them (default: into "
                     "mitsuba_brdfs-out/fit-measured/)"),
    "check": ("mitsuba_brdfs.check",
              "validate any BSDF (a plugin or an XML file): sampling, weights, energy, "
              "stability; writes nothing (--report DIR: a Markdown page with plots)"),
    "to-rgl": ("mitsuba_brdfs.measured.to_rgl",
               "write any BSDF, MERL or RGL file as an RGL file that Mitsuba's measured "
               "renders (to -o OUT.bsdf)"),
    "to-merl": ("mitsuba_brdfs.measured.to_merl",
                "write any BSDF, RGL or MERL file as a MERL file, a measured file to start "
                "from (to -o OUT.binary)"),
    "examples": ("mitsuba_brdfs.copy_examples",
                 "copy the examples (a plugin of your own and its pytest file) where pytest "
                 "finds them (default: into examples/ of the current directory)"),
    "explore": ("mitsuba_brdfs.explore.command",
                "explore BSDFs in the browser: lobes, albedo, a lit sphere, sliders for "
                "every parameter; serves on 127.0.0.1, writes nothing"),
}

#: signal -> (exit status, word for the message)
_STOPS = {signal.SIGINT: (130, "interrupted"), signal.SIGTERM: (143, "terminated")}


class _Parser(argparse.ArgumentParser):
    """argparse, with its errors in one line (the usage is one ``--help`` away) and its help
    in plain text (the docstrings' reST literals, ````x````, as x)."""

    def error(self, message):
        self.exit(2, f"{self.prog}: error: {message} (see {self.prog} --help)\n")

    def format_help(self):
        return re.sub(r"``([^`]+)``", r"\1", super().format_help())


def _prog():
    """The name the user typed: the console script's, else ``python -m mitsuba_brdfs``."""
    name = os.path.basename(sys.argv[0]) if sys.argv and sys.argv[0] else ""
    return name if name.startswith("mitsuba-brdfs") else "python -m mitsuba_brdfs"


def parser(argv=None):
    """The argument parser of every command.

    With ``argv``, only the command it names (its first word not starting with ``-``)
    gets its options: the other commands' modules, which may load NumPy, matplotlib or the
    performance study, are not imported (the top-level ``--help`` needs their names and
    one-line helps only).
    """
    named = None
    if argv is not None:
        named = next((a for a in argv if not a.startswith("-")), None)
    p = _Parser(prog=_prog(), description=__doc__.split("\n\n")[0],
                epilog=f"'{_prog()} COMMAND --help' documents each command.")
    from . import __version__
    p.add_argument("--version", action="version", version=f"mitsuba_brdfs {__version__}")
    common = argparse.ArgumentParser(add_help=False)
    common.add_argument("--debug", action="store_true",
                        help="on an error, show the Python traceback too")
    sub = p.add_subparsers(dest="command", metavar="COMMAND", title="commands")
    for name, (module, help_text) in COMMANDS.items():
        command = sub.add_parser(name, help=help_text, description=help_text, parents=[common])
        if argv is None or name == named:
            importlib.import_module(module).add_arguments(command)
    return p


class _Stop(KeyboardInterrupt):
    """SIGINT or SIGTERM, raised where the command is, so that its ``finally`` blocks
    (the removal of temporary files) run."""


def main(argv=None):
    """Run the command of ``argv`` (default: ``sys.argv[1:]``); returns the exit status."""
    argv = sys.argv[1:] if argv is None else list(argv)
    p = parser(argv)
    try:
        args = p.parse_args(argv)
    except SystemExit as e:  # a bad invocation (status 2, said in one line), or --help
        return e.code
    if args.command is None:  # as Mitsuba's `mitsuba` does: the help
        p.print_help()
        return 0
    command = importlib.import_module(COMMANDS[args.command][0])
    from .output import written
    from .progress import request_stop
    written(clear=True)
    request_stop(None)
    stops = []

    def on_signal(signum, frame):
        # Dr.Jit may wrap the exception raised inside a render into a RuntimeError, or a
        # native call may swallow it: remember that the user asked to stop
        stops.append(signum)
        request_stop(signum)
        if len(stops) == 1:  # a second signal lets the clean-up of the first finish
            raise _Stop

    previous = {s: signal.signal(s, on_signal) for s in _STOPS}
    try:
        return command.run(args)
    except KeyboardInterrupt:
        stops.append(stops[-1] if stops else signal.SIGINT)
    except (ValueError, RuntimeError, OSError, ImportError) as e:
        if not stops:  # bad input: say what, in one line (after the traceback with --debug)
            if args.debug:
                traceback.print_exc()
            done = written()  # e.g. the first scene of several, rendered before the bad one
            after = f" (after writing {', '.join(done)})" if done else ""
            print(f"error: {one_line(_message(e))}{after}", file=sys.stderr)
            return 1 if isinstance(e, ImportError) else 2
    finally:
        for s, handler in previous.items():
            signal.signal(s, handler)
    status, word = _STOPS[stops[-1]]
    files = written()
    if files:
        print(f"\n{word} after writing {', '.join(files)}", file=sys.stderr)
    elif getattr(command, "WRITES_ATOMICALLY", False):
        print(f"\n{word}: no output written", file=sys.stderr)
    else:
        print(f"\n{word}", file=sys.stderr)
    return status


def _message(e):
    """The message of ``e``; where it points to its cause ("see above", as Dr.Jit's
    wrapping of an error inside ``mi.render`` does), the cause's message first."""
    message = str(e)
    cause = e.__cause__ or e.__context__
    if "see above" in message and cause is not None:
        kind = "" if isinstance(cause, RuntimeError) else f"{type(cause).__name__}: "
        return f"{kind}{_message(cause)} (in {message.split(':')[0]})"
    return message


if __name__ == "__main__":
    sys.exit(main())
