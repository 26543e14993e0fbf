"""Measured data: Mitsuba's tensor format, RGL files and their samples, and ``to-rgl``.

Every RGL file here is written by the tests (``to-rgl`` of a BSDF, or by hand), every MERL
file by ``checks.merl_file``: nothing comes from the internet."""
import contextlib
import io
import json
import os

import mitsuba as mi
import numpy as np
import pytest

import user_bsdf
from checks import merl_file, point2, random_upper, sph
from cmdline import run_many
from mitsuba_brdfs.measured import acquire, convert, rgl, roundtrip, sources, tensor, warp
from mitsuba_brdfs.measured.tensor import FormatError
from mitsuba_brdfs.validate.probe import eval_np

#: smaller tables for the quick tests (1.3 MiB): the round trip's bounds hold at this size
QUICK = acquire.Resolution(ndf=64, theta_i=16, vndf=64, grid=64)


def write_rgl(path, spec, res=QUICK, compare=False):
    """to-rgl of the BSDF ``spec`` (a load_dict dict) into ``path``; returns the summary."""
    source = sources.Source(sources.bsdf_evaluator(mi.load_dict(spec)), spec["type"], "bsdf",
                            spec["type"], [])
    return convert.convert(source, str(path), res, compare=compare)


#: the summary of ``plastic_file``'s conversion
PLASTIC = {}


@pytest.fixture(scope="module")
def plastic_file(tmp_path_factory):
    path = tmp_path_factory.mktemp("rgl") / "plastic.bsdf"
    PLASTIC.update(write_rgl(path, {"type": "roughplastic", "alpha": 0.15, "diffuse_reflectance":
                                    {"type": "rgb", "value": [0.6, 0.3, 0.1]}}))
    return path


# -- the tensor format -------------------------------------------------------------------------

def test_tensor_file_round_trip_and_mitsuba_reads_it(tmp_path):
    fields = {"text": "a description",
              **{f"a_{t}": np.arange(24, dtype=t).reshape(2, 3, 4)
                 for t in ("uint8", "int8", "uint16", "int16", "uint32", "int32", "uint64",
                           "int64", "float16", "float32", "float64")},
              "one": np.float32([3.5]), "empty": np.zeros((0, 3), np.float32)}
    path = tmp_path / "t.bsdf"
    size = tensor.write(path, fields)
    assert size == os.path.getsize(path)
    assert tensor.is_tensor_file(path)
    back = tensor.read(path)
    assert list(back) == list(fields)
    assert bytes(back["text"]).decode() == "a description"
    for k, v in fields.items():
        if k != "text":
            assert back[k].dtype == np.asarray(v).dtype and back[k].shape == np.shape(v), k
            np.testing.assert_array_equal(back[k], v)
    # Mitsuba's own reader (Python and C++) sees the same fields
    with contextlib.redirect_stdout(io.StringIO()):
        theirs = mi.tensor_io.read(str(path))
    for k in fields:
        np.testing.assert_array_equal(theirs[k], back[k])
    text = str(mi.TensorFile(str(path)))
    assert '"a_float64"' in text and "shape = [2, 3, 4]" in text
    with pytest.raises(ValueError, match="scalar"):
        tensor.write(tmp_path / "s.bsdf", {"x": np.float32(1)})
    with pytest.raises(ValueError, match="no tensor file code"):
        tensor.write(tmp_path / "s.bsdf", {"x": np.array([True])})
    assert not (tmp_path / "s.bsdf").exists()


def test_a_file_written_by_mitsuba_reads_back(tmp_path):
    path = tmp_path / "m.bsdf"
    with contextlib.redirect_stdout(io.StringIO()):
        mi.tensor_io.write(str(path), x=np.linspace(0, 1, 7, dtype=np.float32).reshape(7, 1),
                           name="abc")
    back = tensor.read(path)
    np.testing.assert_array_equal(back["x"][:, 0], np.linspace(0, 1, 7, dtype=np.float32))
    assert bytes(back["name"]) == b"abc"


