"""fit-measured: MERL files round-trip with their bins at the centres of their cells,
parameters recovered from files made from known ones, the edges (bounds reached, sharp
lobes, absurd values, tiny files, folders), Mitsuba's plugins written back as they load,
the command line. The cross-model matrix is in test_fit_matrix.py."""
import json
import os
import re
import stat
import subprocess

import mitsuba as mi
import numpy as np
import pytest

from checks import merl_file
from cmdline import run_cli, run_code, run_many
from mitsuba_brdfs import fit_measured as F, presets
from mitsuba_brdfs.measured import (data as D, fitting as M, merl, plugins as P, report as R,
                                    variables as V)

#: small files of the same format: fewer bins, the same (non-linear) binning
DIMS = (30, 30, 60)


def _fit(path, spec, samples=5000, evaluations=600, **kw):
    """A fit as the command runs it (``prepare``, ``fit_file``), on fewer pairs."""
    data = D.prepare(path, samples)
    bsdf = mi.load_dict(V.colour_spec(spec, mi.load_dict(spec)))
    return R.fit_file(data, bsdf, evaluations=evaluations, **kw), data, bsdf


def _value(r, key):
    return np.array(r["params"][key + ".value"])


def rgb(*v):
    return {"type": "rgb", "value": list(v)}


# -- the file and its bins -------------------------------------------------------------------

def test_bins_read_back_at_the_centres_of_their_cells(tmp_path):
    """Values round-trip; each bin's sample, at the centre of its cell, is looked up (as
    MERL's reader does) in that bin, at any phi_h; at the lower edges (the BRDF benchmark's
    linearizer) only a third of the database's bins are; the cells' measures sum to 8 pi^2
    (the pairs above the horizon: (2 pi)^2); the fit's samples are the bins' values at
    their centres, weighted by their cells' measures."""
    path = tmp_path / "m.binary"
    f = merl_file(path, presets.ngan2005("ward", "nickel"), (12, 10, 20))
    dims, g = merl.read(path)
    assert dims == (12, 10, 20) and os.path.getsize(path) == merl.expected_size(dims)
    np.testing.assert_array_equal(np.isnan(f), np.isnan(g))
    np.testing.assert_allclose(g[~np.isnan(g)], f[~np.isnan(f)], rtol=1e-15)
    full = np.arange(int(np.prod(merl.DIMS)))
    rng = np.random.default_rng(1)
    for position, share in (("centre", 1.0), ("edge", 0.313)):
        wi, wo = merl.directions(merl.DIMS, rng.uniform(0, 2 * np.pi, len(full)),
                                 position=position)
        back = np.mean(merl.lookup(wi, wo) == full)
        assert abs(back - share) < 1e-3, (position, back)
    m = merl.measure(merl.DIMS)
    wi, wo = merl.directions(merl.DIMS)
    up = (wi[:, 2] > 0) & (wo[:, 2] > 0)
    np.testing.assert_allclose(m.sum(), 8 * np.pi ** 2, rtol=1e-12)
    np.testing.assert_allclose(m[up].sum(), 4 * np.pi ** 2, rtol=2e-4)
    data = D.prepare(path, 300)
    assert len(data.wi) == 300 and np.isfinite(data.f).all()
    assert (data.wi[:, 2] > M.MIN_COS).all() and (data.wo[:, 2] > M.MIN_COS).all()
    index = merl.lookup(data.wi, data.wo, dims)
    np.testing.assert_array_equal(data.f, g[index])
    np.testing.assert_allclose(data.weights, merl.measure(dims, index))


