"""Timing renders honestly: what a render kernel traces, and kernels reused by rebuilt scenes."""
import mitsuba as mi

from mitsuba_brdfs.timing import kernel_stats, paired_fresh, sphere_scene


def test_every_live_bsdf_is_traced_into_a_render():
    """Why the study builds each scene afresh: a live BSDF elsewhere changes the kernel."""
    scene = sphere_scene({"type": "diffuse"}, 16, 4)
    alone = kernel_stats(scene)["instructions_max"]
    other = mi.load_dict({"type": "roughconductor"})  # noqa: F841  (alive, in no scene)
    with_other = kernel_stats(scene)["instructions_max"]
    del other
    import gc
    gc.collect()
    assert with_other > alone
    assert kernel_stats(scene)["instructions_max"] == alone


def test_rebuilt_scenes_reuse_their_kernels():
    """paired_fresh: no JIT compilation inside the timed runs."""
    builders = {"a": lambda: sphere_scene({"type": "ashikhmin_shirley"}, 16, 4),
                "b": lambda: sphere_scene({"type": "roughconductor"}, 16, 4)}
    paired_fresh(builders, runs=1)
    import gc
    for name in ("a", "b", "b", "a"):
        scene = builders[name]()
        st = kernel_stats(scene)
        assert st["cache_hits"] == st["kernels"], (name, st)
        del scene
        gc.collect()
