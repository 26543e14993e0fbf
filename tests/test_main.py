"""The command line: every bad invocation in one line with status 2 before anything runs,
the help of every command, and stops (Ctrl-C: 130, SIGTERM: 143) that leave no partial
file and say what was written."""
import os
import re
import signal
import sys
import time

import drjit as dr
import numpy as np
import pytest

from cmdline import (ROOT, popen, popen_tty, read_rest, run_cli, run_code, run_many,
                     scene_xml, wait_for)
from mitsuba_brdfs.__main__ import COMMANDS, main, parser
from mitsuba_brdfs.output import read_exr
from mitsuba_brdfs.paths import SCENES

SCENE = os.path.join(SCENES, "as_sphere.xml")


def _bad_invocations(tmp):
    """(argv, words of the one-line message): outputs all go to tmp/out (never created)."""
    s = scene_xml(tmp / "s.xml")
    nosensor = scene_xml(tmp / "nosensor.xml", sensor=False)
    (tmp / "bad.xml").write_text("<scene version='3.0.0'><shape type='sphere'></scene>")
    (tmp / "tex.png").write_bytes(b"")
    textured = scene_xml(tmp / "textured.xml", bsdf='<bsdf type="diffuse"><texture type="bitmap" '
                         'name="reflectance"><string name="filename" value="tex.png"/></texture></bsdf>')
    (tmp / "a_file").write_text("")
    (tmp / "sub").mkdir()
    scene_xml(tmp / "sub" / "s.xml")
    # what Mitsuba users get wrong in a scene, and files where folders go and back
    noint = scene_xml(tmp / "noint.xml", integrator="")
    typo = scene_xml(tmp / "typo.xml", bsdf='<bsdf type="wardd"/>')
    (tmp / "nobsdf.xml").write_text(
        open(s).read().replace('<bsdf type="diffuse"/>', ""))
    (tmp / "dark.xml").write_text(
        open(s).read().replace('<emitter type="constant"/>', ""))
    (tmp / "empty.xml").write_text(" \n")
    nobsdf, dark, empty = tmp / "nobsdf.xml", tmp / "dark.xml", tmp / "empty.xml"
    plugin = tmp / "plugin.py"
    plugin.write_text("x = 1\n")
    out = tmp / "out" / "x"
    cases = [
        (["render", noint], "no <integrator>, which Mitsuba's mitsuba command refuses too"),
        (["render", dark], "no <emitter> (nor an area light): every pixel would be black"),
        (["render", nobsdf], "the shape sphere (nobsdf.xml, line 1) has no <bsdf>"),
        (["render", empty], "empty.xml: the file is empty"),
        (["render", typo], "typo.xml (line 1, col "),
        (["render", typo], "unknown bsdf plugin 'wardd' (did you mean 'ward'?)"),
        (["render", s, "-a", tmp / "a_file"], "-a " + str(tmp / "a_file") + ": is a file"),
        (["render", s, "--load", tmp / "sub"], "is a folder, not a Python file"),
        (["check", "wardd"], "unknown plugin 'wardd' (did you mean 'ward'?)"),
        (["check", typo], "unknown bsdf plugin 'wardd' (did you mean 'ward'?)"),
        (["check", nobsdf], "has no <bsdf>, and Mitsuba would give it a grey diffuse"),
        (["check", empty], "the file is empty"),
        (["check", tmp / "sub"], "is a folder, not a plugin name or an XML file"),
        (["check", "lambert", "--load", tmp / "sub"], "is a folder, not a Python file"),
        (["check", "lambert", "--load", tmp / "a_file"], "a_file: the file is empty"),
        (["check", "lambert", "--report", tmp / "a_file"], "is not a folder"),
        (["explore", "wardd", "--no-browser"], "unknown plugin 'wardd' (did you mean 'ward'?)"),
        (["explore", typo, "--no-browser"], "unknown bsdf plugin 'wardd'"),
        (["explore", nobsdf, "--no-browser"], "has no <bsdf>"),
        (["explore", empty, "--no-browser"], "the file is empty"),
        (["explore", tmp / "sub", "--no-browser"], "is a folder"),
        (["manual", "--only", "lamber"], "unknown plugin 'lamber' (did you mean 'lambert'?)"),
        (["manual", "--out", tmp / "a_file", "--text-only"], "is not a folder"),
        (["presets", "show", "nickel"], "show nickel needs --model, one of"),
        (["render", tmp / "missing.xml"], "missing.xml: no such file"),
        (["render", tmp], "is a folder"),
        (["render", tmp / "bad.xml"], "Parsing of XML file"),
        (["render", s, "-D", "res"], "key=value"),
        (["render", s, "-D", "bogus=3"], "unused parameters: $bogus=3"),
        (["render", s, "-D", "spp=0"], "0 samples per pixel"),
        (["render", s, "--spp", "0"], "--spp"),
        (["render", SCENE, "-D", "rs=2", "-D", "res=8", "--spp", "1"], "specular_reflectance"),
        (["render", s, "--variant", "bogus"], "unknown variant 'bogus'"),
        (["render", s, "-m", "scalar_mono"], "'scalar_mono' is not built"),
        (["render", s, "--seed", "-1"], "--seed"),
        (["render", s, "--seed", str(2 ** 32)], "--seed"),
        (["render", nosensor], "no <sensor>"),
        (["render", s, "-s", "1"], "1 sensor(s)"),
        (["render", s, "-t", "0"], "--threads"),
        (["render", s, "--exposure", "inf"], "--exposure"),
        (["render", s, "-a", tmp / "nowhere"], "no such folder"),
        (["render", s, "-o", tmp], "is a folder"),
        (["render", s, "-o", tmp / "a_file" / "x.exr"], "is not a folder"),
        (["render", s, "-o", s], "the scene itself"),
        (["render", textured, "-o", tmp / "tex.png"], "a file the scene loads"),
        (["render", s, "-o", tmp / "x.tiff"], "'.tiff'"),
        (["render", s, "-o", tmp / "x.exr", "--no-exr"], "nothing would be written"),
        (["render", s, "--debug", "-o", out, "-D", "spp=0"], "Traceback"),
        (["render", s, "-D", "res=20000", "--max-memory", "1"],
         "raise the limit with --max-memory"),
        (["render", s, "-D", "res=100000"], "more than Dr.Jit's arrays can (2^32)"),
        (["render", s, "--max-memory", "0"], "--max-memory"),
        (["render", s, "-O", "0"], "-O 0: rendering with Dr.Jit's function merging"),
        (["render", s, "-O", "6"], "-O"),
        (["render", s, "--load", tmp / "nofile.py"], "nofile.py: no such file"),
        (["render", s, nosensor, "-o", tmp / "x.png"], "with several scenes, -o names a folder"),
        (["render", s, tmp / "sub" / "s.xml"], "two scenes named 's'"),
        (["bench", "--threads", "-1"], "--threads"),
        (["properties", "--only", "bogus"], "bogus"),
        (["properties", "--samples", "0"], "--samples"),
        (["fit", "--iterations", "0"], "--iterations"),
        (["figures", "--out", tmp / "a_file"], "is not a folder"),
        (["figures", "--variant", "bogus"], "unknown variant"),
        # a SPEC that names a file (an extension, a folder) and is not there: no such file,
        # in every command (spec.locate), never an unknown plugin
        (["check", "gold-paint.binary"], "gold-paint.binary: no such file (a measured file"),
        (["check", "./ward"], "./ward: no such file"),
        (["check", tmp / "sub" / "x.xml"], "x.xml: no such file"),
        (["check", plugin], "is a Python file: run it with --load"),
        (["to-rgl", "gold-paint.binary", "-o", out], "gold-paint.binary: no such file"),
        (["to-merl", "paper_white_rgb.bsdf", "-o", out], "paper_white_rgb.bsdf: no such file"),
        (["explore", "paper_white_rgb.bsdf", "--no-browser"], "paper_white_rgb.bsdf: no such file"),
        (["fit-measured", "gold-paint.binary", "--model", "ward", "--out", out],
         "gold-paint.binary: no such file"),
        (["fit-measured", "--target", "data/nickel.xml", "--model", "ward", "--out", out],
         "data/nickel.xml: no such file"),
        # a key given twice: refused, never the last one kept silently
        (["check", "ward", "-p", "alpha_u=0.1", "-p", "alpha_u=0.2"],
         "-p alpha_u given twice (-p alpha_u=0.1, -p alpha_u=0.2): give it once"),
        (["to-rgl", "ward", "-p", "alpha_u=0.1", "-p", "alpha_u=0.1", "-o", out],
         "-p alpha_u given twice"),
        (["explore", "ward", "roughplastic", "-p", "alpha=0.1", "-p", "ward:alpha=0.2",
          "--no-browser"], "-p alpha given twice (-p alpha=0.1, -p alpha=0.2): give it once "
                           "(for ward)"),
        (["fit-measured", "--target", "ward", "-p", "alpha_u=0.1", "-p", "alpha_u=0.2",
          "--model", "lambert", "--out", out], "-p alpha_u given twice"),
        (["fit-measured", "--target", "ward", "--model", "ward", "-p", "alpha_u=0.1", "-p",
          "alpha_u=0.2", "--out", out], "-p alpha_u given twice"),
        (["render", s, "-D", "res=8", "-D", "res=16"], "-D res given twice"),
    ]
    if sys.platform.startswith("linux"):  # unwritable even for root
        cases.append((["render", s, "-o", "/proc/x.exr"], "cannot write"))
    if not dr.has_backend(dr.JitBackend.CUDA):
        cases.append((["render", s, "-m", "cuda_ad_rgb"], "CUDA"))
    return [([*argv, *([] if "-o" in argv or argv[0] != "render" else ["-o", out])], words)
            for argv, words in cases]


