"""The model catalog: it renders what is registered and says what it leaves out."""
from mitsuba_brdfs.figures import catalog as C


def test_catalog_skips_unregistered_plugins(tmp_path, capsys):
    entries = [("lambert-like", {"type": "diffuse"}),
               ("missing", {"type": "no_such_model_yet"}),
               ("as", {"type": "ashikhmin_shirley", "nu": 50.0, "nv": 50.0})]
    t = C.render_catalog(out_dir=str(tmp_path), spp=1, res=8, entries=entries)
    out = capsys.readouterr().out
    assert "skipping 'missing'" in out and "no_such_model_yet" in out
    assert t["panels"] == 2 and t["shown"] == ["lambert-like", "as"]
    assert (tmp_path / "catalog.png").exists() and (tmp_path / "catalog_2.exr").exists()
    assert C.render_catalog(out_dir=str(tmp_path), entries=entries[1:2])["panels"] == 0


def test_every_catalog_entry_loads():
    """No catalog entry is skipped: every model, form and option of the catalog loads."""
    notes = []
    assert len(C.available(note=notes.append)) == len(C.CATALOG) and not notes, notes
