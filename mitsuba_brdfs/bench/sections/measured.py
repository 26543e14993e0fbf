"""Section "fitting a measured material" of the study's document: the seconds of
``fit-measured`` on one MERL file, per model, per fit and per evaluation, and of one call
that fits and ranks five models (measured by ``bench.measured.run``), against the target."""
from .explore import load, verdict
from .format import num, sec, table

__all__ = ["MODELS", "steps", "text", "summary"]

#: the models timed: name -> the dict the command loads
MODELS = {"ward": {"type": "ward"}, "cook_torrance": {"type": "cook_torrance"},
          "ashikhmin_shirley": {"type": "ashikhmin_shirley"},
          "ashikhmin_shirley (lambert)": {"type": "ashikhmin_shirley",
                                          "diffuse_term": "lambert"},
          "blinn_phong": {"type": "blinn_phong"}}


def steps(settings):
    """Progress steps of ``run``: one per fit (each run fits every model of ``MODELS``),
    and the several-model call."""
    return settings.measured_runs * len(MODELS) + 1


def summary(m, doc):
    """Summary bullet: the slowest model's seconds per fit against the target, and the
    image judge's per fit against its own."""
    image = m.get("image")
    return [f"- `fit-measured` (section {doc.number('measured')}): one MERL material fitted "
            f"by each of {len(m.get('models', {})) or 1} models in at most "
            f"{sec(m['seconds_per_fit'])} (`{m['model']}`) on {m['threads']} threads "
            f"({1e3 * m['seconds_per_evaluation']:.1f} ms per evaluation; target "
            f"{m['target_seconds']} s: {verdict(m['seconds_per_fit'], m['target_seconds'])})"
            + (f"; the image judge {sec(image['seconds_per_fit'])} per fit (target "
               f"{image['target_seconds']} s: "
               f"{verdict(image['seconds_per_fit'], image['target_seconds'])})"
               if image else "")
            + (f"; {len(m['table']['models'])} models fitted and ranked in one call in "
               f"{sec(m['table']['seconds'])}." if m.get("table") else ".")]


def text(m, doc):
    """The section's text under its heading."""
    later = max(m["runs"] - 1, 1)
    out = ["`python -m mitsuba_brdfs fit-measured FILE --model M` as the command runs it "
           "(`mitsuba_brdfs/bench/measured.py`): a full-size MERL file (90 x 90 x 180 "
           "bins, 35 MB, written from the Cook-Torrance fit of gold-paint) read and "
           f"subsampled to {m['samples']:,} measured pairs, then each model fitted from its "
           f"defaults: L-BFGS-B from several starts within {m['evaluations']} evaluations, "
           "each one eval of the BSDF on the pairs and on the energy term's directions, the "
           "loss and its backpropagation, no rendering. Wall-clock seconds on "
           f"{m['threads']} Dr.Jit threads; "
           + (f"{m['runs']} fits per model, the first compiles the kernels (or loads them "
              "from the disk cache), the median of the others is reported. "
              if m["runs"] > 1 else "one fit per model, which also compiles the kernels. ")
           + f"The target: one material under {m['target_seconds']} s on 2 cores, by any "
           "model." + load(m), ""]
    judged = all("seconds_image" in x for x in m.get("models", {}).values())
    rows = [[name, sec(x["seconds_read"]), f"**{sec(x['seconds_per_fit'])}**",
             sec(x["seconds_first_fit"]), f"{x['evaluations']:.0f}",
             f"{1e3 * x['seconds_per_evaluation']:.1f} ms",
             f"{num(x['start_loss'])} -> {num(x['loss'])}", f"{x['relative_rms']:.3f}"]
            + ([f"{sec(x['seconds_image'])} ({sec(x['seconds_first_image'])} first)",
                f"{x['image_error']:.2f}"] if judged else [])
            for name, x in m.get("models", {}).items()]
    out += table(["model", "read and subsample", "per fit (median)", "first fit",
                  "evaluations", "per evaluation", "loss start -> end", "relative RMS"]
                 + (["image judge", "Delta E ITP"] if judged else []), rows) + [""]
    image = m.get("image")
    if image:
        out += [f"The image judge (`measured/judge.py`, part of every fit above): the fit's "
                f"sphere rendered from three sides, {image['res']} x {image['res']} pixels "
                f"at {image['spp']} samples per pixel, and compared with the file's renders "
                f"by Delta E ITP: **{sec(image['seconds_per_fit'])}** per fit at most "
                f"(median; the first of a model compiles its kernels), target "
                f"{image['target_seconds']} s: "
                f"{verdict(image['seconds_per_fit'], image['target_seconds'])}. The file's "
                f"own renders, once per call (its conversion to an RGL file, which "
                f"Mitsuba's `measured` renders, included): {sec(image['seconds_reference'])}.",
                ""]
    first = (f" (median of {later}; the first, which compiles the kernels or loads them "
             f"from the disk cache, {sec(m['seconds_first_fit'])})" if m["runs"] > 1 else "")
    out += [f"The slowest model, `{m['model']}`, takes **{sec(m['seconds_per_fit'])}** "
            f"per fit{first}, {1e3 * m['seconds_per_evaluation']:.1f} ms per evaluation: "
            f"the target of {m['target_seconds']} s is "
            f"{verdict(m['seconds_per_fit'], m['target_seconds'])}.", ""]
    return out + _table_call(m)


def _table_call(m):
    """The several-model call's paragraph and its table (none where it was not timed)."""
    t = m.get("table")
    if not t:
        return []
    fits = sum(x["seconds"] for x in t["ranked"])
    judged = any(x.get("image_error") is not None for x in t["ranked"])
    out = [f"One call that fits and ranks {len(t['models'])} models, `fit-measured FILE "
           f"--model {','.join(t['models'])}` on the same file, in its own process as a "
           f"user runs it: **{sec(t['seconds'])}**, of which {sec(fits)} the fits (each "
           f"with its held-out loss{' and image judge' if judged else ''}); the rest is "
           "the start-up (Python, Mitsuba, the kernels: compiled, or loaded from the disk "
           "cache), reading the file"
           + (", the file's renders for the image judge" if judged else "")
           + " and writing the table, the XML, the summaries and the plots. Ranked by "
           + ("image error:" if judged else "held-out loss:"), ""]
    rows = [[f"`{x['model']}`"] + ([num(x["image_error"])] if judged else [])
            + [num(x["holdout_loss"]), sec(x["seconds"])] for x in t["ranked"]]
    return out + table(["model"] + (["image error (Delta E ITP)"] if judged else [])
                       + ["held-out loss", "seconds (fit, held-out loss, image judge)"],
                       rows) + [""]
