"""What the study times in fresh processes (run by ``startup``), each printing one JSON line.

Run as a script, not imported: ``python -c "import runpy, sys; runpy.run_path(sys.argv[1],
run_name='__main__')" child.py '<json>'``. Only the standard library is imported before
the clock starts. The JSON says what to run:

``{"what": "first_image", "scene": path, "package": bool}``: the way to a scene's first
image, phase by phase (``first_image``). ``package``: import mitsuba_brdfs (the scene uses
its plugins).

``{"what": "command", "args": [...]}``: ``python -m mitsuba_brdfs ARGS`` with Dr.Jit's
kernel history on; prints ``wall`` (from the first import to the end), ``compile`` (Dr.Jit's
code generation and LLVM of every kernel, or their load from the cache), ``kernels``,
``launches`` and ``disk_hits`` (``_kernel_counts``), and the command's exit status. The
command's own output goes to stderr.
"""
import json
import sys
import time


def _compile_seconds(kernels):
    """Seconds of code generation and backend compile of the kernels."""
    return sum(k.get("codegen_time", 0) + k.get("backend_time", 0) for k in kernels) / 1e3


def _kernel_counts(kernels):
    """``kernels``: distinct kernels (a kernel launched again is counted once),
    ``launches``: every launch, ``disk_hits``: kernels loaded from the disk cache."""
    return {"kernels": len({k.get("hash") for k in kernels}), "launches": len(kernels),
            "disk_hits": sum(bool(k.get("cache_disk")) for k in kernels)}


def _resident_mib():
    """The process's resident memory in MiB (Linux; None elsewhere)."""
    try:
        with open("/proc/self/statm") as f:
            pages = int(f.read().split()[1])
    except (OSError, ValueError, IndexError):
        return None
    import os
    return pages * os.sysconf("SC_PAGE_SIZE") / 2 ** 20


def first_image(config):
    """``import_mitsuba`` (``import mitsuba``, ``mi.set_variant``), ``import_package``
    (``import mitsuba_brdfs``, 0 without) and ``package_mib`` (the resident memory it
    adds, None where it cannot be read), ``load`` (``mi.load_file``), ``first_render``
    (the first ``mi.render``, its image evaluated) = ``trace`` + ``compile`` + ``execute``,
    ``second_render`` (the same again, kernels in memory), and the kernels of the first
    render (``_kernel_counts``).

    ``compile`` is Dr.Jit's code generation and the LLVM compile of every kernel, or their
    load from the kernel cache; ``execute`` the kernels running; ``trace`` the rest (Python
    and C++ building the kernels: a Python BSDF's methods run here). The first render runs
    with ``LaunchBlocking``, so that a kernel does not run while the next one compiles and
    the three add up (the first image takes as long either way, within noise).
    """
    t0 = time.perf_counter()
    import drjit as dr
    import mitsuba as mi
    mi.set_variant(config.get("variant", "llvm_ad_rgb"))
    t1 = t2 = time.perf_counter()
    rss1 = rss2 = _resident_mib()
    if config["package"]:
        import mitsuba_brdfs  # noqa: F401  (registers the plugins)
        t2 = time.perf_counter()
        rss2 = _resident_mib()
    scene = mi.load_file(config["scene"])
    t3 = time.perf_counter()
    with dr.scoped_set_flag(dr.JitFlag.KernelHistory, True), \
            dr.scoped_set_flag(dr.JitFlag.LaunchBlocking, True):
        img = mi.render(scene, seed=0)
        dr.eval(img)
        dr.sync_thread()
        t4 = time.perf_counter()
        kernels = [k for k in dr.kernel_history() if k.get("type") == dr.KernelType.JIT]
    img = mi.render(scene, seed=1)
    dr.eval(img)
    dr.sync_thread()
    t5 = time.perf_counter()
    compile_s = _compile_seconds(kernels)
    execute_s = sum(k.get("execution_time", 0) for k in kernels) / 1e3
    first = t4 - t3
    return {"import_mitsuba": t1 - t0, "import_package": t2 - t1,
            "package_mib": None if rss1 is None else rss2 - rss1, "load": t3 - t2,
            "first_render": first, "compile": compile_s, "execute": execute_s,
            "trace": max(first - compile_s - execute_s, 0.0), "second_render": t5 - t4,
            **_kernel_counts(kernels)}


def command(config):
    """One command of the package's command line, its compile seconds counted."""
    t0 = time.perf_counter()
    import contextlib

    import drjit as dr
    dr.set_flag(dr.JitFlag.KernelHistory, True)
    import runpy
    # as ``python -m mitsuba_brdfs ARGS`` runs it: the package's __main__ module, which
    # exits with the command's status
    sys.argv = ["mitsuba_brdfs", *config["args"]]
    with contextlib.redirect_stdout(sys.stderr):
        try:
            runpy.run_module("mitsuba_brdfs", run_name="__main__", alter_sys=True)
            status = 0
        except SystemExit as e:
            status = 0 if e.code is None else e.code
    wall = time.perf_counter() - t0
    kernels = [k for k in dr.kernel_history() if k.get("type") == dr.KernelType.JIT]
    return {"status": status, "wall": wall, "compile": _compile_seconds(kernels),
            **_kernel_counts(kernels)}


if __name__ == "__main__":
    config = json.loads(sys.argv[-1])
    result = {"first_image": first_image, "command": command}[config["what"]](config)
    print(json.dumps(result), flush=True)
