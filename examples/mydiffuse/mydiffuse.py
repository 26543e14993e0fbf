"""mydiffuse: a user's Lambertian BSDF, the plugin file of the README's testing example.

Import it once a variant is set (``mi.set_variant(...)``): it defines the class in that
variant and registers it as ``mydiffuse``; ``python -m mitsuba_brdfs check mydiffuse
--load mydiffuse.py`` runs it the same way.
"""
import drjit as dr
import mitsuba as mi


class MyDiffuse(mi.BSDF):
    """Lambertian reflection, f = reflectance / pi, sampled cosine-weighted."""

    def __init__(self, props):
        mi.BSDF.__init__(self, props)
        self.reflectance = props.get("reflectance", 0.5)
        self.m_components = [mi.BSDFFlags.DiffuseReflection | mi.BSDFFlags.FrontSide]
        self.m_flags = self.m_components[0]

    def sample(self, ctx, si, sample1, sample2, active=True):
        bs = dr.zeros(mi.BSDFSample3f)
        bs.wo = mi.warp.square_to_cosine_hemisphere(sample2)
        bs.pdf = self.pdf(ctx, si, bs.wo, active)
        bs.eta = 1.0
        bs.sampled_type = +mi.BSDFFlags.DiffuseReflection
        # eval / pdf = reflectance: the cosine and 1/pi cancel
        return bs, mi.Color3f(self.reflectance) & (bs.pdf > 0)

    def eval(self, ctx, si, wo, active=True):
        up = (si.wi.z > 0) & (wo.z > 0)
        return mi.Color3f(self.reflectance / dr.pi * wo.z) & up

    def pdf(self, ctx, si, wo, active=True):
        up = (si.wi.z > 0) & (wo.z > 0)
        return dr.select(up, mi.warp.square_to_cosine_hemisphere_pdf(wo), 0.0)

    def eval_pdf(self, ctx, si, wo, active=True):
        return self.eval(ctx, si, wo, active), self.pdf(ctx, si, wo, active)

    def to_string(self):
        return f"MyDiffuse[reflectance={self.reflectance}]"


mi.register_bsdf("mydiffuse", lambda props: MyDiffuse(props))