def test_a_folder_and_broken_files_are_refused_in_one_line(tmp_path):
    """A folder is named as a folder, a truncated file with both sizes, an unknown model
    with a suggestion, unknown --params with the model's: exit 2, one line, nothing
    written."""
    src = tmp_path / "gold.binary"
    merl_file(src, presets.ngan2005("ward", "gold-paint"), (8, 8, 16))
    bad = tmp_path / "short.binary"
    bad.write_bytes(src.read_bytes()[:-8])
    none = tmp_path / "none"
    size = merl.expected_size((8, 8, 16))
    cases = [(["fit-measured", tmp_path, "--model", "ward", "--out", none],
              f"error: {tmp_path}: a folder, not a measured file"),
             (["fit-measured", bad, "--model", "ward", "--out", none],
              f"has {size} bytes (12 + 3 x 8 x 1024); this file has {size - 8}"),
             (["fit-measured", src, "--model", "wardd", "--out", none],
              "no such plugin (did you mean 'ward'?)"),
             (["fit-measured", src, "--model", "ward", "--params", "alpha_u.value,alpha",
               "--out", none], "--params alpha: not among")]
    for (argv, text), (code, out, err) in zip(cases, run_many([list(map(str, c)) for c, _
                                                               in cases])):
        assert code == 2 and text in err and err.count("\n") == 1, (argv, err)
    assert not none.exists()


def test_files_too_small_or_too_bright_are_refused_before_the_fit(tmp_path):
    """A file of 1 x 1 x 1 bins (one value for the 8 of Ward), values of 1e8 (a BRDF
    reflecting 1e8 times the light), with a wrong scale (MERL's raw table: 1500 times f),
    black: one line each, exit 2, nothing written. A coarse file of 4 x 4 x 8 bins is fitted with
    a warning that its parameters are poorly determined only where its bins are fewer than
    20 per fitted value (Ward: 8 values, 160 bins)."""
    one = tmp_path / "one.binary"
    merl.write(one, np.array([[0.1, 0.1, 0.1]]), (1, 1, 1))
    black = tmp_path / "black.binary"
    merl.write(black, np.zeros((8 * 8 * 16, 3)), (8, 8, 16))
    huge = tmp_path / "huge.binary"
    merl.write(huge, np.full((8 * 8 * 16, 3), 1e8), (8, 8, 16))
    raw = tmp_path / "raw.binary"
    f = merl_file(raw, presets.ngan2005("ward", "gold-paint"), (16, 16, 32))
    merl.write(raw, f / merl.SCALE, (16, 16, 32))
    none = tmp_path / "none"
    runs = run_many([["fit-measured", str(p), "--model", "ward", "--out", str(none)]
                     for p in (one, huge, raw, black)])
    (c1, _, e1), (c2, _, e2), (c3, _, e3), (c4, _, e4) = runs
    assert c4 == 2 and e4 == f"error: {black}: every measured value within 80 deg is 0 or " \
        f"less: a black material, nothing to fit\n", e4
    assert c1 == 2 and e1.count("\n") == 1, e1
    assert "1 measured sample within 80 deg of the normal (1 x 1 x 1 bins), fewer than the " \
           "8 values ward fits" in e1, e1
    for code, err in ((c2, e2), (c3, e3)):
        assert code == 2 and err.count("\n") == 1 and "times the light it receives" in err, err
        assert "a BRDF reflects at most 1" in err, err
    assert "values up to 1e+08" in e2, e2
    assert not none.exists()
    coarse = tmp_path / "coarse.binary"
    merl_file(coarse, presets.ngan2005("ward", "gold-paint"), (4, 4, 8))
    data = D.prepare(coarse)
    r = R.fit_file(data, mi.load_dict(V.colour_spec({"type": "ward"},
                                                    mi.load_dict({"type": "ward"}))))
    assert data.bins < 160
    assert any(f"only {data.bins} measured bins within 80 deg for 8 fitted values" in w
               for w in r["warnings"]), r["warnings"]


# -- recovering what made the file ---------------------------------------------------------------

