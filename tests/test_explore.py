"""The explorer's server: its API through Starlette's test client, and the command line's
refusals (exit status 2 before serving). The page itself: tests/test_explore_browser.py."""
import gc
import json
import os
import socket
import threading
import time

import drjit as dr
import mitsuba as mi
import numpy as np
import pytest

pytest.importorskip("starlette")
pytest.importorskip("httpx2")
from starlette.testclient import TestClient  # noqa: E402

import user_bsdf  # noqa: E402
from mitsuba_brdfs.__main__ import main  # noqa: E402
from mitsuba_brdfs.explore import command  # noqa: E402
from mitsuba_brdfs.explore.entries import make_entries  # noqa: E402
from mitsuba_brdfs.paths import SCENES  # noqa: E402
from mitsuba_brdfs.explore.server import app  # noqa: E402
from mitsuba_brdfs.explore.session import PALETTE, Explorer  # noqa: E402

TOKEN = "test-token"


def serve(explorer):
    """A test client of the page served at 127.0.0.1:8765, which sends the token as the
    page does."""
    return TestClient(app(explorer, "127.0.0.1", 8765, TOKEN), base_url="http://127.0.0.1:8765",
                      headers={"Authorization": f"token {TOKEN}"})


@pytest.fixture
def client():
    user_bsdf.register("explore_raising", flaw="raise")   # (eval and sample raise)
    found = make_entries("lambert", {}, 0, PALETTE)
    found += make_entries("ashikhmin_shirley", {"nu": "20"}, len(found), PALETTE)
    explorer = Explorer(found, "llvm_ad_rgb", ["lambert", "ashikhmin_shirley"])
    c = serve(explorer)
    c.explorer = explorer
    yield c
    # the plugins of this file (one raises) must not outlive it: a render of another test
    # traces every BSDF alive in the process
    explorer.entries.clear()
    explorer.spheres.clear()
    del c, explorer, found
    gc.collect()


def _plots(client, **body):
    r = client.post("/api/plots", json=body)
    assert r.status_code == 200, r.text
    return {e["label"]: e for e in r.json()["entries"]}


def test_page_and_plotly_are_served(client):
    page = client.get("/")
    assert page.status_code == 200 and "/static/plotly.min.js" in page.text
    assert "cdn" not in page.text.lower()
    js = client.get("/static/plotly.min.js")
    assert js.status_code == 200 and len(js.content) > 1_000_000
    assert client.get("/static/plots.js").status_code == 200


def test_controls_come_from_the_docstring(client):
    state = client.get("/api/state").json()
    assert [e["label"] for e in state["entries"]] == ["lambert", "ashikhmin_shirley"]
    assert "roughplastic" in state["plugins"] and "ward" in state["plugins"]
    ctl = {c["name"]: c for c in state["entries"][1]["controls"]}
    assert ctl["nu"]["kind"] == "float" and ctl["nu"]["range"] == "[0, 1e6]"
    assert ctl["nu"]["value"] == 20 and ctl["nu"]["set"] and ctl["nu"]["log"]
    assert ctl["nv"]["value"] == 100 and not ctl["nv"]["set"]  # the default, shown
    assert ctl["specular_reflectance"]["kind"] == "colour"
    assert ctl["sampling"]["choices"] == ["half_vector", "cosine"]


def test_plots_are_the_plugins_values(client):
    plots = _plots(client, theta_i=30, theta_h=20, theta_d=40)
    lam = plots["lambert"]
    theta = np.array(lam["polar"]["theta"])
    value = np.array(lam["polar"]["value"], float)
    # eval = rho / pi cos(theta_o) in the plane of incidence, luminance of 0.5 grey
    np.testing.assert_allclose(value, 0.5 / np.pi * np.cos(np.radians(theta)), rtol=1e-4,
                               atol=1e-6)
    np.testing.assert_allclose(lam["theta_h"]["value"], 0.5 / np.pi, rtol=1e-4)
    a = lam["albedo"]
    np.testing.assert_allclose(a["mean"], 0.5, rtol=1e-5)  # every weight is exactly 0.5
    np.testing.assert_allclose(a["quadrature"], 0.5, rtol=0.01)
    lobe = np.array(plots["ashikhmin_shirley"]["lobe"]["value"], float)
    assert lobe.shape == (19, 37) and np.isfinite(lobe).all()
    image = np.array(plots["ashikhmin_shirley"]["image"])  # f pi as 8-bit sRGB
    assert image.shape == (64, 64, 3)
    assert (image[:, 0, 0] >= image[:, 16, 0]).all() and image[0, 0, 0] > image[0, 16, 0]
    # the polar plot follows the incidence: the specular peak moves
    peak = lambda p: p["polar"]["theta"][int(np.nanargmax(  # noqa: E731
        np.array(p["polar"]["value"], float)))]
    other = _plots(client, theta_i=60)["ashikhmin_shirley"]
    assert peak(plots["ashikhmin_shirley"]) < peak(other)


