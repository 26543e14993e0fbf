"""The study's fit-measured timing: numbers and paragraph from a short run."""
from mitsuba_brdfs.bench.measured import run


def test_measured_timing_reports_its_numbers():
    numbers, paragraph = run(runs=2, iterations=20, samples=2000)
    assert numbers["iterations"] == 20 and numbers["samples"] == 2000
    assert 0 < numbers["seconds_per_iteration"] * 20 <= numbers["seconds_per_fit"]
    assert numbers["loss"] < numbers["start_loss"]
    assert f"{numbers['seconds_per_fit']:.1f} s" in paragraph
    assert f"{1e3 * numbers['seconds_per_iteration']:.1f} ms per iteration" in paragraph