def test_recovers_ward(tmp_path):
    """From the plugin's defaults (rho_s 0.2, rho_d 0.5, alpha 0.1) to a gold-like Ward
    (rho_s 0.13, rho_d 0.16, alpha 0.23): every value within 0.5%, no warning, the albedo
    of the fit that of the data, a relative RMS error near 0."""
    truth = {"type": "ward", "specular_reflectance": rgb(0.13, 0.09, 0.04),
             "diffuse_reflectance": rgb(0.16, 0.08, 0.02), "alpha_u": 0.23, "alpha_v": 0.23}
    merl_file(tmp_path / "w.binary", truth, DIMS)
    r, _, _ = _fit(tmp_path / "w.binary", {"type": "ward"})
    np.testing.assert_allclose(_value(r, "specular_reflectance"), [0.13, 0.09, 0.04], rtol=5e-3)
    np.testing.assert_allclose(_value(r, "diffuse_reflectance"), [0.16, 0.08, 0.02], rtol=5e-3)
    np.testing.assert_allclose(_value(r, "alpha_u"), 0.23, rtol=5e-3)
    np.testing.assert_allclose(_value(r, "alpha_v"), 0.23, rtol=5e-3)
    assert r["warnings"] == [] and r["at_bounds"] == []
    assert r["relative_rms_max"] < 1e-3
    np.testing.assert_allclose(r["albedo"]["fitted"], r["albedo"]["measured"], rtol=2e-3)


def test_recovers_blinn_phong_exponent(tmp_path):
    """An exponent (optimised as its logarithm) from 30 to 400, colours within 1%."""
    truth = {"type": "blinn_phong", "exponent": 400.0,
             "specular_reflectance": rgb(0.3, 0.25, 0.2),
             "diffuse_reflectance": rgb(0.05, 0.2, 0.1)}
    merl_file(tmp_path / "b.binary", truth, DIMS)
    r, _, _ = _fit(tmp_path / "b.binary", {"type": "blinn_phong"})
    np.testing.assert_allclose(_value(r, "exponent"), 400, rtol=0.01)
    np.testing.assert_allclose(_value(r, "specular_reflectance"), [0.3, 0.25, 0.2], rtol=0.01)
    np.testing.assert_allclose(_value(r, "diffuse_reflectance"), [0.05, 0.2, 0.1], rtol=0.01)


def test_a_sharp_lobe_keeps_the_diffuse_colour(tmp_path):
    """Ward alpha 0.005 (a lobe two bins wide at MERL's resolution), fitted from Ward's
    defaults with the command's defaults: the diffuse colour 0.30/0.20/0.10 within 5%
    (the lobe's peak, 600 times the diffuse level, used to take it to 0.24/0.20/0.10)."""
    truth = {"type": "ward", "diffuse_reflectance": rgb(0.3, 0.2, 0.1),
             "specular_reflectance": rgb(0.15, 0.15, 0.15), "alpha_u": 0.005,
             "alpha_v": 0.005}
    merl_file(tmp_path / "sharp.binary", truth, merl.DIMS)
    r, _, _ = _fit(tmp_path / "sharp.binary", {"type": "ward"}, samples=D.SAMPLES,
                   evaluations=None)
    np.testing.assert_allclose(_value(r, "diffuse_reflectance"), [0.3, 0.2, 0.1], rtol=0.05)
    np.testing.assert_allclose(_value(r, "alpha_u"), 0.005, rtol=0.05)


