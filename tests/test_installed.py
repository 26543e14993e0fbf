"""Installed use, as a user does it: ``pip install`` of the wheel into a fresh virtual
environment, then every command from an empty folder outside the checkout.

The wheel is built from a copy of the sources (the checkout stays clean) and installed with
its dependencies as pip resolves them from ``pyproject.toml``: nothing of this environment
is visible there, so a dependency that a command needs and the package does not declare
fails here (as Pillow and matplotlib once did after ``figures`` had rendered). Downloaded
wheels are kept in a folder outside the checkout (``MITSUBA_BRDFS_WHEELHOUSE``, default
``~/.cache/mitsuba_brdfs/wheels``) and pip's own cache is used, so only the first run
downloads. Each command's ``--help`` runs, and a cheap real run of each: the commands that
write use their default output folders, those ``mitsuba_brdfs-out/<command>`` of the
current folder, and nothing is written beside the installed package; ``presets`` lists and
shows; ``fit-measured`` fits a small MERL file made here from known Ward parameters,
``to-rgl`` writes it as an RGL file (to ``mitsuba_brdfs-out/to-rgl/``); ``explore``,
whose extra is not installed, is refused with the pip command that installs it.

Then the README's own commands, as a user types them in that empty folder: ``render
scenes/as_sphere.xml -D res=128`` and ``check mydiffuse --load mydiffuse.py`` (the scene
and the plugin file are the copies installed with the package, said on stderr; the checks
with ``--quick``, to keep the test short), and its testing example: ``examples`` copies
``examples/mydiffuse`` here, and with pytest installed ``pytest examples/mydiffuse`` passes.
"""
import json
import os
import shutil
import subprocess
import sys

import pytest

from checks import merl_file
from cmdline import _DRIVER

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
WHEELHOUSE = os.environ.get("MITSUBA_BRDFS_WHEELHOUSE",
                            os.path.join(os.path.expanduser("~"), ".cache", "mitsuba_brdfs", "wheels"))
COMMANDS = ("render", "figures", "properties", "fit", "bench", "manual", "check", "presets",
            "fit-measured", "to-rgl", "to-merl", "examples", "explore")
#: the measured file of fit-measured: a Ward BRDF of known parameters on a small MERL grid
WARD = {"type": "ward", "specular_reflectance": {"type": "rgb", "value": [0.12, 0.1, 0.08]},
        "diffuse_reflectance": {"type": "rgb", "value": [0.3, 0.2, 0.1]},
        "alpha_u": 0.2, "alpha_v": 0.2}


def _run(cmd, ok=True, **kw):
    r = subprocess.run([str(c) for c in cmd], capture_output=True, text=True, timeout=900, **kw)
    if ok:
        assert r.returncode == 0, (cmd, r.stdout[-2000:], r.stderr[-3000:])
    return r


def _wheel(tmp_path):
    src = tmp_path / "src"
    for folder in ("mitsuba_brdfs", "scenes"):
        shutil.copytree(os.path.join(ROOT, folder), src / folder,
                        ignore=shutil.ignore_patterns("__pycache__"))
    shutil.copytree(os.path.join(ROOT, "examples"), src / "examples",
                    ignore=shutil.ignore_patterns("__pycache__", ".pytest_cache"))
    for f in ("pyproject.toml", "README.md", "LICENSE"):
        shutil.copy(os.path.join(ROOT, f), src)
    _run([sys.executable, "-m", "pip", "wheel", "--no-deps", "--no-build-isolation", "-q",
          "-w", tmp_path / "dist", src])
    (wheel,) = (tmp_path / "dist").glob("mitsuba_brdfs-*.whl")
    return wheel




