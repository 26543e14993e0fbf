"""fit-measured: MERL files round-trip, parameters recovered from files made from known
ones (and one model fitted to another's data), bad files refused, the command line."""
import json
import os
import stat
import subprocess

import mitsuba as mi
import numpy as np

from checks import merl_file
from cmdline import run_cli, run_code, run_many
from mitsuba_brdfs import fit_measured as F, merl, presets

#: small files of the same format: fewer bins, the same (non-linear) binning
DIMS = (30, 30, 60)


def write_from(path, spec, dims=DIMS):
    """A MERL file of the BRDF of ``spec`` at the bins' directions."""
    return merl_file(path, spec, dims)


def test_merl_round_trip_and_lookup(tmp_path):
    path = tmp_path / "m.binary"
    f = write_from(path, presets.ngan2005("ward", "nickel"), (12, 10, 20))
    dims, g = merl.read(path)
    assert dims == (12, 10, 20)
    np.testing.assert_array_equal(np.isnan(f), np.isnan(g))
    np.testing.assert_allclose(g[~np.isnan(g)], f[~np.isnan(f)], rtol=1e-15)
    assert os.path.getsize(path) == merl.expected_size(dims)
    # every bin's directions (turned about n at random) look up to that bin; phi_d is
    # undefined where theta_h = 0 or theta_d = 0
    wi, wo = merl.directions(dims, np.random.default_rng(1).uniform(0, 2 * np.pi, 2400))
    i, j, _ = np.unravel_index(np.arange(2400), dims)
    defined = (i > 0) & (j > 0)
    np.testing.assert_array_equal(merl.lookup(wi, wo, dims)[defined], np.arange(2400)[defined])
    # the fit's subset: measured values of the bins its directions fall in, within 80 deg
    wi, wo, h = F.prepare(path, 300)
    assert len(wi) == 300 and np.isfinite(h).all() and (wi[:, 2] > F.MIN_COS).all()
    np.testing.assert_array_equal(h, g[merl.lookup(wi, wo, dims)])


def _fit(path, spec, samples=5000, iterations=500, **kw):
    """A fit as the command runs it, on fewer pairs and iterations (recovery tests end
    within 3% of the truth with these, within 0.5% at the command's defaults)."""
    bsdf = mi.load_dict(F.colour_spec(spec, mi.load_dict(spec)))
    wi, wo, f = F.prepare(path, samples)
    return F.fit(bsdf, wi, wo, f, iterations, **kw), (wi, wo, f)


def _value(r, key):
    return np.array(r["params"][key + ".value"])


def test_recovers_ward(tmp_path):
    """From the plugin's defaults (rho_s 0.2, rho_d 0.5, alpha 0.1) to a gold-like Ward
    (rho_s 0.13, rho_d 0.16, alpha 0.23): every value within 5%."""
    truth = {"type": "ward", "specular_reflectance": {"type": "rgb", "value": [0.13, 0.09, 0.04]},
             "diffuse_reflectance": {"type": "rgb", "value": [0.16, 0.08, 0.02]},
             "alpha_u": 0.23, "alpha_v": 0.23}
    write_from(tmp_path / "w.binary", truth)
    r, _ = _fit(tmp_path / "w.binary", {"type": "ward"})
    assert r["loss"] < 1e-3 * r["start_loss"]
    np.testing.assert_allclose(_value(r, "specular_reflectance"), [0.13, 0.09, 0.04], rtol=0.05)
    np.testing.assert_allclose(_value(r, "diffuse_reflectance"), [0.16, 0.08, 0.02], rtol=0.05)
    np.testing.assert_allclose(_value(r, "alpha_u"), 0.23, rtol=0.05)
    np.testing.assert_allclose(_value(r, "alpha_v"), 0.23, rtol=0.05)


def test_recovers_blinn_phong_exponent(tmp_path):
    """An exponent (optimised as its logarithm) from 30 to 400, colours within 5%."""
    truth = {"type": "blinn_phong", "exponent": 400.0,
             "specular_reflectance": {"type": "rgb", "value": [0.3, 0.25, 0.2]},
             "diffuse_reflectance": {"type": "rgb", "value": [0.05, 0.2, 0.1]}}
    write_from(tmp_path / "b.binary", truth)
    r, _ = _fit(tmp_path / "b.binary", {"type": "blinn_phong"})
    np.testing.assert_allclose(_value(r, "exponent"), 400, rtol=0.05)
    np.testing.assert_allclose(_value(r, "specular_reflectance"), [0.3, 0.25, 0.2], rtol=0.05)
    np.testing.assert_allclose(_value(r, "diffuse_reflectance"), [0.05, 0.2, 0.1], rtol=0.05)


