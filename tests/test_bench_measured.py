"""The study's fit-measured timing: numbers from a short run, and the section's text."""
from mitsuba_brdfs.bench.measured import measure
from mitsuba_brdfs.bench.sections import measured, numbers
from mitsuba_brdfs.bench.sections.format import Document


def test_measured_timing_reports_its_numbers():
    m = measure(runs=2, iterations=20, samples=2000)
    assert m["iterations"] == 20 and m["samples"] == 2000 and len(m["fits"]) == 2
    assert 0 < m["seconds_per_iteration"] * 20 <= m["seconds_per_fit"]
    assert m["loss"] < m["start_loss"]
    m.update(target_seconds=30, load_average=[3.0, 4.0], cores=2)
    doc = Document(numbers())
    text = "\n".join(measured.text(m, doc))
    assert f"{1e3 * m['seconds_per_iteration']:.1f} ms per iteration" in text
    assert "the target of 30 s is met" in text and "under load" in text
    assert text.count("| 1 |") == 1 and text.count("| 2 |") == 1  # a row per fit
    (line,) = measured.summary(m, doc)
    assert line.startswith("- `fit-measured` (section 10)") and "target 30 s: met" in line
    # over the target, said so
    slow = dict(m, seconds_per_fit=31.0)
    assert "**not met**" in "\n".join(measured.text(slow, doc))
