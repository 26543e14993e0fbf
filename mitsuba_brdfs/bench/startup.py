"""What a fresh process pays besides rendering: the time to its first image, and the
``figures`` command's total, each with an empty and with a filled kernel cache.

Parts 6 and 8 of the performance study (``python -m mitsuba_brdfs bench``). Dr.Jit keeps
the kernels it compiles in a disk cache (``~/.drjit``, or the folder that
``DRJIT_CACHE_DIR`` names) and loads them from there instead of compiling them again. Every
measurement here is a child process whose ``DRJIT_CACHE_DIR`` is a new, empty folder
(*empty*), followed by the same child with the folder as the first one left it (*filled*):
a user's first run after installing, and every run after it.

Part 6 times the first image of the sphere of ``scenes/as_sphere.xml`` with a Python
plugin, then with its closest C++ plugin (the study's ``startup_pairs``, keys of
``speed.CPP_PAIRS``), alternately, split into import, load, trace, compile and render
(``child.first_image``). Part 8 runs ``python -m mitsuba_brdfs figures`` with Dr.Jit's
kernel history on, which gives the seconds spent compiling (``child.command``), and reads
the seconds of each figure from the ``timings.json`` the command writes.
"""
import json
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
import xml.etree.ElementTree as ET

from ..paths import SCENES
from ..progress import advance

__all__ = ["scene_file", "in_child", "first_image", "run", "run_figures_command"]

#: the folder that holds the package: child processes import it from there
ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
#: the script the child processes run
CHILD = os.path.join(os.path.dirname(os.path.abspath(__file__)), "child.py")


def _property(parent, name, value):
    """One XML property of a BSDF dict entry (floats, strings, booleans, rgb dicts)."""
    if isinstance(value, bool):
        ET.SubElement(parent, "boolean", name=name, value=str(value).lower())
    elif isinstance(value, (int, float)):
        ET.SubElement(parent, "float", name=name, value=repr(float(value)))
    elif isinstance(value, str):
        ET.SubElement(parent, "string", name=name, value=value)
    elif isinstance(value, dict) and value.get("type") == "rgb":
        v = value["value"]
        v = v if isinstance(v, (list, tuple)) else [v]
        ET.SubElement(parent, "rgb", name=name, value=", ".join(repr(float(x)) for x in v))
    else:
        raise ValueError(f"startup: cannot write {name} = {value!r} as XML")


def scene_file(bsdf, res, spp, folder, name):
    """``scenes/as_sphere.xml`` with its BSDF replaced by ``bsdf`` (a dict of plain values)
    and its res and spp set, written into ``folder``; returns the path."""
    tree = ET.parse(os.path.join(SCENES, "as_sphere.xml"))
    root = tree.getroot()
    for d in root.iter("default"):
        if d.get("name") in ("res", "spp"):
            d.set("value", str(res if d.get("name") == "res" else spp))
    shape = root.find("shape")
    shape.remove(shape.find("bsdf"))
    el = ET.SubElement(shape, "bsdf", type=bsdf["type"])
    for k, v in bsdf.items():
        if k != "type":
            _property(el, k, v)
    path = os.path.join(folder, f"{name}.xml")
    tree.write(path)
    return path


def in_child(config, cache_dir, timeout=3600):
    """Run ``child.py`` with ``config`` in a fresh process whose kernel cache is
    ``cache_dir``; its JSON, with ``process`` (the process from start to exit, interpreter
    included) and ``error`` (the end of its stderr when it failed)."""
    env = dict(os.environ, DRJIT_CACHE_DIR=cache_dir)
    t0 = time.perf_counter()
    r = subprocess.run([sys.executable, "-c", "import runpy, sys; "
                        "runpy.run_path(sys.argv[1], run_name='__main__')", CHILD,
                        json.dumps(config)],
                       cwd=ROOT, env=env, capture_output=True, text=True, timeout=timeout)
    process = time.perf_counter() - t0
    lines = r.stdout.strip().splitlines()
    try:
        out = json.loads(lines[-1])
    except (IndexError, ValueError):
        out = {}
    out.update({"process": process, "exit": r.returncode,
                "error": "" if r.returncode == 0 else
                " / ".join(r.stderr.strip().splitlines()[-3:])})
    return out


def first_image(scene, package, cache_dir):
    """``child.first_image`` of ``scene`` in a fresh process whose kernel cache is
    ``cache_dir``, with ``first_image`` (import + load + first render)."""
    import mitsuba as mi
    out = in_child({"what": "first_image", "scene": scene, "package": bool(package),
                    "variant": mi.variant() or "llvm_ad_rgb"}, cache_dir)
    if out["exit"] != 0:
        raise RuntimeError(f"first image of {scene} failed: {out['error']}")
    out["first_image"] = (out["import_mitsuba"] + out["import_package"] + out["load"]
                          + out["first_render"])
    return out


def _medians(rows):
    """The median of every number over the runs."""
    keys = [k for k in rows[0] if isinstance(rows[0][k], (int, float))
            and not isinstance(rows[0][k], bool)]
    return {k: statistics.median(r[k] for r in rows) for k in keys}


