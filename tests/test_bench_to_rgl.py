"""The study's to-rgl timing: numbers from a short run, and the section's text."""
from mitsuba_brdfs.bench.sections import numbers, to_rgl
from mitsuba_brdfs.bench.sections.format import Document
from mitsuba_brdfs.bench.to_rgl import measure


def test_to_rgl_timing_reports_its_numbers():
    m = measure(runs=1)
    assert [s["name"].split(" ")[0] for s in m["sources"]] == ["roughplastic", "MERL", "RGL",
                                                               "ward,"]
    assert m["sources"][3]["bytes"] > 10 * m["sources"][0]["bytes"]   # anisotropic
    for s in m["sources"]:
        assert 0 < s["write"] < s["total"] and s["compare"] > 0 and s["bytes"] > 1e6
    m.update(target_seconds=10, load_average=[3.0, 4.0], cores=2)
    doc = Document(numbers())
    text = "\n".join(to_rgl.text(m, doc))
    assert text.count("| MERL file") == 1 and "under load" in text
    (line,) = to_rgl.summary(m, doc)
    assert line.startswith("- `to-rgl` (section 11)")
    slow = dict(m, sources=[dict(s, total=11.0) for s in m["sources"]])
    assert "**not met**" in "\n".join(to_rgl.text(slow, doc))
