"""How close ``to-rgl``'s files come to their sources, up to 88 deg (docs/measured.md).

Each source is written at the command's default resolution (``measured.acquire``) and its
file loaded in Mitsuba's ``measured``; the directional albedo of both (the half-vector
quadrature of ``measured.roundtrip``, relative per channel or to a tenth of the brightest
channel, ``roundtrip.FLOOR``; signed, the channel furthest off) at 0, 45, 70, 80, 85 and
88 deg, the worst of 8 azimuths for an anisotropic source; eval where the source reflects
(``roundtrip.compare``: the median relative error, the share within 10 %); and ``check
measured --only energy`` on the file (the mean sample weight at incidences up to 89 deg
at most 1). The sources: BSDFs (``SOURCES``), MERL files written from two Ngan et al.
fits at MERL's resolution, and the RGL files of ``--folder``. ``--point-values`` writes
the files as before the footprint averages and the grazing incidences (every node holds
the source's eval at its direction, the incidences follow the sigma rule alone), to show
what they change; ``--only TEXT`` keeps the sources whose label holds TEXT. Prints a
Markdown table.

    python scripts/to_rgl_horizon.py [--folder RGL] [--point-values] [--only TEXT]
"""
import argparse
import glob
import math
import os
import subprocess
import sys
import tempfile

import numpy as np

#: (label, the source's load_dict dict)
SOURCES = [
    ("`ashikhmin_shirley` (nu = nv = 100)", {"type": "ashikhmin_shirley"}),
    ("`ashikhmin_shirley` nu = nv = 1000", {"type": "ashikhmin_shirley", "nu": 1000.0,
                                             "nv": 1000.0}),
    ("`ashikhmin_shirley` nu 10, nv 1000", {"type": "ashikhmin_shirley", "nu": 10.0,
                                             "nv": 1000.0}),
    ("`ward`", {"type": "ward"}),
    ("`ward`, alpha_u 0.05, alpha_v 0.3", {"type": "ward", "alpha_u": 0.05, "alpha_v": 0.3}),
    ("`cook_torrance`", {"type": "cook_torrance"}),
    ("`oren_nayar`", {"type": "oren_nayar"}),
    ("`blinn_phong`", {"type": "blinn_phong"}),
    ("`phong`", {"type": "phong"}),
    ("`torrance_sparrow`", {"type": "torrance_sparrow"}),
    ("`lambert`", {"type": "lambert"}),
    ("`toon`", {"type": "toon"}),
    ("Mitsuba's `diffuse`", {"type": "diffuse"}),
    ("Mitsuba's `roughconductor`, GGX, alpha 0.1", {"type": "roughconductor",
                                                     "distribution": "ggx"}),
    ("Mitsuba's `roughconductor`, alpha 0.3 (Beckmann)", {"type": "roughconductor",
                                                         "alpha": 0.3}),
    ("Mitsuba's `roughconductor`, alpha 0.05 (Beckmann)", {"type": "roughconductor",
                                                          "alpha": 0.05}),
    ("Mitsuba's `roughplastic` (alpha 0.1, Beckmann)", {"type": "roughplastic"}),
    ("Mitsuba's `roughplastic`, alpha 0.02", {"type": "roughplastic", "alpha": 0.02}),
    ("Mitsuba's `principled`", {"type": "principled"}),
]
#: MERL files written from these Ngan et al. fits: (label, model, material)
MERL = [("MERL file, 90 x 90 x 180 (written from the Cook-Torrance fit of gold-paint)",
         "cook_torrance", "gold-paint"),
        ("MERL file, 90 x 90 x 180 (written from the Ward fit of blue-metallic-paint)",
         "ward", "blue-metallic-paint")]
PHIS = tuple(np.arange(8) * np.pi / 4 + 0.1)