def test_only_the_plots_asked_for(client):
    r = client.post("/api/plots", json={"theta_i": 10, "parts": ["polar", "lobe"]})
    assert set(r.json()["entries"][1]) == {"id", "label", "colour", "polar", "lobe"}
    r = client.post("/api/plots", json={"parts": ["polar", "sphere"]})
    assert r.status_code == 400 and "parts" in r.json()["error"]
    # the entries asked for (the page asks for the one whose parameter changed)
    r = client.post("/api/plots", json={"parts": ["polar"], "ids": [1]})
    assert [e["label"] for e in r.json()["entries"]] == ["ashikhmin_shirley"]
    r = client.post("/api/plots", json={"ids": "1"})
    assert r.status_code == 400 and "ids" in r.json()["error"]
    # a parameter sent with the request for its plots: its new state, its new plots
    before = _plots(client, ids=[1])["ashikhmin_shirley"]["polar"]["value"]
    r = client.post("/api/plots", json={"ids": [1], "set": {"id": 1, "name": "nu",
                                                            "value": 500}})
    assert r.status_code == 200 and r.json()["state"]["version"] == 1
    assert r.json()["entries"][0]["polar"]["value"] != before
    r = client.post("/api/plots", json={"set": {"id": 1, "name": "nu", "value": -3}})
    assert r.status_code == 400 and "[0, 1e6]" in r.json()["error"]
    assert client.get("/api/state").json()["entries"][1]["version"] == 1
    r = client.post("/api/plots", json={"theta_i": 95})
    assert r.status_code == 400 and "theta_i must be in [0, 89.9]" in r.json()["error"]


def test_a_change_is_drawn_and_bad_values_are_refused(client):
    before = _plots(client)["ashikhmin_shirley"]["polar"]["value"]
    r = client.patch("/api/entries/1", json={"name": "nu", "value": 500})
    assert r.status_code == 200 and r.json()["version"] == 1
    after = _plots(client)["ashikhmin_shirley"]["polar"]["value"]
    assert after != before
    # a choice loads the plugin again; a colour; back to the default
    for name, value in (("sampling", "cosine"), ("specular_reflectance", [0.9, 0.5, 0.1]),
                        ("nu", None)):
        r = client.patch("/api/entries/1", json={"name": name, "value": value})
        assert r.status_code == 200, r.text
    ctl = {c["name"]: c for c in r.json()["controls"]}
    assert not ctl["nu"]["set"] and ctl["specular_reflectance"]["value"] == [0.9, 0.5, 0.1]
    for name, value, words in (("nu", -3, ["nu", "[0, 1e6]", "-3"]),
                               ("nu", "lots", ["nu", "a number"]),
                               ("specular_reflectance", "0.5, 2, 0", ["specular_reflectance",
                                                                      "[0, 1]", "2"]),
                               ("sampling", "best", ["sampling", "half_vector"]),
                               ("shininess", 3, ["no parameter", "shininess"])):
        r = client.patch("/api/entries/1", json={"name": name, "value": value})
        assert r.status_code == 400, (name, value)
        message = r.json()["error"]
        assert all(w in message for w in words), message
    assert _plots(client)["ashikhmin_shirley"]["polar"]["value"]