def test_every_bad_invocation_is_one_line_with_status_2(tmp_path):
    cases = _bad_invocations(tmp_path)
    before = sorted(os.listdir(tmp_path))
    for (argv, words), (code, out, err) in zip(cases, run_many([a for a, _ in cases])):
        if "--debug" in argv:  # the traceback, on demand
            assert code == 2 and words in err, (argv, err)
            continue
        lines = err.strip().splitlines()
        assert code == 2 and len(lines) == 1 and words in lines[0], (argv, code, err)
        assert "Traceback" not in err and out == "", (argv, out)
    assert sorted(os.listdir(tmp_path)) == before  # nothing written, not even a folder


def test_bad_invocation_as_a_process(tmp_path):
    """The same through ``python -m``: argparse's error, and the scene's."""
    s = scene_xml(tmp_path / "s.xml")
    r = run_cli("render", s, "--seed", "-1")
    assert r.returncode == 2 and len(r.stderr.strip().splitlines()) == 1
    assert "--seed: must be in 0..4294967295, got -1" in r.stderr
    r = run_cli("render", s, "-D", "spp=0", "-o", tmp_path / "x")
    assert r.returncode == 2 and r.stderr.startswith("error: ") and "Traceback" not in r.stderr
    assert sorted(os.listdir(tmp_path)) == ["s.xml"]


