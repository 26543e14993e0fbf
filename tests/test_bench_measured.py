"""The study's fit-measured timing: numbers from a short run, and the section's text."""
from mitsuba_brdfs.bench.measured import MODELS, measure
from mitsuba_brdfs.bench.sections import measured, numbers
from mitsuba_brdfs.bench.sections.format import Document
from mitsuba_brdfs.measured import acquire
from mitsuba_brdfs.measured.fitting import PENALTIES, STAGE_BUDGET


def test_measured_timing_reports_its_numbers():
    """Two models, two short fits each (each judged by tiny renders): per-model seconds,
    the slowest reported against the target, a row per model, the image judge's seconds
    per fit against its target, the verdict said both ways; one call of the command
    fitting and ranking two models: its seconds (more than its fits'), the models ranked
    by held-out loss, said in the text and the summary."""
    models = {k: MODELS[k] for k in ("ward", "cook_torrance")}
    small = acquire.Resolution(ndf=32, theta_i=8, vndf=32, grid=16)
    m = measure(runs=2, evaluations=20, samples=2000, models=models,
                table=("lambert", "cook_torrance"), image=(16, 4, small),
                table_args=["--image-spp", "0"])
    # the image judge, timed per fit and once for the file's renders
    image = m["image"]
    assert image["res"] == 16 and image["spp"] == 4 and image["target_seconds"] == 5
    assert 0 < image["seconds_per_fit"] == max(x["seconds_image"] for x in m["models"].values())
    assert image["seconds_reference"] > 0
    for x in m["models"].values():
        assert x["image_error"] > 0 and all(0 < f["image"] < f["total"] for f in x["fits"])
    assert m["evaluations"] == 20 and m["samples"] == 2000 and set(m["models"]) == set(models)
    # the budget of the fit, and of each stage of the albedo constraint where it runs
    most = 20 * (1 + STAGE_BUDGET * (1 + len(PENALTIES)))
    for x in m["models"].values():
        assert len(x["fits"]) == 2 and x["evaluations"] <= most
        assert 0 < x["seconds_per_evaluation"] * x["evaluations"] <= x["seconds_per_fit"]
        assert x["loss"] < x["start_loss"]
    assert m["seconds_per_fit"] == max(x["seconds_per_fit"] for x in m["models"].values())
    m.update(target_seconds=30, load_average=[3.0, 4.0], cores=2)
    doc = Document(numbers())
    text = "\n".join(measured.text(m, doc))
    assert f"{1e3 * m['seconds_per_evaluation']:.1f} ms per evaluation" in text
    assert "The image judge (`measured/judge.py`, part of every fit above)" in text
    assert "| image judge | Delta E ITP |" in text
    assert "the target of 30 s is met" in text and "under load" in text
    assert text.count("| ward |") == 1 and text.count("| cook_torrance |") == 1
    (line,) = measured.summary(m, doc)
    assert line.startswith("- `fit-measured` (section 10)") and "target 30 s: met" in line
    assert "the image judge" in line and "target 5 s: met" in line
    t = m["table"]
    assert t["models"] == ["lambert", "cook_torrance"]
    assert [x["model"] for x in t["ranked"]] == ["cook_torrance", "lambert"]  # its own data
    assert t["ranked"][0]["holdout_loss"] < t["ranked"][1]["holdout_loss"]
    assert 0 < sum(x["seconds"] for x in t["ranked"]) < t["seconds"]
    assert ("One call that fits and ranks 2 models, `fit-measured FILE --model "
            "lambert,cook_torrance`") in text and "| `cook_torrance` | " in text, text
    assert "2 models fitted and ranked in one call in" in line
    # over the target, said so
    slow = dict(m, seconds_per_fit=31.0)
    assert "**not met**" in "\n".join(measured.text(slow, doc))
