"""The ``bench`` command: a ``bench --quick`` run writes a sane study.

The command's run leaves out the sections that other tests measure (``OWN_TESTS``):
``measured`` and ``to_rgl`` (tests/test_bench_measured.py, tests/test_bench_to_rgl.py); the
explorer's, the error against time and the speed against Mitsuba's C++ plugins run here
in this process (their measurements as ``--quick`` makes them, on the lead model and
``lambert`` for the last two; their text and plots drawn from the results): every kind of
number of the study is still measured, once, by one test."""
import json
import math
import os
import subprocess
import sys

import pytest

from mitsuba_brdfs import image_fit as F

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def _finite_positive(x):
    return isinstance(x, (int, float)) and math.isfinite(x) and x > 0


#: the sections measured by tests of their own
OWN_TESTS = ("explore", "measured", "to_rgl", "error", "cpp")


@pytest.mark.slow
def test_bench_quick_writes_a_sane_study(tmp_path):
    from mitsuba_brdfs.bench.sections import KEYS
    sections = [k for k in KEYS if k not in OWN_TESTS]
    r = subprocess.run([sys.executable, "-m", "mitsuba_brdfs", "bench", "--quick", "--out",
                        str(tmp_path), "--sections", *sections], cwd=ROOT, capture_output=True,
                       text=True, timeout=900)
    assert r.returncode == 0, r.stderr[-3000:]
    doc = (tmp_path / "performance.md").read_text()
    res = json.loads((tmp_path / "perf" / "results.json").read_text())
    assert res["mode"] == "quick" and len(res["git"]["commit"]) == 40
    assert res["sections"] == sections and "ashikhmin_shirley" in res["available"]
    assert res["git"]["commit"] in doc and "--quick" in doc
    assert _finite_positive(res["total_seconds"])  # (its length is timing, not asserted)
    for png in ("effects", "stable_vs_naive", "memory", "startup"):
        p = tmp_path / "perf" / f"{png}.png"
        assert p.exists() and p.stat().st_size > 1000, png
        assert f"perf/{png}.png" in doc

    # 4. effects: every ratio finite and positive; compile and instruction counts reported
    check_pairs(res["effects"])
    # a lobe of constant zero weight is not traced
    for key, p in res["effects"]["pairs"].items():
        if p["kind"] == "lobe":
            assert p["instr_a"] < p["instr_b"], key
    for f, s in res["figures"]["scenes"].items():
        assert _finite_positive(s["ratio"]), f

    # 3. accuracy: the stable forms are exact to float32, their ratios finite
    forms = res["accuracy"]["stable_vs_naive"]["forms"]
    for name, row in forms.items():
        assert _finite_positive(row["ratio_naive_stable"]), name
        for e, er in row["error"].items():
            assert er["stable"]["nonfinite"] == 0 and float(er["stable"]["max"]) < 1e-3, (name, e)
    chi2 = res["accuracy"]["chi2"]["samples"]
    assert all(not r["clean"]["rejected"] for r in chi2.values())
    assert any(v["rejected"] for r in chi2.values() for v in r["scale"].values())

    # 5. memory: every CLI render succeeded and was measured
    for m in res["memory"]["renders"]:
        assert m["status"] == 0 and _finite_positive(m["peak_rss_mib"]), m

    # 6. first image: every phase measured; an empty cache compiles every kernel (none is
    # loaded from it), the filled one runs as many; only the Python plugin imports the
    # package. How many kernels Dr.Jit finds in a filled cache is its business (now and
    # then it compiles some anew), and compile times are timings: neither is asserted.
    pairs = res["startup"]["pairs"]
    assert "lambert" in pairs
    for key, p in pairs.items():
        for side in ("python", "cpp"):
            empty, filled = p["empty"][side], p["filled"][side]
            for m in (empty, filled):
                assert all(m[k] >= 0 for k in ("import_mitsuba", "load", "trace", "compile",
                                                "execute", "second_render")), (key, side, m)
                assert _finite_positive(m["first_image"]) and m["process"] > m["first_image"]
                assert m["kernels"] > 0
            assert empty["disk_hits"] == 0 and 0 <= filled["disk_hits"] <= filled["kernels"]
            assert filled["kernels"] == empty["kernels"] and empty["compile"] > 0, (key, side)
            assert (empty["import_package"] > 0) == (side == "python")
            # the package's resident memory: what plugins need, not NumPy or plotting
            # (NumPy alone is ~10 MiB); none without it
            assert (0 < empty["package_mib"] < 8) if side == "python" \
                else empty["package_mib"] == 0, (side, empty["package_mib"])
        assert _finite_positive(p["empty"]["first_image_ratio"]["ratio"])

    # 7. optimisation: traced and frozen loops both ran; the frozen ones were recorded
    # once or twice and replayed; fit frozen and traced end at the same values
    opt = res["optimisation"]
    assert "lambert" in opt["pairs"]
    for key, p in opt["pairs"].items():
        for c in ("python_plain", "python_frozen", "cpp_plain", "cpp_frozen"):
            assert _finite_positive(p[c]["seconds"]) and p[c]["update"] >= 0, (key, c)
        assert 1 <= p["python_frozen"]["recordings"] <= 2 and p["python_plain"]["recordings"] == 0
        assert _finite_positive(p["python_frozen_vs_plain"]["ratio"])
    assert [(f["res"], f["spp"]) for f in opt["fit"]] == [(16, 1)]
    assert "| 16 x 16 | 1 |" in doc and "MiB of resident memory" in doc
    for fit in opt["fit"]:
        assert _finite_positive(fit["frozen"]) and _finite_positive(fit["plain"])
        assert fit["loop_plain"] >= fit["plain"] and not fit["default"]
        assert 1 <= fit["recordings"] <= 2
        for k, v in fit["final_frozen"].items():
            assert math.isclose(v, fit["final_plain"][k], rel_tol=1e-4), k
            assert math.isclose(fit["errors_frozen"][k],
                                abs(v - F.TRUE[k]) / F.TRUE[k], rel_tol=1e-6), k

    # 8. the figures command ran with both caches: compiled every kernel with the empty
    # one (loaded none); what the filled one holds for it is Dr.Jit's business (a fresh
    # machine once loaded none), not asserted; its figures were timed
    fc = res["figures_command"]
    assert all(r["exit"] == 0 and r["status"] == 0 for v in fc["runs"].values() for r in v)
    e, f = fc["empty"], fc["filled"]
    assert _finite_positive(e["process"]) and _finite_positive(f["process"])
    assert e["disk_hits"] == 0 and 0 < e["kernels"] <= e["launches"]
    assert 0 <= f["disk_hits"] <= f["kernels"] <= f["launches"]
    assert e["compile"] > 0 and 0 < fc["compile_share"] < 1
    assert set(e["figures"]) == set(fc["settings"]["only"])
    for title in ("## 6. Time to the first image", "## 7. Optimisation loops",
                  "## 8. The figures command"):
        assert title in doc, title


