"""Measured data in the explorer: RGL and MERL files as entries (Mitsuba's ``measured``
plugin on the RGL file; on a MERL file's, the RGL file ``to-rgl`` makes of it, cached), and
a model fitted to one through the page's API. Every file is written here
(``explore_page.measured_files``: ``to-rgl`` of a ``ward``, a MERL file of a Cook-Torrance
BRDF). The page itself: tests/test_explore_measured_browser.py."""
import contextlib
import gc
import io
import os
import threading

import mitsuba as mi
import numpy as np
import pytest

pytest.importorskip("starlette")
pytest.importorskip("httpx2")
from starlette.testclient import TestClient  # noqa: E402

from explore_page import RGL_RESOLUTION, measured_files  # noqa: E402
from mitsuba_brdfs import presets  # noqa: E402
from mitsuba_brdfs.__main__ import main  # noqa: E402
from mitsuba_brdfs.explore import fitting, measurement  # noqa: E402
from mitsuba_brdfs.explore.entries import make_entries  # noqa: E402
from mitsuba_brdfs.explore.server import app  # noqa: E402
from mitsuba_brdfs.explore.session import MAX_ENTRIES, PALETTE, Explorer  # noqa: E402
from mitsuba_brdfs.measured import tensor  # noqa: E402
from mitsuba_brdfs.validate.directions import sph  # noqa: E402
from mitsuba_brdfs.validate.probe import eval_np  # noqa: E402

TOKEN = "test-token"
LUMINANCE = np.array([0.2126, 0.7152, 0.0722])


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    folder = tmp_path_factory.mktemp("measured")
    rgl, binary = measured_files(str(folder))
    return {"rgl": rgl, "merl": binary, "folder": folder}


@pytest.fixture
def cache(tmp_path, monkeypatch):
    """A cache folder of the test's own."""
    folder = tmp_path / "cache"
    monkeypatch.setenv("MITSUBA_BRDFS_CACHE", str(folder))
    return folder


def serve(explorer):
    c = TestClient(app(explorer, "127.0.0.1", 8765, TOKEN), base_url="http://127.0.0.1:8765",
                   headers={"Authorization": f"token {TOKEN}"})
    c.explorer = explorer
    return c


#: the budget of the fits here (``explore --fit-samples 1000 --fit-evaluations 120``): the
#: files' own models found again
SAMPLES, EVALUATIONS = 1000, 120


@pytest.fixture
def client(files, cache):
    """gold.binary (0), ward.bsdf (1), lambert (2)."""
    found = make_entries(files["merl"], {}, 0, PALETTE)
    found += make_entries(files["rgl"], {}, 1, PALETTE)
    found += make_entries("lambert", {}, 2, PALETTE)
    c = serve(Explorer(found, "llvm_ad_rgb", ["lambert"], SAMPLES, EVALUATIONS))
    yield c
    c.explorer.entries.clear()
    c.explorer.spheres.clear()
    del c, found
    gc.collect()


def _plots(client, **body):
    r = client.post("/api/plots", json=body)
    assert r.status_code == 200, r.text
    return {e["label"]: e for e in r.json()["entries"]}


# -- measured entries ---------------------------------------------------------------------------

