"""Installed use: the package built as a wheel and installed into a fresh virtual
environment renders a figure from its own scenes into the current directory."""
import importlib.util
import os
import shutil
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
#: the installed dependencies the new environment reuses (nothing is downloaded)
DEPENDENCIES = ("mitsuba", "drjit", "numpy", "OpenEXR", "tqdm", "PIL")


def _run(cmd, **kw):
    r = subprocess.run(cmd, capture_output=True, text=True, timeout=600, **kw)
    assert r.returncode == 0, (cmd, r.stdout[-2000:], r.stderr[-3000:])
    return r.stdout


def _folder_of(module):
    """The folder (site-packages) from which ``module`` is imported."""
    spec = importlib.util.find_spec(module)
    where = spec.submodule_search_locations[0] if spec.submodule_search_locations else spec.origin
    return os.path.dirname(where)


def test_wheel_renders_a_figure_into_the_current_directory(tmp_path):
    # the wheel, built from a copy of the sources (the checkout stays clean)
    src = tmp_path / "src"
    for folder in ("mitsuba_brdfs", "scenes"):
        shutil.copytree(os.path.join(ROOT, folder), src / folder,
                        ignore=shutil.ignore_patterns("__pycache__"))
    for f in ("pyproject.toml", "README.md"):
        shutil.copy(os.path.join(ROOT, f), src)
    pip = [sys.executable, "-m", "pip", "--disable-pip-version-check"]
    _run(pip + ["wheel", "--no-deps", "--no-build-isolation", "--no-index", "-q",
                "-w", str(tmp_path / "dist"), str(src)])
    (wheel,) = (tmp_path / "dist").glob("mitsuba_brdfs-*.whl")

    # a fresh environment that sees the installed dependencies, and the wheel installed in it
    env_dir = tmp_path / "env"
    _run([sys.executable, "-m", "venv", "--without-pip", str(env_dir)])
    python = env_dir / "bin" / "python"
    site = _run([str(python), "-c", "import sysconfig; print(sysconfig.get_path('purelib'))"]).strip()
    with open(os.path.join(site, "dependencies.pth"), "w") as f:
        f.write("\n".join(sorted({_folder_of(m) for m in DEPENDENCIES})) + "\n")
    _run(pip + ["--python", str(python), "install", "--no-deps", "--no-index", "-q", str(wheel)])

    # run from an empty folder, with nothing of the checkout on the path
    work = tmp_path / "work"
    work.mkdir()
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    where = _run([str(python), "-c", "import mitsuba_brdfs; print(mitsuba_brdfs.__file__)"],
                 cwd=work, env=env)
    assert where.startswith(site), where
    _run([str(env_dir / "bin" / "mitsuba-brdfs"), "figures", "--only", "as_sphere"], cwd=work,
         env=env)
    assert sorted(os.listdir(work / "renders")) == ["as_sphere.exr", "as_sphere.png",
                                                    "timings.json"]
    assert (work / "renders" / "as_sphere.png").stat().st_size > 1000
    # every scene shipped, nothing written beside the installed package
    def shipped(folder):
        return sorted(f for f in os.listdir(folder) if f.endswith((".xml", ".png")))
    installed = os.path.join(site, "mitsuba_brdfs", "scenes")
    assert shipped(installed) == shipped(os.path.join(ROOT, "scenes")) and len(shipped(installed)) >= 7
    for out in ("renders", "docs"):
        assert not os.path.exists(os.path.join(site, out))
        assert not os.path.exists(os.path.join(site, "mitsuba_brdfs", out))
