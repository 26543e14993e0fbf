"""The command line: bad input in one line with status 2, Ctrl-C with status 130 and no
output."""
import os
import signal
import subprocess
import sys
import time

import mitsuba as mi
import pytest

from mitsuba_brdfs.__main__ import main, parser
from mitsuba_brdfs.scenes import SCENES

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SCENE = os.path.join(SCENES, "as_sphere.xml")


def run_cli(*args, **kw):
    return subprocess.run([sys.executable, "-m", "mitsuba_brdfs", *args], cwd=ROOT,
                          capture_output=True, text=True, timeout=300, **kw)


@pytest.mark.parametrize("args, msg", [
    (["render", "missing.xml"], "missing.xml"),
    (["render", SCENE, "-D", "res"], "key=value"),
    (["render", SCENE, "-D", "rs=2", "-D", "res=8", "--spp", "1"], "specular_reflectance"),
])
def test_cli_bad_input_is_reported(tmp_path, args, msg):
    r = run_cli(*args, "-o", str(tmp_path / "z.exr"))
    assert r.returncode == 2 and msg in r.stderr and "Traceback" not in r.stderr
    assert os.listdir(tmp_path) == []


def test_interrupt_exits_130_without_output(tmp_path, monkeypatch):
    out = tmp_path / "i.exr"
    real, calls = mi.render, []

    def interrupted(*a, **kw):
        calls.append(1)
        if len(calls) == 2:
            raise KeyboardInterrupt
        return real(*a, **kw)

    monkeypatch.setattr(mi, "render", interrupted)
    code = main(["render", SCENE, "-o", str(out), "--spp", "4", "-D", "res=16",
                 "--pass-samples", "256"])
    assert code == 130 and len(calls) == 2 and os.listdir(tmp_path) == []


def test_sigint_during_render_leaves_no_files(tmp_path):
    out = tmp_path / "s.exr"
    p = subprocess.Popen([sys.executable, "-m", "mitsuba_brdfs", "render", SCENE, "-o", str(out),
                          "--spp", "100000", "-D", "res=64", "--pass-samples", "40000"],
                         cwd=ROOT, stderr=subprocess.PIPE, text=True)
    # wait for the progress bar (the scene is loaded, passes are running); it redraws
    # its line with carriage returns, so read characters, not lines
    seen = ""
    while "spp" not in seen and p.poll() is None:
        seen += p.stderr.read(1)
    assert "spp" in seen
    time.sleep(1.0)
    p.send_signal(signal.SIGINT)
    err = p.communicate(timeout=120)[1]
    assert p.returncode == 130, err
    assert "interrupted" in err
    assert os.listdir(tmp_path) == []


@pytest.mark.parametrize("command, out", [("figures", "renders"), ("properties", "docs"),
                                          ("fit", os.path.join("docs", "fit")),
                                          ("bench", "docs"), ("manual", os.path.join("docs", "plugins"))])
def test_outputs_default_to_the_current_directory(command, out):
    """Never into the package's folder (site-packages, once installed)."""
    assert parser().parse_args([command]).out == out
