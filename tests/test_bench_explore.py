"""The study's section on the explorer: its text and summary from given numbers (the
measurement itself runs in ``bench --quick``, tests/test_bench_command.py)."""
from mitsuba_brdfs.bench.sections import explore, numbers
from mitsuba_brdfs.bench.sections.format import Document

SERVER = {"plots_ms": 95.0, "sphere_ms": 60.0, "pass_ms": 55.0, "first_plots_ms": 900.0,
          "first_sphere_ms": 400.0, "repeats": 15, "threads": 2, "variant": "llvm_ad_rgb"}
PAGE = {"param_ms": 170.0, "param_fetch_ms": 50.0, "param_script_ms": 80.0,
        "param_sphere_ms": 320.0, "incidence_script_ms": 30.0,
        "incidence_ms": 90.0, "incidence_fetch_ms": 30.0, "repeats": 10,
        "renderer": "SwiftShader driver"}
TARGETS = {"plots_ms": 150, "sphere_ms": 500}


def test_explorer_section_compares_the_medians_with_the_targets():
    doc = Document(numbers())
    ex = {"server": SERVER, "page": PAGE, "targets": TARGETS, "load_average": [4.1, 4.5],
          "cores": 2}
    text = "\n".join(explore.text(ex, doc))
    assert "| a parameter typed: the page redrawn | **170.0 ms** (requests 50.0 ms, " \
           "scripts 80.0 ms) | 150 ms | **not met** |" in text
    assert "| a parameter changed: every plot's data (server) | **95.0 ms** | 150 ms | met |" \
        in text
    assert "the first pass of its sphere in the page | **320.0 ms** | 500 ms | met |" in text
    assert "under load" in text and "4.1 at the start" in text
    (line,) = explore.summary(ex, doc)
    assert "section 9" in line and "170.0 ms" in line and "**not met**" in line

    # without chromium: the server's numbers, and the reason the page is missing
    ex = {"server": SERVER, "targets": TARGETS,
          "skipped": ["the page's redraw was not measured: no chromium"]}
    text = "\n".join(explore.text(ex, doc))
    assert "page redrawn" not in text and "not measured: no chromium" in text
    assert "not measured" in explore.summary(ex, doc)[0]


def test_the_page_fits_are_timed():
    """``measure_fits`` times the page's fit as the server runs it (a small MERL file, one
    model and a small budget here; the full table: ``python -m mitsuba_brdfs.bench.explore``)."""
    from mitsuba_brdfs.bench.explore import FIT_TARGET_S, fits_table, measure_fits
    r = measure_fits(["cook_torrance"], repeats=1, dims=(30, 30, 60), samples=1000,
                     evaluations=120)
    f = r["fits"]["cook_torrance"]
    assert f["first_s"] > 0 and f["median_s"] > 0 and 0 < f["evaluations"] <= r["budget"]["most"]
    assert f["relative_rms"] < 0.02 and f["holdout_loss"] < 1e-3  # the file's own model
    assert "| `cook_torrance` |" in fits_table(r) and FIT_TARGET_S == 5
