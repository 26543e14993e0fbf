"""Section "fitting a measured material" of the study's document: the seconds of
``fit-measured`` on one MERL file, per fit and per iteration (measured by
``bench.measured.run``), against the target."""
from .explore import load, verdict
from .format import num, sec, table

__all__ = ["steps", "text", "summary"]


def steps(settings):
    """Progress steps of the measurement: one per fit."""
    return settings.measured_runs


def summary(m, doc):
    """Summary bullet: seconds per fit against the target."""
    return [f"- `fit-measured` (section {doc.number('measured')}): one MERL material fitted "
            f"with `{m['model']}` in {sec(m['seconds_per_fit'])} on {m['threads']} threads "
            f"({1e3 * m['seconds_per_iteration']:.1f} ms per iteration; target "
            f"{m['target_seconds']} s: {verdict(m['seconds_per_fit'], m['target_seconds'])})."]


def text(m, doc):
    """The section's text under its heading."""
    later = max(m["runs"] - 1, 1)
    out = [f"`python -m mitsuba_brdfs fit-measured FILE --model {m['model']}` as the command "
           "runs it (`mitsuba_brdfs/bench/measured.py`): a full-size MERL file (90 x 90 x 180 "
           "bins, 35 MB, written from the Cook-Torrance fit of gold-paint) read and "
           f"subsampled to {m['samples']:,} measured pairs, then `{m['model']}` fitted from its "
           f"defaults: {m['iterations']} Adam iterations, each one eval of the BSDF on the "
           "pairs, the loss and its backpropagation, no rendering. Wall-clock seconds on "
           f"{m['threads']} Dr.Jit threads; "
           + (f"{m['runs']} fits, the first compiles the kernels (or loads them from the disk "
              "cache), the median of the others is reported. " if m["runs"] > 1 else
              "one fit, which also compiles the kernels. ") + 
           f"The target: one material under {m['target_seconds']} s on 2 cores."
           + load(m), ""]
    rows = [[str(i), sec(f["read"]), sec(f["fit"]), f"**{sec(f['total'])}**",
             f"{1e3 * f['per_iteration']:.1f} ms", f"{num(f['start_loss'])} -> {num(f['loss'])}"]
            for i, f in enumerate(m.get("fits", []), 1)]
    out += table(["fit", "read and subsample", "fit", "total", "per iteration",
                  "loss first -> last"], rows) + [""]
    first = (f" (median of {later}; the first, which compiles the kernels or loads them "
             f"from the disk cache, {sec(m['seconds_first_fit'])})" if m["runs"] > 1 else "")
    out += [f"A fit takes **{sec(m['seconds_per_fit'])}**{first}, "
            f"{1e3 * m['seconds_per_iteration']:.1f} ms per iteration: the target of "
            f"{m['target_seconds']} s is {verdict(m['seconds_per_fit'], m['target_seconds'])}.",
            ""]
    return out
