"""``python -m mitsuba_brdfs to-rgl SOURCE -o OUT.bsdf``: any BSDF, MERL file or RGL file as
an RGL file that Mitsuba's ``measured`` plugin renders.

SOURCE is what ``check`` takes (a plugin of Mitsuba's, of this package or of a ``--load``
file, with ``-p KEY=VALUE`` parameters; an XML file holding one ``<bsdf>``), a MERL
``.binary`` file or an RGL ``.bsdf`` file (``measured.sources``). The file is a virtual
measurement as Dupuy & Jakob take a real one (``measured.acquire``): the NDF from the
retro-reflection by power iteration, sigma, the incidences, a VNDF per incidence, and the
luminance and RGB values on the adapted grid. An anisotropic source (eval changes when
both directions turn about the normal) gets an anisotropic file: its incidences at
``--phi-i`` azimuths per quarter turn too, over the whole circle.

Then the file is loaded in ``measured`` and compared with the source (``--no-compare``
skips it): the directional albedo at 0, 45, 70, 80, 85 and 88 deg and the median relative
error of eval where the source reflects (``measured.roundtrip``), printed under the file's
name with every option of a BSDF source, its plugin's defaults included (Mitsuba's
``roughconductor`` is a Beckmann lobe unless ``-p distribution=ggx``).

Resolutions (``--theta-i``, ``--grid``, ``--vndf``, ``--ndf``, ``--phi-i``): 16
incidences, a 64 x 64 adapted grid, 64 x 64 VNDFs and a 128-node NDF by default, a 1.25
MiB file (RGL's database files: 8 incidences, 32 x 32 or 64 x 64, 0.6-1.0 MiB); an
anisotropic file 17 x 16 incidences, 21 MiB. ``docs/measured.md`` gives the errors per
resolution. Exit status 0, 2 for a usage error (an unknown plugin, a file
that is neither, a truncated file, a source that reflects nothing) in one line.

    python -m mitsuba_brdfs to-rgl roughconductor -p alpha=0.2 -o rough_gold.bsdf
    python -m mitsuba_brdfs to-rgl gold-paint.binary -o gold-paint.bsdf
"""
import json

from ..arguments import int_range
from .writing import add_source_arguments
from .convert import convert, preflight

__all__ = ["add_arguments", "run"]

#: the file is written whole (``output.atomic``)
WRITES_ATOMICALLY = True


def add_arguments(p):
    from .acquire import Resolution
    d = Resolution()
    add_source_arguments(p, "OUT.bsdf", "RGL")
    p.add_argument("--theta-i", type=int_range(3, 256), default=d.theta_i, metavar="N",
                   help=f"incidences measured (default: {d.theta_i})")
    p.add_argument("--grid", type=int_range(4, 512), default=d.grid, metavar="N",
                   help=f"nodes per side of the adapted grid (default: {d.grid})")
    p.add_argument("--vndf", type=int_range(4, 1024), default=d.vndf, metavar="N",
                   help=f"nodes per side of each VNDF table (default: {d.vndf})")
    p.add_argument("--ndf", type=int_range(8, 1024), default=d.ndf, metavar="N",
                   help=f"polar nodes of the NDF and sigma (default: {d.ndf})")
    p.add_argument("--phi-i", type=int_range(1, 64), default=d.phi_i, metavar="N",
                   help=f"an anisotropic source's azimuths of incidence: N steps per quarter "
                        f"turn, 4 N + 1 over the whole circle (default: {d.phi_i}, every "
                        f"{90 / d.phi_i:g} deg)")
    p.add_argument("--description", metavar="TEXT",
                   help="the file's description (default: names the source)")
    p.add_argument("--no-compare", action="store_true",
                   help="do not compare the written file with the source")
    p.add_argument("--json", action="store_true",
                   help="print a summary as JSON (nothing else on stdout)")


def run(args):
    from .writing import open_for_writing
    from .acquire import Resolution
    from ..output import jsonable
    from ..progress import progress_bar
    source = open_for_writing(args, "to-rgl", "to-rgl writes RGB files")
    res = Resolution(ndf=args.ndf, theta_i=args.theta_i, vndf=args.vndf, grid=args.grid,
                     phi_i=args.phi_i)
    isotropic = preflight(source)
    steps = 3 + (0 if args.no_compare else 1)
    with progress_bar(steps, "to-rgl", unit="steps", enabled=not args.json) as bar:
        summary = convert(source, args.output, res, args.description, not args.no_compare, bar,
                          isotropic)
    if args.json:
        print(json.dumps(jsonable(summary), indent=1, allow_nan=False))
        return 0
    r = summary["resolution"]
    incidences = (f"{r['theta_i']} incidences" if isotropic else
                  f"{r['azimuths']} x {r['theta_i']} incidences, anisotropic")
    ndf = (f"{r['ndf']}-node NDF" if isotropic else
           f"{r['ndf_phi']} x {r['ndf_aniso']} NDF")
    print(f"{summary['output']}: {source.description} as an RGL file, "
          f"{summary['bytes'] / 2**20:.2f} MiB ({incidences}, {r['grid']} x {r['grid']} "
          f"grid, {r['vndf']} x {r['vndf']} VNDF, {ndf}) in {summary['seconds']:.1f} s")
    if summary["options"]:
        print("  source: " + ", ".join(
            f"{k} = {v}" + (" (default)" if k in summary["defaults"] else "")
            for k, v in summary["options"].items()))
    if summary["nodes_averaged"]:
        print(f"  {summary['nodes_averaged']} of {summary['nodes']} grid nodes hold the "
              f"source's average over their footprint (where it is not smooth), the others "
              f"its eval")
    for note in summary["notes"]:
        print(f"  note: {note}")
    if summary.get("negative_values_clipped"):
        print(f"  note: {summary['negative_values_clipped']} negative values clipped to 0")
    if "compare" in summary:
        c = summary["compare"]
        print("  albedo (source -> file, error; the worst azimuth):")
        for t, v in c["albedo"].items():
            print(f"    {t:>2} deg {_rgb(v['source'])} -> {_rgb(v['file'])} "
                  f"({100 * v['error']:.2f} %)")
        print(f"  eval where the source reflects: median error "
              f"{100 * c['eval_median_error']:.2f} %, {100 * c['eval_within_10_percent']:.1f} % "
              f"of {c['pairs']} pairs within 10 %")
    return 0


def _rgb(values):
    return "(" + ", ".join(f"{v:.4f}" for v in values) + ")"
