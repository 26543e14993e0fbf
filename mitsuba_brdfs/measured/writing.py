"""The source of a command that writes a measured file (``to-rgl``, ``to-merl``): its
arguments checked in one line before any work, its variant set, the source opened."""

__all__ = ["open_for_writing"]


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
