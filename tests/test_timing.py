"""Timing renders honestly: what a render kernel traces, and kernels reused by rebuilt scenes."""
import mitsuba as mi

from mitsuba_brdfs.sphere import sphere_scene
from mitsuba_brdfs.timing import kernel_stats, paired_fresh


def test_every_live_bsdf_is_traced_into_a_render():
    """Why the study builds each scene afresh: a live BSDF elsewhere changes the kernel.
    (Garbage of the tests this process ran before is collected first: a BSDF freed between
    two measurements would change the kernel too.)"""
    import gc
    gc.collect()
    scene = sphere_scene({"type": "diffuse"}, 16, 4)
    alone = kernel_stats(scene)["instructions_max"]
    other = mi.load_dict({"type": "roughconductor"})  # noqa: F841  (alive, in no scene)
    with_other = kernel_stats(scene)["instructions_max"]
    del other
    gc.collect()
    assert with_other > alone
    assert kernel_stats(scene)["instructions_max"] == alone


def test_rebuilt_scenes_trace_the_same_kernels():
    """A scene built again after the last one was freed traces the same program: as many
    kernels, of the same sizes, as its first build, whichever scene was built in between;
    so the study can rebuild a scene for every timed render.

    Whether Dr.Jit then finds each kernel in its cache is its business (now and then a
    rebuilt scene compiles one anew; ``paired_fresh`` times such a render again, see the
    next test): cache hits are not asserted."""
    import gc
    builders = {"a": lambda: sphere_scene({"type": "ashikhmin_shirley"}, 16, 4),
                "b": lambda: sphere_scene({"type": "roughconductor"}, 16, 4)}
    first = {}
    for name in ("a", "b", "b", "a"):
        scene = builders[name]()
        st = kernel_stats(scene)
        shape = (st["kernels"], st["instructions_max"], st["ops"])
        assert first.setdefault(name, shape) == shape, (name, first[name], shape)
        del scene
        gc.collect()
    assert first["a"][0] > 0 and first["a"] != first["b"]


def test_a_render_that_compiled_is_timed_again():
    """paired_fresh: no JIT compilation inside the timed runs. The first timed build of
    "a" traces a kernel this process has not run yet (Mitsuba's max_depth is a constant
    in the kernel, and no other test uses 977); the render is timed again on the next
    build, whose kernel the warm-up compiled."""
    import gc
    calls = []

    def build_a():
        calls.append(1)
        depth = 977 if len(calls) == 2 else 3  # only the first timed build differs
        return sphere_scene({"type": "lambert"}, 16, 4, integrator="path", max_depth=depth)

    builders = {"a": build_a, "b": lambda: sphere_scene({"type": "diffuse"}, 16, 4)}
    times, stats = paired_fresh(builders, runs=1)
    gc.collect()
    assert times["a:recompiled"] >= 1 and len(calls) >= 3, (times, len(calls))
    assert len(times["a"]) == len(times["b"]) == 1