def test_cook_torrance_fits_what_its_scales_make(tmp_path):
    """Cook-Torrance's k, m_D, m_S and specular_scale only scale one another: fitted from
    the plugin's defaults to the nickel preset's file (k 1/2, s 8 / pi), the diffuse colour
    k m_D and the specular amplitude (1 - k) s m_S come back within 1%, f0 and the
    roughness within 1%, written with s = 1 (the lecture's model holds them: k m_D and
    (1 - k) m_S at most 1 together); a brighter lobe (m_S 1, s 8 / pi, k 1/2) is written
    with m_S's largest channel 1 and s what remains. On the Ward material where m_S and f0 used to
    pin at 1 and k m_D to take 0.53/0.55/0.59 for 0.22/0.30/0.40, the diffuse colour is
    within 25%, and f0 on its bound (Ward's lobe has no Fresnel rise) is said."""
    preset = presets.ngan2005("cook_torrance", "nickel")
    merl_file(tmp_path / "ct.binary", preset, DIMS)
    r, _, _ = _fit(tmp_path / "ct.binary", {"type": "cook_torrance"})
    k, s = _value(r, "k")[0], _value(r, "specular_scale")[0]
    raw = presets.raw("cook_torrance", "nickel")
    np.testing.assert_allclose(k * _value(r, "diffuse_reflectance"), raw["diffuse"], rtol=0.01)
    np.testing.assert_allclose((1 - k) * s * _value(r, "specular_reflectance"),
                               0.5 * 8 / np.pi * np.array(raw["albedo"]), rtol=0.01)
    np.testing.assert_allclose(_value(r, "f0"), raw["fresnel"], rtol=0.01)
    np.testing.assert_allclose(_value(r, "roughness"), raw["roughness"], rtol=0.01)
    assert s == 1 and np.isclose(k, max(raw["diffuse"]) / (max(raw["diffuse"]) + 0.5 * 8
                                                            / np.pi * max(raw["albedo"])))
    bright = {"type": "cook_torrance", "k": 0.5, "specular_reflectance": 1.0,
              "specular_scale": 8 / np.pi, "diffuse_reflectance": rgb(0.6, 0.5, 0.4),
              "roughness": 0.2, "f0": 0.5}
    merl_file(tmp_path / "bright.binary", bright, DIMS)
    r, _, _ = _fit(tmp_path / "bright.binary", {"type": "cook_torrance"})
    k, s = _value(r, "k")[0], _value(r, "specular_scale")[0]
    np.testing.assert_allclose(k * _value(r, "diffuse_reflectance"), [0.3, 0.25, 0.2], rtol=1e-3)
    np.testing.assert_allclose((1 - k) * s * _value(r, "specular_reflectance"), 4 / np.pi,
                               rtol=1e-3)
    np.testing.assert_allclose([k, max(_value(r, "specular_reflectance"))], [0.3, 1], rtol=1e-3)
    ward = {"type": "ward", "diffuse_reflectance": rgb(0.22, 0.30, 0.40),
            "specular_reflectance": rgb(0.10, 0.08, 0.06), "alpha_u": 0.14, "alpha_v": 0.14}
    merl_file(tmp_path / "w.binary", ward, DIMS)
    r, _, _ = _fit(tmp_path / "w.binary", {"type": "cook_torrance"})
    k = _value(r, "k")[0]
    np.testing.assert_allclose(k * _value(r, "diffuse_reflectance"), [0.22, 0.30, 0.40],
                               rtol=0.25)
    assert _value(r, "specular_scale")[0] == 1
    assert {a["parameter"] for a in r["at_bounds"]} == {"f0[r]", "f0[g]", "f0[b]"}
    assert any("f0[r] = 1 (upper bound)" in w for w in r["warnings"]), r["warnings"]


def test_ward_fitted_to_cook_torrance_data(tmp_path):
    """Ward fitted to the Cook-Torrance fit of gold-paint: a loss no larger than that of
    Ngan et al.'s own Ward fit of the material on the same samples (for both shape
    losses), and a Ward alpha within 25% of the Beckmann m (the two slope distributions
    agree for small slopes). The loss alone, without the albedo constraint: the optimiser
    is judged."""
    merl_file(tmp_path / "ct.binary", presets.ngan2005("cook_torrance", "gold-paint"), DIMS)
    m = presets.raw("cook_torrance", "gold-paint")["roughness"]
    for loss in M.LOSSES:
        r, data, _ = _fit(tmp_path / "ct.binary", {"type": "ward"}, loss=loss,
                          albedo_tolerance=None)
        published = R.fit_file(data, mi.load_dict(presets.ngan2005("ward", "gold-paint")),
                               evaluations=0, loss=loss)["loss"]
        assert r["loss"] <= published, (loss, r["loss"], published)
        np.testing.assert_allclose(_value(r, "alpha_u"), m, rtol=0.25)


