"""``python -m mitsuba_brdfs to-merl SOURCE -o OUT.binary``: any BSDF, RGL file or MERL file
as a MERL file.

SOURCE is what ``to-rgl`` takes (``measured.sources``): a plugin of Mitsuba's, of this
package or of a ``--load`` file, with ``-p KEY=VALUE`` parameters; an XML file holding one
``<bsdf>``; an RGL ``.bsdf`` file (through Mitsuba's ``measured``) or a MERL ``.binary``
file. The file holds the source's BRDF (eval / cos theta_o) at the centre of each of MERL's
bins (``merl.directions``; 90 x 90 x 180 bins by default, ``--dims`` others), unmeasured
(negative in the file, as MERL marks them) where a direction is within 1e-6 of the horizon.
MERL's format is isotropic: an anisotropic source is written as it is at phi_h = 0, with a
note. A file to start from when no measurement is at hand: ``fit-measured``, ``explore``
and ``to-rgl`` read it as they read the database's files.

Exit status 0, 2 for a usage error (an unknown plugin, a file that is neither, an output
that may not be replaced) in one line; the file is written whole (``output.atomic``).

    python -m mitsuba_brdfs to-merl cook_torrance -p roughness=0.2 -o my-paint.binary
    python -m mitsuba_brdfs to-merl paper_white_rgb.bsdf -o paper_white.binary
"""
import json
import os
import time

from .writing import add_source_arguments

__all__ = ["parse_dims", "add_arguments", "run"]

#: the file is written whole (``output.atomic``)
WRITES_ATOMICALLY = True


def parse_dims(text):
    """``--dims TH,TD,PD``: MERL's bins along theta_h, theta_d and phi_d (each 1..1000)."""
    import argparse
    parts = text.split(",")
    try:
        dims = tuple(int(p) for p in parts)
    except ValueError:
        dims = ()
    if len(dims) != 3 or not all(1 <= d <= 1000 for d in dims):
        raise argparse.ArgumentTypeError(f"expected three integers in 1..1000 such as "
                                         f"90,90,180, got {text!r}")
    return dims


def add_arguments(p):
    from .merl import DIMS
    add_source_arguments(p, "OUT.binary", "MERL")
    p.add_argument("--dims", type=parse_dims, default=DIMS, metavar="TH,TD,PD",
                   help=f"bins along theta_h, theta_d, phi_d (default: "
                        f"{','.join(map(str, DIMS))}, MERL's database)")
    p.add_argument("--json", action="store_true",
                   help="print a summary as JSON (nothing else on stdout)")


def run(args):
    import numpy as np
    from . import merl, sources
    from .writing import open_for_writing
    from ..output import atomic
    from ..progress import advance, progress_bar
    t0 = time.perf_counter()
    source = open_for_writing(args, "to-merl", "MERL files hold RGB, written")
    notes = list(source.notes)
    isotropic = (source.isotropic if source.isotropic is not None
                 else sources.is_isotropic(source.evaluate))
    if not isotropic:
        notes.append("anisotropic: a MERL file is isotropic, so it holds the source as it "
                     "is at phi_h = 0 (to-rgl writes anisotropic RGL files)")
    dims = tuple(args.dims)
    with progress_bar(2, "to-merl", unit="steps", enabled=not args.json) as bar:
        wi, wo = merl.directions(dims)
        ok = (wi[:, 2] > 1e-6) & (wo[:, 2] > 1e-6)
        f = np.full((len(wi), 3), np.nan)
        f[ok] = np.asarray(source.evaluate(wi[ok], wo[ok]), float) / wo[ok][:, 2:3]
        advance(bar, 1, "evaluated")
        if not np.isfinite(f[ok]).all():
            bad = int((~np.isfinite(f[ok]).all(axis=1)).sum())
            raise ValueError(f"{source.name}: eval is not finite at {bad} of MERL's bins")
        negative = int((f[ok] < 0).any(axis=1).sum())
        if negative:  # MERL marks unmeasured bins by negative values: keep them measured
            f[ok] = np.maximum(f[ok], 0.0)
            notes.append(f"{negative} bins with negative values (out-of-gamut colours) "
                         f"written as 0 (a negative value marks a bin unmeasured in MERL's "
                         f"format)")
        with atomic(args.output) as tmp:
            merl.write(tmp, f, dims)
        advance(bar, 1, "written")
    summary = {"source": source.name, "kind": source.kind, "description": source.description,
               "output": args.output, "bytes": os.path.getsize(args.output),
               "dims": list(dims), "unmeasured": int((~ok).sum()), "notes": notes,
               "seconds": round(time.perf_counter() - t0, 3)}
    if args.json:
        print(json.dumps(summary, indent=1))
        return 0
    print(f"{args.output}: {source.description} as a MERL file, "
          f"{summary['bytes'] / 2**20:.2f} MiB ({dims[0]} x {dims[1]} x {dims[2]} bins, "
          f"{summary['unmeasured']} unmeasured: a direction on or below the horizon) in "
          f"{summary['seconds']:.1f} s")
    for note in notes:
        print(f"  note: {note}")
    return 0
