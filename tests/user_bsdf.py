"""The tests' user BSDF: a Lambertian plugin as a user writes it in Python, with one flaw
chosen by its string parameter ``flaw`` (the checks must each find their own), one source for
every test that needs a user's plugin.

``SOURCE`` is the plugin file's text, as ``--load FILE.py`` runs it (``write(path, name)``
writes it, registered under ``name``); ``register(name)`` defines the class in the active
variant and registers it in this process. Parameters: ``reflectance`` (a float or an RGB
colour; 0.5), ``flaw``:

- ``none``: sound;
- ``below``: light below the horizon (eval uses |cos theta_o|);
- ``cosine``: the README's forgotten cosine (eval without cos theta_o, the samples still
  weighing the reflectance);
- ``nan``: NaN at grazing incidence; ``negative``: negative values near the horizon;
- ``asymmetric``: eval not reciprocal;
- ``scalar``: 1 % more in scalar variants than in JIT ones;
- ``masked``: a NaN pdf across the surface, where eval is 0 (what integrators mask);
- ``pdf``: pdf() twice the density of the samples (their weights eval / pdf follow it);
- ``pdf_shape``: pdf() of another shape than the samples' density, their weights still
  eval / density;
- ``weight``: sample weights 1.3 times eval / pdf;
- ``divide``: a division by a pdf of 0 (which raises in scalar variants);
- ``raise``: eval and sample raise (a plugin that fails).

``HOOK`` (set through ``set_hook``), when not None, is called at the start of each method:
a test's gate, to hold a check or a render while it looks.
"""
import textwrap

__all__ = ["SOURCE", "write", "register", "set_hook"]

SOURCE = textwrap.dedent('''
    import drjit as dr
    import mitsuba as mi

    #: called at the start of each method when not None (a test's gate)
    HOOK = None
    #: the reflectance and the flaw when none is given
    REFLECTANCE, FLAW = 0.5, "none"


    def _hook():
        if HOOK is not None:
            HOOK()


    class UserDiffuse(mi.BSDF):
        def __init__(self, props):
            mi.BSDF.__init__(self, props)
            self.flaw = props.get("flaw", FLAW)
            rho = props.get("reflectance", REFLECTANCE)
            self.rho = mi.Color3f(*rho) if hasattr(rho, "__len__") else mi.Color3f(rho)
            self.m_components = [mi.BSDFFlags.DiffuseReflection | mi.BSDFFlags.FrontSide]
            self.m_flags = self.m_components[0]

        def eval(self, ctx, si, wo, active=True):
            _hook()
            if self.flaw == "raise":
                raise ValueError("the user's plugin fails")
            cos_o = dr.abs(wo.z) if self.flaw == "below" else dr.maximum(wo.z, 0)
            if self.flaw == "cosine":
                cos_o = dr.select(wo.z > 0, 1.0, 0.0)
            f = cos_o / dr.pi * (si.wi.z > 0)
            if self.flaw == "asymmetric":
                f *= 1 + si.wi.x
            if self.flaw == "nan":
                f *= dr.sqrt(si.wi.z - 1e-6) / dr.sqrt(si.wi.z)
            if self.flaw == "negative":
                f *= 1.25 * wo.z - 0.25 * (wo.z > 0)
            if self.flaw == "scalar" and not dr.is_jit_v(mi.Float):
                f *= 1.01
            return self.rho * f

        def pdf(self, ctx, si, wo, active=True):
            _hook()
            pdf = mi.warp.square_to_cosine_hemisphere_pdf(wo) * ((si.wi.z > 0) & (wo.z > 0))
            if self.flaw == "masked":  # NaN across the surface, where eval is 0
                pdf = dr.select(wo.z < 0, dr.nan, pdf)
            if self.flaw == "pdf_shape":
                pdf *= 1 + 0.5 * wo.x
            return 2 * pdf if self.flaw == "pdf" else pdf

        def eval_pdf(self, ctx, si, wo, active=True):
            return self.eval(ctx, si, wo, active), self.pdf(ctx, si, wo, active)

        def sample(self, ctx, si, sample1, sample2, active=True):
            _hook()
            if self.flaw == "raise":
                raise ValueError("the user's plugin fails")
            bs = dr.zeros(mi.BSDFSample3f, dr.width(sample2))
            bs.wo = mi.warp.square_to_cosine_hemisphere(sample2)
            bs.pdf = self.pdf(ctx, si, bs.wo)
            bs.eta = 1.0
            bs.sampled_type = mi.UInt32(+mi.BSDFFlags.DiffuseReflection)
            if self.flaw == "pdf_shape":  # the samples' own density, whatever pdf() claims
                pdf = mi.warp.square_to_cosine_hemisphere_pdf(bs.wo)
            else:  # (in a scalar variant a Python float division by a pdf of 0 raises)
                pdf = bs.pdf if self.flaw == "divide" else dr.maximum(bs.pdf, 1e-30)
            weight = self.eval(ctx, si, bs.wo) / pdf
            if self.flaw == "weight":
                weight *= 1.3
            if self.flaw == "cosine":  # the reflectance, as if eval had its cosine
                weight = self.rho
            return bs, dr.select(bs.pdf > 0, weight, 0)

        def traverse(self, callback):
            pass

        def to_string(self):
            return f"UserDiffuse[flaw={self.flaw}]"


    def register(name):
        mi.register_bsdf(name, lambda props: UserDiffuse(props))
''')

#: the namespaces ``register`` ran the source in (one per registration)
_NAMESPACES = []


def write(path, name, reflectance=0.5, flaw="none", hook=""):
    """The plugin file: ``SOURCE``, registering the plugin as ``name`` (of default
    ``reflectance`` and ``flaw``) when it is run; ``hook``: source code that defines
    ``HOOK`` there."""
    with open(path, "w") as f:
        f.write(SOURCE + f"\nREFLECTANCE, FLAW = {reflectance!r}, {flaw!r}\n{hook}\n"
                f"register({name!r})\n")
    return str(path)


def register(name, reflectance=0.5, flaw="none"):
    """Define the plugin in the active variant and register it as ``name`` (of default
    ``reflectance`` and ``flaw``)."""
    namespace = {}
    exec(compile(SOURCE, "user_bsdf", "exec"), namespace)
    namespace["REFLECTANCE"], namespace["FLAW"] = reflectance, flaw
    namespace["register"](name)
    _NAMESPACES.append(namespace)


def set_hook(hook):
    """Call ``hook()`` at the start of each method of the plugins ``register`` made."""
    for namespace in _NAMESPACES:
        namespace["HOOK"] = hook
