"""fit-measured across models at MERL's resolution (90 x 90 x 180 bins), with the quick
tests' pairs and budget (3000 pairs, 400 evaluations; ``scripts/fit_matrix.py`` runs the
command's defaults): a file of each source model's material (Ngan et al.'s fits of gold-paint:
Ward's, and Ashikhmin-Shirley's with its Lambertian diffuse term; random materials of the
others), fitted by every other model; each verdict 'within' or 'cannot reach', as
tests/test_fit_matrix.py judges them (``mitsuba_brdfs.measured.matrix``). A file of its
own, so that the test processes share the matrix."""
import pytest

from mitsuba_brdfs.measured import merl
from checks import check_fit_matrix


@pytest.mark.slow
@pytest.mark.parametrize("source, name", [("ward", "gold-paint"), ("cook_torrance", "random-2"),
                                          ("ashikhmin_shirley", "random-2"),
                                          ("ashikhmin_shirley_lambert", "gold-paint"),
                                          ("blinn_phong", "random-3")])
def test_every_other_model_fits_or_is_shown_unable_at_merl_resolution(tmp_path, source, name):
    """Each source model's material at MERL's resolution: each verdict one of the two."""
    check_fit_matrix(tmp_path / "m.binary", source, name, merl.DIMS, samples=3000,
                     evaluations=400)