def _ratios(a, b, key):
    """Median, min and max of the per-run ratios a / b of ``key``, or None."""
    rs = [x[key] / y[key] for x, y in zip(a, b) if y[key] > 0]
    return {"ratio": statistics.median(rs), "ratio_min": min(rs), "ratio_max": max(rs),
            "runs": len(rs)} if rs else None


def run(settings, available, progress=None):
    """Part 6: the first image, Python plugin against its C++ neighbour, empty and filled
    kernel cache; ``startup_runs`` rounds, the two plugins in alternating order."""
    from .speed import CPP_PAIRS, _missing
    out = {"settings": {"res": settings.startup_res, "spp": settings.startup_spp,
                        "runs": settings.startup_runs, "integrator": "direct"},
           "pairs": {}, "skipped": []}
    pairs = []
    for key, ours, theirs, note in CPP_PAIRS:
        if key not in settings.startup_pairs:
            continue
        miss = _missing(ours, available)
        if miss:
            out["skipped"].append(f"{key}: plugin `{miss[0]}` is not registered")
            continue
        pairs.append((key, ours, theirs))
    with tempfile.TemporaryDirectory() as tmp:
        files, rows = {}, {}
        for key, ours, theirs in pairs:
            files[key] = {
                "python": scene_file(ours, settings.startup_res, settings.startup_spp, tmp,
                                     key + "_python"),
                "cpp": scene_file(theirs, settings.startup_res, settings.startup_spp, tmp,
                                  key + "_cpp")}
            rows[key] = {side: {"empty": [], "filled": []} for side in ("python", "cpp")}
        for r in range(settings.startup_runs):
            for key, ours, theirs in pairs:
                for side in (("python", "cpp") if r % 2 == 0 else ("cpp", "python")):
                    cache = tempfile.mkdtemp(dir=tmp)
                    for state in ("empty", "filled"):
                        rows[key][side][state].append(
                            first_image(files[key][side], side == "python", cache))
                    shutil.rmtree(cache, ignore_errors=True)
                    advance(progress, 1, f"{key} {side}")
    for key, ours, theirs in pairs:
        res = {"python": ours, "cpp": theirs, "plugin": ours["type"],
               "cpp_plugin": theirs["type"], "runs": rows[key]}
        for state in ("empty", "filled"):
            py, cpp = rows[key]["python"][state], rows[key]["cpp"][state]
            res[state] = {"python": _medians(py), "cpp": _medians(cpp),
                          "first_image_ratio": _ratios(py, cpp, "first_image"),
                          "process_ratio": _ratios(py, cpp, "process")}
        out["pairs"][key] = res
    return out


def _figures_once(names, cache_dir, timeout):
    """One ``figures`` command in a fresh process (``child.command``), with the seconds of
    its rendering loop (``loop``) and of each figure as its ``timings.json`` says."""
    import mitsuba as mi
    with tempfile.TemporaryDirectory() as out_dir:
        args = (["figures", "--out", out_dir, "--variant", mi.variant() or "llvm_ad_rgb"]
                + (["--only", *names] if names else []))
        out = in_child({"what": "command", "args": args}, cache_dir, timeout)
        timings = {}
        path = os.path.join(out_dir, "timings.json")
        if os.path.exists(path):
            with open(path) as f:
                timings = json.load(f)
    out["loop"] = timings.pop("last_run", {}).get("seconds_total")
    out["figures"] = {k: v["seconds_total"] for k, v in timings.items()
                      if isinstance(v, dict) and "seconds_total" in v}
    return out


def run_figures_command(settings, available, progress=None, timeout=3600):
    """Part 8: ``python -m mitsuba_brdfs figures`` (``--only`` the settings' figures, all
    of them when empty) with an empty, then a filled kernel cache, ``figcmd_runs`` times."""
    names = list(settings.figcmd_only)
    out = {"settings": {"only": names, "runs": settings.figcmd_runs, "quality": "preview"},
           "runs": {"empty": [], "filled": []}}
    with tempfile.TemporaryDirectory() as tmp:
        for r in range(settings.figcmd_runs):
            cache = tempfile.mkdtemp(dir=tmp)
            for state in ("empty", "filled"):
                out["runs"][state].append(_figures_once(names, cache, timeout))
                advance(progress, 1, f"figures {state} cache")
            shutil.rmtree(cache, ignore_errors=True)
    ok = {s: [x for x in v if x["exit"] == 0 and x.get("status") == 0]
          for s, v in out["runs"].items()}
    if ok["empty"] and ok["filled"]:
        for state, rows in ok.items():
            med = {k: statistics.median(x[k] for x in rows)
                   for k in ("process", "compile", "kernels", "launches", "disk_hits")}
            loops = [x["loop"] for x in rows if x.get("loop")]
            med["loop"] = statistics.median(loops) if loops else None
            med["figures"] = {name: statistics.median(x["figures"].get(name) or 0.0 for x in rows)
                              for name in rows[0]["figures"]}
            out[state] = med
        # the share of the first run that compiling takes; the rest is the same either way
        out["compile_share"] = out["empty"]["compile"] / out["empty"]["process"]
    return out