def test_the_plugins_own_refusal_is_its_cause_and_changes_nothing(client):
    """A value in its control's range that the plugin refuses (oren_nayar's EON roughness
    with the qualitative form): the plugin's sentence, without Mitsuba's loader's wrapper
    ("failed to instantiate unknown plugin of type ..."), and the entry as it was."""
    added = client.post("/api/entries", json={"spec": "oren_nayar"}).json()[0]
    url = f"/api/entries/{added['id']}"
    r = client.patch(url, json={"name": "roughness", "value": 0.5})
    assert r.status_code == 400
    error = r.json()["error"]
    assert error.startswith("oren_nayar: parameter 'roughness' must be given only with "
                            "form 'energy_preserving'"), error
    assert "instantiate" not in error and "Traceback" not in error and "Error:" not in error
    state = next(e for e in client.get("/api/state").json()["entries"]
                 if e["id"] == added["id"])
    assert state["version"] == 0 and not any(c["set"] for c in state["controls"])
    # with the form that takes it, it is taken; sigma is then out of use
    assert client.patch(url, json={"name": "form", "value": "energy_preserving"}).status_code == 200
    ctl = {c["name"]: c for c in client.patch(url, json={"name": "roughness",
                                                         "value": 0.5}).json()["controls"]}
    assert ctl["roughness"]["active"] and ctl["roughness"]["value"] == 0.5
    assert not ctl["sigma"]["active"]


def _controls(r):
    assert r.status_code == 200, r.text
    return {c["name"]: c for c in r.json()["controls"]}


def test_paired_parameters_are_set_one_at_a_time(client):
    """ashikhmin_shirley's alpha_u/alpha_v come both or neither: the page sends one field at
    a time, the partner keeps its value (or takes the same one when it was not in use), the
    exponents they replace go out, and which parametrisation is in use is said."""
    url = "/api/entries/1"  # ashikhmin_shirley with nu = 20
    ctl = _controls(client.patch(url, json={"name": "nv", "value": 500}))
    assert ctl["nu"]["active"] and ctl["nv"]["active"] and not ctl["alpha_u"]["active"]
    assert ctl["alpha_u"]["partners"] == ["alpha_v"]
    assert set(ctl["alpha_u"]["alternatives"]) == {"alpha", "nu", "nv"}
    ctl = _controls(client.patch(url, json={"name": "alpha_u", "value": 0.3}))
    assert (ctl["alpha_u"]["value"], ctl["alpha_v"]["value"]) == (0.3, 0.3)
    assert ctl["alpha_u"]["active"] and ctl["alpha_v"]["active"]
    assert not ctl["nu"]["active"] and not ctl["nu"]["set"] and not ctl["nv"]["set"]
    ctl = _controls(client.patch(url, json={"name": "alpha_v", "value": 0.05}))
    assert (ctl["alpha_u"]["value"], ctl["alpha_v"]["value"]) == (0.3, 0.05)
    # the plugin really has them: its traverse, and the export
    x = client.get("/api/export/1").json()
    assert '<float name="alpha_u" value="0.3"/>' in x["xml"]
    assert '<float name="alpha_v" value="0.05"/>' in x["xml"] and "nu" not in x["xml"]
    # alpha replaces both; an exponent brings the exponents back
    ctl = _controls(client.patch(url, json={"name": "alpha", "value": 0.2}))
    assert ctl["alpha"]["active"] and not ctl["alpha_u"]["set"] and not ctl["alpha_v"]["set"]
    ctl = _controls(client.patch(url, json={"name": "nu", "value": 40}))
    assert ctl["nu"]["value"] == 40 and ctl["nv"]["value"] == 100 and ctl["nv"]["active"]
    assert not ctl["alpha"]["set"] and not ctl["alpha"]["active"]
    # back to the default: a pair goes together
    client.patch(url, json={"name": "alpha_u", "value": 0.3})
    ctl = _controls(client.patch(url, json={"name": "alpha_v", "value": None}))
    assert not ctl["alpha_u"]["set"] and not ctl["alpha_v"]["set"] and ctl["nu"]["active"]
    # and through the plots' request, as the page sends a slider's value
    r = client.post("/api/plots", json={"ids": [1], "set": {"id": 1, "name": "alpha_v",
                                                            "value": 0.1}})
    assert r.status_code == 200, r.text
    ctl = {c["name"]: c for c in r.json()["state"]["controls"]}
    assert ctl["alpha_u"]["value"] == ctl["alpha_v"]["value"] == 0.1


