"""fit-measured's inputs and outputs beyond one MERL file and one model: RGL files (written
here by ``to-rgl``), ``--target SPEC -p ...`` (one model converted into another), several
models ranked by held-out loss (the table, ``--json``, the plot), and the files it refuses.
Small files and few evaluations: the fits themselves are judged in test_fit_measured.py
and test_fit_matrix.py."""
import json
import os

import mitsuba as mi
import numpy as np

from checks import merl_file
from cmdline import run_code, run_many
from mitsuba_brdfs import presets
from mitsuba_brdfs.measured import data as D, tensor

#: a small RGL file: to-rgl's coarsest tables that still fit a lobe
SMALL_RGL = ["--theta-i", "8", "--grid", "16", "--vndf", "32", "--ndf", "32", "--no-compare"]
#: a short fit (the image judge is tested in test_fit_measured_judge.py)
SHORT = ["--samples", "2000", "--evaluations", "60", "--image-spp", "0"]
HEAD = ("| model | loss (shape + energy) | held-out loss | relative RMS R, G, B | albedo error "
        "at 0 / 45 / 75 deg | albedo goal | evaluations | seconds |")


def _rows(stdout):
    """The table's rows: [[cell, ...]] after its head and rule."""
    lines = stdout.splitlines()
    assert lines[0] == HEAD, lines[0]
    rows = []
    for line in lines[2:]:
        if not line.startswith("|"):
            break
        rows.append([c.strip() for c in line.strip("|").split("|")])
    return rows


def test_several_models_are_ranked_by_held_out_loss(tmp_path):
    """``--model lambert,ward,cook_torrance`` on a Cook-Torrance file: the table has a row
    per model in order of held-out loss (Cook-Torrance first: its own data), with the loss,
    the held-out loss, the albedo error at 0 / 45 / 75 deg and the seconds; ``--json``
    prints {"fits": [...]} in that order, each with model, params, loss and holdout_loss
    (the files written hold the same); one model's ``--json`` is its summary with
    holdout_loss; one plot of the measured slices with every fit over it, labelled."""
    src = tmp_path / "ct.binary"
    merl_file(src, presets.ngan2005("cook_torrance", "gold-paint"), (16, 16, 32))
    models = "lambert,ward,cook_torrance"
    out = tmp_path / "out"
    cases = [["fit-measured", src, "--model", models, "--out", out, *SHORT],
             ["fit-measured", src, "--model", models, "--out", tmp_path / "j", "--json",
              *SHORT],
             ["fit-measured", src, "--model", "ward", "--out", tmp_path / "one", "--json",
              *SHORT],
             ["fit-measured", src, "--model", "ward,ward", "--out", tmp_path / "x"],
             ["fit-measured", src, "--model", "ward,lambert", "-p", "alpha_u=0.1", "--out",
              tmp_path / "x"]]
    (c1, table, e1), (c2, js, e2), (c3, one, e3), (c4, _, e4), (c5, _, e5) = run_many(
        [list(map(str, c)) for c in cases])
    assert c1 == 0 and c2 == 0 and c3 == 0, (e1[-2000:], e2[-2000:], e3[-2000:])
    rows = _rows(table)
    assert [r[0] for r in rows] == ["cook_torrance", "ward", "lambert"], table
    held = [float(r[2]) for r in rows]
    assert held == sorted(held) and held[0] < 0.05 < held[1], held
    for r in rows:
        assert float(r[1].split()[0]) >= 0 and float(r[-1]) > 0, r
        assert len(r[4].split(" / ")) == 3 and all(x.endswith("%") for x in r[4].split(" / "))
    fits = json.loads(js)["fits"]
    assert [f["model"] for f in fits] == ["cook_torrance", "ward", "lambert"]
    assert [f["holdout_loss"] for f in fits] == sorted(f["holdout_loss"] for f in fits)
    for f in fits:
        assert {"model", "params", "loss", "holdout_loss", "albedo", "relative_rms",
                "xml"} <= set(f), sorted(f)
        assert f["params"] and f["loss"] >= 0 and f["holdout_loss"] >= 0
    written = json.load(open(out / "ct.binary_fits.json"))["fits"]
    assert [f["model"] for f in written] == ["cook_torrance", "ward", "lambert"]
    summary = json.loads(one)
    assert "fits" not in summary and summary["model"] == "ward"
    assert summary["holdout_loss"] > 0 and summary["holdout_samples"] > 0
    assert {"loss", "params", "relative_rms", "albedo", "at_bounds", "warnings",
            "constraint"} <= set(summary)
    names = sorted(os.listdir(out))
    assert names == sorted([f"ct.binary_{m}.{e}" for m in models.split(",") for e in ("xml", "json")]
                           + ["ct.binary_fits.png", "ct.binary_fits.json"]), names
    import matplotlib.image
    image = matplotlib.image.imread(out / "ct.binary_fits.png")
    assert image.shape[0] > 200 and image.shape[1] > 600
    assert c4 == 2 and "a model named twice" in e4 and e4.count("\n") == 1, e4
    assert c5 == 2 and "-p and --params set one model's parameters" in e5, e5


