"""The fit example: a short run lowers the loss and writes its figures."""
import os

import numpy as np

from mitsuba_brdfs import image_fit as F
from mitsuba_brdfs.__main__ import main


def test_short_fit_lowers_the_loss(tmp_path):
    import gc
    import weakref

    class Cycle:
        pass
    garbage = Cycle()
    garbage.me = garbage
    before = weakref.ref(garbage)
    del garbage
    lines, collector = [], []

    def progress(line):
        lines.append(line)
        collector.append((gc.isenabled(), before() is None))
    r = F.fit(iterations=8, spp=2, res=24, out=str(tmp_path), tile_res=32, progress=progress)
    # Python's cycle collector ran before the fit and not while it ran (what it frees, and
    # when, moved the fitted values' last digits), and is on again after it
    assert collector and all(c == (False, True) for c in collector) and gc.isenabled()
    # the step is frozen: recorded on the first calls, replayed afterwards
    assert r["frozen"] and 1 <= r["recordings"] <= 2, r["recordings"]
    assert len(lines) == 8 and all("loss" in ln for ln in lines)
    assert len(r["history"]["loss"]) == 8
    assert np.isfinite(r["history"]["loss"]).all()
    # start and end measured against the target with the same seed and samples
    assert r["loss_after"] < 0.8 * r["loss_before"], (r["loss_before"], r["loss_after"])
    # every parameter moved from the start towards the truth
    for k in ("nu", "nv", "rs"):
        assert abs(r["final"][k] - F.TRUE[k]) < abs(F.START[k] - F.TRUE[k]), (k, r["final"])
    assert 0.0 <= r["final"]["rs"] <= 1.0
    for path in r["outputs"]:
        with open(path, "rb") as f:
            assert f.read(8) == b"\x89PNG\r\n\x1a\n", path
    assert sorted(os.listdir(tmp_path)) == ["before_target_after.png", "loss.png"]


def test_frozen_fit_follows_the_traced_one(tmp_path):
    """Replaying the recorded step gives the loop that traces every iteration: the same
    losses and final values, to float32 rounding."""
    kw = dict(iterations=6, spp=2, res=16, tile_res=8, target_spp=4, progress=None)
    frozen = F.fit(out=str(tmp_path / "frozen"), **kw)
    traced = F.fit(out=str(tmp_path / "traced"), freeze=False, **kw)
    assert traced["recordings"] == 0 and not traced["frozen"]
    assert frozen["recordings"] >= 1
    np.testing.assert_allclose(frozen["history"]["loss"], traced["history"]["loss"], rtol=1e-4)
    for k in ("nu", "nv", "rs"):
        np.testing.assert_allclose(frozen["final"][k], traced["final"][k], rtol=1e-4)
        assert frozen["final"][k] != F.START[k]
    assert len(frozen["history"]["seconds"]) == 6


def test_fit_command(tmp_path, capsys):
    code = main(["fit", "--iterations", "2", "--spp", "1", "--res", "16", "--out", str(tmp_path)])
    assert code == 0
    out, err = capsys.readouterr()
    assert "wrote" in out and "fit: 100%" in err and "2/2 it" in err  # a progress bar
    assert "frozen, recorded" in out
    assert (tmp_path / "loss.png").exists() and (tmp_path / "before_target_after.png").exists()


def test_fit_rejects_bad_options(tmp_path, capsys):
    assert main(["fit", "--iterations", "0", "--out", str(tmp_path)]) == 2
    assert "iterations" in capsys.readouterr().err
    assert not os.listdir(tmp_path)