def test_oren_nayars_a_and_b_are_partners(client):
    added = client.post("/api/entries", json={"spec": "oren_nayar"}).json()[0]
    url = f"/api/entries/{added['id']}"
    ctl = _controls(client.patch(url, json={"name": "b", "value": 0.2}))
    assert ctl["a"]["value"] == ctl["b"]["value"] == 0.2 and not ctl["sigma"]["active"]
    ctl = _controls(client.patch(url, json={"name": "a", "value": 0.9}))
    assert (ctl["a"]["value"], ctl["b"]["value"]) == (0.9, 0.2)
    ctl = _controls(client.patch(url, json={"name": "sigma", "value": 0.4}))
    assert ctl["sigma"]["active"] and not ctl["a"]["set"] and not ctl["b"]["set"]


def test_tooltips_are_plain_text(client):
    for e in client.get("/api/state").json()["entries"]:
        for c in e["controls"]:
            assert "``" not in c["doc"] and "(Default:" not in c["doc"], c
    ctl = {c["name"]: c for c in client.get("/api/state").json()["entries"][1]["controls"]}
    assert ctl["alpha_u"]["doc"].startswith("instead of nu, nv: Beckmann roughness")


def test_a_plugin_that_raises_is_said_in_its_place(client):
    added = client.post("/api/entries", json={"spec": "explore_raising"})
    assert added.status_code == 200
    ident = added.json()[0]["id"]
    plots = _plots(client)
    assert "the user's plugin fails" in plots["explore_raising"]["error"]
    assert plots["lambert"]["polar"]["value"]  # the others are drawn
    r = client.get(f"/api/sphere/{ident}?pass=0")
    assert r.status_code == 400 and "fails" in r.json()["error"]
    # the others' spheres still render while it is there (a render calls only its BSDF)
    r = client.get("/api/sphere/0?pass=0")
    assert r.status_code == 200 and r.content[:4] == b"\x89PNG", r.text
    assert client.delete(f"/api/entries/{ident}").status_code == 200
    assert "explore_raising" not in _plots(client)
    r = client.post("/api/entries", json={"spec": "no_such_plugin"})
    assert r.status_code == 400 and "unknown plugin 'no_such_plugin'" in r.json()["error"]


def test_mitsubas_plugin_gets_controls_from_traverse(client):
    r = client.post("/api/entries", json={"spec": "roughplastic"})
    entry = r.json()[0]
    ctl = {c["name"]: c for c in entry["controls"]}
    assert ctl["alpha"]["kind"] == "float" and ctl["alpha"]["hi"] == 1
    assert ctl["distribution"]["choices"] == ["beckmann", "ggx"]
    before = _plots(client)["roughplastic"]["polar"]["value"]
    r = client.patch(f"/api/entries/{entry['id']}", json={"name": "alpha", "value": 0.3})
    assert r.status_code == 200
    assert _plots(client)["roughplastic"]["polar"]["value"] != before
    x = client.get(f"/api/export/{entry['id']}").json()
    assert '<float name="alpha" value="0.3"/>' in x["xml"]


def test_export_loads_as_the_same_bsdf(client):
    client.patch("/api/entries/1", json={"name": "specular_reflectance",
                                         "value": [0.9, 0.5, 0.1]})
    x = client.get("/api/export/1").json()
    from_xml = mi.load_string(x["xml"].replace("<bsdf ", '<bsdf version="3.0.0" ', 1))
    from_dict = eval(x["python"], {"mi": mi})
    for b in (from_xml, from_dict):
        p = mi.traverse(b)
        assert dr.allclose(p["nu.value"], 20)
        assert dr.allclose(p["specular_reflectance.value"], mi.Color3f(0.9, 0.5, 0.1))


