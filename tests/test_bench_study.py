"""The performance study's record of where its numbers come from."""
from mitsuba_brdfs.bench import study


def test_git_info_names_the_commit():
    g = study.git_info()
    assert len(g["commit"]) == 40 and g["date"]
    assert isinstance(g["dirty"], list)