def test_plot_labels_every_fit(tmp_path):
    """The several-model plot: three panels (theta_d), each with the measured slice (dots)
    and a line per fit, labelled with its model and held-out loss, in ranked order."""
    src = tmp_path / "w.binary"
    merl_file(src, presets.ngan2005("ward", "gold-paint"), (16, 16, 32))
    code = ("import json, sys\n"
            "from mitsuba_brdfs import output\n"
            "save = output.save_figure\n"
            "def spy(fig, path, **kw):\n"
            "    print(json.dumps([[line.get_label() for line in ax.get_lines()]\n"
            "                      for ax in fig.axes]), file=sys.stderr)\n"
            "    save(fig, path, **kw)\n"
            "output.save_figure = spy\n"
            "from mitsuba_brdfs.__main__ import main\n"
            "sys.exit(main(sys.argv[1:]))\n")
    r = run_code(code, "fit-measured", src, "--model", "lambert,ward", "--json", "--out",
                 tmp_path / "o", *SHORT)
    assert r.returncode == 0, r.stderr[-2000:]
    fits = json.loads(r.stdout)["fits"]
    panels = json.loads([line for line in r.stderr.splitlines() if line.startswith("[[")][0])
    labels = ["measured"] + [f"{f['model']} (held-out {f['holdout_loss']:.3g})" for f in fits]
    assert fits[0]["model"] == "ward" and panels == [labels] * 3, (panels, labels)
    assert os.path.getsize(tmp_path / "o" / "w.binary_fits.png") > 10000


def test_rgl_files_targets_and_refusals(tmp_path):
    """An RGL file written by ``to-rgl`` from a Ward material: several models fitted and
    ranked, Ward first with the material's parameters (the file's nodes hold its values),
    its widths held equal (an isotropic file);
    its spectral twin (each node's green value at four wavelengths: a flat spectrum, grey
    in sRGB) gives Ward back in grey. ``--target roughconductor -p alpha=0.3
    --model cook_torrance`` converts one model into another within 10% of its albedo and
    a relative RMS error below 0.1; ``--target lambert -p reflectance=...`` fitted by
    Mitsuba's ``diffuse`` gives the reflectance back. A truncated RGL file, a foreign
    file, a folder and a missing file: exit status 2, one line naming the file, nothing
    written."""
    rgl, spectral = tmp_path / "ward.bsdf", tmp_path / "ward_spectral.bsdf"
    cut, foreign, folder = tmp_path / "cut.bsdf", tmp_path / "notes.bsdf", tmp_path / "dir"
    folder.mkdir()
    foreign.write_text("tensor data? no: a text file\n" * 100)
    none = tmp_path / "none"
    first = run_many([["to-rgl", "ward", "-p", "alpha_u=0.2", "-p", "alpha_v=0.2", "-p",
                       "diffuse_reflectance=0.3,0.2,0.1", "-p",
                       "specular_reflectance=0.1,0.15,0.2", "-o", str(rgl), *SMALL_RGL]])
    assert first[0][0] == 0, first[0][2][-2000:]
    fields = tensor.read(rgl)
    green = fields.pop("rgb")[:, :, 1:2]
    fields["spectra"] = np.repeat(green, 4, axis=2)
    fields["wavelengths"] = np.array([400, 500, 600, 700], np.float32)
    tensor.write(spectral, fields)
    cut.write_bytes(rgl.read_bytes()[:30000])
    no_judge = ["--image-spp", "0"]
    cases = [["fit-measured", rgl, "--model", "lambert,ward", "--json", "--out",
              tmp_path / "r", "--samples", "3000", "--evaluations", "300", *no_judge],
             ["fit-measured", "--target", "roughconductor", "-p", "alpha=0.3", "--model",
              "cook_torrance", "--json", "--out", tmp_path / "t", "--evaluations", "300",
              "--samples", "3000", *no_judge],
             ["fit-measured", "--target", "lambert", "-p", "reflectance=0.2,0.4,0.6",
              "--model", "diffuse", "--json", "--out", tmp_path / "d", *SHORT],
             ["fit-measured", spectral, "--model", "ward", "--json", "--out", tmp_path / "s",
              "--samples", "3000", "--evaluations", "300", *no_judge]]
    refused = [(cut, "cut.bsdf: truncated or corrupt tensor file"),
               (foreign, "notes.bsdf: neither an RGL file"),
               (folder, "dir: a folder, not a measured file"),
               (tmp_path / "missing.bsdf", "missing.bsdf: no such file")]
    cases += [["fit-measured", path, "--model", "ward", "--out", none] for path, _ in refused]
    results = run_many([list(map(str, c)) for c in cases])
    for case, (code, _, err) in zip(cases[:4], results):
        assert code == 0, (case, err[-2000:])
    fits = json.loads(results[0][1])["fits"]
    assert [f["model"] for f in fits] == ["ward", "lambert"]
    assert all(f["kind"] == "rgl" and f["file"] == str(rgl) for f in fits)
    truth = {"specular_reflectance.value": [0.1, 0.15, 0.2],
             "diffuse_reflectance.value": [0.3, 0.2, 0.1], "alpha_u.value": [0.2],
             "alpha_v.value": [0.2]}
    # the file's nodes hold Ward's values but where it is not smooth over a cell, which
    # hold its average over their footprint (measured.footprint)
    for key, value in truth.items():
        np.testing.assert_allclose(fits[0]["params"][key], value, rtol=3e-3, err_msg=key)
    assert fits[0]["constraint"]["status"] == "met" and fits[0]["relative_rms_max"] < 0.03
    assert fits[0]["isotropy"] == {"data": "isotropic", "fit": "isotropic",
                                   "tied": ["alpha_u=alpha_v"]}
    grey = json.loads(results[3][1])
    assert grey["kind"] == "rgl" and grey["negative_values"] == 0
    white = D.srgb_matrix(fields["wavelengths"]).sum(1)    # a flat spectrum of 1, in sRGB
    np.testing.assert_allclose(white, 1, atol=6e-3)
    for key, value in truth.items():
        expect = value[1] * white if len(value) == 3 else value
        np.testing.assert_allclose(grey["params"][key], expect, rtol=3e-3, err_msg=key)
    ct = json.loads(results[1][1])
    assert ct["kind"] == "bsdf" and ct["target"] == "roughconductor alpha=0.3"
    assert ct["relative_rms_max"] < 0.1 and ct["constraint"]["status"] == "met", ct
    assert np.max(np.abs(ct["albedo"]["relative_difference"])) < 0.1, ct["albedo"]
    assert os.path.exists(tmp_path / "t" / "roughconductor_cook_torrance.xml")
    d = json.loads(results[2][1])
    np.testing.assert_allclose(d["params"]["reflectance.value"], [0.2, 0.4, 0.6], rtol=1e-3)
    for (path, text), (code, out, err) in zip(refused, results[4:]):
        assert code == 2 and out == "" and err.count("\n") == 1, (path, err)
        assert err.startswith(f"error: {path}") and text in err, (path, err)
    assert not none.exists()