def test_sphere_refines_in_passes(client):
    r0 = client.get("/api/sphere/1?pass=0&theta=45&phi=135")
    r1 = client.get("/api/sphere/1?pass=1&theta=45&phi=135")
    assert r0.headers["content-type"] == "image/png" and r0.content[:4] == b"\x89PNG"
    assert (r0.headers["x-passes"], r1.headers["x-passes"]) == ("1", "2")
    # on a dark grey, so that the unlit side's outline shows: the corners grey, the sphere's
    # unlit edge (lit from the upper left) darker, its lit side brighter
    import io
    from PIL import Image
    from mitsuba_brdfs.explore.sphere import BACKGROUND
    img = np.asarray(Image.open(io.BytesIO(r1.content)).convert("RGB")).astype(int)
    n = len(img)
    assert (img[[0, 0, -1, -1], [0, -1, 0, -1]] == BACKGROUND).all()
    assert img[int(0.8 * n), int(0.8 * n)].max() < BACKGROUND - 20
    assert img[int(0.35 * n), int(0.35 * n)].min() > 2 * BACKGROUND
    # the mean is kept: asked again (another exposure, another page), nothing is rendered
    again = client.get("/api/sphere/1?pass=0&theta=45&phi=135&exposure=1")
    assert again.headers["x-passes"] == "2" and again.content != r1.content
    assert client.get("/api/sphere/1?pass=9999&theta=45&phi=135").headers["x-passes"] == "3"
    moved = client.get("/api/sphere/1?pass=2&theta=60&phi=0")
    assert moved.headers["x-passes"] == "1"  # a new light starts again
    assert client.patch("/api/entries/1", json={"name": "nu", "value": 30}).status_code == 200
    changed = client.get("/api/sphere/1?pass=1&theta=60&phi=0")
    assert changed.headers["x-passes"] == "1"  # and so does a change of the BSDF
    assert client.get("/api/sphere/1?pass=0&theta=500").status_code == 400


def _without_seconds(record):
    """A BSDF's check record without the seconds (which timing changes)."""
    out = {k: v for k, v in record.items() if k != "seconds"}
    out["checks"] = [{**c, "numbers": {k: v for k, v in c["numbers"].items() if k != "seconds"}}
                     for c in record["checks"]]
    return out


def _check_both_ways(client, capsys, status):
    """(the page's check of entry 0, ``check lambert --quick --json``'s record of it)."""
    out = client.post("/api/check/0", json={}).json()
    assert main(["check", "lambert", "--quick", "--json"]) == status
    (expected,) = json.loads(capsys.readouterr().out)["bsdfs"]
    assert {k: out.pop(k) for k in ("id", "label", "cancelled")} == {
        "id": 0, "label": "lambert", "cancelled": False}
    return out, expected


def test_the_check_is_what_check_json_says(client, capsys):
    """The page's check of an entry (on demand; none running after it) is check --json's
    record of the same BSDF, number for number (quick settings, the same samples)."""
    out, expected = _check_both_ways(client, capsys, 0)
    assert out["name"] == "lambert" and out["verdict"].startswith("PASS")
    assert out["passed"] and {c["name"] for c in out["checks"]} >= {"chi2", "furnace"}
    assert client.get("/api/state").json()["check"] is None
    assert _without_seconds(out) == _without_seconds(expected)


def test_numbers_json_lacks_are_written_as_check_json_writes_them(client, capsys,
                                                                  monkeypatch):
    from mitsuba_brdfs.validate import suite
    numbers = {"albedo": [float("inf"), np.float32("nan")], "worst": np.float64("-inf"),
               "theta": np.array([0.0, 45.0]), "count": np.int64(3)}
    monkeypatch.setattr(suite, "run", lambda *args, **kwargs: [
        suite.Result("furnace", "FAIL", numbers, "the albedo is infinite")])
    out, expected = _check_both_ways(client, capsys, 1)
    assert out["checks"][0]["numbers"] == {"albedo": ["inf", "nan"], "worst": "-inf",
                                           "theta": [0.0, 45.0], "count": 3}
    assert _without_seconds(out) == _without_seconds(expected)
    # a control's open range is no number: its ends are null, which the page reads so
    ctl = {c["name"]: c for c in client.get("/api/state").json()["entries"][1]["controls"]}
    assert (ctl["nu"]["lo"], ctl["nu"]["hi"]) == (0, 1e6)
    assert (ctl["sampling"]["lo"], ctl["sampling"]["hi"]) == (None, None)


def test_check_runs_one_at_a_time_and_is_cancelled(client):
    """While a check runs, another is refused (409, nothing started) and the page's other
    requests are answered; DELETE /api/check stops it after the check under way."""
    # the user's plugin, whose methods wait for the gate: the check runs until it opens
    gate = threading.Event()
    user_bsdf.register("explore_gated")
    user_bsdf.set_hook(gate.wait)
    ident = client.post("/api/entries", json={"spec": "explore_gated"}).json()[0]["id"]
    result = {}
    worker = threading.Thread(target=lambda: result.update(client.explorer.check(ident)))
    worker.start()
    try:
        for _ in range(6000):  # until the check has started (it then waits at the gate)
            running = client.get("/api/state").json()["check"]
            if running:
                break
            time.sleep(0.005)
        assert running == {"id": ident, "label": "explore_gated"}
        r = client.post("/api/check/0", json={})
        assert r.status_code == 409 and "explore_gated's is running" in r.json()["error"]
        assert _plots(client, ids=[0])["lambert"]["polar"]["value"]  # the page goes on
        r = client.delete("/api/check")
        assert r.status_code == 200 and r.json() == {"cancelled": "explore_gated"}
    finally:
        gate.set()
        worker.join(timeout=300)
        user_bsdf.set_hook(None)
    assert result == {"id": ident, "label": "explore_gated", "cancelled": True}
    assert client.get("/api/state").json()["check"] is None
    assert client.delete("/api/check").json() == {"cancelled": None}