def test_a_start_at_the_answer_stays_there(tmp_path):
    """Cook-Torrance started at the very parameters its data was made from (nickel:
    m = 0.042) ends there; Blinn-Phong on the same data reaches the same loss from the
    preset and from its defaults (the model cannot do better); Adam, from the defaults,
    comes within 5% of L-BFGS-B's loss in 800 steps. The loss alone, without the albedo
    constraint: the optimiser is judged."""
    preset = presets.ngan2005("cook_torrance", "nickel")
    merl_file(tmp_path / "ct.binary", preset, DIMS)
    r, _, _ = _fit(tmp_path / "ct.binary", preset, evaluations=300)
    assert r["loss"] <= r["start_loss"] < 1e-9
    np.testing.assert_allclose(_value(r, "roughness"), preset["roughness"], rtol=1e-4)
    ends = []
    for spec in (presets.ngan2005("blinn_phong", "nickel"), {"type": "blinn_phong"}):
        r, _, _ = _fit(tmp_path / "ct.binary", spec, albedo_tolerance=None)
        assert r["loss"] <= r["start_loss"]
        ends.append(r["loss"])
    np.testing.assert_allclose(ends[0], ends[1], rtol=1e-3)
    r, _, _ = _fit(tmp_path / "ct.binary", {"type": "blinn_phong"}, optimizer="adam",
                   evaluations=800, albedo_tolerance=None)
    assert r["loss"] <= 1.05 * ends[1], (r["loss"], ends[1])


def test_bin_positions_bias_the_fit(tmp_path):
    """A Ward file written at the cells' centres and read there gives Ward back (0.3%); read
    at the lower edges (the BRDF benchmark's linearizer) rho_s and alpha come out low; a
    file written at the lower edges and read at the centres, high (the numbers at full
    resolution are in docs/presets.md)."""
    truth = {"type": "ward", "diffuse_reflectance": rgb(0.2, 0.2, 0.2),
             "specular_reflectance": rgb(0.1, 0.1, 0.1), "alpha_u": 0.05, "alpha_v": 0.05}
    out = {}
    for written in merl.POSITIONS:
        merl_file(tmp_path / f"{written}.binary", truth, DIMS, position=written)
        for read in merl.POSITIONS:
            data = D.prepare(tmp_path / f"{written}.binary", 5000, position=read)
            bsdf = mi.load_dict(V.colour_spec({"type": "ward"}, mi.load_dict({"type": "ward"})))
            r = R.fit_file(data, bsdf, evaluations=600)
            out[written, read] = (_value(r, "specular_reflectance")[0] / 0.1 - 1,
                                  _value(r, "alpha_u")[0] / 0.05 - 1)
    assert max(map(abs, out["centre", "centre"])) < 3e-3, out
    assert max(map(abs, out["edge", "edge"])) < 3e-3, out
    assert out["centre", "edge"][0] < -0.05 and out["centre", "edge"][1] < -0.02, out
    assert out["edge", "centre"][0] > 0.05 and out["edge", "centre"][1] > 0.02, out


# -- the edges -----------------------------------------------------------------------------------

def test_bounds_reached_end_on_the_bound_and_are_said(tmp_path):
    """Ashikhmin-Shirley fitted to a Ward lobe of alpha 1e-3 (an exponent of 2e6): nu and
    nv (held equal: a MERL file is isotropic) end exactly on 1e6. Ward started at its smallest alpha, 1e-4 (float32 9.9999997e-5,
    a lobe within MERL's first bin), on 1.5 times a white Ward lobe of that alpha: alpha
    stays exactly on that float32 (float64 steps rounded to float32 used to fall below it
    and be refused by the plugin). Each says so (the summary's at_bounds and a warning), and
    its XML loads with those values. (Without the albedo constraint: Ashikhmin-Shirley's
    own diffuse term cannot follow Ward's Lambertian one at grazing angles, and the
    constraint would widen the lobe to make up for it.)"""
    sharp = {"type": "ward", "diffuse_reflectance": rgb(0.2, 0.2, 0.2),
             "specular_reflectance": rgb(0.3, 0.3, 0.3), "alpha_u": 1e-3, "alpha_v": 1e-3}
    merl_file(tmp_path / "sharp.binary", sharp, merl.DIMS)
    mirror = {"type": "ward", "diffuse_reflectance": rgb(0.1, 0.1, 0.1),
              "specular_reflectance": rgb(1, 1, 1), "alpha_u": 1e-4, "alpha_v": 1e-4}
    merl.write(tmp_path / "mirror.binary", 1.5 * merl.from_bsdf(mi.load_dict(mirror)))
    for file, spec, keys, value, kw in (
            ("sharp", {"type": "ashikhmin_shirley"}, ("nu", "nv"), 1e6,
             {"albedo_tolerance": None}),
            ("mirror", {"type": "ward", "alpha_u": 1e-4, "alpha_v": 1e-4},
             ("alpha_u", "alpha_v"), np.float32(1e-4), {})):
        r, _, bsdf = _fit(tmp_path / f"{file}.binary", spec, samples=D.SAMPLES, **kw)
        tied = "=".join(keys)               # a MERL file is isotropic: the widths as one
        assert r["isotropy"]["tied"] == [tied]
        for key in keys:
            assert _value(r, key)[0] == value, (key, r["params"])
        assert {"parameter": tied, "value": float(value),
                "end": "lower" if value < 1 else "upper"} in r["at_bounds"]
        assert any(f"{tied} = {float(value):.7g} (" in w for w in r["warnings"]), r["warnings"]
        xml = P.bsdf_xml(spec, r["params"])
        (tmp_path / "fit.xml").write_text(xml)
        again = mi.traverse(mi.load_file(str(tmp_path / "fit.xml")))
        assert again[keys[0] + ".value"][0] == value


