"""Error messages of the command line as a new user meets them: a plugin's error keeps its
quotes, a misspelt parameter is called unknown with the closest name the plugin takes, and
``check`` names the BSDFs of a scene by their plugin type."""
from cmdline import run_many

SCENE = """<scene version="3.0.0">
  <shape type="sphere"><bsdf type="lambert"/></shape>
  <shape type="sphere" id="floor"><bsdf type="diffuse"/></shape>
</scene>
"""
BAD = """<scene version="3.0.0">
  <shape type="sphere"><bsdf type="lambert"><float name="reflectance" value="1.5"/></bsdf></shape>
</scene>
"""
MISSPELT = """<scene version="3.0.0">
  <shape type="sphere"><bsdf type="ward"><float name="alpah_u" value="0.1"/></bsdf></shape>
</scene>
"""


def test_messages(tmp_path):
    for name, text in (("scene.xml", SCENE), ("bad.xml", BAD), ("misspelt.xml", MISSPELT)):
        (tmp_path / name).write_text(text)
    (misspelt, unknown_mitsuba, typo_toon, scene, bad, render_misspelt) = run_many([
        ["check", "ward", "-p", "alpah_u=0.1", "--quick"],
        ["check", "roughplastic", "-p", "alpah=0.1", "--quick"],
        ["check", "toon", "-p", "specular_rmp=0.1", "--quick"],
        ["check", tmp_path / "scene.xml", "--quick", "--only", "flags"],
        ["render", tmp_path / "bad.xml", "-o", tmp_path / "bad.exr"],
        ["render", tmp_path / "misspelt.xml", "-o", tmp_path / "misspelt.exr"],
    ], cwd=tmp_path)
    assert misspelt[0] == 2
    assert misspelt[2].strip() == (
        "error: ward: unknown parameter 'alpah_u' (did you mean 'alpha_u'?); ward takes "
        "specular_reflectance, diffuse_reflectance, alpha_u, alpha_v, form")
    # Mitsuba's own plugins: the closest name that its exposed parameters offer
    assert unknown_mitsuba[0] == 2
    assert "roughplastic: unknown parameter 'alpah' (did you mean 'alpha'?)" in unknown_mitsuba[2]
    assert "did you mean 'specular_ramp'?" in typo_toon[2]
    # a scene's BSDFs named by their plugin type and their shape
    assert scene[0] == 0, scene[2]
    assert "lambert (shape 0): PASS" in scene[1]
    assert "diffuse (shape 'floor'): PASS" in scene[1]
    # a plugin's error keeps the closing quote of its type
    assert bad[0] == 2
    assert 'plugin of type "lambert": ParameterError: lambert: parameter' in bad[2]
    assert "unknown parameter 'alpah_u' (did you mean 'alpha_u'?)" in render_misspelt[2]


# -- unknown plugin names: one function, every command -----------------------------------------

def test_unknown_plugin_names_get_the_closest_name_of_their_kind():
    from mitsuba_brdfs.messages import explain_unknown, plugin_names, unknown_plugin
    bsdfs = plugin_names("bsdf")
    assert {"diffuse", "roughplastic", "ward", "ashikhmin_shirley"} <= set(bsdfs)
    assert "sphere" not in bsdfs and "sphere" in plugin_names("shape")
    assert unknown_plugin("wardd", "bsdf") == "unknown plugin 'wardd' (did you mean 'ward'?)"
    assert unknown_plugin("roughplastik", "bsdf").endswith("(did you mean 'roughplastic'?)")
    assert unknown_plugin("spheer", "shape", say_kind=True) == \
        "unknown shape plugin 'spheer' (did you mean 'sphere'?)"
    assert unknown_plugin("qqqqqq") == "unknown plugin 'qqqqqq'"
    # Mitsuba's parser message, from a file and from a dictionary
    assert explain_unknown('At s.xml (line 4, col 6): failed to instantiate bsdf plugin of '
                           'type "wardd": [PluginManager] Plugin "wardd" not found!') == \
        "s.xml (line 4, col 6): unknown bsdf plugin 'wardd' (did you mean 'ward'?)"
    assert explain_unknown('At dictionary node "root": failed to instantiate unknown plugin '
                           'of type "wardd": [PluginManager] Plugin "wardd" not found!') == \
        "unknown plugin 'wardd' (did you mean 'ward'?)"


def test_every_command_suggests_the_plugin_name(tmp_path):
    """check, explore, render and a scene file go through ``messages.unknown_plugin``; a
    plugin that a --load file registers is among the names suggested."""
    (tmp_path / "typo.xml").write_text(
        '<scene version="3.0.0"><integrator type="path"/>\n'
        '<shape type="sphere"><bsdf type="ashikmin_shirley"/></shape></scene>')
    (tmp_path / "mybsdf.py").write_text(
        "import mitsuba as mi\n"
        "mi.register_bsdf('mybsdf', lambda props: mi.load_dict({'type': 'diffuse'}))\n")
    cases = [["check", "wardd"], ["check", tmp_path / "typo.xml"],
             ["render", tmp_path / "typo.xml"], ["explore", "wardd", "--no-browser"],
             ["check", "mybsdff", "--load", tmp_path / "mybsdf.py"]]
    results = run_many(cases, cwd=tmp_path)
    for argv, (code, out, err) in zip(cases, results):
        assert code == 2 and out == "" and len(err.strip().splitlines()) == 1, (argv, err)
    check, scene, render, explore, loaded = (r[2] for r in results)
    assert "unknown plugin 'wardd' (did you mean 'ward'?)" in check
    assert "unknown plugin 'wardd' (did you mean 'ward'?)" in explore
    for err in (scene, render):
        assert ("typo.xml (line 2, col 23): unknown bsdf plugin 'ashikmin_shirley' (did you "
                "mean 'ashikhmin_shirley'?)") in err, err
    assert "unknown plugin 'mybsdff' (did you mean 'mybsdf'?)" in loaded
    assert sorted(p.name for p in tmp_path.iterdir()) == ["mybsdf.py", "typo.xml"]


def test_the_explorer_page_suggests_the_plugin_name():
    """A SPEC typed into the explorer's page: its API answers with the suggestion."""
    pytest = __import__("pytest")
    pytest.importorskip("starlette")
    from mitsuba_brdfs.explore.entries import EntryError
    from mitsuba_brdfs.explore.session import Explorer
    with pytest.raises(EntryError, match=r"unknown plugin 'wardd' \(did you mean 'ward'\?\)"):
        Explorer([], "llvm_ad_rgb").add("wardd")