class _Tutorial(mi.BSDF):
    """A user's diffuse plugin written as Mitsuba's own plugins are: every method takes the
    ``active`` mask, without a default."""

    def __init__(self, props):
        mi.BSDF.__init__(self, props)
        self.reflectance = mi.Float(props.get("reflectance", 0.6))
        c = mi.BSDFFlags.DiffuseReflection | mi.BSDFFlags.FrontSide
        self.m_components = [c]
        self.m_flags = c

    def sample(self, ctx, si, sample1, sample2, active):
        bs = dr.zeros(mi.BSDFSample3f)
        bs.wo = mi.warp.square_to_cosine_hemisphere(sample2)
        bs.pdf = mi.warp.square_to_cosine_hemisphere_pdf(bs.wo)
        bs.eta = 1.0
        bs.sampled_type = mi.UInt32(+mi.BSDFFlags.DiffuseReflection)
        ok = active & (si.wi.z > 0) & (bs.pdf > 0)
        return bs, mi.Color3f(dr.select(ok, self.reflectance, 0.0))

    def eval(self, ctx, si, wo, active):
        ok = active & (si.wi.z > 0) & (wo.z > 0)
        return mi.Color3f(dr.select(ok, self.reflectance * wo.z / dr.pi, 0.0))

    def pdf(self, ctx, si, wo, active):
        ok = active & (si.wi.z > 0) & (wo.z > 0)
        return dr.select(ok, mi.warp.square_to_cosine_hemisphere_pdf(wo), 0.0)

    def eval_pdf(self, ctx, si, wo, active):
        return self.eval(ctx, si, wo, active), self.pdf(ctx, si, wo, active)

    def traverse(self, callback):
        callback.put("reflectance", self.reflectance, mi.ParamFlags.Differentiable)

    def to_string(self):
        return "Tutorial[]"


def test_a_plugin_that_takes_active_without_a_default_is_drawn(client):
    """The plots call a plugin as Mitsuba's integrators do (with ``active``): a plugin
    written as Mitsuba's are is drawn with its values, rendered and checked."""
    mi.register_bsdf("explore_tutorial", lambda props: _Tutorial(props))
    added = client.post("/api/entries", json={"spec": "explore_tutorial"})
    assert added.status_code == 200, added.text
    ident = added.json()[0]["id"]
    r = client.patch(f"/api/entries/{ident}", json={"name": "reflectance", "value": 0.5})
    assert r.status_code == 200, r.text
    plot = _plots(client, theta_i=30, ids=[ident])["explore_tutorial"]
    assert "error" not in plot, plot["error"]
    theta = np.radians(plot["polar"]["theta"])
    np.testing.assert_allclose(plot["polar"]["value"], 0.5 / np.pi * np.cos(theta), atol=2e-6)
    albedo = plot["albedo"]
    np.testing.assert_allclose(albedo["mean"], 0.5, rtol=1e-6)
    np.testing.assert_allclose(albedo["quadrature"], 0.5, rtol=0.02)
    sphere = client.get(f"/api/sphere/{ident}?pass=0")
    assert sphere.status_code == 200 and sphere.content[:4] == b"\x89PNG", sphere.text
    check = client.post(f"/api/check/{ident}", json={})
    assert check.status_code == 200 and check.json()["passed"], check.json()["verdict"]
    assert client.delete(f"/api/entries/{ident}").status_code == 200