def test_missing_llvm_is_the_packages_message(tmp_path):
    """No libLLVM: the package's LLVMVersionError in one line, not an ImportError traceback,
    for every command (Dr.Jit itself prints two lines when it is imported)."""
    s = scene_xml(tmp_path / "s.xml")
    out = tmp_path / "out"
    env = {"DRJIT_LIBLLVM_PATH": "/nonexistent"}
    r = run_cli("render", s, "-o", out / "x", env=env)
    assert r.returncode == 2 and "Traceback" not in r.stderr, r.stderr
    last = r.stderr.strip().splitlines()[-1]
    assert last.startswith("error: ") and "found no LLVM library" in last and "libllvm19" in last
    cases = [["figures", "--out", out], ["properties", "--out", out], ["fit", "--out", out],
             ["bench", "--quick", "--out", out], ["manual", "--text-only", "--out", out],
             ["check", "lambert", "--quick"]]
    for argv, (code, _, err) in zip(cases, run_many(cases, env=env)):
        assert code == 2 and err.startswith("error: ") and "found no LLVM library" in err, (argv, err)
        assert len(err.strip().splitlines()) == 1, (argv, err)
    assert sorted(os.listdir(tmp_path)) == ["s.xml"]


def test_help_lists_every_command_and_where_it_writes():
    results = run_many([["--help"]] + [[name, "--help"] for name in COMMANDS])
    code, out, _ = results[0]
    assert code == 0
    for name, (_, help_text) in COMMANDS.items():
        assert name in out and help_text.split()[0] in out
    # fit-measured reads MERL and RGL files and --target BSDFs
    assert "measured MERL or RGL file, or to any BSDF (--target)" in " ".join(out.split())
    where = {"render": "current directory", "figures": "mitsuba_brdfs-out/figures/",
             "properties": "mitsuba_brdfs-out/properties/", "fit": "mitsuba_brdfs-out/fit/",
             "bench": "mitsuba_brdfs-out/bench/", "manual": "mitsuba_brdfs-out/manual/"}
    assert "``" not in out, out  # plain text: no reST literals
    for (code, out, _), name in zip(results[1:], COMMANDS):
        assert code == 0 and "--debug" in out and "``" not in out, (name, out)
        if name in where:
            assert where[name] in " ".join(out.split()), (name, out)
    render_help = " ".join(results[1][1].split())
    for option in ("-m", "--variant", "-t", "-s", "-D", "-a", "-o", "-q", "-v", "--spp",
                   "--seed", "--exposure"):
        assert f"{option} " in render_help or f"{option}," in render_help, option