def test_ward_fitted_to_cook_torrance_data(tmp_path):
    """Ward fitted to the Cook-Torrance fit of gold-paint: a loss no larger than that of
    Ngan et al.'s own Ward fit of the material on the same pairs (for both losses), and a
    Ward alpha within 25% of the Beckmann m (the two slope distributions agree for small
    slopes)."""
    write_from(tmp_path / "ct.binary", presets.ngan2005("cook_torrance", "gold-paint"))
    m = presets.raw("cook_torrance", "gold-paint")["roughness"]
    for loss in F.LOSSES:
        r, (wi, wo, f) = _fit(tmp_path / "ct.binary", {"type": "ward"}, loss=loss)
        published = F.fit(mi.load_dict(presets.ngan2005("ward", "gold-paint")), wi, wo, f,
                          iterations=0, loss=loss)["loss"]
        assert r["loss"] <= published, (loss, r["loss"], published)
        np.testing.assert_allclose(_value(r, "alpha_u"), m, rtol=0.25)


def test_command_line(tmp_path):
    """A small file fitted through the command line: summary, XML that loads, plot; a
    truncated file refused with both sizes (exit 2) before anything is written."""
    src = tmp_path / "gold.binary"
    write_from(src, presets.ngan2005("ward", "gold-paint"), (16, 16, 32))
    out = tmp_path / "out"
    r = run_cli("fit-measured", src, "--model", "ward_duer", "--init", "gold-paint", "--iterations", "40",
                "--json", "--out", out)
    assert r.returncode == 0, r.stderr
    summary = json.loads(r.stdout)
    assert summary["loss"] <= summary["start_loss"]
    for path in summary["outputs"]:
        assert os.path.getsize(path) > 0
    assert summary["xml"].startswith('<bsdf version="3.0.0" type="ward">')
    assert isinstance(mi.load_file(summary["outputs"][0]), mi.BSDF)
    bad = tmp_path / "short.binary"
    bad.write_bytes(src.read_bytes()[:-8])
    r = run_cli("fit-measured", bad, "--model", "ward", "--out", tmp_path / "none")
    size = merl.expected_size((16, 16, 32))
    assert r.returncode == 2
    assert f"has {size} bytes" in r.stderr and f"this file has {size - 8}" in r.stderr, r.stderr
    assert not (tmp_path / "none").exists()
    r = run_cli("fit-measured", src, "--model", "wardd", "--out", tmp_path / "none")
    assert r.returncode == 2 and "did you mean 'ward'" in r.stderr, r.stderr
    r = run_cli("fit-measured", src, "--model", "ward", "--params", "alpha_u.value,alpha",
                "--out", tmp_path / "none")
    assert r.returncode == 2 and "--params alpha: not among" in r.stderr, r.stderr
    assert not (tmp_path / "none").exists()


def test_a_start_at_the_answer_stays_there(tmp_path):
    """Cook-Torrance started at the very parameters its data was made from (nickel: m =
    0.042, which a step of the learning rate in m itself would cross zero): the fit ends
    at the start's loss and values, not elsewhere; from the plugin's defaults it comes
    within 1e-3 of the start loss. Blinn-Phong on the same data reaches the same loss from
    the preset and from its defaults (the model cannot do better)."""
    preset = presets.ngan2005("cook_torrance", "nickel")
    write_from(tmp_path / "ct.binary", preset)
    r, (wi, wo, f) = _fit(tmp_path / "ct.binary", preset, iterations=300)
    assert r["loss"] <= 2 * r["start_loss"] + 1e-9, (r["start_loss"], r["loss"])
    np.testing.assert_allclose(_value(r, "roughness"), preset["roughness"], rtol=1e-3)
    np.testing.assert_allclose(_value(r, "specular_reflectance"),
                               preset["specular_reflectance"]["value"], rtol=1e-3)
    r, _ = _fit(tmp_path / "ct.binary", {"type": "cook_torrance", "distribution": "beckmann",
                                          "geometry": "cook_torrance"}, iterations=800)
    assert r["loss"] < 1e-3 * r["start_loss"], (r["start_loss"], r["loss"])
    ends = []
    for spec in (presets.ngan2005("blinn_phong", "nickel"), {"type": "blinn_phong"}):
        r, _ = _fit(tmp_path / "ct.binary", spec, iterations=800)
        assert r["loss"] <= r["start_loss"]
        ends.append(r["loss"])
    np.testing.assert_allclose(ends[0], ends[1], rtol=0.01)


