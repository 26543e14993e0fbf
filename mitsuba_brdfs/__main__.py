"""``python -m mitsuba_brdfs <command> ...``: the package's command line.

Commands: ``render`` (one scene, in passes, EXR + PNG), ``figures`` (the paper figures and
the model catalog), ``properties`` (albedo, reciprocity and sampling of every model),
``fit`` (differentiable rendering example), ``bench`` (the performance study).
``python -m mitsuba_brdfs <command> --help`` documents each. This module only parses the
arguments and dispatches: each command's module has ``add_arguments(parser)`` and
``run(args)``. Ctrl-C stops a command with exit status 130 and leaves no partial output
files.
"""
import argparse
import importlib
import signal
import sys

#: command -> (module, one-line help); each module has add_arguments(parser) and run(args)
COMMANDS = {
    "render": ("mitsuba_brdfs.render", "render one scene XML to EXR + PNG"),
    "figures": ("mitsuba_brdfs.figures.command", "render the figures into renders/"),
    "properties": ("mitsuba_brdfs.properties",
                   "measure albedo, reciprocity and sampling of every model into docs/"),
    "fit": ("mitsuba_brdfs.fit", "recover nu, nv, Rs of the brushed cylinder by differentiable rendering"),
    "bench": ("mitsuba_brdfs.bench.command",
              "measure what accuracy costs in time into docs/performance.md (--quick: a check)"),
    "manual": ("mitsuba_brdfs.manual",
               "write a reference page per plugin from its docstring into docs/plugins/"),
    "check": ("mitsuba_brdfs.check",
              "validate any BSDF (a plugin or an XML file): sampling, weights, energy, "
              "stability; writes nothing (--report DIR: a Markdown page with plots)"),
}


def parser():
    """The argument parser of every command."""
    p = argparse.ArgumentParser(prog="python -m mitsuba_brdfs", description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = p.add_subparsers(dest="command", required=True)
    for name, (module, help_text) in COMMANDS.items():
        importlib.import_module(module).add_arguments(
            sub.add_parser(name, help=help_text, description=help_text))
    return p


def main(argv=None):
    args = parser().parse_args(argv)
    command = importlib.import_module(COMMANDS[args.command][0])
    interrupted = []

    def on_sigint(signum, frame):
        # Dr.Jit may wrap the KeyboardInterrupt raised inside a render into a RuntimeError:
        # remember that the user asked to stop
        interrupted.append(True)
        raise KeyboardInterrupt

    previous = signal.signal(signal.SIGINT, on_sigint)
    try:
        return command.run(args)
    except KeyboardInterrupt:
        interrupted.append(True)
    except (ValueError, RuntimeError, FileNotFoundError) as e:
        if not interrupted:  # bad input: say what, without a traceback
            print(f"error: {_short(str(e))}", file=sys.stderr)
            return 2
    finally:
        signal.signal(signal.SIGINT, previous)
    print("\ninterrupted: no output written", file=sys.stderr)
    return 130


def _short(message):
    """Mitsuba embeds a plugin's Python traceback in its error: keep the context and the cause."""
    if "Traceback" not in message:
        return message
    head = message.split("Traceback")[0].rstrip(' :"')
    lines = [ln for ln in message.splitlines() if ln.strip()]
    return f"{head}: {lines[-1].strip()}"


if __name__ == "__main__":
    sys.exit(main())
