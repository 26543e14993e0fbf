"""Error messages of the command line as a new user meets them: a plugin's error keeps its
quotes, a misspelt parameter is called unknown with the closest name the plugin takes, and
``check`` names the BSDFs of a scene by their plugin type."""
import re

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
    (misspelt, unknown_mitsuba, typo_toon, scene, bad, render_misspelt, unused_d,
     unused_p) = run_many([
        ["check", "ward", "-p", "alpah_u=0.1", "--quick"],
        ["check", "roughplastic", "-p", "alpah=0.1", "--quick"],
        ["check", "toon", "-p", "specular_rmp=0.1", "--quick"],
        ["check", tmp_path / "scene.xml", "--quick", "--only", "flags"],
        ["render", tmp_path / "bad.xml", "-o", tmp_path / "bad.exr"],
        ["render", tmp_path / "misspelt.xml", "-o", tmp_path / "misspelt.exr"],
        ["render", "scene.xml", "-D", "res=16"],
        ["check", "scene.xml", "-p", "res=16"],
    ], cwd=tmp_path)
    # a -D (render) or -p (check) the scene has no $KEY for: the file and the option named
    assert unused_d[0] == 2 and unused_d[2] == (
        "error: scene.xml: Found unused parameters: $res=16 (a -D KEY=VALUE whose $KEY the "
        "scene does not use)\n"), unused_d
    assert unused_p[0] == 2 and "(a -p KEY=VALUE whose $KEY" in unused_p[2], unused_p
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
    # a plugin's error: where in the file, the plugin once, its own message
    assert bad[0] == 2
    assert re.fullmatch(r"error: \S*bad\.xml \(line 2, col \d+\): lambert: parameter "
                        r"'reflectance' must be a reflectance in \[0, 1\] .*\(got 1\.5\)\n",
                        bad[2]), bad[2]
    assert re.search(r"misspelt\.xml \(line 2, col \d+\): ward: unknown parameter 'alpah_u' "
                     r"\(did you mean 'alpha_u'\?\)", render_misspelt[2]), render_misspelt[2]


def test_a_plugins_error_is_said_once_after_where():
    """Mitsuba wraps what a plugin raises in its parser's context ("At FILE (line, col):
    failed to instantiate bsdf plugin of type ..."): the line says where, the plugin's name
    once and its message; Mitsuba's C++ class tags go, a user's exception keeps its class."""
    from mitsuba_brdfs.messages import one_line
    tb = ("Traceback (most recent call last):\n  File \"<string>\", line 4, in <module>\n"
          "  File \"/x/params.py\", line 244, in scalar\n")
    cases = {
        ('[parser.cpp:1718] At s.xml (line 5, col 27): failed to instantiate bsdf plugin of '
         'type "ward": ' + tb + "ParameterError: ward: parameter 'alpha_u' must be an RMS slope "
         "in [0.0001, 1] (got 7)"):
        "s.xml (line 5, col 27): ward: parameter 'alpha_u' must be an RMS slope in [0.0001, 1] "
        "(got 7)",
        ('[parser.cpp:1718] At dictionary node "root": failed to instantiate unknown plugin of '
         'type "ward": ' + tb + "ParameterError: ward: parameter 'form' must be one of 'ward', "
         "'duer', 'balanced' (got 'wardd')"):
        "ward: parameter 'form' must be one of 'ward', 'duer', 'balanced' (got 'wardd')",
        ('[parser.cpp:1718] At dictionary node "b": failed to instantiate unknown plugin of '
         'type "mybsdf": ' + tb + "ZeroDivisionError: division by zero"):
        'dictionary node "b": mybsdf: ZeroDivisionError: division by zero',
        ('[parser.cpp:1718] At n.xml (line 2, col 49): failed to instantiate bsdf plugin of '
         'type "diffuse": [SRGBReflectanceSpectrum] Invalid RGB reflectance value [2, 2, 2], '
         'must be in the range [0, 1]!'):
        "n.xml (line 2, col 49): diffuse: Invalid RGB reflectance value [2, 2, 2], must be in "
        "the range [0, 1]!",
        ('[parser.cpp:444] While loading n.xml (line 2, col 49): Found 1 unreferenced property '
         'in bsdf plugin of type "ward":\n  - float "alpah_u": 0.7'):
        "n.xml (line 2, col 49): ward: unknown parameter 'alpah_u' (did you mean 'alpha_u'?); "
        "ward takes specular_reflectance, diffuse_reflectance, alpha_u, alpha_v, form",
        "Found unused parameters: res": "Found unused parameters: res (a -D KEY=VALUE whose "
                                        "$KEY the scene does not use)",
    }
    for raw, said in cases.items():
        assert one_line(raw) == said, raw


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