def _install(python, wheel):
    """pip install of the wheel (or of a package by name) and its dependencies: from the
    wheelhouse alone when it holds them all, else after downloading what it lacks into it."""
    os.makedirs(WHEELHOUSE, exist_ok=True)
    # this environment's pip, run for that environment's Python (``--python``): the new
    # environment needs no pip of its own
    pip = [sys.executable, "-m", "pip", "--python", python, "--disable-pip-version-check"]
    # --no-compile: the environment's processes compile what they import, once (``user_env``
    # lets them write it), instead of pip compiling every module of every dependency
    offline = pip + ["install", "-q", "--no-compile", "--no-index", "--find-links", WHEELHOUSE,
                     wheel]
    if _run(offline, ok=False).returncode != 0:
        _run(pip + ["download", "-q", "--dest", WHEELHOUSE, wheel])
        if os.path.isfile(wheel):  # ours: built each time
            os.remove(os.path.join(WHEELHOUSE, os.path.basename(wheel)))
        _run(offline)


def user_env():
    """A user's environment: nothing of this one on the path, and Python writing the
    bytecode of what it imports (as it does unless told not to)."""
    return {k: v for k, v in os.environ.items()
            if k not in ("PYTHONPATH", "VIRTUAL_ENV", "PYTHONDONTWRITEBYTECODE")}