_LOADED = """
import contextlib, io, sys
from mitsuba_brdfs.__main__ import main
with contextlib.redirect_stdout(io.StringIO()):
    code = main(sys.argv[1:])
heavy = ("numpy", "matplotlib", "mitsuba_brdfs.bench.study", "mitsuba_brdfs.fit",
         "mitsuba_brdfs.render")
print(code, *sorted(m for m in heavy if m in sys.modules))
"""


def test_help_imports_only_the_command_it_shows():
    """The top-level help needs no command module; a command's help only its own."""
    assert run_code(_LOADED, "--help").stdout.split() == ["0"]
    code, *loaded = run_code(_LOADED, "render", "--help").stdout.split()
    assert code == "0" and "mitsuba_brdfs.render" in loaded
    assert not {"mitsuba_brdfs.fit", "mitsuba_brdfs.bench.study", "matplotlib"} & set(loaded)
    code, *loaded = run_code(_LOADED, "fit", "--help").stdout.split()
    assert code == "0" and "mitsuba_brdfs.fit" in loaded
    assert "mitsuba_brdfs.bench.study" not in loaded


def test_no_command_prints_the_help(capsys):
    assert main([]) == 0
    assert "render" in capsys.readouterr().out


_INTERRUPT_PASS = r"""
import sys
import mitsuba as mi
from mitsuba_brdfs.__main__ import main
render, calls = mi.render, []
def interrupted(*a, **kw):
    calls.append(1)
    if len(calls) == int(sys.argv[1]):
        raise KeyboardInterrupt
    return render(*a, **kw)
mi.render = interrupted
status = main(sys.argv[2:])
print(len(calls))
sys.exit(status)
"""


@pytest.mark.parametrize("stop_in", [1, 2])
def test_interrupt_keeps_the_passes_done(tmp_path, stop_in):
    """Ctrl-C in the first pass: status 130, nothing written; in the second: the first
    pass is written, and the message says how many samples it holds (in a process of its
    own: the render measures compile times with Dr.Jit's kernel history, which would stay
    switched on here)."""
    r = run_code(_INTERRUPT_PASS, stop_in, "render", SCENE, "-o", tmp_path / "i", "--spp",
                 "4", "-D", "res=16", "--pass-samples", "256", "-q")
    assert r.returncode == 130 and r.stdout.split() == [str(stop_in)], r.stderr
    if stop_in == 1:
        assert "interrupted: no output written" in r.stderr
        assert os.listdir(tmp_path) == []
        return
    assert "stopped after 1 pass(es): writing the 1 spp they hold" in r.stderr
    assert f"interrupted after writing {tmp_path / 'i.exr'}, {tmp_path / 'i.png'}" in r.stderr
    assert sorted(os.listdir(tmp_path)) == ["i.exr", "i.png"]
    img = read_exr(tmp_path / "i.exr")
    assert img.shape == (16, 16, 3) and np.isfinite(img).all() and img.mean() > 0.01


def test_sigint_during_a_huge_render_keeps_the_passes_done(tmp_path):
    """1e11 spp in passes of 1 spp ("renders until stopped"): the first pass starts at once
    (passes are made one at a time, no list of 1e11 passes first); Ctrl-C stops it with
    130, and the passes done are written."""
    s = scene_xml(tmp_path / "s.xml")
    # at a terminal, as Ctrl-C is typed: the bar is redrawn every 0.1 s
    p, stderr = popen_tty("import sys; from mitsuba_brdfs.__main__ import main; "
                          "sys.exit(main())", "render", s, "-o", tmp_path / "out" / "x",
                          "--spp", "100000000000", "--pass-samples", "64")
    with p:
        # the bar names the pass from its second redraw on
        seen = wait_for(stderr, ", pass ", p)
        assert "100G spp" in seen and ", pass " in seen, seen
        # past the first pass: a signal in the middle of Mitsuba's very first render has
        # been seen to end the process as if no handler were installed (status -2, rarely)
        time.sleep(0.5)
        p.send_signal(signal.SIGINT)
        err = read_rest(stderr)
        p.wait(timeout=120)
    assert p.returncode == 130, err
    m = re.search(r"stopped after (\d+) pass\(es\): writing the (\d+) spp they hold", err)
    assert m and int(m.group(1)) >= 2 and m.group(1) == m.group(2), err
    assert "interrupted after writing" in err
    assert sorted(os.listdir(tmp_path / "out")) == ["x.exr", "x.png"]
    assert read_exr(tmp_path / "out" / "x.exr").mean() > 0.01


