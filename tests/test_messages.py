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