def _albedo_errors(evaluate, written, isotropic):
    """The signed albedo error (the channel furthest off, of the worst azimuth) at each of
    ``roundtrip.ALBEDO_THETAS``."""
    from mitsuba_brdfs.measured import roundtrip
    errors = []
    for theta in roundtrip.ALBEDO_THETAS:
        worst = 0.0
        for phi in (PHIS[:1] if isotropic else PHIS):
            a = roundtrip.quadrature_albedo(evaluate, theta, 96, phi)
            b = roundtrip.quadrature_albedo(written, theta, 96, phi)
            e = (b - a) / np.maximum(np.abs(a), roundtrip.FLOOR * np.abs(a).max())
            k = int(np.argmax(np.abs(e)))
            worst = e[k] if abs(e[k]) > abs(worst) else worst
        errors.append(worst)
    return errors


def _energy(path):
    """``check measured --only energy`` on the file: (PASS or FAIL, its largest albedo)."""
    r = subprocess.run([sys.executable, "-m", "mitsuba_brdfs", "check", "measured", "-p",
                        f"filename={path}", "--only", "energy"], capture_output=True,
                       text=True)
    line = next((x.strip() for x in r.stdout.splitlines() if "energy" in x), "")
    if not line:
        return "?", ""
    largest = line.split("largest albedo ")[-1].split(" +-")[0]
    at = line.split("at theta_i = ")[-1].split(" deg")[0]
    return line.split()[0], f"{largest} at {at} deg"


def sources(folder, tmp):
    """(label, ``sources.Source``) of every source."""
    import mitsuba as mi
    from mitsuba_brdfs import presets
    from mitsuba_brdfs.measured import merl
    from mitsuba_brdfs.measured import sources as S
    for label, spec in SOURCES:
        yield label, S.Source(S.bsdf_evaluator(mi.load_dict(spec)), spec["type"], "bsdf",
                              label, [])
    for label, model, material in MERL:
        path = os.path.join(tmp, f"{material}.binary")
        merl.write(path, merl.from_bsdf(mi.load_dict(presets.ngan2005(model, material))))
        yield label, S.open_source(path)
    for path in sorted(glob.glob(os.path.join(folder, "*.bsdf"))) if folder else ():
        name = os.path.splitext(os.path.basename(path))[0]
        yield f"RGL `{name}`", S.open_source(path)


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--folder", help="a folder of RGL files (their RGB files) to convert too")
    p.add_argument("--point-values", action="store_true",
                   help="write the files as before the footprint averages and the grazing "
                        "incidences")
    p.add_argument("--only", help="only the sources whose label holds this text")
    args = p.parse_args(argv)
    import drjit as dr
    import mitsuba as mi
    dr.set_thread_count(2)
    from mitsuba_brdfs.variant import set_variant
    set_variant("llvm_ad_rgb")
    from mitsuba_brdfs.measured import acquire, convert, footprint, roundtrip
    from mitsuba_brdfs.measured import sources as S
    if args.point_values:
        footprint.REFINE_TOL = math.inf
        acquire._incidences = acquire._sigma_rule
    thetas = " / ".join(str(t) for t in roundtrip.ALBEDO_THETAS)
    print(f"| source | albedo error at {thetas} deg (%) | eval: median error (%) | "
          f"within 10 % | `check measured`: energy (largest albedo) |")
    print("|---|---|---|---|---|")
    with tempfile.TemporaryDirectory() as tmp:
        for label, source in sources(args.folder, tmp):
            if args.only and args.only not in label:
                continue
            path = os.path.join(tmp, "x.bsdf")
            s = convert.convert(source, path, acquire.Resolution(), compare=False)
            written = S.bsdf_evaluator(mi.load_dict({"type": "measured", "filename": path}))
            errors = _albedo_errors(source.evaluate, written, s["isotropic"])
            c = roundtrip.compare(source.evaluate, written, phis=(0.0,))
            verdict, largest = _energy(path)
            cells = " / ".join(f"{100 * e:+.1f}" for e in errors)
            print(f"| {label} | {cells} | {100 * c['eval_median']:.2f} | "
                  f"{100 * c['eval_within_10']:.1f} | {verdict} ({largest}) |", flush=True)


if __name__ == "__main__":
    main()
