"""fit-measured's image judge (``measured.judge``: the fit and the measurement rendered on
one sphere, Delta E ITP), ``--rank-by``, ``--select image``, the three losses and
isotropic fits of isotropic data. Small files, tiny renders (24 x 24 pixels, 16 spp) and
short fits: what is checked is what the command does with the judge, not how good the
fits are."""
import json
import math
import os

import mitsuba as mi
import numpy as np

from checks import merl_file
from cmdline import run_many
from mitsuba_brdfs import presets
from mitsuba_brdfs.measured import judge as J, losses, select

SHORT = ["--samples", "2000", "--evaluations", "40", "--image-res", "24", "--image-spp", "16"]


def test_judge_ranks_selects_and_ties(tmp_path):
    """A MERL file (rendered through its RGL conversion) and ``--target`` BSDFs (rendered
    as themselves): every fit carries its image error, the table shows it beside the
    held-out loss, the fits are ranked by it (or by held-out loss), the renders are
    written; ``--select image`` keeps the candidate (3 losses x 4 starts) that looks
    closest; an isotropic file gives Ward's widths as one, ``--anisotropic`` or an
    anisotropic target two; the judge's options are refused where it is off."""
    src = tmp_path / "ct.binary"
    merl_file(src, presets.ngan2005("cook_torrance", "gold-paint"), (16, 16, 32))
    aniso = ["--target", "ward", "-p", "alpha_u=0.05", "-p", "alpha_v=0.3"]
    iso = ["--target", "ward", "-p", "alpha_u=0.1", "-p", "alpha_v=0.1"]
    cases = [["fit-measured", src, "--model", "lambert,cook_torrance", "--out",
              tmp_path / "a", *SHORT],
             ["fit-measured", *iso, "--model", "lambert,ward", "--out", tmp_path / "b",
              "--json", "--rank-by", "holdout", "--loss", "cbrt", *SHORT],
             ["fit-measured", *iso, "--model", "ward", "--select", "image", "--json",
              "--out", tmp_path / "c", *SHORT],
             ["fit-measured", *aniso, "--model", "ward", "--json", "--out", tmp_path / "d",
              *SHORT],
             ["fit-measured", src, "--model", "ward", "--anisotropic", "--json", "--out",
              tmp_path / "e", *SHORT[:4], "--image-spp", "0"],
             ["fit-measured", src, "--model", "ward", "--select", "image", "--image-spp", "0",
              "--out", tmp_path / "x"],
             ["fit-measured", src, "--model", "ward", "--rank-by", "image", "--image-spp",
              "0", "--out", tmp_path / "x"]]
    (ca, table, ea), (cb, jb, eb), (cc, jc, ec), (cd, jd, ed), (ce, je, ee), (cx, _, ex), \
        (cy, _, ey) = run_many([list(map(str, c)) for c in cases])
    assert ca == cb == cc == cd == ce == 0, (ea[-2000:], eb[-2000:], ec[-2000:], ed[-2000:],
                                             ee[-2000:])
    # the table: the image error beside the held-out loss, ranked by it
    lines = table.splitlines()
    assert lines[0].startswith("| model | loss (shape + energy) | held-out loss | image "
                               "error (Delta E ITP mean / p95) |"), lines[0]
    rows = [[c.strip() for c in line.strip("|").split("|")] for line in lines[2:4]]
    means = [float(r[3].split(" / ")[0]) for r in rows]
    assert {r[0] for r in rows} == {"cook_torrance", "lambert"} and means == sorted(means)
    assert "its RGL file (to-rgl) through Mitsuba's measured" in table
    assert os.path.getsize(tmp_path / "a" / "ct.binary_images.png") > 5000
    fits = json.load(open(tmp_path / "a" / "ct.binary_fits.json"))["fits"]
    assert [f["model"] for f in fits] == [r[0] for r in rows]
    for f in fits:
        e = f["image_error"]
        assert e["metric"] == "delta_e_itp" and 0 < e["mean"] <= e["p95"], e
        assert set(f["holdout_losses"]) == {"l2cos", "log", "cbrt"}
        assert f["holdout_loss"] == f["holdout_losses"]["l2cos"] and f["rank_by"] == "image"
        assert 0 < f["seconds_image"] < f["seconds_total"]
    # by held-out loss, with the cube-root loss
    b = json.loads(jb)["fits"]
    held = [f["holdout_loss"] for f in b]
    assert held == sorted(held) and all(f["loss_kind"] == "cbrt" for f in b)
    assert [f["model"] for f in b] == ["ward", "lambert"]          # the target's model
    assert b[0]["holdout_loss"] == b[0]["holdout_losses"]["cbrt"]
    # --select image: the candidate that looks closest, each of them listed
    c = json.loads(jc)
    assert c["selected_by"] == "image" and len(c["candidates"]) == 12
    assert {(x["loss"], x["start"]) for x in c["candidates"]} == {
        (k, s) for k in losses.LOSSES for s in range(4)}
    assert c["image_error"]["mean"] == min(x["image_error"]["mean"] for x in c["candidates"])
    # isotropic data: one width; an anisotropic target, or --anisotropic: two
    assert c["isotropy"] == {"data": "isotropic", "fit": "isotropic",
                             "tied": ["alpha_u=alpha_v"]}
    assert "the target BSDF itself" in " ".join(c["notes"])
    assert c["params"]["alpha_u.value"] == c["params"]["alpha_v.value"]
    d = json.loads(jd)
    assert d["isotropy"] == {"data": "anisotropic", "fit": "anisotropic", "tied": []}
    assert d["params"]["alpha_u.value"][0] < 0.5 * d["params"]["alpha_v.value"][0]
    e = json.loads(je)
    assert e["isotropy"]["fit"] == "anisotropic" and e["image_error"] is None
    for code, err, what in ((cx, ex, "--select image"), (cy, ey, "--rank-by image")):
        assert code == 2 and what in err and err.count("\n") == 1, err


