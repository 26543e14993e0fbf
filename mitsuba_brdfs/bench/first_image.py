"""One fresh process's way to its first image, timed phase by phase (run by ``startup``).

Run as a script, not imported (``startup.first_image``): ``python -c "import runpy, sys;
runpy.run_path(sys.argv[1], run_name='__main__')" first_image.py '<json>'``, the JSON
being ``{"scene": path of a scene file, "package": whether to import mitsuba_brdfs,
"variant": ...}``. It prints one JSON line on stdout:

``import_mitsuba``  ``import mitsuba`` and ``mi.set_variant``
``import_package``  ``import mitsuba_brdfs`` (0 when the scene needs no plugin of ours)
``load``            ``mi.load_file``
``first_render``    the first ``mi.render``, its image evaluated: ``trace`` + ``compile`` +
                    ``execute``, where
``compile``         Dr.Jit's code generation and the LLVM compile of every kernel, or their
                    load from the kernel cache (``DRJIT_CACHE_DIR``) on a hit
``execute``         the kernels running
``trace``           the rest: Python and C++ building the kernels (a Python BSDF's methods
                    run here), launches
``second_render``   the same render again in the same process (kernels in memory)

and ``kernels`` and ``disk_hits`` (kernels loaded from the cache) of the first render.
Only the standard library is imported before the clock starts.
"""
import json
import sys
import time


def main(config):
    t0 = time.perf_counter()
    import drjit as dr
    import mitsuba as mi
    mi.set_variant(config.get("variant", "llvm_ad_rgb"))
    t1 = time.perf_counter()
    if config["package"]:
        import mitsuba_brdfs  # noqa: F401  (registers the plugins)
    t2 = time.perf_counter()
    scene = mi.load_file(config["scene"])
    t3 = time.perf_counter()
    with dr.scoped_set_flag(dr.JitFlag.KernelHistory, True):
        img = mi.render(scene, seed=0)
        dr.eval(img)
        dr.sync_thread()
        t4 = time.perf_counter()
        kernels = [k for k in dr.kernel_history() if k.get("type") == dr.KernelType.JIT]
    img = mi.render(scene, seed=1)
    dr.eval(img)
    dr.sync_thread()
    t5 = time.perf_counter()
    compile_s = sum(k.get("codegen_time", 0) + k.get("backend_time", 0) for k in kernels) / 1e3
    execute_s = sum(k.get("execution_time", 0) for k in kernels) / 1e3
    first = t4 - t3
    return {"import_mitsuba": t1 - t0, "import_package": t2 - t1, "load": t3 - t2,
            "first_render": first, "compile": compile_s, "execute": execute_s,
            "trace": max(first - compile_s - execute_s, 0.0), "second_render": t5 - t4,
            "kernels": len(kernels), "disk_hits": sum(bool(k.get("cache_disk")) for k in kernels)}


if __name__ == "__main__":
    print(json.dumps(main(json.loads(sys.argv[-1]))), flush=True)
