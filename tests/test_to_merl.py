"""The ``to-merl`` command (``measured.to_merl``): any BSDF, RGL or MERL file as a MERL file,
a measured file to start from. Small grids, one process for every command line."""
import json
import os

import mitsuba as mi
import numpy as np

from cmdline import run_many
from mitsuba_brdfs.measured import merl

DIMS = (16, 16, 32)
WARD = {"type": "ward", "alpha_u": 0.15, "alpha_v": 0.15,
        "specular_reflectance": {"type": "rgb", "value": [0.3, 0.2, 0.1]},
        "diffuse_reflectance": {"type": "rgb", "value": [0.1, 0.3, 0.5]}}


def test_to_merl_writes_the_sources_brdf_at_merls_bins(tmp_path):
    """A plugin's file holds its BRDF at the bins' centres (as ``merl.from_bsdf``), the
    bins below the horizon unmeasured; a MERL file gives itself back; an RGL file (to-rgl's
    of the same plugin, through Mitsuba's measured) comes close; an anisotropic source says it is written at phi_h = 0;
    a file that is neither, a bad --dims and a missing source are refused in one line."""
    ward = tmp_path / "ward.binary"
    (tmp_path / "junk.binary").write_bytes(b"\0" * 100)
    dims = ",".join(map(str, DIMS))
    cases = [["to-merl", "ward", "-p", "alpha_u=0.15", "-p", "alpha_v=0.15", "-p",
              "specular_reflectance=0.3,0.2,0.1", "-p", "diffuse_reflectance=0.1,0.3,0.5",
              "-o", ward, "--dims", dims],
             ["to-merl", ward, "-o", tmp_path / "again.binary", "--dims", dims, "--json"],
             ["to-rgl", "ward", "-p", "alpha_u=0.15", "-p", "alpha_v=0.15", "-p",
              "specular_reflectance=0.3,0.2,0.1", "-p", "diffuse_reflectance=0.1,0.3,0.5",
              "-o", tmp_path / "ward.bsdf", "--no-compare"],
             ["to-merl", tmp_path / "ward.bsdf", "-o", tmp_path / "rgl.binary", "--dims", dims],
             ["to-merl", "ward", "-p", "alpha_u=0.05", "-p", "alpha_v=0.3", "-o",
              tmp_path / "aniso.binary", "--dims", dims],
             ["to-merl", tmp_path / "junk.binary", "-o", tmp_path / "x.binary"],
             ["to-merl", "ward", "-o", tmp_path / "x.binary", "--dims", "16,16"],
             ["to-merl", "nothere.bsdf", "-o", tmp_path / "x.binary"]]
    results = run_many([[str(a) for a in c] for c in cases])
    for case, (code, out, err) in zip(cases[:5], results):
        assert code == 0, (case, out[-1000:], err[-1500:])
    made, again, _, from_rgl, aniso = results[:5]
    assert made[1].startswith(f"{ward}: ward alpha_u=0.15") and "16 x 16 x 32 bins" in made[1]

    # the plugin's BRDF at the bins' centres, unmeasured (NaN) below the horizon
    dims, f = merl.read(ward)
    expect = merl.from_bsdf(mi.load_dict(WARD), DIMS)
    assert dims == DIMS and np.array_equal(np.isnan(f), np.isnan(expect))
    ok = ~np.isnan(expect)
    np.testing.assert_allclose(f[ok], expect[ok], rtol=1e-5, atol=1e-7)
    assert np.isnan(f).any(axis=1).sum() == json.loads(again[1])["unmeasured"]

    # a MERL file gives itself back; the plugin's RGL file (to-rgl's) comes close
    summary = json.loads(again[1])
    assert summary["kind"] == "merl" and summary["dims"] == list(DIMS)
    _, f2 = merl.read(tmp_path / "again.binary")
    np.testing.assert_allclose(f2[ok], f[ok], rtol=1e-6)
    _, f3 = merl.read(tmp_path / "rgl.binary")
    lum = lambda x: x @ [0.2126, 0.7152, 0.0722]
    bright = ok.all(axis=1) & (lum(np.nan_to_num(f)) > 0.1 * np.nanmax(lum(f)))
    rel = np.abs(lum(f3[bright]) / lum(f[bright]) - 1)
    assert np.median(rel) < 0.05, np.median(rel)  # 0.022: the RGL file's interpolation

    assert "note: anisotropic: a MERL file is isotropic" in aniso[1]
    for (code, out, err), words in zip(results[5:], [
            "junk.binary: not a MERL BRDF", "--dims: expected three integers",
            "nothere.bsdf: no such file"]):
        assert code == 2 and words in err and len(err.strip().splitlines()) == 1, err
    assert not os.path.exists(tmp_path / "x.binary")