def test_spectra_turn_into_srgb_as_mitsuba_turns_them():
    """A spectral RGL file's values become linear sRGB by the matrix of Mitsuba's
    ``spectrum_list_to_srgb`` (CIE 1931 under D65): the same colour for spectra inside the
    gamut (to float32's precision), for any wavelengths; linear outside it, where Mitsuba's
    function clamps negative channels at 0 (a single wavelength's colour: 500 nm has a
    negative red, kept)."""
    rng = np.random.default_rng(3)
    for wavelengths in ([400, 500, 600, 700], np.linspace(360, 1000, 65), [380, 450, 451, 780]):
        m = D.srgb_matrix(wavelengths)
        for _ in range(3):
            v = rng.uniform(0.2, 1, len(wavelengths))
            ref = np.array(mi.spectrum_list_to_srgb([float(w) for w in wavelengths],
                                                    v.tolist(), False, True)).ravel()
            np.testing.assert_allclose(m @ v, ref, rtol=2e-5)
    m = D.srgb_matrix([400, 500, 600, 700])
    assert m[0, 1] < -0.1 and m[1, 1] > 0
    np.testing.assert_allclose(m @ [1, 2, 0, 0], m[:, 0] + 2 * m[:, 1], rtol=1e-12)


def test_a_file_and_its_rgl_file_keep_their_own_outputs_and_numbers_agree(tmp_path):
    """``fit-measured ct.binary`` then ``fit-measured ct.bsdf`` (to-rgl's of it) into one
    folder: each keeps its outputs (named after the file with its extension). With
    ``--evaluations 0`` nothing is fitted: the albedo goal is "not tried", never "met"
    beside the start's errors, and a warning says so. The progress bar ends on the loss
    the table gives."""
    src = tmp_path / "ct.binary"
    merl_file(src, presets.ngan2005("cook_torrance", "gold-paint"), (16, 16, 32))
    out = tmp_path / "out"
    zero = ["--model", "ward", "--evaluations", "0", "--samples", "1000", "--out", out,
            "--image-spp", "0"]
    (c1, _, e1), (c2, t2, e2), (c3, t3, e3) = run_many([list(map(str, c)) for c in (
        ["to-rgl", src, "-o", tmp_path / "ct.bsdf", *SMALL_RGL],
        ["fit-measured", src, *zero], ["fit-measured", tmp_path / "ct.bsdf", *zero])])
    assert c1 == c2 == c3 == 0, (e1[-1500:], e2[-1500:], e3[-1500:])
    assert sorted(os.listdir(out)) == sorted(f"ct.{ext}_ward.{kind}" for ext in ("binary", "bsdf")
                                             for kind in ("xml", "png", "json"))
    for table, err in ((t2, e2), (t3, e3)):
        (row,) = _rows(table)
        worst = max(abs(float(x.rstrip("%"))) for x in row[4].split(" / "))
        assert worst > 10 and row[5].startswith("not tried (0 evaluations; "), row
        assert "warning: nothing fitted (0 evaluations): the start reflects " in table
        # the bar's last words: the table's loss, said as such
        assert err.rstrip().endswith(f"ward: loss {row[1].split()[0]}, as in the table]"), \
            err[-300:]