def test_a_parameter_without_an_upper_end_stays_finite():
    """Torrance-Sparrow's eta (in [1, inf)) is fitted as its logarithm in a box open above
    (as L-BFGS-B was given it: a bound there changes its steps); a step however long gives
    at most ``UNBOUNDED_TOP``, a finite float32, which the plugin accepts and the summary
    reports as the upper end. (exp() of a long step was a float32 infinity, which
    ``params.update()`` refuses: a fit of a real RGL file whose data asked for a larger eta
    ended with that error.)"""
    bsdf = mi.load_dict({"type": "torrance_sparrow"})
    params = mi.traverse(bsdf)
    (block,) = V.blocks(bsdf, params, ["eta.value"])
    assert block.bounds == [(0.0, None)]
    for y in (np.log(1e29), np.log(V.UNBOUNDED_TOP), 100.0, 1e3):
        value = block.decode(np.array([y]))["eta.value"]
        assert np.isfinite(value).all() and 0 < value[0] <= V.UNBOUNDED_TOP, (y, value)
        V.write(params, "eta.value", value)
        params.update()
        assert params["eta.value"][0] == value[0]
    assert block.ends(np.array([1e3])) == [("eta", float(value[0]), "upper")]
    assert block.ends(np.array([np.log(1e29)])) == []


