"""Section "writing a measured material as an RGL file" of the study's document: the
seconds of ``to-rgl`` for a BSDF, a MERL file, an RGL file and an anisotropic BSDF (measured by
``bench.to_rgl.run``), against the target."""
from .explore import load, verdict
from .format import sec, table

__all__ = ["steps", "text", "summary"]


def steps(settings):
    """Progress steps of the measurement: one per conversion (four sources)."""
    return 4 * settings.to_rgl_runs


def _slowest(m):
    return max(s["total"] for s in m["sources"])


def summary(m, doc):
    """Summary bullet: the slowest source's seconds against the target."""
    parts = ", ".join(f"{s['name'].split(' (')[0].split(',')[0]} {sec(s['total'])}"
                      for s in m["sources"])
    return [f"- `to-rgl` (section {doc.number('to_rgl')}): a material written as an RGL "
            f"file and compared with its source in {parts} on {m['threads']} threads "
            f"(target {m['target_seconds']} s: {verdict(_slowest(m), m['target_seconds'])})."]


def text(m, doc):
    """The section's text under its heading."""
    r = m["resolution"]
    out = [f"`python -m mitsuba_brdfs to-rgl SOURCE -o OUT.bsdf` as the command runs it "
           "(`mitsuba_brdfs/bench/to_rgl.py`), at its default resolution "
           f"({r['theta_i']} incidences, a {r['grid']} x {r['grid']} adapted grid, "
           f"{r['vndf']} x {r['vndf']} VNDFs, a {r['ndf']}-node NDF): open the source "
           "(read a MERL file, load an RGL file in `measured`), measure it and write the "
           "file (retro-reflection, NDF, VNDFs, values: `mitsuba_brdfs/measured/acquire.py`), "
           "then compare the file with the source (the albedo at 0, 45, 70, 80, 85 and 88 "
           "deg by quadrature, at three azimuths for the anisotropic source; eval at 14,000 "
           "pairs drawn where the source reflects). "
           f"Wall-clock seconds on {m['threads']} Dr.Jit threads; "
           + (f"{m['runs']} conversions of each source, the median of all but the first "
              "(which compiles the kernels) reported. " if m["runs"] > 1 else
              "one conversion of each source, which also compiles the kernels. ")
           + f"The target: under {m['target_seconds']} s on 2 cores, comparison included."
           + load(m), ""]
    rows = [[s["name"], sec(s["open"]), sec(s["write"]), sec(s["compare"]),
             f"**{sec(s['total'])}**", sec(s["first"]), f"{s['bytes'] / 2 ** 20:.2f} MiB"]
            for s in m["sources"]]
    out += table(["source", "open", "measure and write", "compare", "total", "first run",
                  "file"], rows) + [""]
    out += [f"The slowest takes **{sec(_slowest(m))}**: the target of {m['target_seconds']} s "
            f"is {verdict(_slowest(m), m['target_seconds'])}. For an isotropic source most "
            "of it is the comparison (`--no-compare` leaves it out); an anisotropic file "
            "measures 17 times as many incidences.", ""]
    return out