def test_an_rgl_file_is_drawn_through_measured(client, files):
    """The entry is Mitsuba's ``measured`` on the file: no controls (it exposes nothing),
    the page told it is measured data; its plots are measured's values, its albedo's
    samples come from measured's importance sampling; its sphere renders; it exports."""
    state = {e["label"]: e for e in client.get("/api/state").json()["entries"]}
    e = state["ward.bsdf"]
    assert e["plugin"] == "measured" and e["controls"] == [] and e["exportable"]
    assert e["measured"]["kind"] == "rgl" and e["measured"]["rgl"] == files["rgl"]
    assert "measured data" in e["measured"]["text"] and "no parameters" in e["measured"]["text"]
    assert e["fit"] is None
    data = _plots(client, theta_i=30)["ward.bsdf"]
    bsdf = mi.load_dict({"type": "measured", "filename": files["rgl"]})
    t = np.radians(data["polar"]["theta"])
    wo = np.stack([np.sin(t), 0 * t, np.cos(t)], -1)
    wi = np.repeat(sph(np.radians(30), np.pi), len(t), 0)
    expect = np.asarray(eval_np(bsdf, wi, wo), float) @ LUMINANCE
    got = np.array([np.nan if v is None else v for v in data["polar"]["value"]])
    assert np.allclose(got, expect, rtol=1e-4, atol=1e-7) and expect.max() > 0.1
    a = data["albedo"]
    for theta, q, m, s in zip(a["theta"], a["quadrature"], a["mean"], a["stderr"]):
        if theta <= 75:
            assert abs(q - m) < 3 * s + 0.02 * q, (theta, q, m, s)
    png = client.get("/api/sphere/1?pass=0")
    assert png.status_code == 200 and png.content[:4] == b"\x89PNG"
    xml = client.get("/api/export/1").json()["xml"]
    assert 'type="measured"' in xml and files["rgl"] in xml
    again = mi.load_string(xml.replace("<bsdf ", '<bsdf version="3.0.0" ', 1))
    assert np.allclose(eval_np(again, wi, wo), eval_np(bsdf, wi, wo))
    r = client.patch("/api/entries/1", json={"name": "alpha", "value": 0.2})
    assert r.status_code == 400 and "no parameter 'alpha'" in r.json()["error"]
    assert client.patch("/api/entries/1", json={"colour": "#00ff00"}).status_code == 200


def test_a_merl_file_is_converted_once_and_cached(files, cache, monkeypatch):
    """The first start converts the MERL file as ``to-rgl`` does (the same tables) into the
    cache, under the file's SHA-256; the second reads it back without converting; a file
    changed in place gets a new one; a cache that cannot be written, a temporary file."""
    import hashlib
    (e,) = make_entries(files["merl"], {}, 0, PALETTE)
    m = e.state()["measured"]
    assert m["kind"] == "merl" and os.path.dirname(m["rgl"]) == str(cache)
    digest = hashlib.sha256(open(files["merl"], "rb").read()).hexdigest()
    assert digest[:16] in os.path.basename(m["rgl"]) and "kept in" in m["note"]
    out = str(cache.parent / "gold.bsdf")
    with contextlib.redirect_stdout(io.StringIO()):
        assert main(["to-rgl", files["merl"], "-o", out, "--no-compare"]) == 0
    mine, theirs = tensor.read(m["rgl"]), tensor.read(out)
    assert sorted(mine) == sorted(theirs)
    for k in mine:
        assert np.array_equal(mine[k], theirs[k]), k
    written = os.stat(m["rgl"]).st_mtime_ns
    # the second start: nothing converted
    with monkeypatch.context() as patched:
        patched.setattr("mitsuba_brdfs.measured.acquire.acquire",
                        lambda *a, **k: pytest.fail("converted again"))
        (again,) = make_entries(files["merl"], {}, 0, PALETTE)
    assert again.measured["rgl"] == m["rgl"] and again.measured["cached"]
    assert "read from the cache" in again.measured["note"]
    assert os.stat(m["rgl"]).st_mtime_ns == written
    # the same name, other values: another file
    changed = cache.parent / "gold.binary"
    from checks import merl_file
    merl_file(changed, presets.ngan2005("cook_torrance", "gold-metallic-paint"), (30, 30, 60))
    (other,) = make_entries(str(changed), {}, 0, PALETTE)
    assert other.measured["rgl"] != m["rgl"] and len(os.listdir(cache)) == 2
    # a cache that cannot be written (a file where its folder would be)
    blocked = cache.parent / "blocked"
    blocked.write_text("")
    monkeypatch.setenv("MITSUBA_BRDFS_CACHE", str(blocked / "rgl"))
    (tmp,) = make_entries(files["merl"], {}, 0, PALETTE)
    assert "cannot be written" in tmp.measured["note"] and os.path.isfile(tmp.measured["rgl"])
    assert not tmp.measured["rgl"].startswith(str(blocked))


