"""The figures of Ashikhmin & Shirley 2000 (Figures 1-4 and 6) and the sphere of
``scenes/as_sphere.xml``.

Each scene says in its comment block what it shows, why its light and camera, and how
its integrator was chosen; ``Figure.check`` names the panels whose integrator
``python -m mitsuba_brdfs figures --check`` compares with a deeper path tracer.
"""
from .panels import Figure, Panel

__all__ = ["FIGURES", "EXPONENTS", "VIEWS"]

EXPONENTS = (10, 100, 1000, 10000)
VIEWS = ((10, "near-normal"), (60, "oblique"), (84, "grazing"))

FIGURES = {f.name: f for f in [
    Figure("as_sphere", "Ashikhmin-Shirley sphere: nu = 20, nv = 1000, Rs = 0.05, red Rd",
           [Panel("as_sphere.xml")], spp={"preview": 64, "final": 256},
           res={"preview": 256, "final": 512}),
    # Fig. 1: nu grows along a row, nv down a column; u is horizontal on screen
    Figure("fig1_exponents",
           "Fig. 1: metal spheres (Rd = 0). nu (exponent along u, horizontal on screen) "
           "grows to the right, nv (along v, vertical) downward",
           [Panel("fig1_exponents.xml", f"nu = {nu}, nv = {nv}", {"nu": nu, "nv": nv})
            for nv in EXPONENTS for nu in EXPONENTS],
           spp={"preview": 256, "final": 1024}, res={"preview": 160, "final": 320}, columns=4,
           check=(0, 8)),  # nu = nv = 10 and nu = 10, nv = 1000
    # Fig. 2: the exponents are given per direction on the cylinder (see the scene)
    Figure("fig2_brushed_cylinder",
           "Fig. 2: brushed metal cylinder, Rd = 0, Rs = 0.9, nu = 10, nv = 100",
           [Panel("fig2_brushed_cylinder.xml",
                  "u along the axis (nu = 10), v around (nv = 100): brushed around the "
                  "cylinder, the highlight streaks along it",
                  {"n_axis": 10, "n_around": 100}),
            Panel("fig2_brushed_cylinder.xml",
                  "u and v swapped (Mitsuba's own mapping, u around): brushed along the "
                  "axis, the highlight spreads around",
                  {"n_axis": 100, "n_around": 10})],
           spp={"preview": 256, "final": 1024}, res={"preview": 320, "final": 640},
           check=(0, 1)),
    Figure("fig3_polished",
           "Fig. 3: polished red floor, nu = nv = 400, Rs = 0.05, from near-normal to grazing",
           [Panel("fig3_polished.xml", f"{a} deg from the normal ({name})", {"view": a})
            for a, name in VIEWS],
           spp={"preview": 256, "final": 1024}, res={"preview": 288, "final": 576},
           check=(0, 2)),
    Figure("fig4_lambert_vs_as",
           "Fig. 4: a Lambertian sphere and an ashikhmin_shirley sphere with nu = nv = 5",
           [Panel("fig4_lambert_vs_as.xml",
                  "left: Lambert (Mitsuba's diffuse); right: ashikhmin_shirley nu = nv = 5, "
                  "Rs = 0.05; the same diffuse colour")],
           spp={"preview": 256, "final": 1024},
           res={"preview": (480, 240), "final": (960, 480)}),
    # Fig. 6 is about the sample counts: they stay 9, 26, 100 at every quality
    Figure("fig6_sampling", "Fig. 6: path tracer with the paper's sampling at 9, 26, 100 spp",
           [Panel("fig6_sampling.xml", f"{n} spp", spp=n) for n in (9, 26, 100)],
           spp={"preview": 100, "final": 100}, res={"preview": 288, "final": 576}),
]}
