"""fit-measured across models at MERL's resolution (90 x 90 x 180 bins), with the quick
tests' pairs and budget (3000 pairs, 400 evaluations; ``scripts/fit_matrix.py`` runs the
command's defaults): a file of each source model's material (Ngan et al.'s fits of gold-paint:
Ward's, and Ashikhmin-Shirley's with its Lambertian diffuse term; random materials of the
others), each fitted by two other models, every model fitting two of them (``PAIRS``);
each verdict 'within' or 'cannot reach', as tests/test_fit_matrix.py judges them (``mitsuba_brdfs.measured.matrix``). A file of its
own, so that the test processes share the matrix."""
import pytest

from mitsuba_brdfs.measured import merl
from checks import check_fit_matrix


#: (source model, its material, the models that fit it): each source by two others, each
#: model fitting two sources (the whole matrix: ``scripts/fit_matrix.py``)
PAIRS = [("ward", "gold-paint", ["cook_torrance", "ashikhmin_shirley_lambert"]),
         ("cook_torrance", "random-2", ["ward", "blinn_phong"]),
         ("ashikhmin_shirley", "random-2", ["cook_torrance", "ashikhmin_shirley_lambert"]),
         ("ashikhmin_shirley_lambert", "gold-paint", ["ashikhmin_shirley", "blinn_phong"]),
         ("blinn_phong", "random-3", ["ashikhmin_shirley", "ward"])]


@pytest.mark.slow
@pytest.mark.parametrize("source, name, models", PAIRS, ids=[f"{s}-{n}" for s, n, _ in PAIRS])
def test_other_models_fit_or_are_shown_unable_at_merl_resolution(tmp_path, source, name,
                                                                 models):
    """Each source model's material at MERL's resolution: each verdict one of the two."""
    out = check_fit_matrix(tmp_path / "m.binary", source, name, merl.DIMS, samples=3000,
                           evaluations=400, models=models)
    assert sorted(out) == sorted(models)