def test_fits_a_mitsuba_plugin_with_slow_updates(tmp_path):
    """``roughplastic`` (its alpha and eta updates recompute tables): a few iterations from
    its defaults lower the loss and keep alpha in [1e-3, 1], eta in [1, 3] and the
    reflectance in [0, 1]; the result is the best met."""
    write_from(tmp_path / "bp.binary", {"type": "blinn_phong", "exponent": 300.0})
    spec = {"type": "roughplastic", "distribution": "beckmann"}
    r, _ = _fit(tmp_path / "bp.binary", spec, samples=2000, iterations=8)
    assert r["loss"] < r["start_loss"] and r["loss"] <= min(r["history"]) + 1e-6
    assert 1e-3 <= r["params"]["alpha"][0] <= 1 and 1 <= r["params"]["eta"][0] <= 3
    assert all(0 <= x <= 1 for x in _value(r, "diffuse_reflectance"))


def test_fits_a_mitsuba_plugin(tmp_path):
    """Mitsuba's own ``diffuse``, through the parameters ``mi.traverse`` exposes (its
    reflectance, given as one number, fitted as a colour), recovers a Lambertian albedo."""
    write_from(tmp_path / "l.binary", {"type": "lambert",
                                        "reflectance": {"type": "rgb", "value": [0.3, 0.5, 0.7]}})
    r, _ = _fit(tmp_path / "l.binary", {"type": "diffuse"}, samples=2000, iterations=150)
    np.testing.assert_allclose(_value(r, "reflectance"), [0.3, 0.5, 0.7], rtol=0.01)


def _chattr(flag, path):
    """``chattr FLAG path``; False where chattr is missing or the file system refuses it."""
    try:
        return subprocess.run(["chattr", flag, str(path)], capture_output=True).returncode == 0
    except FileNotFoundError:
        return False


def test_targets_that_cannot_be_replaced_are_refused_before_the_fit(tmp_path):
    """A read-only summary (0444, refused by its mode, root included), an immutable XML
    (chattr +i) and an append-only plot (chattr +a), where the file system allows them:
    status 2 and one line naming the file, before any fit (no progress shown) and before
    anything is written: the other outputs do not appear, the file is unchanged."""
    src = tmp_path / "gp.binary"
    write_from(src, presets.ngan2005("ward", "gold-paint"), (8, 8, 16))
    cases, kept = [], []
    for name, kind in (("ro", "read-only (mode 0444)"), ("imm", "immutable"),
                       ("app", "append-only")):
        out = tmp_path / name
        xml, png, js = F.outputs(src, "ward", out)
        target = {"ro": js, "imm": xml, "app": png}[name]
        os.makedirs(out)
        with open(target, "w") as f:
            f.write("mine")
        if name == "ro":
            os.chmod(target, 0o444)
        elif not _chattr("+i" if name == "imm" else "+a", target):
            continue
        cases.append(["fit-measured", src, "--model", "ward", "--iterations", "5", "--out", out])
        kept.append((target, kind, out))
    try:
        results = run_many(cases)
        for (target, kind, out), (code, stdout, err) in zip(kept, results):
            assert code == 2 and stdout == "", (code, stdout, err)
            assert err.startswith(f"error: fit-measured: {target}: the file ") and kind in err, err
            assert "refusing to replace it" in err and err.count("\n") == 1, err
            assert os.listdir(out) == [os.path.basename(target)]
        assert len(results) >= 1
    finally:
        for target, kind, out in kept:
            _chattr("-i" if kind == "immutable" else "-a", target)
    for target, kind, out in kept:
        with open(target) as f:
            assert f.read() == "mine", target
    assert stat.S_IMODE(os.stat(kept[0][0]).st_mode) == 0o444


def test_an_interruption_names_the_files_written(tmp_path):
    """Stopped (Ctrl-C) after the XML was written: status 130, the message names the XML,
    the plot and the summary are not there, and no partial file is left."""
    src = tmp_path / "gp.binary"
    write_from(src, presets.ngan2005("ward", "gold-paint"), (8, 8, 16))
    out = tmp_path / "out"
    code = ("import sys\n"
            "from mitsuba_brdfs import fit_measured\n"
            "def stop(*args, **kwargs):\n"
            "    raise KeyboardInterrupt\n"
            "fit_measured.plot_slices = stop\n"
            "from mitsuba_brdfs.__main__ import main\n"
            "sys.exit(main(sys.argv[1:]))\n")
    r = run_code(code, "fit-measured", src, "--model", "ward", "--iterations", "3", "--out", out)
    xml = F.outputs(src, "ward", out)[0]
    assert r.returncode == 130, r.stderr
    assert r.stderr.strip().endswith(f"interrupted after writing {xml}"), r.stderr
    assert os.listdir(out) == [os.path.basename(xml)]