def test_no_garbage_collection_runs_during_a_fit():
    """A fit's result depends on its inputs alone, not on when Python's collector runs:
    cyclic garbage made before it is freed when it starts, none is collected while it runs
    (the collector is off, also while another fit runs in a thread), and the collector is
    on again after the last one, also when a fit raises. (With collections at moments set
    by what else the process did, the same fits of the same files in one process ended at
    other minima in two runs of four.)"""
    import gc
    import threading
    import weakref

    class Cycle:
        pass

    def garbage():
        a = Cycle()
        a.me = a
        return weakref.ref(a)

    wi = np.array([[0.3, 0.0, 0.95]] * 50) / np.linalg.norm([0.3, 0.0, 0.95])
    wo = np.array([[-0.3, 0.1, 0.9]] * 50) / np.linalg.norm([-0.3, 0.1, 0.9])
    seen = []

    def fit(out=None, together=None):
        before, made, ticks = garbage(), [], []

        def tick(loss):
            if together is not None and not ticks:
                together.wait(timeout=300)   # both fits inside from here on
            # on, the garbage of before the fit freed, what the fit made so far kept
            ticks.append((gc.isenabled(), before() is None,
                          all(r() is not None for r in made)))
            made.append(garbage())
        M.fit(mi.load_dict({"type": "lambert"}), wi, wo, np.full((50, 3), 0.2),
              evaluations=5, albedo_tolerance=None, progress=tick)
        seen.extend(ticks)
        if out is not None:
            out.append(len(ticks))

    assert gc.isenabled()
    fit()
    assert len(seen) >= 3 and all(t == (False, True, True) for t in seen), seen
    assert gc.isenabled()
    # fits in two threads: the collector stays off until both end
    counts, seen[:] = [], []
    together = threading.Barrier(2)
    threads = [threading.Thread(target=fit, args=(counts, together)) for _ in range(2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert len(counts) == 2 and not any(on for on, *_ in seen) and gc.isenabled()
    assert all(kept for *_, kept in seen)
    # a fit that raises leaves the collector as it found it
    with pytest.raises(ValueError):
        M.fit(mi.load_dict({"type": "lambert"}), wi, wo, np.full((50, 3), 0.2),
              loss="nope")
    assert gc.isenabled()
    gc.disable()
    try:
        fit()
        assert not gc.isenabled()   # off before, off after
    finally:
        gc.enable()


def test_mitsuba_plugins_write_back_as_they_load(tmp_path):
    """Every Mitsuba plugin fit-measured accepts: a few evaluations, the fitted XML loads in
    ``check`` and holds the fitted values (roughplastic's and roughdielectric's relative
    index eta as int_ior over ext_ior, which is what they read); the plugins without a
    lobe that eval sees are refused in one line."""
    from mitsuba_brdfs.check import load_bsdfs
    merl_file(tmp_path / "bp.binary", {"type": "blinn_phong", "exponent": 300.0}, (16, 16, 32))
    data = D.prepare(tmp_path / "bp.binary", 1000)
    for name in P.MITSUBA_PLUGINS:
        extra = {"ext_ior": 1.33} if name == "roughdielectric" else {}
        spec, bsdf = P.load_model({"type": name, **extra}, name)
        # (without the albedo constraint: its stages move the same parameters, written back
        # the same way; a Mitsuba plugin's constrained fit: roughplastic's, below)
        r = R.fit_file(data, bsdf, evaluations=4, albedo_tolerance=None)
        xml = P.bsdf_xml(spec, r["params"])
        path = tmp_path / f"{name}.xml"
        path.write_text(xml)
        ((_, loaded),) = load_bsdfs(str(path), {})
        params = mi.traverse(loaded)
        for key, v in r["params"].items():
            np.testing.assert_allclose(np.ravel(params[key]), v, rtol=1e-6, err_msg=(name, key))
        if name in ("plastic", "roughplastic", "roughdielectric"):
            assert '<float name="eta"' not in xml and ('name="int_ior"' in xml) == \
                ("eta" in r["params"]), xml
    for name in ("conductor", "dielectric", "null"):
        with pytest.raises(ValueError, match=f"--model {name}: it has no reflection that "
                                             f"eval sees"):
            P.load_model({"type": name}, name)


def test_fits_a_mitsuba_plugin_with_slow_updates(tmp_path):
    """``roughplastic`` (its alpha and eta updates recompute tables): a few evaluations from
    its defaults lower the loss and keep alpha in [1e-3, 1], eta in (1, 3] and the
    reflectance in [0, 1]."""
    merl_file(tmp_path / "bp.binary", {"type": "blinn_phong", "exponent": 300.0}, (16, 16, 32))
    r, _, _ = _fit(tmp_path / "bp.binary", {"type": "roughplastic", "distribution": "beckmann"},
                   samples=2000, evaluations=12)
    assert r["loss"] < r["start_loss"]
    assert 1e-3 <= r["params"]["alpha"][0] <= 1 and 1 < r["params"]["eta"][0] <= 3
    assert all(0 <= x <= 1 for x in _value(r, "diffuse_reflectance"))


def test_fits_a_mitsuba_plugin(tmp_path):
    """Mitsuba's own ``diffuse``, through the parameters ``mi.traverse`` exposes (its
    reflectance, given as one number, fitted as a colour), recovers a Lambertian albedo."""
    merl_file(tmp_path / "l.binary", {"type": "lambert", "reflectance": rgb(0.3, 0.5, 0.7)},
              (16, 16, 32))
    r, _, _ = _fit(tmp_path / "l.binary", {"type": "diffuse"}, samples=2000, evaluations=150)
    np.testing.assert_allclose(_value(r, "reflectance"), [0.3, 0.5, 0.7], rtol=1e-3)


# -- the command line ----------------------------------------------------------------------------

def test_command_line(tmp_path):
    """A small file fitted through the command line: the table (relative RMS per channel,
    albedo of fit and data), the summary (relative_rms, albedo, at_bounds, warnings), the
    XML that loads, the plot; progress on stderr at most one line per 5 s when stderr is
    not a terminal (the bar's start, its end, one per 5 s between)."""
    src = tmp_path / "gold.binary"
    merl_file(src, presets.ngan2005("ward", "gold-paint"), (16, 16, 32))
    out = tmp_path / "out"
    r = run_cli("fit-measured", src, "--model", "ward_duer", "--init", "gold-paint",
                "--evaluations", "40", "--json", "--out", out, "--image-spp", "0")
    assert r.returncode == 0, r.stderr
    summary = json.loads(r.stdout)
    assert summary["loss"] <= summary["start_loss"]
    assert summary["holdout_loss"] > 0 and summary["holdout_samples"] > 0
    assert len(summary["relative_rms"]) == 3
    assert summary["relative_rms_max"] == max(summary["relative_rms"]) > 0.05  # Duer's form
    assert summary["albedo"]["thetas"] == [0, 45, 75]
    assert np.shape(summary["albedo"]["fitted"]) == np.shape(summary["albedo"]["measured"]) \
        == (3, 3)
    assert isinstance(summary["at_bounds"], list) and isinstance(summary["warnings"], list)
    for path in summary["outputs"]:
        assert os.path.getsize(path) > 0
    assert summary["xml"].startswith('<bsdf version="3.0.0" type="ward">')
    assert isinstance(mi.load_file(summary["outputs"][0]), mi.BSDF)
    r = run_cli("fit-measured", src, "--model", "blinn_phong", "--out", out, "--image-spp", "0",
                "--evaluations", "80")
    assert r.returncode == 0, r.stderr
    lines = r.stdout.splitlines()
    assert lines[0].startswith("| model | loss (shape + energy) | held-out loss | relative "
                               "RMS R, G, B | albedo error at 0 / 45 / 75 deg | albedo goal |")
    assert re.match(r"\| blinn_phong \| [\d.e-]+ \(.*\) \| [\d.e-]+ \|", lines[2]), lines[2]
    draws = r.stderr.count("fit-measured:")
    assert 1 <= draws <= 2 + json.load(open(out / "gold.binary_blinn_phong.json"))["seconds"] / 5, \
        r.stderr


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
    merl_file(src, presets.ngan2005("ward", "gold-paint"), (8, 8, 16))
    cases, kept = [], []
    for name, kind in (("ro", "read-only (mode 0444)"), ("imm", "immutable"),
                       ("app", "append-only")):
        out = tmp_path / name
        xml, png, js = F.outputs("gp.binary", ["ward"], out)
        target = {"ro": js, "imm": xml, "app": png}[name]
        os.makedirs(out)
        with open(target, "w") as f:
            f.write("mine")
        if name == "ro":
            os.chmod(target, 0o444)
        elif not _chattr("+i" if name == "imm" else "+a", target):
            continue
        cases.append(["fit-measured", src, "--model", "ward", "--evaluations", "5",
                      "--out", out])
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
    merl_file(src, presets.ngan2005("ward", "gold-paint"), (8, 8, 16))
    out = tmp_path / "out"
    code = ("import sys\n"
            "from mitsuba_brdfs.measured import slices\n"
            "def stop(*args, **kwargs):\n"
            "    raise KeyboardInterrupt\n"
            "slices.plot_slices = stop\n"
            "from mitsuba_brdfs.__main__ import main\n"
            "sys.exit(main(sys.argv[1:]))\n")
    r = run_code(code, "fit-measured", src, "--model", "ward", "--evaluations", "3",
                 "--out", out, "--image-spp", "0")
    xml = F.outputs("gp.binary", ["ward"], out)[0]
    assert r.returncode == 130, r.stderr
    assert r.stderr.strip().endswith(f"interrupted after writing {xml}"), r.stderr
    assert os.listdir(out) == [os.path.basename(xml)]