def test_files_that_cannot_be_shown_are_refused_in_one_line(files, cache, client, capsys,
                                                             monkeypatch):
    folder = cache.parent
    monkeypatch.chdir(folder)  # the page loads files of the folder served
    short = folder / "short.binary"
    short.write_bytes(open(files["merl"], "rb").read()[:1000])
    noise = folder / "noise.bsdf"
    noise.write_bytes(bytes(range(256)) * 8)
    cut = folder / "cut.bsdf"
    cut.write_bytes(open(files["rgl"], "rb").read()[:5000])
    black = folder / "black.binary"
    from mitsuba_brdfs.measured import merl
    merl.write(str(black), np.zeros((int(np.prod((30, 30, 60))), 3)), (30, 30, 60))
    cases = [(short, "MERL BRDF of 30 x 30 x 60 bins has"), (noise, "neither an RGL file"),
             (cut, "truncated"), (black, "reflects nothing back")]
    for path, why in cases:
        with pytest.raises(ValueError) as info:
            make_entries(str(path), {}, 0, PALETTE)
        text = str(info.value)
        assert why in text and str(path) in text and "\n" not in text, text
        before = len(client.get("/api/state").json()["entries"])
        r = client.post("/api/entries", json={"spec": str(path)})
        assert r.status_code == 400 and why in r.json()["error"]
        assert len(client.get("/api/state").json()["entries"]) == before
        assert main(["explore", str(path), "--port", "0", "--no-browser"]) == 2
        err = capsys.readouterr().err
        assert why in err and err.count("\n") == 1, err
    with pytest.raises(ValueError, match="measured data take no -p parameters"):
        make_entries(files["rgl"], {"alpha": "0.1"}, 0, PALETTE)
    mi.set_variant("llvm_ad_spectral")
    with pytest.raises(ValueError, match="RGB variants only"):
        measurement.rgl_file(files["merl"])
    with pytest.raises(ValueError, match="an RGB RGL file"):
        measurement.rgl_file(files["rgl"])


def test_the_weights_of_rgl_samples_are_their_measure(files):
    """A fit (the page's, ``fit-measured``'s: ``measured.data.prepare``) weighs each sample
    of an RGL file by the measure of the direction pairs it stands for: at each incidence
    the weights add up to its band of wi (between the midpoints to its neighbours) times
    the solid angle within 80 deg, and the weights times f cos to the band times the
    directional albedo over those outgoing directions (Mitsuba's measured, by
    quadrature)."""
    from mitsuba_brdfs.measured import rgl
    from mitsuba_brdfs.measured.data import prepare
    d = prepare(files["rgl"], samples=10 ** 9, holdout=0)   # every sample within 80 deg
    m = rgl.load(files["rgl"])
    edges = np.concatenate([[0], (m.theta_i[1:] + m.theta_i[:-1]) / 2, [np.pi / 2]])
    cap = 2 * np.pi * (1 - np.cos(np.radians(80)))
    n = 160   # the quadrature: midpoints in cos theta_o (within 80 deg) and phi_o
    c = np.cos(np.radians(80)) + (np.arange(n) + 0.5) / n * (1 - np.cos(np.radians(80)))
    phi = (np.arange(2 * n) + 0.5) / (2 * n) * 2 * np.pi
    c, phi = (x.ravel() for x in np.meshgrid(c, phi, indexing="ij"))
    wo = np.stack([np.sqrt(1 - c * c) * np.cos(phi), np.sqrt(1 - c * c) * np.sin(phi), c], -1)
    bsdf = mi.load_dict({"type": "measured", "filename": files["rgl"]})
    theta = np.arccos(np.clip(d.wi[:, 2], -1, 1))
    seen = 0
    for k, t in enumerate(m.theta_i):
        here = np.abs(theta - t) < 1e-4
        if not here.any():
            continue
        seen += 1
        band = 2 * np.pi * (np.cos(edges[k]) - np.cos(edges[k + 1]))
        w = d.weights[here]
        assert abs(w.sum() / (band * cap) - 1) < 0.05, np.degrees(t)
        wi = np.repeat([[np.sin(t), 0, np.cos(t)]], len(wo), 0)
        albedo = np.asarray(eval_np(bsdf, wi, wo), float).sum(0) * cap / len(wo)
        got = (w[:, None] * d.f[here] * d.wo[here, 2:3]).sum(0) / band
        assert np.allclose(got, albedo, rtol=0.06), (np.degrees(t), got, albedo)
    assert seen == (np.degrees(m.theta_i) < 80).sum() >= 5


