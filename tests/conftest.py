"""Test setup: the llvm_ad_rgb variant on 2 threads, plugins registered, every test
starting in llvm_ad_rgb.

Nothing here is imported by the tests. What they share lives in modules pytest does not
collect: ``checks.py`` (helpers and checkers, with those of ``mitsuba_brdfs.validate``),
``reference.py`` (the float64 references of every model), ``phong_family.py`` (the tests the
two Phong-family models share), ``cmdline.py`` (driving the command line) and
``explore_page.py`` (the explorer's server and page, as users and other sites use them),
``user_bsdf.py`` (a user's plugin, with the flaws the checks find);
``test_layout.py`` keeps it so."""
import drjit as dr
import mitsuba as mi
import pytest

mi.set_variant("llvm_ad_rgb")
dr.set_thread_count(2)
import mitsuba_brdfs  # noqa: E402,F401  (registers the plugins)


@pytest.fixture(autouse=True)
def _llvm_rgb():
    """Every test starts in llvm_ad_rgb, whatever the previous one switched to."""
    if mi.variant() != "llvm_ad_rgb":
        mi.set_variant("llvm_ad_rgb")
    yield
    if mi.variant() != "llvm_ad_rgb":
        mi.set_variant("llvm_ad_rgb")
