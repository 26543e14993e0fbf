"""The ``bench`` command: a whole ``bench --quick`` run writes a sane study."""
import json
import math
import os
import subprocess
import sys

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def _finite_positive(x):
    return isinstance(x, (int, float)) and math.isfinite(x) and x > 0


@pytest.mark.slow
def test_bench_quick_writes_a_sane_study(tmp_path):
    r = subprocess.run([sys.executable, "-m", "mitsuba_brdfs", "bench", "--quick", "--out",
                        str(tmp_path)], cwd=ROOT, capture_output=True, text=True, timeout=900)
    assert r.returncode == 0, r.stderr[-3000:]
    doc = (tmp_path / "performance.md").read_text()
    res = json.loads((tmp_path / "perf" / "results.json").read_text())
    assert res["mode"] == "quick" and len(res["git"]["commit"]) == 40
    assert res["git"]["commit"] in doc and "--quick" in doc
    # the reduced run stays reduced (the study must not silently grow)
    assert res["total_seconds"] < 180, res["section_seconds"]
    for png in ("error_vs_time", "speed_vs_cpp", "effects", "stable_vs_naive", "memory"):
        p = tmp_path / "perf" / f"{png}.png"
        assert p.exists() and p.stat().st_size > 1000, png
        assert f"perf/{png}.png" in doc

    # 1. error against time: positive times, RMSE falling with spp under MIS
    err = res["error"]
    assert "ashikhmin_shirley" in res["available"] and "as_metal_1000" in err["scenes"]
    for key, sc in err["scenes"].items():
        for name, s in sc["strategies"].items():
            assert all(_finite_positive(t) for t in s["seconds"]), (key, name)
            assert all(math.isfinite(e) and e >= 0 for e in s["rel_rmse"]), (key, name)
            if "MIS" in name:
                assert s["rel_rmse"][-1] < s["rel_rmse"][0], (key, name, s["rel_rmse"])
    for row in err["bsdf_alone"]["incidences"].values():
        assert float(row["efficiency_ratio"]) > 10  # importance sampling wins by far

    # 2./4. every ratio finite and positive; compile and instruction counts reported
    for sec in ("cpp", "effects"):
        assert res[sec]["pairs"], sec
        for key, p in res[sec]["pairs"].items():
            assert all(_finite_positive(p[k]) for k in ("ratio", "ratio_min", "ratio_max",
                                                        "median_a", "median_b")), (sec, key)
            assert p["ratio_min"] <= p["ratio"] <= p["ratio_max"]
            assert p["instr_a"] > 0 and p["instr_b"] > 0 and p["compile_a"] >= 0
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
