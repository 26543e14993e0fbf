"""The source of a command that writes a measured file (``to-rgl``, ``to-merl``): its
arguments declared, checked in one line before any work, its variant set, the source
opened."""

__all__ = ["add_source_arguments", "open_for_writing"]


def add_source_arguments(p, metavar, kind):
    """The arguments ``open_for_writing`` reads: SOURCE, ``-p``, ``--load``, ``-o`` (of
    ``metavar``, the ``kind`` file to write) and ``--variant``."""
    from ..arguments import add_load
    p.add_argument("source", metavar="SOURCE",
                   help="a BSDF plugin (Mitsuba's, this package's, or one registered by "
                        "--load), an XML file with one <bsdf>, a MERL .binary file or an RGL "
                        ".bsdf file")
    p.add_argument("-p", dest="params", action="append", default=[], metavar="KEY=VALUE",
                   help="a parameter of the plugin (as check takes it; repeatable)")
    add_load(p)
    p.add_argument("-o", "--output", required=True, metavar=metavar,
                   help=f"the {kind} file to write")
    p.add_argument("--variant", default="llvm_ad_rgb",
                   help="Mitsuba variant, an RGB one (default: llvm_ad_rgb)")


def open_for_writing(args, command, writes):
    """The source of a command that writes a measured file (``to-rgl``, ``to-merl``) from
    its arguments (``source``, ``params``, ``output``, ``variant``, ``load``): a missing
    source, an output that may not be written and a variant that is not RGB refused in one
    line before any work (``writes``: what the command writes, for the message), the
    variant set and the ``--load`` files run."""
    import os
    from ..arguments import UsageError
    from ..output import check_folder, check_target
    from ..spec import locate, parse_params
    from ..variant import run_file, set_variant
    params = parse_params(args.params)
    locate(args.source)  # a file that is not there: refused before any work
    check_folder(os.path.dirname(os.path.abspath(args.output)), f"{command}: -o {args.output}")
    check_target(args.output, f"{command}: -o {args.output}")
    if "_rgb" not in args.variant:
        raise UsageError(f"{command}: --variant {args.variant}: {writes}, in an RGB variant "
                         f"(llvm_ad_rgb, scalar_rgb, ...)")
    set_variant(args.variant)
    for path in args.load:
        run_file(path)
    from .sources import open_source
    return open_source(args.source, params)
