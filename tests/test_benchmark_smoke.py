"""The speed benchmark runs end to end (tiny settings; the timing itself is not a test)."""
import json
import os
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def test_bench_as_vs_roughconductor_runs(tmp_path):
    out = tmp_path / "b.json"
    r = subprocess.run([sys.executable, os.path.join(ROOT, "benchmarks", "bench_as_vs_roughconductor.py"),
                        "--runs", "2", "--res", "16", "--spp", "2", "--threads", "2",
                        "--json", str(out)], capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stderr
    assert "ashikhmin_shirley / roughconductor:" in r.stdout
    res = json.loads(out.read_text())
    s = res["vs_roughconductor"]
    assert s["runs"] == 2 and 0 < s["ratio_min"] <= s["ratio"] <= s["ratio_max"]
    assert all(len(res["times"][k]) == 2 for k in ("ashikhmin_shirley", "roughconductor"))
    assert res["kernels"]["ashikhmin_shirley"]["kernels"] >= 1
