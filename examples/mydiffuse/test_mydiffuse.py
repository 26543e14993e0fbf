"""The pytest file of the README's testing example: ``pytest examples/mydiffuse``."""
import mitsuba as mi
import pytest

mi.set_variant("llvm_ad_rgb")

import mydiffuse  # noqa: E402,F401  (defines the plugin in this variant and registers it)
from mitsuba_brdfs.validate import assert_valid  # noqa: E402


@pytest.mark.parametrize("reflectance", [0.0, 0.5, 1.0])
def test_mydiffuse_passes_every_check(reflectance):
    # strict: a warning (a NaN where integrators would mask it) fails too;
    # reciprocal: a BSDF that is not reciprocal fails (by default it is a NOTE)
    assert_valid({"type": "mydiffuse", "reflectance": reflectance}, strict=True,
                 reciprocal=True)
