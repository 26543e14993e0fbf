"""How close ``to-rgl``'s files come to their sources near the horizon.

Each source is written at the command's default resolution (``measured.acquire``) and its
file loaded in Mitsuba's ``measured``; the directional albedo of both (the half-vector
quadrature of ``measured.roundtrip``, relative per channel, ``roundtrip.FLOOR``) at 70,
80, 85 and 88 deg, the largest error over 8 azimuths for an anisotropic source; and
``check measured --only energy`` on the file (the mean sample weight at incidences up to
89 deg at most 1). ``--point-values`` writes the files as before the footprint averages
and the grazing incidences (every node holds the source's eval at its direction, and the
incidences follow the sigma rule alone), to show what they change. Prints a Markdown
table (docs/measured.md, "Near the horizon").

    python scripts/to_rgl_horizon.py [--point-values]
"""
import math
import os
import subprocess
import sys
import tempfile

import numpy as np

#: (label, the source's load_dict dict)
SOURCES = [
    ("`ashikhmin_shirley` nu = nv = 100", {"type": "ashikhmin_shirley", "nu": 100.0,
                                            "nv": 100.0}),
    ("`ashikhmin_shirley` nu 10, nv 1000", {"type": "ashikhmin_shirley", "nu": 10.0,
                                             "nv": 1000.0}),
    ("`ashikhmin_shirley` (defaults)", {"type": "ashikhmin_shirley"}),
    ("Mitsuba's `roughplastic` (alpha 0.1, Beckmann)", {"type": "roughplastic"}),
    ("Mitsuba's `roughplastic`, alpha 0.02", {"type": "roughplastic", "alpha": 0.02}),
    ("`ward` (defaults)", {"type": "ward"}),
    ("`ward`, alpha_u 0.05, alpha_v 0.3", {"type": "ward", "alpha_u": 0.05, "alpha_v": 0.3}),
    ("Mitsuba's `roughconductor`, GGX, alpha 0.1", {"type": "roughconductor",
                                                     "distribution": "ggx"}),
    ("Mitsuba's `roughconductor`, alpha 0.05 (Beckmann)", {"type": "roughconductor",
                                                          "alpha": 0.05}),
]
THETAS = (70, 80, 85, 88)
PHIS = tuple(np.arange(8) * np.pi / 4 + 0.1)


def main(point_values=False):
    import drjit as dr
    import mitsuba as mi
    dr.set_thread_count(2)
    from mitsuba_brdfs.variant import set_variant
    set_variant("llvm_ad_rgb")
    from mitsuba_brdfs.measured import acquire, convert, footprint, roundtrip, sources
    if point_values:
        footprint.REFINE_TOL = math.inf
        acquire._incidences = acquire._sigma_rule
    print("| source | albedo error at " + " / ".join(map(str, THETAS)) + " deg (%) "
          "| `check measured`: energy |")
    print("|---|---|---|")
    with tempfile.TemporaryDirectory() as tmp:
        for label, spec in SOURCES:
            evaluate = sources.bsdf_evaluator(mi.load_dict(spec))
            source = sources.Source(evaluate, spec["type"], "bsdf", label, [])
            path = os.path.join(tmp, "x.bsdf")
            s = convert.convert(source, path, acquire.Resolution(), compare=False)
            written = sources.bsdf_evaluator(mi.load_dict({"type": "measured",
                                                          "filename": path}))
            errors = []
            for theta in THETAS:
                worst = 0.0
                for phi in (PHIS[:1] if s["isotropic"] else PHIS):
                    a = roundtrip.quadrature_albedo(evaluate, theta, 96, phi)
                    b = roundtrip.quadrature_albedo(written, theta, 96, phi)
                    scale = np.maximum(np.abs(a), roundtrip.FLOOR * np.abs(a).max())
                    e = (b - a) / scale
                    k = int(np.argmax(np.abs(e)))
                    worst = e[k] if abs(e[k]) > abs(worst) else worst
                errors.append(worst)
            check = subprocess.run([sys.executable, "-m", "mitsuba_brdfs", "check",
                                    "measured", "-p", f"filename={path}", "--only", "energy"],
                                   capture_output=True, text=True)
            line = next((x.strip() for x in check.stdout.splitlines() if "energy" in x), "")
            verdict = line.split()[0] if line else "?"
            largest = line.split("largest albedo ")[-1].split(" (bound")[0] if line else ""
            cells = [f"{100 * e:+.1f}" for e in errors]
            print(f"| {label} | {' / '.join(cells)} | {verdict} ({largest}) |", flush=True)


if __name__ == "__main__":
    main("--point-values" in sys.argv[1:])