def test_foreign_truncated_and_corrupt_files_are_refused_in_one_line(tmp_path, plastic_file):
    data = plastic_file.read_bytes()
    cases = {"text.bsdf": b"<bsdf type='diffuse'/>\n", "empty.bsdf": b"",
             "header.bsdf": data[:40], "half.bsdf": data[:len(data) // 2],
             "last_byte.bsdf": data[:-1]}
    corrupt = bytearray(data)
    corrupt[12] = 2                      # version 2.0
    cases["version.bsdf"] = bytes(corrupt)
    expected = {"text.bsdf": "not a tensor file", "empty.bsdf": "not a tensor file",
                "header.bsdf": "truncated", "half.bsdf": "truncated",
                "last_byte.bsdf": "truncated", "version.bsdf": "version 2.0"}
    for name, content in cases.items():
        path = tmp_path / name
        path.write_bytes(content)
        with pytest.raises(FormatError, match=expected[name]) as e:
            rgl.load(path)
        assert str(path) in str(e.value) and "\n" not in str(e.value), name
    with pytest.raises(FormatError, match="no such file"):
        tensor.read(tmp_path / "missing.bsdf")


def test_a_tensor_file_without_rgl_fields_is_named(tmp_path, plastic_file):
    fields = tensor.read(plastic_file)
    for drop, message in (("vndf", "needs the field 'vndf'"), ("rgb", "needs the field 'rgb'")):
        path = tmp_path / f"no_{drop}.bsdf"
        tensor.write(path, {k: v for k, v in fields.items() if k != drop})
        with pytest.raises(FormatError, match=message):
            rgl.load(path)
    bad = dict(fields, luminance=fields["luminance"][:, :, :16])
    tensor.write(tmp_path / "lum.bsdf", bad)
    with pytest.raises(FormatError, match="field 'luminance'"):
        rgl.load(tmp_path / "lum.bsdf")


# -- the parameterization ----------------------------------------------------------------------

def test_marginal2d_samples_as_mitsuba_does(plastic_file):
    """The NumPy warp gives the points of Mitsuba's MarginalContinuous2D2 on an RGL file's
    VNDF slices (float32 there): to 1e-4 wherever the density is not vanishing."""
    m = rgl.load(plastic_file)
    theirs = mi.MarginalContinuous2D2(m.fields["vndf"], [m.phi_i.tolist(), m.theta_i.tolist()],
                                      True, True)
    u = np.concatenate([np.random.default_rng(1).uniform(0, 1, (20000, 2)),
                        rgl.node_grid(32)])
    for l in (0, 5, 15):
        ours, pdf = warp.Marginal2D(m.vndf[0, l]).sample(u)
        q, qpdf = theirs.sample(point2(u[:, 0], u[:, 1]),
                                [mi.Float(0.0), mi.Float(float(m.theta_i[l]))])
        q, qpdf = np.array(q).T, np.array(qpdf)
        dense = qpdf > 1e-2 * qpdf.mean()
        assert dense.mean() > 0.8
        np.testing.assert_allclose(ours[dense], q[dense], atol=1e-4)
        np.testing.assert_allclose(pdf[dense], qpdf[dense], rtol=1e-3)


def test_power_iteration_recovers_a_microfacet_ndf():
    """The retro-reflection of a GGX conductor (Fresnel 1) gives back its NDF: to 2 % within
    40 deg of the normal for alpha 0.1 and 0.3 (the model assumes masking and shadowing
    coincide in retro-reflection, which Mitsuba's separable G does not: hence not exact)."""
    theta, w = acquire._theta_nodes(128)
    dirs = acquire._retro_directions(theta)
    near = theta < np.radians(40)
    for alpha in (0.1, 0.3):
        b = mi.load_dict({"type": "roughconductor", "distribution": "ggx", "alpha": alpha,
                          "material": "none"})
        d, sigma, it = acquire.power_iteration(eval_np(b, dirs, dirs)[:, 1], theta, w)
        t2 = np.tan(theta[near]) ** 2
        ggx = 1 / (np.pi * alpha ** 2 * np.cos(theta[near]) ** 4 * (1 + t2 / alpha ** 2) ** 2)
        np.testing.assert_allclose(d[near], ggx, rtol=0.02)
        assert sigma[0] == pytest.approx(1) and it < 100


def test_projected_area_of_a_uniform_ndf():
    """sigma(w) of D = 1/pi (a Lambertian surface's) is (1 + cos theta) / 2, the clamped
    cosine lobe cut by the horizon: the closed-form azimuthal integral and the quadrature,
    against the exact value."""
    theta, w = acquire._theta_nodes(256)
    t = np.radians([0, 30, 60, 89])
    s = acquire.projected_area(t, theta, w, np.full(len(theta), 1 / np.pi))
    np.testing.assert_allclose(s, (1 + np.cos(t)) / 2, rtol=1e-4)


# -- the samples of an RGL file ------------------------------------------------------------------

def test_samples_are_what_measured_evaluates_and_what_was_measured(plastic_file):
    """At the samples' directions, Mitsuba's measured returns the samples' values (f cos) to
    float32 rounding, and those are the source's: the tables hold the measurement exactly
    at their nodes, but at the few where the source is not smooth, which hold
    its average over their footprint (``footprint.footprint_average``; fewer than 10 %)."""
    s = rgl.read_samples(plastic_file)
    assert not s.spectral and s.isotropic and s.value.shape == (len(s.wi), 3)
    assert len(s.wi) > 10000 and (s.wo[:, 2] > 0).all() and (s.wi[:, 2] > 0).all()
    assert s.negative == 0 and s.description.startswith("to-rgl")
    assert abs(os.path.getsize(plastic_file) / QUICK.size_bytes() - 1) < 0.01
    measured = mi.load_dict({"type": "measured", "filename": str(plastic_file)})
    source = mi.load_dict({"type": "roughplastic", "alpha": 0.15, "diffuse_reflectance":
                           {"type": "rgb", "value": [0.6, 0.3, 0.1]}})
    averaged = PLASTIC["nodes_averaged"] / len(s.wi)
    assert 0 < averaged < 0.1
    for other, share in ((measured, 0.99), (source, 0.99 - averaged)):
        e = eval_np(other, s.wi, s.wo)
        rel = np.abs(e - s.eval) / np.maximum(e, 1e-3 * e.max())
        assert np.median(rel) < 1e-5 and np.quantile(rel, share) < 1e-3, np.quantile(rel, share)
    np.testing.assert_allclose(s.eval, s.value * s.wo[:, 2:3])
    assert set(np.unique(s.incidence)) == set(range(16))


def test_spectral_files_give_samples_per_wavelength(tmp_path, plastic_file):
    """A spectral RGL file (``spectra`` and ``wavelengths``) gives one value per wavelength,
    and Mitsuba's measured (in a spectral variant) evaluates the same."""
    fields = tensor.read(plastic_file)
    rgb = fields.pop("rgb")
    wavelengths = np.array([400, 500, 600, 700], np.float32)
    weights = np.array([0.2, 0.6, 1.0, 1.4], np.float32)[None, None, :, None, None]
    fields["spectra"] = rgb[:, :, 1:2] * weights
    fields["wavelengths"] = wavelengths
    path = tmp_path / "spectral.bsdf"
    tensor.write(path, fields)
    s = rgl.read_samples(path)
    assert s.spectral and s.value.shape[1] == 4
    np.testing.assert_allclose(s.value[:, 3] / s.value[:, 0], 7, rtol=1e-5)
    with pytest.raises(FormatError, match="spectral variants only"):
        sources.rgl_evaluator(str(path))
    mi.set_variant("llvm_ad_spectral")
    bsdf = mi.load_dict({"type": "measured", "filename": str(path)})
    from mitsuba_brdfs.validate.probe import interaction, vec
    pick = np.random.default_rng(0).choice(len(s.wi), 500, replace=False)
    si = interaction(s.wi[pick])
    si.wavelengths = mi.UnpolarizedSpectrum(*wavelengths.tolist())
    e = np.array(bsdf.eval(mi.BSDFContext(), si, vec(s.wo[pick]))).T
    rel = np.abs(e - s.eval[pick]) / np.maximum(e, 1e-3 * e.max())
    assert np.quantile(rel, 0.99) < 1e-3


def test_one_reader_for_rgl_and_merl_files(tmp_path, plastic_file):
    """measured.read gives the samples of either format; MERL's are its measured bins at
    their directions, with the file's values; anything else is refused in one line."""
    from mitsuba_brdfs.measured import merl
    from mitsuba_brdfs.measured import read
    s = read(plastic_file)
    assert s.kind == "rgl" and len(s.wi) == len(rgl.read_samples(plastic_file).wi)
    path = tmp_path / "d.binary"
    f = merl_file(path, {"type": "roughplastic", "alpha": 0.2}, (16, 16, 32))
    m = read(path)
    assert m.kind == "merl" and m.incidence is None and not m.spectral
    assert len(m.wi) == np.isfinite(f).all(1).sum() - np.sum(
        np.isfinite(f).all(1) & ((merl.directions((16, 16, 32))[0][:, 2] <= 1e-4)
                                 | (merl.directions((16, 16, 32))[1][:, 2] <= 1e-4)))
    np.testing.assert_allclose(m.value, f[merl.lookup(m.wi, m.wo, (16, 16, 32))])
    (tmp_path / "x.txt").write_text("hello")
    with pytest.raises(FormatError, match="neither an RGL file .* nor a MERL file"):
        read(tmp_path / "x.txt")


# -- to-rgl: the round trip --------------------------------------------------------------------

ROUND_TRIP = [
    {"type": "ashikhmin_shirley"},
    {"type": "cook_torrance"},
    {"type": "oren_nayar"},
    {"type": "roughconductor", "alpha": 0.3},
    {"type": "roughplastic", "alpha": 0.1},
    {"type": "diffuse"},
]


@pytest.mark.parametrize("spec", ROUND_TRIP, ids=lambda s: s["type"])
def test_round_trip_albedo_and_eval(tmp_path, spec):
    """A file written from a BSDF gives its directional albedo within 3 % at 0, 45 and 70
    deg, 5 % at 80 and 85 deg, 10 % at 88 deg, and its eval within 10 % (median) where it
    reflects."""
    r = write_rgl(tmp_path / "x.bsdf", spec, compare=True)["compare"]
    for theta, a in r["albedo"].items():
        assert a["error"] < roundtrip.bound(theta), (theta, a)
    assert r["eval_median_error"] < 0.1 and r["eval_within_10_percent"] > 0.8, r


def test_round_trip_of_a_merl_file(tmp_path):
    """A MERL file (written here from a Cook-Torrance fit) as an RGL file: albedo within
    5 % up to 80 deg, eval within 10 % (median) of the MERL table as MERL's reader looks it
    up. (Nearer the horizon this small table's bins, 3 deg of theta_d and most of them
    unmeasured there, are what differ; the full-size file's test below holds it to the
    grazing bounds.)"""
    from mitsuba_brdfs import presets
    path = tmp_path / "gold.binary"
    merl_file(path, presets.ngan2005("cook_torrance", "gold-paint"), (30, 30, 60))
    source = sources.open_source(str(path))
    assert source.kind == "merl" and "unmeasured" in source.notes[0]
    r = convert.convert(source, str(tmp_path / "gold.bsdf"), QUICK)["compare"]
    for theta, a in r["albedo"].items():
        assert int(theta) > 80 or a["error"] < 0.05, (theta, a)
    assert r["eval_median_error"] < 0.1


def test_an_rgl_file_converted_again_keeps_its_channel_albedos(tmp_path, plastic_file):
    """An RGL file with negative values (out-of-gamut colours) converted by to-rgl: no
    negative value left, each channel's albedo kept (clipping alone would raise the
    dark channel)."""
    fields = tensor.read(plastic_file)
    rng = np.random.default_rng(0)
    noisy = fields["rgb"].copy()
    noisy[:, :, 2] += rng.normal(0, 0.05, noisy[:, :, 2].shape).astype(np.float32)
    fields["rgb"] = noisy
    path = tmp_path / "noisy.bsdf"
    tensor.write(path, fields)
    assert rgl.read_samples(path).negative > 1000
    summary = convert.convert(sources.open_source(str(path)), str(tmp_path / "out.bsdf"), QUICK)
    assert summary["negative_values_clipped"] > 1000
    assert rgl.load(tmp_path / "out.bsdf").values.min() >= 0
    for theta, a in summary["compare"]["albedo"].items():
        assert a["error"] < roundtrip.bound(theta, 0.05), (theta, a)


def test_clip_keeping_albedo_keeps_channel_sums():
    v = np.array([[1.0, 0.2], [2.0, -0.1], [1.0, 0.05], [-0.5, -0.3]])
    c = acquire.clip_keeping_albedo(v)
    assert c.min() >= 0
    np.testing.assert_allclose(c.sum(0), [3.5, 0.0])
    np.testing.assert_allclose(acquire.clip_keeping_albedo(np.abs(v)), np.abs(v))


def test_written_files_avoid_the_defects_of_rgl_files(plastic_file):
    """What check finds in RGL's files: NaN eval at the horizon and negative values; a
    written file has neither (its last incidence is below 90 deg)."""
    from mitsuba_brdfs.validate.directions import hard_directions, hard_pairs
    m = rgl.load(plastic_file)
    assert m.theta_i[-1] < np.radians(90) and m.values.min() >= 0
    bsdf = mi.load_dict({"type": "measured", "filename": str(plastic_file)})
    wi, wo = hard_pairs(hard_directions())
    e = eval_np(bsdf, wi, wo)
    assert np.isfinite(e).all() and e.min() >= 0
    # the pair at which every RGL file of the database gives NaN
    e = eval_np(bsdf, [[0.8279, 0.5609, 1.761e-08]], [[-0.8279, -0.5609, 0.0001084]])
    assert np.isfinite(e).all()


def test_sampling_of_a_written_file_matches_its_eval(plastic_file):
    """measured's sample() on a written file: its weights are eval / pdf and their mean the
    albedo (the quadrature of eval), at three incidences."""
    from mitsuba_brdfs.validate.energy import albedo_at, quadrature
    bsdf = mi.load_dict({"type": "measured", "filename": str(plastic_file)})
    for theta in (0, 45, 70):
        wi = sph(np.radians(theta), 0.3)[0]
        mc, err = albedo_at(bsdf, wi, n=200_000)
        (q, qerr), _ = quadrature(bsdf, wi, 96, same_side=True)
        np.testing.assert_allclose(mc, q, atol=5 * err.max() + 2 * qerr.max() + 2e-3)


def test_renders_as_its_source(plastic_file):
    """A sphere under a point light and an environment: the file renders as the BSDF it was
    written from, pixel means within 2 % and the image within 5 % (RMS, relative)."""
    from checks import small_scene
    spec = {"type": "roughplastic", "alpha": 0.15,
            "diffuse_reflectance": {"type": "rgb", "value": [0.6, 0.3, 0.1]}}
    imgs = [np.array(mi.render(small_scene(b, res=48), spp=256, seed=1))
            for b in (spec, {"type": "measured", "filename": str(plastic_file)})]
    assert np.isfinite(imgs[1]).all()
    np.testing.assert_allclose(imgs[1].mean((0, 1)), imgs[0].mean((0, 1)), rtol=0.02)
    rms = np.sqrt(np.mean((imgs[1] - imgs[0]) ** 2)) / np.sqrt(np.mean(imgs[0] ** 2))
    assert rms < 0.05


def test_delta_sources_are_refused(tmp_path):
    conductor = sources.Source(sources.bsdf_evaluator(mi.load_dict({"type": "conductor"})),
                               "conductor", "bsdf", "conductor", [])
    with pytest.raises(ValueError, match="reflects nothing back"):
        convert.convert(conductor, str(tmp_path / "c.bsdf"), QUICK)
    assert not os.listdir(tmp_path)


@pytest.fixture(scope="module")
def ward_file(tmp_path_factory):
    """An anisotropic file: Ward, alpha_u 0.05, alpha_v 0.3, at a small resolution."""
    path = tmp_path_factory.mktemp("aniso") / "ward.bsdf"
    spec = {"type": "ward", "alpha_u": 0.05, "alpha_v": 0.3}
    summary = write_rgl(path, spec, acquire.Resolution(ndf=64, theta_i=12, vndf=32, grid=48,
                                                       phi_i=2, ndf_aniso=48, ndf_phi=25),
                        compare=True)
    return path, spec, summary


def test_an_anisotropic_source_gets_an_anisotropic_file(ward_file):
    """Anisotropic Ward: the file measures 9 azimuths of incidence over the whole circle
    (measured folds nothing then), its albedo (at three azimuths) is within 3 % up to 70
    deg (``roundtrip.bound`` beyond) and its eval within 10 % (median); the samples read
    back are measured's eval, and Ward's at all but the nodes that hold an average; a fit
    to it keeps Ward's two widths apart."""
    path, spec, summary = ward_file
    m = rgl.load(path)
    assert not m.isotropic and len(m.phi_i) == 9 and m.ndf.shape == (25, 48)
    assert summary["resolution"]["azimuths"] == 9
    np.testing.assert_allclose(m.phi_i[[0, -1]], [-np.pi, np.pi], rtol=1e-6)
    for theta, a in summary["compare"]["albedo"].items():
        assert a["error"] < roundtrip.bound(theta), (theta, a)
    assert summary["compare"]["eval_median_error"] < 0.1
    s = rgl.read_samples(path)
    assert not s.isotropic and set(np.unique(s.phi_index)) == set(range(9))
    # fitted, the file keeps an anisotropic model's two widths apart
    from mitsuba_brdfs.measured import data as D, report
    data = D.prepare(path, samples=2000, holdout=100)
    r = report.fit_file(data, mi.load_dict({"type": "ward"}), evaluations=0)
    assert not data.isotropic and r["isotropy"] == {"data": "anisotropic",
                                                    "fit": "anisotropic", "tied": []}
    for other, share in ((mi.load_dict({"type": "measured", "filename": str(path)}), 0.99),
                         (mi.load_dict(spec), 0.99 - summary["nodes_averaged"] / summary["nodes"])):
        e = eval_np(other, s.wi, s.wo)
        rel = np.abs(e - s.eval) / np.maximum(e, 1e-3 * e.max())
        assert np.median(rel) < 1e-5 and np.quantile(rel, share) < 1e-3, np.quantile(rel, share)


def test_is_isotropic():
    assert sources.is_isotropic(sources.bsdf_evaluator(mi.load_dict({"type": "ward"})))
    assert not sources.is_isotropic(sources.bsdf_evaluator(mi.load_dict(
        {"type": "ashikhmin_shirley", "nu": 100, "nv": 110})))


# -- the command line ----------------------------------------------------------------------------

def test_command_line(tmp_path):
    """to-rgl of this package's plugin, Mitsuba's, a user's (--load), an XML file's <bsdf>
    and a MERL file; each file loads in measured. Bad input: one line, exit status 2,
    nothing written."""
    user_bsdf.write(tmp_path / "flat.py", "flatuser")
    (tmp_path / "b.xml").write_text('<bsdf version="3.0.0" type="roughconductor">'
                                    '<float name="alpha" value="$a"/></bsdf>')
    merl_file(tmp_path / "d.binary", {"type": "diffuse"}, (16, 16, 32))
    (tmp_path / "junk.binary").write_bytes(b"\0" * 100)
    (tmp_path / "two.xml").write_text(
        '<scene version="3.0.0"><shape type="sphere"><bsdf type="diffuse"/></shape>'
        '<shape type="cube"><bsdf type="ward"/></shape></scene>')
    small = ["--theta-i", "8", "--grid", "16", "--vndf", "32", "--ndf", "32"]
    out = str(tmp_path / "o")
    cases = [
        ["to-rgl", "lambert", "-p", "reflectance=0.2,0.4,0.6", "-o", out + "1.bsdf", "--json",
         *small],
        ["to-rgl", "roughconductor", "-p", "alpha=0.4", "-o", out + "2.bsdf", *small],
        ["to-rgl", "flatuser", "--load", str(tmp_path / "flat.py"), "-o", out + "3.bsdf",
         "--no-compare", *small],
        ["to-rgl", str(tmp_path / "b.xml"), "-p", "a=0.3", "-o", out + "4.bsdf", *small],
        ["to-rgl", str(tmp_path / "d.binary"), "-o", out + "5.bsdf", *small],
        # refused
        ["to-rgl", "nosuchplugin", "-o", out + "x.bsdf"],
        ["to-rgl", str(tmp_path / "junk.binary"), "-o", out + "x.bsdf"],
        ["to-rgl", str(tmp_path / "two.xml"), "-o", out + "x.bsdf"],
        ["to-rgl", "diffuse", "-o", str(tmp_path / "b.xml" / "x.bsdf")],
        ["to-rgl", "diffuse", "-o", out + "x.bsdf", "--variant", "llvm_ad_spectral"],
        ["to-rgl", "diffuse", "-o", out + "x.bsdf", "--grid", "2"],
    ]
    results = run_many(cases, cwd=tmp_path)
    for k in range(5):
        code, stdout, stderr = results[k]
        assert code == 0, (cases[k], stderr[-2000:])
        b = mi.load_dict({"type": "measured", "filename": f"{out}{k + 1}.bsdf"})
        assert np.isfinite(eval_np(b, random_upper(np.random.default_rng(0), 100),
                                   random_upper(np.random.default_rng(1), 100))).all()
    summary = json.loads(results[0][1])
    assert summary["resolution"] == {"ndf": 32, "theta_i": 8, "vndf": 32, "grid": 16}
    assert summary["compare"]["albedo"]["0"]["error"] < 0.03
    np.testing.assert_allclose(summary["compare"]["albedo"]["0"]["source"], [0.2, 0.4, 0.6],
                               rtol=2e-3)
    assert "albedo (source -> file" in results[1][1] and "88 deg" in results[1][1]
    assert "distribution = beckmann (default)" in results[1][1] and "median error" in results[1][1]
    assert "compare" not in results[2][1]
    messages = ["unknown plugin 'nosuchplugin'", "junk.binary: not a MERL BRDF", "holds 2 BSDFs",
                "is not a folder", "RGB variant", "--grid"]
    for case, (code, stdout, stderr), message in zip(cases[5:], results[5:], messages):
        assert code == 2, (case, stderr)
        assert len(stderr.strip().splitlines()) == 1 and message in stderr, (case, stderr)
    assert not os.path.exists(out + "x.bsdf")


def test_reads_a_truncated_rgl_source_as_a_usage_error(tmp_path, plastic_file):
    cut = tmp_path / "cut.bsdf"
    cut.write_bytes(plastic_file.read_bytes()[:100000])
    code, stdout, stderr = run_many([["to-rgl", str(cut), "-o", str(tmp_path / "y.bsdf")]])[0]
    assert code == 2 and "cut.bsdf: truncated" in stderr and len(stderr.strip().splitlines()) == 1
    assert not (tmp_path / "y.bsdf").exists()


# -- the studies ---------------------------------------------------------------------------------

@pytest.mark.slow
@pytest.mark.parametrize("spec", [
    {"type": "ashikhmin_shirley"}, {"type": "ward"}, {"type": "cook_torrance"},
    {"type": "oren_nayar"}, {"type": "blinn_phong"}, {"type": "phong"},
    {"type": "torrance_sparrow"}, {"type": "lambert"},
    {"type": "roughconductor", "alpha": 0.3}, {"type": "roughconductor", "alpha": 0.05},
    {"type": "roughplastic", "alpha": 0.1}, {"type": "roughplastic", "alpha": 0.02},
    {"type": "diffuse"}], ids=lambda s: "-".join(str(v) for v in s.values()))
def test_round_trip_at_the_default_resolution(tmp_path, spec):
    r = write_rgl(tmp_path / "x.bsdf", spec, acquire.Resolution(), compare=True)["compare"]
    # roughplastic's lobe of alpha 0.02 at 88 deg: half of it falls where the file's grid
    # has no nodes (docs/measured.md, "near the horizon"): 22 % too dark there
    sharp = spec == {"type": "roughplastic", "alpha": 0.02}
    for theta, a in r["albedo"].items():
        assert a["error"] < (0.25 if sharp and theta == "88" else roundtrip.bound(theta)), \
            (theta, a)
    assert r["eval_median_error"] < 0.02, r


@pytest.mark.slow
def test_round_trip_of_a_full_size_merl_file(tmp_path):
    from mitsuba_brdfs import presets
    from mitsuba_brdfs.measured import merl
    path = tmp_path / "gold.binary"
    merl_file(path, presets.ngan2005("cook_torrance", "gold-paint"), merl.DIMS)
    r = convert.convert(sources.open_source(str(path)), str(tmp_path / "g.bsdf"),
                       acquire.Resolution())["compare"]
    for theta, a in r["albedo"].items():
        assert a["error"] < roundtrip.bound(theta, 0.05), (theta, a)
    assert r["eval_median_error"] < 0.05


@pytest.mark.slow
def test_check_passes_a_written_file_but_for_measured_own_pdf(plastic_file):
    """The check suite on a written file: everything but the negative pdf() that measured's
    arithmetic gives at nearly opposite grazing pairs (``docs/check.md``), and at a few of
    120,000 samples a sample pdf up to 0.2 % off pdf() (measured's float32 warps, where a
    node's value averages a steep lobe: the check allows 0.1 %)."""
    from mitsuba_brdfs.validate import suite
    bsdf = mi.load_dict({"type": "measured", "filename": str(plastic_file)})
    results = {r.name: r for r in suite.run(bsdf, suite.SETTINGS["quick"], "measured")}
    failed = [n for n, r in results.items() if r.status == "FAIL"]
    assert failed in (["hard_cases"], ["weight", "hard_cases"]), failed
    if "weight" in failed:
        w = results["weight"].numbers
        assert w["pdf_max_rel"] < 0.002 and w["weight_off"] + w["pdf_off"] <= 5, w
    message = results["hard_cases"].message
    assert "negative pdf where eval is not 0" in message
    assert "negative eval" not in message and "sample weight" not in message