@pytest.mark.slow
def test_explorer_section_measures():
    """Section 9's measurement as ``bench --quick`` makes it: the server's medians, and the
    page's in chromium (or why it was not measured)."""
    from mitsuba_brdfs.bench import explore
    from mitsuba_brdfs.bench.study import QUICK
    ex = explore.run(QUICK, None)
    assert all(_finite_positive(ex["server"][k]) for k in ("plots_ms", "sphere_ms", "pass_ms"))
    if "page" in ex:
        assert _finite_positive(ex["page"]["param_ms"]) and _finite_positive(
            ex["page"]["param_sphere_ms"])
        assert ex["page"]["param_fetch_ms"] < ex["page"]["param_ms"]
    else:
        assert "not measured" in ex["skipped"][0]


def check_pairs(section):
    """Every ratio of a section of paired renders finite and positive; compile and
    instruction counts reported."""
    assert section["pairs"]
    for key, p in section["pairs"].items():
        assert all(_finite_positive(p[k]) for k in ("ratio", "ratio_min", "ratio_max",
                                                    "median_a", "median_b")), key
        assert p["ratio_min"] <= p["ratio"] <= p["ratio_max"]
        assert p["instr_a"] > 0 and p["instr_b"] > 0 and p["compile_a"] >= 0


@pytest.mark.slow
def test_error_and_cpp_sections_measure(tmp_path):
    """Sections 1 and 2 as ``bench --quick`` measures them, on the lead model (and ``lambert``
    for section 2), with their text, summary and plot drawn from the results."""
    from mitsuba_brdfs.bench import error, plugins, speed
    from mitsuba_brdfs.bench.sections import cpp as cpp_section, error as error_section, numbers
    from mitsuba_brdfs.bench.sections.format import Document
    from mitsuba_brdfs.bench.study import QUICK
    plugins.register()
    available = {"ashikhmin_shirley", "lambert"}
    err = error.run(QUICK, available)
    cpp = speed.run_cpp(QUICK, available)
    doc = Document(numbers())
    for section, data, png in ((error_section, err, "error_vs_time.png"),
                               (cpp_section, cpp, "speed_vs_cpp.png")):
        assert section.text(data, doc) and section.summary(data, doc)
        assert section.plot(data, tmp_path / png) is not False
        assert (tmp_path / png).stat().st_size > 1000, png

    # 1. error against time: positive times, RMSE falling with spp under MIS
    assert "as_metal_1000" in err["scenes"]
    assert {k for k, *_ in error.SCENES if k.startswith("as_")} == set(err["scenes"])
    for key, sc in err["scenes"].items():
        for name, s in sc["strategies"].items():
            assert all(_finite_positive(t) for t in s["seconds"]), (key, name)
            assert all(math.isfinite(e) and e >= 0 for e in s["rel_rmse"]), (key, name)
            if "MIS" in name:
                assert s["rel_rmse"][-1] < s["rel_rmse"][0], (key, name, s["rel_rmse"])
    for row in err["bsdf_alone"]["incidences"].values():
        # importance sampling wins by far: in variance (fixed samples); the efficiency
        # (variance x time) is timing, only required to be measured
        assert float(row["variance_ratio"]) > 10 and _finite_positive(row["efficiency_ratio"])
    # 2. every ratio finite and positive; compile and instruction counts reported
    check_pairs(cpp)
    assert {p["plugin"] for p in cpp["pairs"].values()} == available
