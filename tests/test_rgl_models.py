"""``scripts/rgl_models.py``: the models fitted to every RGL file of a folder, ranked (by
the image judge, or by held-out loss without it), as a Markdown table. The RGL files are
written here by ``to-rgl`` (small resolution), from a glossy ``ward`` and a ``lambert``:
nothing comes from the internet."""
import contextlib
import importlib.util
import io
import json
import math
import os

import pytest

from explore_page import RGL_RESOLUTION
from mitsuba_brdfs.__main__ import main

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def _script():
    spec = importlib.util.spec_from_file_location(
        "rgl_models", os.path.join(ROOT, "scripts", "rgl_models.py"))
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _entry(label, holdout, loss=1.0, errors=(0.01, -0.02, 0.3)):
    return {"label": label, "holdout_loss": holdout, "loss": loss, "albedo_error": errors}


def test_ranking_and_table_mark_the_lowest_held_out_loss():
    s = _script()
    fits = [_entry("a", 0.5), _entry("b", math.nan), _entry("c", 0.1, 2.0),
            _entry("d", 0.1, 1.0)]
    assert [f["label"] for f in s.ranked(fits)] == ["d", "c", "a", "b"]   # NaN last, ties by loss
    text = s.table({"m1": fits, "m2": [_entry("a", 0.2)]}, ["a", "b", "c", "d"])
    lines = text.splitlines()
    assert lines[0] == "| material | `a` | `b` | `c` | `d` | best |"
    assert lines[2] == ("| `m1` | 0.5 (+1 / -2 / +30 %) | - (+1 / -2 / +30 %) | 0.1 (+1 / -2 / "
                        "+30 %) | **0.1** (+1 / -2 / +30 %) | `d` |")
    assert lines[3] == "| `m2` | **0.2** (+1 / -2 / +30 %) | - | - | - | `a` |"   # b, c, d missing
    # with the image judge's errors: the best by image error in bold, both rankings named
    judged = [dict(_entry("a", 0.5), image_error={"mean": 2.0}, holdout_log=0.3),
              dict(_entry("b", 0.1), image_error={"mean": 3.0}, holdout_log=0.2)]
    assert [f["label"] for f in s.ranked(judged)] == ["a", "b"]
    assert [f["label"] for f in s.ranked(judged, "holdout")] == ["b", "a"]
    lines = s.table({"m": judged}, ["a", "b"]).splitlines()
    assert lines[0] == "| material | `a` | `b` | best by image | best by held-out loss |"
    assert lines[2] == "| `m` | **2.00** (0.5 / 0.3) | 3.00 (0.1 / 0.2) | `a` | `b` (differs) |"
    assert s.parse_extra("ward:form=duer") == ("ward, form=duer", "ward", ["form=duer"])
    with pytest.raises(Exception):
        s.parse_extra("ward")


def test_script_fits_two_rgl_files_and_ranks_the_source_model_first(tmp_path):
    import drjit as dr
    dr.set_thread_count(2)
    folder = tmp_path / "rgl"
    folder.mkdir()
    (folder / "notes.txt").write_text("not an RGL file")          # skipped by its header
    sources = {"glossy": ["ward", "-p", "specular_reflectance=0.3", "-p", "alpha_u=0.1",
                          "-p", "alpha_v=0.1", "-p", "diffuse_reflectance=0.2,0.3,0.5"],
               "matte": ["lambert", "-p", "reflectance=0.6,0.4,0.2"]}
    for name, source in sources.items():
        with contextlib.redirect_stdout(io.StringIO()), \
                contextlib.redirect_stderr(io.StringIO()):
            assert main(["to-rgl", *source, *RGL_RESOLUTION, "--no-compare",
                         "-o", str(folder / f"{name}.bsdf")]) == 0
    # a truncated file: said in one line, the others fitted all the same, exit status 1
    (folder / "cut.bsdf").write_bytes((folder / "matte.bsdf").read_bytes()[:5000])
    s = _script()
    out = tmp_path / "out"
    with contextlib.redirect_stdout(io.StringIO()) as printed, \
            contextlib.redirect_stderr(io.StringIO()):
        assert s.main([str(folder), "--out", str(out), "--model", "lambert,ward",
                       "--extra", "oren_nayar:form=energy_preserving",
                       "--fit-args", "--image-spp 0"]) == 1
    results = json.loads((out / "rgl_models.json").read_text())
    assert list(results["materials"]) == ["glossy", "matte"]
    assert "truncated" in results["failed"]["cut"]
    assert results["files"]["glossy"] == os.path.abspath(folder / "glossy.bsdf")
    assert f"failed: cut: {results['failed']['cut']}" in printed.getvalue()
    assert results["labels"] == ["lambert", "ward", "oren_nayar, form=energy_preserving"]
    glossy = results["materials"]["glossy"]
    assert glossy[0]["label"] == "ward"                        # the source's model first
    by = {f["label"]: f for f in glossy}
    assert by["lambert"]["holdout_loss"] > 10 * by["ward"]["holdout_loss"]
    assert by["oren_nayar, form=energy_preserving"]["options"] == ["form=energy_preserving"]
    matte = {f["label"]: f for f in results["materials"]["matte"]}
    assert matte["lambert"]["holdout_loss"] < 1e-4           # a Lambert file fits exactly
    assert max(abs(e) for e in matte["lambert"]["albedo_error"]) < 0.02
    for fits in results["materials"].values():                # the fitted XML is there
        for f in fits:
            assert (out / f["xml"]).is_file(), f["xml"]
    table = (out / "rgl_models.md").read_text()
    assert table.strip() in printed.getvalue()
    row = next(line for line in table.splitlines() if line.startswith("| `glossy`"))
    assert row.count("**") == 2 and row.endswith("| `ward` |")
    assert row.split(" | ")[2].startswith("**")                 # the ward column is bold
