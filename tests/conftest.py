"""Test setup: the llvm_ad_rgb variant on 2 threads, plugins registered, every test
starting in llvm_ad_rgb (or in the variant it is parametrized by).

Nothing here is imported by the tests. What they share lives in modules pytest does not
collect: ``checks.py`` (helpers and checkers, with those of ``mitsuba_brdfs.validate``),
``reference.py`` (the float64 references of every model), ``phong_family.py`` (the tests the
two Phong-family models share), ``cmdline.py`` (driving the command line) and
``explore_page.py`` (the explorer's server and page, as users and other sites use them),
``user_bsdf.py`` (a user's plugin, with the flaws the checks find);
``test_layout.py`` keeps it so."""
import gc

import drjit as dr
import mitsuba as mi
import pytest

mi.set_variant("llvm_ad_rgb")
dr.set_thread_count(2)
import mitsuba_brdfs  # noqa: E402,F401  (registers the plugins)


#: where a test's run keeps the test that runs after it in this process
NEXT = pytest.StashKey()


@pytest.hookimpl(tryfirst=True)
def pytest_runtest_protocol(item, nextitem):
    item.stash[NEXT] = nextitem


def declared_variant(item):
    """The variant a test is parametrized by (its ``variant`` argument), or None."""
    callspec = getattr(item, "callspec", None)
    return callspec.params.get("variant") if callspec is not None else None


def _test(item):
    """The test a case belongs to: its function, in its class or module."""
    return item.parent.nodeid, item.originalname


@pytest.fixture(autouse=True)
def _variant(request):
    """Every test starts in llvm_ad_rgb, or in the variant it is parametrized by (its
    ``variant`` argument), whatever the previous one switched to; after it, the process
    is back in llvm_ad_rgb (where fixtures and other modules expect it), except between
    two cases of one test parametrized by variant (the next one switches to its own):
    switching to a JIT variant runs Mitsuba's Python integrators again (~0.08 s of CPU),
    and the cases of such a test run variant by variant."""
    item = request.node
    want = declared_variant(item) or "llvm_ad_rgb"
    if mi.variant() != want:
        mi.set_variant(want)
    yield
    nextitem = item.stash.get(NEXT, None)
    stays = (declared_variant(item) is not None and nextitem is not None
             and _test(nextitem) == _test(item))
    if not stays and mi.variant() != "llvm_ad_rgb":
        mi.set_variant("llvm_ad_rgb")


#: the files that take longest (CPU seconds on an empty kernel cache, measured), run first:
#: ``make test`` hands whole files to its two processes in this order, so that no long file
#: starts last while the other process has nothing left to do
HEAVIEST_FIRST = ("test_bench_command.py", "test_check.py", "test_fit_measured.py",
                  "test_gradients.py", "test_models.py", "test_variants.py",
                  "test_fit_matrix_merl.py", "test_installed.py", "test_measured.py",
                  "test_presets.py", "test_explore_fuzz.py", "test_fit_measured_inputs.py",
                  "test_textures.py", "test_explore_measured.py", "test_fit_measured_judge.py",
                  "test_fit_matrix.py", "test_explore_browser.py", "test_new_model.py",
                  "test_scenes_lobes.py")


def pytest_collection_modifyitems(items):
    """The heaviest files first (``HEAVIEST_FIRST``), the others in their usual order; the
    cases of a test parametrized by variant variant by variant (in the order the variants
    first appear), so that the process switches variant once a variant (``_variant``)."""
    rank = {name: i for i, name in enumerate(HEAVIEST_FIRST)}
    first = {}
    for i, item in enumerate(items):
        first.setdefault(_test(item), i)
        first.setdefault((*_test(item), declared_variant(item)), i)
    items.sort(key=lambda item: (rank.get(item.path.name, len(rank)), first[_test(item)],
                                 first[(*_test(item), declared_variant(item))]))


def pytest_collection_finish(session):
    """What collection left alive (the modules, Mitsuba's bindings, Matplotlib, SciPy)
    is moved out of the garbage collector's sight: a collection then looks only at what
    the tests made. Tests collect before and after each render (``checks.py``), and with
    ~115,000 objects of the imported modules in sight a collection takes ~60 ms, with
    them frozen under 1 ms (the suite spent ~2 minutes of CPU on it). What collection made
    and dropped (BSDFs loaded to list parameters) is freed first, not frozen."""
    gc.collect()
    gc.freeze()
