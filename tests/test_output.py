"""Files written whole (``mitsuba_brdfs.output``): EXR and PNG, failed writes, targets that
may not be replaced, modes kept."""
import json
import os
import stat
import subprocess

import numpy as np
import OpenEXR
import pytest

from mitsuba_brdfs import output as O

# -- files --------------------------------------------------------------------------------

def test_exr_round_trip(tmp_path):
    rng = np.random.default_rng(0)
    img = (rng.random((7, 11, 3)) * 50).astype(np.float32)
    img[0, 0] = [1e-8, 65504.0 * 4, 0.0]
    path = tmp_path / "x.exr"
    O.write_exr(path, img)
    back, names = O.read_exr(path, names=True)
    assert back.dtype == np.float32 and back.shape == img.shape and names == ["R", "G", "B"]
    assert np.array_equal(back, img)
    assert os.listdir(tmp_path) == ["x.exr"]  # no temporary left behind


def test_exr_keeps_channel_names(tmp_path):
    img = np.arange(4 * 3 * 5, dtype=np.float32).reshape(4, 3, 5)
    names = ["R", "G", "B", "depth.T", "albedo.R"]
    O.write_exr(tmp_path / "a.exr", img, names)
    with OpenEXR.File(str(tmp_path / "a.exr"), separate_channels=True) as f:
        ch = {k: v.pixels for k, v in f.channels().items()}
    assert sorted(ch) == sorted(names)
    for i, n in enumerate(names):
        assert np.array_equal(ch[n], img[..., i])


def test_tonemap_is_srgb():
    x = np.array([[[0.0, 1.0, 0.5], [2.0, -1.0, 0.0031308]]])
    t = O.tonemap(x)
    assert t.dtype == np.uint8
    assert t[0, 0].tolist() == [0, 255, 188] and t[0, 1].tolist() == [255, 0, 10]


def test_failed_write_leaves_nothing(tmp_path, monkeypatch):
    path = tmp_path / "y.exr"
    O.write_exr(path, np.ones((2, 2, 3), np.float32))
    before = path.read_bytes()

    def boom(header, pixels, tmp):
        with open(tmp, "wb") as f:
            f.write(b"half")
        raise KeyboardInterrupt

    monkeypatch.setattr(O, "_write_openexr", boom)
    with pytest.raises(KeyboardInterrupt):
        O.write_exr(path, np.zeros((2, 2, 3), np.float32))
    assert path.read_bytes() == before and os.listdir(tmp_path) == ["y.exr"]


def test_exr_reads_back_through_openexr(tmp_path):
    rng = np.random.default_rng(1)
    img = (rng.random((5, 9, 3)) * 10).astype(np.float32)
    img[2, 3] = [0.0, 1e-6, 3e4]
    O.write_exr(tmp_path / "a.exr", img)
    with OpenEXR.File(str(tmp_path / "a.exr"), separate_channels=True) as f:
        ch = f.channels()
        back = np.stack([ch[c].pixels for c in "RGB"], axis=-1)
    assert back.dtype == np.float32 and np.array_equal(back, img)


@pytest.mark.parametrize("flag, word", [("+i", "immutable"), ("+a", "append-only")])
def test_an_immutable_or_append_only_target_is_not_called_read_only(tmp_path, flag, word):
    """A writable mode (0644) with chattr +i or +a: refused as immutable or append-only,
    not as read-only (``os.access`` says no write for these, root included), by
    ``check_target`` and by ``atomic`` alike; the file unchanged. Skipped where chattr is
    missing or the file system refuses the attribute."""
    path = tmp_path / "t.png"
    path.write_bytes(b"mine")
    path.chmod(0o644)
    try:
        done = subprocess.run(["chattr", flag, str(path)], capture_output=True).returncode == 0
    except FileNotFoundError:
        pytest.skip("no chattr here")
    try:
        if not done:
            pytest.skip(f"the file system refuses chattr {flag}")
        with pytest.raises(ValueError) as e:
            O.check_target(path, "-o t.png")
        message = str(e.value)
        assert word in message and "read-only" not in message and "refusing" in message, message
        with pytest.raises(OSError, match="immutable or append-only"):
            O.write_text(path, "theirs")
    finally:
        subprocess.run(["chattr", "-" + flag[1:], str(path)], capture_output=True)
    assert path.read_bytes() == b"mine" and sorted(os.listdir(tmp_path)) == ["t.png"]


def test_a_replaced_file_keeps_its_mode(tmp_path):
    path = tmp_path / "a.png"
    path.write_bytes(b"old")
    path.chmod(0o640)
    O.write_png(path, np.zeros((2, 2, 3), np.float32))
    assert stat.S_IMODE(path.stat().st_mode) == 0o640 and path.read_bytes() != b"old"
    O.write_text(tmp_path / "new.txt", "x")
    umask = os.umask(0)
    os.umask(umask)
    assert stat.S_IMODE((tmp_path / "new.txt").stat().st_mode) == 0o666 & ~umask


def test_jsonable_is_what_json_holds():
    """The package's one JSON contract: NumPy values as Python ones, tuples as lists, keys
    as strings, the non-finite floats JSON lacks as strings."""
    x = {1: (np.float32(0.5), np.int64(2), np.bool_(True)), "a": np.array([[1.0, np.inf]]),
         "b": [float("nan"), -float("inf"), np.float64(-np.inf)], "c": "inf", "d": None}
    assert O.jsonable(x) == {"1": [0.5, 2, True], "a": [[1.0, "inf"]],
                             "b": ["nan", "-inf", "-inf"], "c": "inf", "d": None}
    text = json.dumps(O.jsonable(x), allow_nan=False)  # valid JSON
    assert json.loads(text)["a"] == [[1.0, "inf"]]
    assert type(O.jsonable(np.float32(0.1))) is float and type(O.jsonable(np.int32(1))) is int
