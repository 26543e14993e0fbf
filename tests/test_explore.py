"""The explorer's server: its API through Starlette's test client, and the command line's
refusals (exit status 2 before serving). The page itself: tests/test_explore_browser.py."""
import os
import json
import socket

import drjit as dr
import mitsuba as mi
import numpy as np
import pytest

pytest.importorskip("starlette")
pytest.importorskip("httpx2")
from starlette.testclient import TestClient  # noqa: E402

from mitsuba_brdfs.__main__ import main  # noqa: E402
from mitsuba_brdfs.explore import command  # noqa: E402
from mitsuba_brdfs.explore.entries import make_entries  # noqa: E402
from mitsuba_brdfs.paths import SCENES  # noqa: E402
from mitsuba_brdfs.explore.server import PALETTE, Explorer, app  # noqa: E402


class _Raising(mi.BSDF):
    """A user's plugin whose eval and sample raise."""

    def __init__(self, props):
        mi.BSDF.__init__(self, props)
        c = mi.BSDFFlags.DiffuseReflection | mi.BSDFFlags.FrontSide
        self.m_components = [c]
        self.m_flags = c

    def eval(self, ctx, si, wo, active=True):
        raise RuntimeError("my plugin is broken")

    def sample(self, ctx, si, s1, s2, active=True):
        raise RuntimeError("my plugin is broken")

    def pdf(self, ctx, si, wo, active=True):
        return mi.Float(0)

    def to_string(self):
        return "Raising[]"


@pytest.fixture
def client():
    mi.register_bsdf("explore_raising", lambda props: _Raising(props))
    found = make_entries("lambert", {}, 0, PALETTE)
    found += make_entries("ashikhmin_shirley", {"nu": "20"}, len(found), PALETTE)
    return TestClient(app(Explorer(found, "llvm_ad_rgb", ["lambert", "ashikhmin_shirley"])))


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
    # the plugin's own refusal (alpha with nu/nv set) leaves the entry as it was
    client.patch("/api/entries/1", json={"name": "nu", "value": 50})
    r = client.patch("/api/entries/1", json={"name": "alpha", "value": 0.2})
    assert r.status_code == 400 and "ashikhmin_shirley" in r.json()["error"]
    state = client.get("/api/state").json()["entries"][1]
    assert {c["name"]: c["set"] for c in state["controls"]}["alpha"] is False
    assert _plots(client)["ashikhmin_shirley"]["polar"]["value"]


def test_a_plugin_that_raises_is_said_in_its_place(client):
    added = client.post("/api/entries", json={"spec": "explore_raising"})
    assert added.status_code == 200
    ident = added.json()[0]["id"]
    plots = _plots(client)
    assert "my plugin is broken" in plots["explore_raising"]["error"]
    assert plots["lambert"]["polar"]["value"]  # the others are drawn
    r = client.get(f"/api/sphere/{ident}?pass=0")
    assert r.status_code == 400 and "broken" in r.json()["error"]
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
    moved = client.get("/api/sphere/1?pass=2&theta=60&phi=0")
    assert moved.headers["x-passes"] == "1"  # a new light starts again
    assert client.get("/api/sphere/1?pass=0&theta=500").status_code == 400


def test_check_on_demand(client):
    r = client.post("/api/check/0")
    assert r.status_code == 200
    out = r.json()
    assert out["passed"] and {c["name"] for c in out["checks"]} >= {"chi2", "furnace"}


def test_xml_spec_gives_its_values():
    found = make_entries(os.path.join(SCENES, "as_sphere.xml"), {"nu": "30"}, 0, PALETTE)
    props = found[0].props
    assert props["type"] == "ashikhmin_shirley" and props["nu"] == 30 and props["nv"] == 1000
    assert props["diffuse_reflectance"] == {"type": "rgb", "value": [0.6, 0.08, 0.05]}
    # a textured floor (a checkerboard with a transform): controls from traverse, no export
    floor = next(e for e in make_entries(os.path.join(SCENES, "fig3_polished.xml"), {}, 0,
                                         PALETTE) if e.props is None)
    ex = TestClient(app(Explorer([floor])))
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
