"""The ``figures`` command: renders the chosen figures and records their timings."""
import json
import os
import subprocess
import sys

import numpy as np
from PIL import Image

from mitsuba_brdfs.__main__ import main
from mitsuba_brdfs.figures import command, paper
from mitsuba_brdfs.figures.panels import Figure, Panel

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def run_cli(*args):
    return subprocess.run([sys.executable, "-m", "mitsuba_brdfs", *args], cwd=ROOT,
                          capture_output=True, text=True, timeout=300)


def test_figures_command_renders_and_writes_timings(tmp_path, monkeypatch, capsys):
    fig = Figure("tiny", "tiny", [Panel("as_sphere.xml", "a"), Panel("as_sphere.xml", "b")],
                 spp={"preview": 1, "final": 2}, res={"preview": 8, "final": 10}, columns=1)
    monkeypatch.setitem(paper.FIGURES, "tiny", fig)
    monkeypatch.setattr(command, "NAMES", command.NAMES + ["tiny"])
    assert main(["figures", "--only", "tiny", "--quality", "final", "--out", str(tmp_path)]) == 0
    assert "tiny: " in capsys.readouterr().out
    t = json.loads((tmp_path / "timings.json").read_text())
    assert t["tiny"]["spp"] == 2 and t["tiny"]["resolution"] == 10
    assert t["last_run"]["figures"] == ["tiny"] and t["last_run"]["seconds_total"] > 0
    png = np.array(Image.open(tmp_path / "tiny.png"))
    assert png.shape[1] == 10 + 2 * 6 and png.shape[0] > 2 * 10  # one column, two rows


def test_figures_command_writes_timings(tmp_path):
    r = run_cli("figures", "--only", "as_sphere", "--out", str(tmp_path))
    assert r.returncode == 0, r.stderr
    t = json.loads((tmp_path / "timings.json").read_text())
    assert t["as_sphere"]["spp"] == paper.FIGURES["as_sphere"].spp["preview"]
    assert (tmp_path / "as_sphere.png").exists() and (tmp_path / "as_sphere.exr").exists()