def test_a_scene_named_as_the_readme_names_it_is_found_from_any_folder(tmp_path, monkeypatch,
                                                                          capsys):
    """``explore scenes/as_sphere.xml`` away from a checkout: the installed copy, with the
    controls and the export its XML gives (as check and render find it)."""
    monkeypatch.chdir(tmp_path)
    (entry,) = make_entries("scenes/as_sphere.xml", {"nu": "30"}, 0, PALETTE)
    assert entry.source == os.path.join(SCENES, "as_sphere.xml")
    assert entry.label == "ashikhmin_shirley (shape 0) (as_sphere.xml)"
    assert entry.props["type"] == "ashikhmin_shirley" and entry.props["nu"] == 30
    assert {c["name"] for c in entry.controls} >= {"nu", "nv", "specular_reflectance"}
    ex = serve(Explorer([entry]))
    x = ex.get(f"/api/export/{entry.id}")
    assert x.status_code == 200 and '<float name="nu" value="30"/>' in x.json()["xml"]
    assert "using the one that comes with mitsuba_brdfs" in capsys.readouterr().err
    assert os.listdir(tmp_path) == []


def test_xml_spec_gives_its_values():
    found = make_entries(os.path.join(SCENES, "as_sphere.xml"), {"nu": "30"}, 0, PALETTE)
    props = found[0].props
    assert props["type"] == "ashikhmin_shirley" and props["nu"] == 30 and props["nv"] == 1000
    assert props["diffuse_reflectance"] == {"type": "rgb", "value": [0.6, 0.08, 0.05]}
    # a textured floor (a checkerboard with a transform): controls from traverse, no export
    floor = next(e for e in make_entries(os.path.join(SCENES, "fig3_polished.xml"), {}, 0,
                                         PALETTE) if e.props is None)
    ex = serve(Explorer([floor]))
    assert ex.get(f"/api/export/{floor.id}").status_code == 400
    r = ex.patch(f"/api/entries/{floor.id}", json={"name": "nu", "value": 50})
    assert r.status_code == 200 and mi.traverse(floor.bsdf)["nu.value"] == 50


def test_command_line_refuses_before_serving(capsys, monkeypatch):
    assert main(["explore", "no_such_plugin", "--port", "0", "--no-browser"]) == 2
    assert "unknown plugin 'no_such_plugin'" in capsys.readouterr().err
    assert main(["explore", "lambert", "-p", "reflectance", "--port", "0"]) == 2
    assert "bad -p 'reflectance'" in capsys.readouterr().err
    assert main(["explore", "lambert", "-p", "ward:alpha_u=0.1", "--port", "0"]) == 2
    assert "'ward' is not one of the SPECs" in capsys.readouterr().err
    assert main(["explore", "lambert", "-p", "reflectance=2", "--port", "0"]) == 2
    assert "reflectance" in capsys.readouterr().err
    # the plugin's own sentence, not Mitsuba's loader's wrapper around it
    assert main(["explore", "ashikhmin_shirley", "-p", "alpha_u=0.2", "--port", "0"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: ashikhmin_shirley: parameter 'alpha_v' must be given with "
                          "'alpha_u'") and "instantiate" not in err and "Error:" not in err
    assert main(["explore", "roughplastic", "-p", "alpha=x", "--port", "0"]) == 2
    err = capsys.readouterr().err
    assert err.startswith('error: roughplastic: The property "alpha" has the wrong type') and \
        "instantiate" not in err
    # a plugin of Mitsuba's would load it: refused with the range its control has
    assert main(["explore", "roughplastic", "-p", "alpha=-3", "--port", "0"]) == 2
    assert "roughplastic: parameter 'alpha' must be in [0, 1] (got -3)" in capsys.readouterr().err
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen(1)
        port = taken.getsockname()[1]
        assert main(["explore", "lambert", "--port", str(port), "--no-browser"]) == 2
        assert f"port {port}" in capsys.readouterr().err
    monkeypatch.setattr(command.importlib.util, "find_spec",
                        lambda m: None if m == "uvicorn" else object())
    assert main(["explore", "lambert", "--port", "0"]) == 2
    err = capsys.readouterr().err
    assert "pip install 'mitsuba_brdfs[explore]'" in err and "uvicorn" in err


def test_params_split_by_spec():
    got = command.split_params(["alpha=0.2", "ward:form=duer"], ["ward", "roughplastic"])
    assert got == {"ward": {"alpha": "0.2", "form": "duer"}, "roughplastic": {"alpha": "0.2"}}
    assert json.dumps(got)