def test_the_judge_sees_colour_not_noise():
    """The same BSDF and seed: Delta E 0; a second seed (Monte Carlo noise alone) reads
    far less than a reflectance 20 % brighter; the views keep the sphere's pixels away
    from its edge."""
    white = {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.5, 0.3, 0.2]}}
    judge = J.Judge(mi.load_dict(white), res=24, spp=16)
    assert judge.mask.shape == (3, 24, 24) and 0.2 < judge.mask.mean() < 0.6
    same, _ = judge.error(mi.load_dict(white))
    assert same["mean"] == 0 and same["metric"] == "delta_e_itp"
    noise = J.Judge(mi.load_dict(white), res=24, spp=16, seed=5)
    floor = J.delta_e_itp(noise._reference[judge.mask], judge._reference[judge.mask])
    brighter, views = judge.error(mi.load_dict(
        {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.6, 0.36, 0.24]}}))
    assert views.shape == (3, 24, 24, 3) and 2 * floor.mean() < brighter["mean"]
    assert brighter["p95"] >= brighter["mean"] > 1


def test_losses_and_ranking():
    """The cube root keeps a negative measured value's sign and stays finite at 0; ranking
    by image puts fits without an image error last, by held-out loss NaN last."""
    np.testing.assert_allclose(losses.mapped_np([-8.0, 8.0], "cbrt"), [-2.0, 2.0], rtol=1e-6)
    assert losses.mapped_np([-1.0], "cbrt", model=True)[0] == np.cbrt(losses.EPSILON)
    assert losses.mapped_np([math.e - 1], "log")[0] == 1.0
    fits = {"a": {"holdout_loss": 0.1, "loss": 1, "image_error": {"mean": 3.0}},
            "b": {"holdout_loss": 0.2, "loss": 1, "image_error": {"mean": 2.0}},
            "c": {"holdout_loss": math.nan, "loss": 1, "image_error": None},
            "d": {"holdout_loss": 0.05, "loss": 1, "image_error": None}}
    assert select.ranked(fits, "image") == ["b", "a", "d", "c"]
    assert select.ranked(fits, "holdout") == ["d", "a", "b", "c"]