# -- fits --------------------------------------------------------------------------------------

def test_a_model_fitted_to_a_merl_file(client):
    """The MERL file holds a Cook-Torrance BRDF: ``cook_torrance`` fitted to it finds it
    again (relative RMS error below 2 %, the albedo within 2 %, the roughness of the
    BRDF) within the page's budget; the fitted model is an entry with its controls,
    drawn with the others, and its held-out loss is what it gives on the held-out
    samples."""
    from mitsuba_brdfs.measured.quality import shape_loss
    budget = client.get("/api/state").json()["fit_budget"]
    assert budget == {"samples": SAMPLES, "evaluations": EVALUATIONS, "most": 300}
    # the page's own budget: at most 250 evaluations a stage, 625 in all
    assert fitting.budget() == {"samples": 4000, "evaluations": 250, "most": 625}
    r = client.post("/api/fit/0", json={"model": "cook_torrance"})
    assert r.status_code == 200, r.text
    out = r.json()
    f, new = out["fit"], out["entry"]
    assert not out["cancelled"] and f["model"] == "cook_torrance" and f["to"] == "gold.binary"
    assert f["relative_rms_max"] < 0.02 and f["samples"] == budget["samples"]
    assert f["holdout_samples"] == min(5000, f["bins"] // 5) and f["bins"] > 2 * f["samples"]
    assert 0 < f["evaluations"] <= budget["most"] and f["budget"] == budget
    assert np.allclose(f["albedo"]["fitted"], f["albedo"]["measured"], rtol=0.02)
    assert f["command"].endswith(f"--model cook_torrance --samples {budget['samples']} "
                                 f"--evaluations {budget['evaluations']} --seed 0 --image-spp 0")
    assert new["label"] == "cook_torrance fit to gold.binary" and new["fit"]["id"] == 0
    assert {c["name"] for c in new["controls"]} >= {"roughness", "diffuse_reflectance"}
    roughness = next(c["value"] for c in new["controls"] if c["name"] == "roughness")
    preset = presets.ngan2005("cook_torrance", "gold-paint")["roughness"]
    assert abs(roughness / preset - 1) < 0.05, (roughness, preset)
    entry = client.explorer.entries[new["id"]]
    held = client.explorer.entries[0].fit_data["measured"].holdout
    assert np.isclose(shape_loss(entry.bsdf, *held), f["holdout_loss"], rtol=1e-3, atol=1e-12)
    state = client.get("/api/state").json()
    assert state["fit"] is None and [e["id"] for e in state["entries"]] == [0, 1, 2, new["id"]]
    labels = _plots(client, parts=["polar", "albedo"])
    assert "cook_torrance fit to gold.binary" in labels
    # a model that cannot follow the data says so by its error
    r = client.post("/api/fit/0", json={"model": "lambert"}).json()["fit"]
    assert r["relative_rms_max"] > 0.3 and r["holdout_loss"] > 0.1


def test_a_model_fitted_to_an_rgl_file(client, cache, monkeypatch):
    """The RGL file is a ``ward`` measured by ``to-rgl``: ``ward`` fitted to its samples
    finds its roughness and colours again; and both roughnesses of an anisotropic one
    (an anisotropic RGL file: incidences at several azimuths)."""
    r = client.post("/api/fit/1", json={"model": "ward"})
    assert r.status_code == 200, r.text
    f, new = r.json()["fit"], r.json()["entry"]
    assert f["relative_rms_max"] < 0.03, f
    values = {c["name"]: c["value"] for c in new["controls"]}
    assert abs(values["alpha_u"] / 0.15 - 1) < 0.05 and abs(values["alpha_v"] / 0.15 - 1) < 0.05
    assert np.allclose(values["specular_reflectance"], [0.3, 0.2, 0.1], rtol=0.05)
    assert np.allclose(values["diffuse_reflectance"], [0.2, 0.3, 0.5], rtol=0.05)
    path = str(cache.parent / "brushed.bsdf")
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
        assert main(["to-rgl", "ward", "-p", "alpha_u=0.08", "-p", "alpha_v=0.3",
                     *RGL_RESOLUTION, "--phi-i", "2", "--no-compare", "-o", path]) == 0
    from mitsuba_brdfs.measured import reader
    assert not reader.read(path).isotropic
    monkeypatch.chdir(cache.parent)  # the page loads files of the folder served
    ident = client.post("/api/entries", json={"spec": path}).json()[0]["id"]
    r = client.post(f"/api/fit/{ident}", json={"model": "ward"}).json()
    values = {c["name"]: c["value"] for c in r["entry"]["controls"]}
    assert r["fit"]["relative_rms_max"] < 0.03, r["fit"]
    assert abs(values["alpha_u"] / 0.08 - 1) < 0.05 and abs(values["alpha_v"] / 0.3 - 1) < 0.05


def same(a, b):
    """Equal, numbers to float32's last digits (the data's albedo, by Mitsuba's measured
    plugin loaded anew, may differ there)."""
    if isinstance(a, dict) and isinstance(b, dict):
        return a.keys() == b.keys() and all(same(a[k], b[k]) for k in a)
    if isinstance(a, list) and isinstance(b, list):
        return len(a) == len(b) and all(same(x, y) for x, y in zip(a, b))
    if isinstance(a, float) and isinstance(b, float):
        return a == pytest.approx(b, rel=1e-6, abs=1e-7)
    return a == b


@pytest.mark.parametrize("kind, model", [("merl", "ward"), ("rgl", "lambert")])
def test_the_page_fits_as_fit_measured_does(files, cache, kind, model, tmp_path, capsys):
    """For the same file, model, samples, seed and budget, the page's fit and
    ``fit-measured --json`` report the same parameters, errors and warnings (here a small
    budget, at which ward leaves gold-paint's albedo by more than 10 %: the albedo
    constraint's stages run and are warned about). The page announces the most
    evaluations a fit takes, stages included, and keeps within it."""
    import json
    samples, evaluations = 1000, 20
    path = files[kind]
    found = make_entries(path, {}, 0, PALETTE)
    c = serve(Explorer(found, "llvm_ad_rgb", fit_samples=samples, fit_evaluations=evaluations))
    budget = c.get("/api/state").json()["fit_budget"]
    assert budget == {"samples": samples, "evaluations": evaluations, "most": 50}
    r = c.post("/api/fit/0", json={"model": model})
    assert r.status_code == 200, r.text
    page = r.json()["fit"]
    capsys.readouterr()
    assert main(["fit-measured", path, "--model", model, "--samples", str(samples),
                 "--evaluations", str(evaluations), "--seed", "0", "--image-spp", "0",
                 "--json", "--out", str(tmp_path)]) == 0
    command = json.loads(capsys.readouterr().out)
    files = ("xml", "outputs")  # the command's (the page exports the fitted entry)
    timed = ("seconds", "seconds_per_evaluation", "seconds_total")
    assert sorted(k for k in command if k not in files) == sorted(
        k for k in page if k not in ("to", "budget", "command", "id"))
    for key in command:
        if key not in timed + files:
            assert same(page[key], command[key]), (key, page[key], command[key])
    assert page["command"].split()[3:] == ["fit-measured", path, "--model", model,
                                           "--samples", "1000", "--evaluations", "20",
                                           "--seed", "0", "--image-spp", "0"]
    assert page["evaluations"] <= budget["most"]
    if kind == "merl":   # the constraint ran: more than a stage's budget, within the total
        assert page["constraint"]["status"] != "met" and page["warnings"]
        assert page["evaluations"] > evaluations


def test_the_fit_runs_one_at_a_time_blocks_nothing_and_is_cancelled(client, monkeypatch):
    """While a fit runs, a second is refused (409), the page's other requests are answered,
    and DELETE /api/fit stops it after the evaluation under way: nothing is added."""
    from mitsuba_brdfs.measured import report
    gate, started = threading.Event(), threading.Event()
    fit_file = report.fit_file

    def gated_fit(*args, progress=None, **kw):
        def step(loss):
            started.set()
            gate.wait(60)
            progress(loss)
        return fit_file(*args, progress=step, **kw)
    monkeypatch.setattr(report, "fit_file", gated_fit)
    result = {}
    worker = threading.Thread(target=lambda: result.update(client.explorer.fit(0, "ward")))
    worker.start()
    try:
        assert started.wait(120)
        assert client.get("/api/state").json()["fit"] == {"id": 0, "label": "gold.binary",
                                                          "model": "ward"}
        r = client.post("/api/fit/1", json={"model": "ward"})
        assert r.status_code == 409 and "ward's fit to gold.binary is running" in r.json()["error"]
        assert _plots(client, ids=[2])["lambert"]["polar"]["value"]  # the page goes on
        assert client.post("/api/entries", json={"spec": "ward"}).status_code == 200
        r = client.delete("/api/fit")
        assert r.status_code == 200 and r.json() == {"cancelled": "gold.binary"}
    finally:
        gate.set()
        worker.join(timeout=300)
    assert result == {"id": 0, "label": "gold.binary", "model": "ward", "cancelled": True}
    state = client.get("/api/state").json()
    assert state["fit"] is None and len(state["entries"]) == 4  # the ward added, no fit
    assert client.delete("/api/fit").json() == {"cancelled": None}


def test_fits_that_cannot_be_made_are_refused(client):
    """A field that is not a model of the package, a BSDF that is not measured data, a full
    page, a variant without AD, and what the guard refuses: 4xx, nothing fitted."""
    def post(ident, body):
        r = client.post(f"/api/fit/{ident}", json=body)
        return r.status_code, r.json()["error"]
    code, why = post(0, {"model": "roughplastic"})
    assert code == 400 and "not a model of this package" in why and "ward" in why
    code, why = post(2, {"model": "ward"})
    assert code == 400 and "lambert is not measured data" in why
    assert post(0, {"model": 3})[0] == 400
    assert post(0, {"model": "ward", "samples": 9})[0] == 400
    assert post(0, {})[0] == 400
    assert post(99, {"model": "ward"})[0] == 404
    assert post("x", {"model": "ward"})[0] == 400
    for _ in range(MAX_ENTRIES - 3):
        assert client.post("/api/entries", json={"spec": "lambert"}).status_code == 200
    code, why = post(0, {"model": "ward"})
    assert code == 400 and f"at most {MAX_ENTRIES}" in why
    # the guard: another site's simple POST, another origin, no token: refused, no fit
    hostile = [({"Content-Type": "text/plain"}, 403),
               ({"Origin": "http://evil.example.com"}, 403),
               ({"Authorization": "token wrong"}, 403)]
    for headers, status in hostile:
        r = client.post("/api/fit/0", content=b'{"model": "lambert"}',
                        headers={"Content-Type": "application/json", **headers})
        assert r.status_code == status and r.json()["error"].startswith("refused")
    r = client.post("/api/fit/0", content=b'{"model": "' + b"x" * (2 << 20) + b'"}',
                    headers={"Content-Type": "application/json"})
    assert r.status_code == 413
    plain = serve(Explorer(list(client.explorer.entries.values())[:1], "llvm_rgb"))
    r = plain.post("/api/fit/0", json={"model": "ward"})
    assert r.status_code == 400 and "automatic differentiation" in r.json()["error"]
    assert client.get("/api/state").json()["fit"] is None
