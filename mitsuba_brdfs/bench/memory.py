"""Peak memory of command-line renders: passes keep it bounded whatever the spp.

Part 5 of the performance study (``python -m mitsuba_brdfs bench``). Each render is the
package's command line, ``python -m mitsuba_brdfs render
scenes/as_sphere.xml``, run as a child process; its peak resident set size
comes from ``os.wait4`` (the kernel's ``ru_maxrss`` of that child alone). The same spp is
also rendered in one pass (no splitting) for contrast, as far as that fits the machine.
"""
import os
import subprocess
import sys
import tempfile
import time

from ..paths import SCENES
from ..progress import advance

__all__ = ["peak_rss_of", "run"]


#: the folder that holds the package: the child processes import it from there
ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def peak_rss_of(cmd, env=None, timeout=3600):
    """Run ``cmd``; returns (exit status, peak RSS in MiB, seconds, stderr tail)."""
    with tempfile.TemporaryFile() as err:
        t0 = time.perf_counter()
        proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=err, env=env,
                                cwd=ROOT)
        deadline = t0 + timeout
        while True:
            pid, status, usage = os.wait4(proc.pid, os.WNOHANG)
            if pid:
                break
            if time.perf_counter() > deadline:
                proc.kill()
                pid, status, usage = os.wait4(proc.pid, 0)
                break
            time.sleep(0.05)
        seconds = time.perf_counter() - t0
        proc.returncode = os.waitstatus_to_exitcode(status)  # reaped here, not by Popen
        err.seek(0)
        tail = err.read().decode(errors="replace").strip().splitlines()[-3:]
    # Linux reports ru_maxrss in KiB
    return proc.returncode, usage.ru_maxrss / 1024.0, seconds, tail


def run(settings, available, progress=None):
    """Measure the section: peak memory of each CLI render (``available`` is not needed)."""
    from ..passes import DEFAULT_PASS_SAMPLES, pass_sizes
    scene = os.path.join(SCENES, "as_sphere.xml")
    res = settings.mem_res
    pass_samples = settings.mem_pass_samples or DEFAULT_PASS_SAMPLES
    out = {"scene": "scenes/as_sphere.xml", "res": res,
           "pass_samples": pass_samples, "renders": []}
    jobs = [(spp, pass_samples) for spp in settings.mem_spps]
    jobs += [(spp, res * res * spp) for spp in settings.mem_onepass_spps]
    import mitsuba as mi
    with tempfile.TemporaryDirectory() as tmp:
        for spp, ps in jobs:
            out_exr = os.path.join(tmp, f"mem_{spp}_{ps}.exr")
            cmd = [sys.executable, "-m", "mitsuba_brdfs", "render", scene, "-o", out_exr,
                   "--spp", str(spp), "-D", f"res={res}", "--pass-samples", str(ps),
                   "--variant", mi.variant() or "llvm_ad_rgb"]
            status, rss, secs, tail = peak_rss_of(cmd)
            out["renders"].append({
                "spp": spp, "pass_samples": ps, "passes": len(pass_sizes(spp, res * res, ps)),
                "samples": res * res * spp, "status": status, "peak_rss_mib": rss,
                "seconds": secs, "error": "" if status == 0 else " / ".join(tail)})
            advance(progress, 1, f"memory {spp} spp")
    return out
