"""The pytest file of the README's testing example: ``pytest examples/mydiffuse``."""
import mitsuba as mi
import pytest

mi.set_variant("llvm_ad_rgb")

import mydiffuse  # noqa: E402,F401  (registers "mydiffuse" in this variant)
from mitsuba_brdfs.validate import assert_valid  # noqa: E402


@pytest.mark.parametrize("reflectance", [0.0, 0.5, 1.0])
def test_mydiffuse_passes_every_check(reflectance):
    assert_valid({"type": "mydiffuse", "reflectance": reflectance}, reciprocal=True)


def test_mydiffuse_is_valid_in_scalar_rgb():
    assert_valid("mydiffuse", variant="scalar_rgb")