@pytest.mark.slow
def test_wheel_installed_with_pip_runs_every_command(tmp_path):
    wheel = _wheel(tmp_path)
    env_dir = tmp_path / "env"
    _run([sys.executable, "-m", "venv", "--without-pip", env_dir])
    python = env_dir / "bin" / "python"
    _install(python, wheel)

    # an empty folder outside the checkout, nothing of this environment on the path
    work = tmp_path / "work"
    work.mkdir()
    env = user_env()
    site = _run([python, "-c", "import sysconfig; print(sysconfig.get_path('purelib'))"],
                cwd=work, env=env).stdout.strip()
    where = _run([python, "-c", "import mitsuba_brdfs, mitsuba, matplotlib, PIL; "
                  "print(mitsuba_brdfs.__file__, mitsuba.__file__, matplotlib.__file__, PIL.__file__)"],
                 cwd=work, env=env).stdout.split()
    assert all(w.startswith(site) for w in where), (site, where)

    # the console script, and (below, with the runs) each command's --help
    assert "commands" in _run([env_dir / "bin" / "mitsuba-brdfs", "--help"], cwd=work, env=env).stdout

    # explore's extra is not installed here (a plain pip install of the wheel)
    missing = _run([python, "-c", "import importlib.util as u; print(all(u.find_spec(m) is None "
                    "for m in ('starlette', 'uvicorn', 'plotly')))"], cwd=work, env=env)
    assert missing.stdout.strip() == "True", missing.stdout

    # a cheap real run of each command, in one process (as tests/cmdline.run_many does)
    scene = os.path.join(site, "mitsuba_brdfs", "scenes", "as_sphere.xml")
    measured = tmp_path / "gp.binary"  # outside the working folder
    merl_file(measured, WARD, (16, 16, 32))
    cases = [["render", scene, "-D", "res=16", "-D", "spp=4", "-o", "sphere"],
             ["figures", "--only", "as_sphere"],
             ["properties", "--only", "lambert", "--samples", "4096"],
             ["fit", "--iterations", "2", "--spp", "1", "--res", "16"],
             ["bench", "--quick", "--sections", "memory"],
             ["manual", "--text-only", "--only", "lambert"],
             ["check", "lambert", "--quick"],
             ["presets", "list"],
             ["presets", "show", "gold-paint", "--model", "ward"],
             ["fit-measured", str(measured), "--model", "ward", "--iterations", "30",
              "--samples", "2000", "--json"],
             ["to-rgl", str(measured), "-o", "mitsuba_brdfs-out/to-rgl/gp.bsdf", "--grid", "16",
              "--theta-i", "8", "--vndf", "32", "--ndf", "32"],
             # the README's quick start and testing example, as written (checks: --quick)
             ["render", "scenes/as_sphere.xml", "-D", "res=128"],
             ["check", "mydiffuse", "--load", "mydiffuse.py", "--quick"],
             ["examples"],
             ["explore"]]
    helps = [[command, "--help"] for command in COMMANDS]
    r = _run([python, "-c", _DRIVER], cwd=work, env=env, input=json.dumps(helps + cases))
    results = json.loads(r.stdout.split("@@@")[-1])
    assert len(results) == len(helps) + len(cases)
    for (command, _), (code, out, err) in zip(helps, results):
        assert code == 0 and "--debug" in out, (command, out[-500:], err[-500:])
    results = results[len(helps):]
    for argv, (code, out, err) in zip(cases[:-1], results):
        assert code == 0, (argv, out[-1500:], err[-3000:])
    presets_list, presets_show, fitted, _, quick, mine, copied, explore = results[-8:]
    assert "note: scene scenes/as_sphere.xml is not in this folder; using the one that comes " \
           "with mitsuba_brdfs" in quick[2] and "wrote as_sphere.exr and as_sphere.png" in quick[1]
    assert "note: --load mydiffuse.py is not in this folder" in mine[2]
    assert "mydiffuse: PASS" in mine[1]
    assert "copied examples/mydiffuse/mydiffuse.py" in copied[1]
    assert "86 materials" in presets_list[1] and "\ngold-paint\n" in presets_list[1]
    assert json.loads(presets_show[1])["type"] == "ward"
    summary = json.loads(fitted[1])
    assert summary["model"] == "ward" and summary["loss"] < summary["start_loss"]
    code, out, err = explore
    assert code == 2 and out == "", (code, out, err)
    assert err.startswith("error: explore needs ") and "pip install 'mitsuba_brdfs[explore]'" in err, err

    out = work / "mitsuba_brdfs-out"
    expected = {"figures": ["as_sphere.png", "timings.json"],
                "properties": ["properties.md", "albedo.png"],
                "fit": ["loss.png", "before_target_after.png"],
                "bench": ["performance.md", os.path.join("perf", "results.json")],
                "manual": ["lambert.md", "README.md"],
                "fit-measured": ["gp.binary_ward.xml", "gp.binary_ward.png", "gp.binary_ward.json"],
                "to-rgl": ["gp.bsdf"]}
    for command, files in expected.items():
        for f in files:
            assert (out / command / f).is_file(), (command, f, sorted(os.listdir(out / command)))
    assert sorted(os.listdir(work)) == ["as_sphere.exr", "as_sphere.png", "examples",
                                        "mitsuba_brdfs-out", "sphere.exr", "sphere.png"]
    # the testing example, with pytest installed as the README says
    _install(python, "pytest")
    tested = _run([python, "-m", "pytest", "examples/mydiffuse", "-q", "-p", "no:cacheprovider"],
                  cwd=work, env=env)
    assert "3 passed" in tested.stdout, tested.stdout
    # every scene shipped, nothing written beside the installed package
    def shipped(folder):
        return sorted(f for f in os.listdir(folder) if f.endswith((".xml", ".png")))
    installed = os.path.join(site, "mitsuba_brdfs", "scenes")
    assert shipped(installed) == shipped(os.path.join(ROOT, "scenes")) and len(shipped(installed)) >= 7
    # the licence with the third-party notice of the presets' data, in the wheel
    (licence,) = [os.path.join(d, "LICENSE") for d in
                  (os.path.join(site, e, "licenses") for e in os.listdir(site)
                   if e.startswith("mitsuba_brdfs-") and e.endswith(".dist-info"))]
    text = open(licence).read()
    assert text.startswith("BSD 3-Clause License") and "Pieter Peers" in text
    examples = os.path.join(site, "mitsuba_brdfs", "examples", "mydiffuse")
    assert sorted(f for f in os.listdir(examples) if f.endswith(".py")) == \
        ["mydiffuse.py", "test_mydiffuse.py"]
    for out in ("renders", "docs", "mitsuba_brdfs-out"):
        assert not os.path.exists(os.path.join(site, out))
        assert not os.path.exists(os.path.join(site, "mitsuba_brdfs", out))