_SLOW_PNG = r"""
import sys, time
from mitsuba_brdfs import output
from mitsuba_brdfs.__main__ import main
write = output._write_bitmap
def slow(bmp, path, file_format):
    write(bmp, path, file_format)
    if path.endswith(".png"):
        print("WRITING", file=sys.stderr, flush=True)
        time.sleep(120)
output._write_bitmap = slow
sys.exit(main(sys.argv[1:]))
"""


def test_sigterm_during_a_write_leaves_no_partial_file(tmp_path):
    """SIGTERM while the PNG is being written (the EXR is done): status 143, the
    temporary PNG removed, and the message names the one file written."""
    s = scene_xml(tmp_path / "s.xml")
    out = tmp_path / "out"
    p = popen(_SLOW_PNG, "render", s, "-o", out / "x", "-q")
    seen = wait_for(p.stderr, "WRITING", p)
    assert "WRITING" in seen, seen + p.stderr.read()
    assert any(f.startswith(".partial-") for f in os.listdir(out))
    p.send_signal(signal.SIGTERM)
    err = p.communicate(timeout=60)[1]
    assert p.returncode == 143, err
    assert f"terminated after writing {out / 'x.exr'}" in err
    assert os.listdir(out) == ["x.exr"]


@pytest.mark.parametrize("command", ["figures", "properties", "fit", "bench", "manual"])
def test_outputs_default_to_an_untracked_folder_of_the_current_directory(command):
    """Never into the package's folder (site-packages, once installed), nor into the
    tracked docs/ or renders/ of a checkout: into mitsuba_brdfs-out/<command>, which the
    repository ignores; its help says so."""
    out = parser().parse_args([command]).out
    assert out == os.path.join("mitsuba_brdfs-out", command)
    with open(os.path.join(ROOT, ".gitignore")) as f:
        assert "/mitsuba_brdfs-out/" in f.read().split(), "the default output is not ignored"
    assert "mitsuba_brdfs-out/" in COMMANDS[command][1]


def test_the_readme_example_edited_after_examples_copied_it(tmp_path, monkeypatch):
    """The README's flow after ``pip install``: ``examples`` copies the plugin here, the user
    drops the cosine from its eval, and ``check mydiffuse --load mydiffuse.py`` checks that
    edited copy (said on stderr), not the pristine one installed with the package."""
    from mitsuba_brdfs.paths import EXAMPLES, copied_example, installed_copy
    copy, = run_many([["examples"]], cwd=tmp_path)
    assert copy[0] == 0, copy
    plugin = tmp_path / "examples" / "mydiffuse" / "mydiffuse.py"
    text = plugin.read_text()
    assert "self.reflectance / dr.pi * wo.z" in text
    plugin.write_text(text.replace("self.reflectance / dr.pi * wo.z", "self.reflectance / dr.pi"))
    (code, out, err), = run_many([["check", "mydiffuse", "--load", "mydiffuse.py", "--quick",
                                   "--only", "weight"]], cwd=tmp_path)
    assert code == 1 and "FAIL  weight" in out, (out, err)
    assert err.startswith("note: --load mydiffuse.py is not in this folder; using the copy the "
                          "examples command made here, examples/mydiffuse/mydiffuse.py"), err
    # elsewhere (and in a checkout, whose examples/ is the package's own) the installed one
    monkeypatch.chdir(tmp_path / "examples")
    assert copied_example("mydiffuse.py") is None
    assert installed_copy("mydiffuse.py") == os.path.join(EXAMPLES, "mydiffuse", "mydiffuse.py")
    monkeypatch.chdir(os.path.dirname(EXAMPLES))
    assert copied_example("mydiffuse.py") is None
