"""The diffuse + glossy two-lobe BSDF that every model of the package specialises.

A model supplies the physics of its lobes as small methods; this base supplies what all
two-lobe reflectance models do alike (as Mitsuba's roughplastic does):

- flags and components: one glossy component, then one diffuse one, for the lobes the
  model has (``LOBES``), fixed when the plugin is built, so that wrappers, which copy the
  flags, stay right after any update; a lobe whose weight is a constant zero (a metal's
  diffuse lobe) does no work: it is neither sampled nor traced into the kernel, until an
  update gives it a weight or a parameter is differentiated (``_live``);
- every parameter is checked against its range at load and again when ``params.update()``
  changes it (``parameters_changed``), with the same message;
- frozen functions (``@dr.freeze``): which lobes are traced is a Python decision, which a
  frozen function cannot see; so the plugin also holds a Dr.Jit value whose type encodes
  it (``_lobe_key``), and a frozen function records anew when the lobes change instead of
  replaying the kernel of the other lobes;
- ``ctx.component`` / ``ctx.type_mask``: a disabled lobe is neither evaluated nor sampled;
  ``ctx.is_enabled`` is a Python bool, so each context traces only its own lobes;
- sampling: pick a lobe with probability proportional to its estimated albedo at the
  incident direction, sample it, then evaluate the whole mixture at the sampled
  direction: ``pdf`` is the weighted average of the lobe pdfs and ``weight = eval / pdf``;
- ``sampling = cosine`` (``cosine_only``) replaces all of it by cosine-weighted sampling,
  the baseline that prices importance sampling;
- one-sided: both directions must be above the surface, else 0;
- polarization: the models are unpolarized, so in ``*_polarized`` variants every value
  ``eval``/``sample`` return is a depolarizer Mueller matrix (``mi.depolarizer``), as
  Mitsuba's ``diffuse`` and ``roughplastic`` return; the lobes compute plain
  ``UnpolarizedSpectrum`` colours in every variant;
- albedo: ``eval_diffuse_reflectance`` (the ``aov`` integrator's ``albedo``) returns the
  diffuse colour, or where that is black (a metal) the specular colour at normal
  incidence, clamped to [0, 1] (see ``eval_diffuse_reflectance``). ``has_attribute`` and
  ``eval_attribute[_1|_3]`` are Mitsuba's own: its ``BSDF`` base finds the parameter
  textures through ``traverse``, as for its C++ plugins (none of which overrides them).

A model class implements the methods that ``TwoLobeModel`` declares and leaves
unimplemented (each says its contract in one line; they act on ``p``, the model's
``Point`` of parameter values that ``_at`` evaluates at the shading point), and sets the
class attributes below (``LOBES``, ``GLOSSY_EXTRA_FLAGS``, ``cosine_only``, ``RECIPROCAL``).
Only what a model's sampling reaches is needed: a model with a diffuse lobe alone needs no
glossy methods nor albedo estimates, and a ``cosine_only`` model (``toon``) needs neither
glossy sampler nor estimates (its lobe is never chosen between).

``lambert_f`` is the Lambertian term every diffuse lobe of the package is built on.

Methods are copied into a ``mi.BSDF`` subclass per variant (see ``plugin.py``): model
code calls base methods through ``self`` and never uses ``super()``.
"""
import drjit as dr
import mitsuba as mi

from .frame import cos_theta
from .numerics import channel_mean, safe_div
from .params import ParamReader, check_range, constructing, texture_range
from . import relations

__all__ = ["TwoLobeModel", "LambertDiffuseModel", "Point", "lambert_f"]


def _values(tex, params=None):
    """The texture's parameters (key -> Dr.Jit value), to take a refused update back
    (``params``: ``mi.traverse(tex)``, where the caller has it).

    ``params.update()`` assigns new values into the texture's own arrays, so each value is
    held as a new, detached array object on the same data (Dr.Jit copies on write: no data
    is copied, and no gradient graph is kept alive).
    """
    params = mi.traverse(tex) if params is None else params
    return {k: type(params[k])(dr.detach(params[k])) for k in params.keys()}


def _restore(tex, values):
    params = mi.traverse(tex)
    for k, v in values.items():
        params[k] = v
    params.update()


def _lobe_key(present):
    """A Dr.Jit value whose type says which lobes are present, or None (scalar variants).

    ``@dr.freeze`` decides whether it may replay a recording from the Dr.Jit values it
    finds in its inputs (a plugin's attributes among them), their types included; it does
    not see Python values such as ``_present``. Holding this value as an attribute makes a
    change of the lobes a change of type, so the frozen function records the kernel of the
    new lobes (once; it is cached beside the other).
    """
    if not dr.is_jit_v(mi.Float):
        return None
    kind = {(True, True): mi.Float, (True, False): mi.UInt32, (False, True): mi.Int32,
            (False, False): mi.Bool}[tuple(bool(x) for x in present)]
    return dr.zeros(kind, 1)


def _as(cls, x):
    """x as the Dr.Jit type ``cls`` (``mi.Vector3f``, ``mi.Point2f``, ``mi.Float``,
    ``mi.Bool``): a Python list, tuple or number converted as Mitsuba's bindings convert the
    arguments of its C++ plugins, so ``bsdf.eval(ctx, si, wo=[0, 0, 1])`` and
    ``bsdf.sample(ctx, si, 0.5, [0.5, 0.5])`` work as they do for ``diffuse``."""
    return x if isinstance(x, cls) else cls(x)


def lambert_f(rho, wo):
    """rho / pi cos(theta_o): the Lambertian term with its cosine (wo = light direction)."""
    return rho * dr.inv_pi * cos_theta(wo)


class Point:
    """A model's parameter values at one shading point: what ``_at`` returns and every lobe
    method reads as ``p``. A model subclasses it with its fields as ``__slots__`` and fills
    them by keyword (``_At(kd=..., ks=...)``)."""
    __slots__ = ()

    def __init__(self, **values):
        for name, value in values.items():
            setattr(self, name, value)


class TwoLobeModel:
    """Base of the package's reflectance models (see the module docstring).

    ``NAME``, the plugin name, is set by ``core.registry.bsdf_plugin``.
    """

    #: the model's load-time choices (its forms): parameter name -> the values it accepts,
    #: which the model reads them with, and tests and the study enumerate
    OPTIONS = {}
    #: relations between the model's parameters (``core.relations``): checked at load,
    #: stated by the manual, followed by the explorer's controls
    RELATIONS = ()
    #: the model's lobes (glossy, diffuse): each one is a component of the BSDF
    LOBES = (True, True)
    #: extra flags of the glossy component (e.g. Anisotropic)
    GLOSSY_EXTRA_FLAGS = 0
    #: True when every direction is drawn from the cosine-weighted hemisphere
    cosine_only = False
    #: False for models whose f(light, viewer) is not symmetric (e.g. original Phong):
    #: under TransportMode.Importance the roles of wi and wo are then swapped
    RECIPROCAL = True

    # -- construction -------------------------------------------------------------------

    def __init__(self, props):
        mi.BSDF.__init__(self, props)
        with constructing():  # see ``params.constructing``: no nested waits for kernels
            reader = ParamReader(self.NAME, props)
            relations.check(reader, self.RELATIONS, self.OPTIONS)
            self._read_parameters(reader)
            self._ranges = reader.ranges
            # the values of textures given as numbers or colours: nothing is read back
            # from a kernel for them while the scene loads
            self._known = {id(tex): reader.known[name]
                           for name, tex in self._textures().items() if name in reader.known}
            self._declare_components()
            self.parameters_changed([])

    def traverse(self, callback):
        for name, tex in self._textures().items():
            callback.put(name, tex, mi.ParamFlags.Differentiable)

    def _declare_components(self):
        """One component per lobe of the model (``LOBES``), fixed for the plugin's life.

        Wrappers (twosided, blendbsdf, mask, normalmap, ...) copy the flags when they are
        built, so the flags must already hold every lobe that an update could switch on; a
        lobe whose weight is zero is kept out of the kernel instead (``_enabled``).
        """
        has_glossy, has_diffuse = self.LOBES
        varying = any(t.is_spatially_varying() for t in self._textures().values())
        extra = mi.BSDFFlags.SpatiallyVarying if varying else mi.BSDFFlags.Empty
        comps = []
        self.glossy_index = self.diffuse_index = -1
        if has_glossy:
            self.glossy_index = len(comps)
            comps.append(mi.BSDFFlags.GlossyReflection | mi.BSDFFlags.FrontSide
                         | self.GLOSSY_EXTRA_FLAGS | extra)
        if has_diffuse:
            self.diffuse_index = len(comps)
            comps.append(mi.BSDFFlags.DiffuseReflection | mi.BSDFFlags.FrontSide | extra)
        flags = mi.BSDFFlags.Empty
        for c in comps:
            flags = flags | c
        # whole lists: appending to m_components in place does not reach C++
        self.m_components = comps
        self.m_flags = flags

    def parameters_changed(self, keys=[]):
        """Check the updated parameters as at load, then note which lobes do any work.

        ``keys`` names the textures that ``params.update()`` changed (empty at load, where
        the reader has checked them already). A refused value is taken back: the texture
        gets its last accepted values again before the error is raised, so the plugin never
        renders with a value it refused.
        """
        textures = self._textures()
        if not keys:
            self._accepted = {name: _values(tex) for name, tex in textures.items()}
        for root in dict.fromkeys(name.split(".")[0] for name in keys):
            if root not in textures:
                continue
            tex = textures[root]
            self._known.pop(id(tex), None)
            traversed = mi.traverse(tex)   # once: the check and the values kept share it
            if root in self._ranges:
                try:
                    checked = check_range(self.NAME, root, tex, self._ranges[root], traversed)
                except Exception:
                    _restore(tex, self._accepted[root])
                    raise
                if not tex.is_spatially_varying():  # read once: the lobes reuse it
                    self._known[id(tex)] = checked
            self._accepted[root] = _values(tex, traversed)
        self._present = self._lobes_present()
        self._lobe_key = _lobe_key(self._present)
        self._update()

    def _update(self):
        """Per-scene work of a model after its parameters changed (none by default)."""

    # -- what a model implements ---------------------------------------------------------

    def _read_parameters(self, reader):
        """Read and validate the parameters with ``reader`` (``ParamReader``) onto ``self``."""
        raise NotImplementedError

    def _textures(self):
        """Parameter name -> texture, for every texture parameter, in traverse order."""
        raise NotImplementedError

    def _lobes_present(self):
        """(glossy, diffuse): whether each lobe's weight is not a constant zero."""
        raise NotImplementedError

    def _at(self, si, active):
        """The model's ``Point``: its parameter values at the shading point ``si``."""
        raise NotImplementedError

    def _glossy_f(self, p, wi, wo):
        """The glossy BRDF times cos(theta_o)."""
        raise NotImplementedError

    def _glossy_pdf(self, p, wi, wo):
        """The density of ``_glossy_sample`` (solid angle of wo)."""
        raise NotImplementedError

    def _glossy_sample(self, p, wi, u):
        """A direction wo of the glossy lobe from a 2D uniform sample ``u``."""
        raise NotImplementedError

    def _glossy_albedo(self, p, wi):
        """An estimate of the glossy albedo at wi (chooses between the lobes only)."""
        raise NotImplementedError

    def _diffuse_f(self, p, wi, wo):
        """The diffuse BRDF times cos(theta_o)."""
        raise NotImplementedError

    def _diffuse_albedo(self, p, wi):
        """An estimate of the diffuse albedo at wi (chooses between the lobes only)."""
        raise NotImplementedError

    def _diffuse_sample(self, p, wi, u):
        """A direction of the diffuse lobe: cosine-weighted unless the model has its own."""
        return mi.warp.square_to_cosine_hemisphere(u)

    def _diffuse_pdf(self, p, wi, wo):
        """The density of ``_diffuse_sample``: cos(theta_o) / pi unless the model has its own."""
        return mi.warp.square_to_cosine_hemisphere_pdf(wo)

    def _diffuse_colour(self, p):
        """The colour the albedo AOV reports (see ``eval_diffuse_reflectance``)."""
        raise NotImplementedError

    def _specular_colour(self, p):
        """The specular colour at normal incidence, or None (no specular lobe)."""
        return None

    def _options(self):
        """Load-time options shown by ``to_string`` (enum choices etc.)."""
        return {}

    # -- lobe bookkeeping ----------------------------------------------------------------

    def _is_constant(self, tex, value):
        """True if the texture returns ``value`` everywhere (``value = 0``: a lobe whose
        weight it is does no work)."""
        if tex.is_spatially_varying():
            return False
        known = self._known.get(id(tex))
        return (known if known is not None else texture_range(tex)) == (value, value)

    def _live(self):
        """(glossy, diffuse): the lobes traced into the kernel, as Python bools.

        A lobe whose weight is a constant zero does no work and is left out, unless a
        parameter is being differentiated: its gradient must flow (an optimisation may
        start from black), so every lobe is traced then.
        """
        g, d = self._present
        if not (g and d) and self._differentiated():
            return True, True
        return g, d

    def _differentiated(self):
        for tex in self._textures().values():
            params = mi.traverse(tex)
            if any(dr.grad_enabled(params[k]) for k in params.keys()):
                return True
        return False

    def _enabled(self, ctx):
        """(glossy on, diffuse on) as Python bools, from the live lobes and the context."""
        g_live, d_live = self._live()
        g = g_live and self.glossy_index >= 0 and ctx.is_enabled(
            mi.BSDFFlags.GlossyReflection, self.glossy_index)
        d = d_live and self.diffuse_index >= 0 and ctx.is_enabled(
            mi.BSDFFlags.DiffuseReflection, self.diffuse_index)
        return g, d

    def _glossy_probability(self, p, wi, g_on, d_on):
        """Probability of sampling the glossy lobe (a Python number when it is 0 or 1)."""
        if self.cosine_only or not g_on:
            return 0.0
        if not d_on:
            return 1.0
        wg = self._glossy_albedo(p, wi)
        wd = self._diffuse_albedo(p, wi)
        total = wg + wd
        return dr.select(total > 0, safe_div(wg, total), 0.5)

    def _f(self, p, wi, wo, g_on, d_on, adjoint=False):
        """f(wi, wo) cos(theta_o) of the enabled lobes.

        ``adjoint`` (Importance transport of a non-reciprocal model): wi is then the light
        side, so the model's f is evaluated with the two directions exchanged and the
        cosine moved from wi back to wo.
        """
        if adjoint:
            return safe_div(self._f(p, wo, wi, g_on, d_on), cos_theta(wi)) * cos_theta(wo)
        value = dr.zeros(mi.UnpolarizedSpectrum)
        if g_on:
            value += self._glossy_f(p, wi, wo)
        if d_on:
            value += self._diffuse_f(p, wi, wo)
        return value

    def _adjoint(self, ctx):
        """True when the model's wi/wo roles must be swapped (a Python bool)."""
        return (not self.RECIPROCAL) and ctx.mode == mi.TransportMode.Importance

    def _pdf(self, p, wi, wo, g_on, d_on):
        if not (g_on or d_on):
            return dr.zeros(mi.Float)
        if self.cosine_only:
            return mi.warp.square_to_cosine_hemisphere_pdf(wo)
        pg = self._glossy_probability(p, wi, g_on, d_on)
        pdf = dr.zeros(mi.Float)
        if not (isinstance(pg, float) and pg == 1.0):
            pdf += (1 - pg) * self._diffuse_pdf(p, wi, wo)
        if not (isinstance(pg, float) and pg == 0.0):
            pdf += pg * self._glossy_pdf(p, wi, wo)
        return pdf

    @staticmethod
    def _valid(wi, wo, active):
        return mi.Bool(active) & (cos_theta(wi) > 0) & (cos_theta(wo) > 0)

    # -- the BSDF interface --------------------------------------------------------------

    def sample(self, ctx, si, sample1, sample2, active=True):
        g_on, d_on = self._enabled(ctx)
        wi = si.wi
        sample1, sample2 = _as(mi.Float, sample1), _as(mi.Point2f, sample2)
        active = _as(mi.Bool, active) & (cos_theta(wi) > 0)
        width = max(dr.width(wi), dr.width(sample1), dr.width(sample2))
        bs = dr.zeros(mi.BSDFSample3f, width)
        if not (g_on or d_on):
            return bs, dr.zeros(mi.Spectrum, width)

        p = self._at(si, active)
        pg = self._glossy_probability(p, wi, g_on, d_on)
        if self.cosine_only:
            pick_glossy = mi.Bool(not d_on)
            wo = mi.warp.square_to_cosine_hemisphere(sample2)
        elif not (g_on and d_on):  # a single lobe: no choice traced into the kernel
            # (decided on the Python flags: in scalar variants pg is a Python float too)
            pick_glossy = mi.Bool(g_on)
            wo = (self._glossy_sample(p, wi, sample2) if g_on
                  else self._diffuse_sample(p, wi, sample2))
        else:
            pick_glossy = sample1 < pg
            wo = dr.select(pick_glossy, self._glossy_sample(p, wi, sample2),
                           self._diffuse_sample(p, wi, sample2))

        f = self._f(p, wi, wo, g_on, d_on, self._adjoint(ctx))
        pdf = self._pdf(p, wi, wo, g_on, d_on)
        # a half-vector sample may leave the hemisphere: zero weight (AS 2000, sec. 3)
        ok = active & (cos_theta(wo) > 0) & (pdf > 0)

        bs.wo = wo
        bs.pdf = dr.select(ok, pdf, 0)
        bs.eta = 1.0
        gflags = mi.UInt32(+self.m_components[self.glossy_index]) if g_on else mi.UInt32(0)
        dflags = mi.UInt32(+self.m_components[self.diffuse_index]) if d_on else mi.UInt32(0)
        bs.sampled_type = dr.select(pick_glossy, gflags, dflags)
        bs.sampled_component = dr.select(pick_glossy, mi.UInt32(max(self.glossy_index, 0)),
                                         mi.UInt32(max(self.diffuse_index, 0)))
        weight = dr.select(ok, f / dr.select(ok, pdf, 1), 0)
        return bs, mi.depolarizer(weight)

    def _query(self, ctx, si, wo, active):
        """What eval, pdf and eval_pdf open with: None when the context enables no lobe,
        else (glossy on, diffuse on, active narrowed to both directions above the surface,
        the ``Point`` at si)."""
        g_on, d_on = self._enabled(ctx)
        if not (g_on or d_on):
            return None
        active = self._valid(si.wi, wo, _as(mi.Bool, active))
        return g_on, d_on, active, self._at(si, active)

    def eval(self, ctx, si, wo, active=True):
        wo = _as(mi.Vector3f, wo)
        q = self._query(ctx, si, wo, active)
        if q is None:
            return dr.zeros(mi.Spectrum, max(dr.width(si.wi), dr.width(wo)))
        g_on, d_on, active, p = q
        f = self._f(p, si.wi, wo, g_on, d_on, self._adjoint(ctx))
        return mi.depolarizer(dr.select(active, f, 0))

    def pdf(self, ctx, si, wo, active=True):
        wo = _as(mi.Vector3f, wo)
        q = self._query(ctx, si, wo, active)
        if q is None:
            return dr.zeros(mi.Float, max(dr.width(si.wi), dr.width(wo)))
        g_on, d_on, active, p = q
        return dr.select(active, self._pdf(p, si.wi, wo, g_on, d_on), 0)

    def eval_pdf(self, ctx, si, wo, active=True):
        wo = _as(mi.Vector3f, wo)
        q = self._query(ctx, si, wo, active)
        if q is None:
            width = max(dr.width(si.wi), dr.width(wo))
            return dr.zeros(mi.Spectrum, width), dr.zeros(mi.Float, width)
        g_on, d_on, active, p = q
        f = self._f(p, si.wi, wo, g_on, d_on, self._adjoint(ctx))
        return (mi.depolarizer(dr.select(active, f, 0)),
                dr.select(active, self._pdf(p, si.wi, wo, g_on, d_on), 0))

    def eval_diffuse_reflectance(self, si, active=True):
        """The albedo AOV: the diffuse colour, the specular colour where it is black.

        Mitsuba's fallback (eval at wo = n, times pi) would report the highlight's peak,
        far above 1 for sharp lobes. As ``roughplastic`` returns its
        ``diffuse_reflectance`` and ``principled`` its ``base_color`` (metals included),
        this returns the model's diffuse colour (``_diffuse_colour``); where that is black
        in every channel (a metal, or the metal parts of a texture), the specular colour
        at normal incidence (``_specular_colour``). Clamped to [0, 1]: an albedo never
        exceeds 1. It does not depend on the directions, nor on the context's lobes. In a
        polarized variant it is the colour times the identity Mueller matrix, as
        ``diffuse`` and ``roughplastic`` return theirs.
        """
        active = _as(mi.Bool, active)
        p = self._at(si, active)
        albedo = self._diffuse_colour(p)
        specular = self._specular_colour(p)
        if specular is not None:
            albedo = dr.select(dr.all(albedo == 0), specular, albedo)
        return mi.Spectrum(dr.select(active, dr.clip(albedo, 0, 1), 0))

    def class_name(self):
        """The model's class name (``Lambert``, ``AshikhminShirley``), as Mitsuba's C++
        plugins give theirs (``SmoothDiffuse``)."""
        return type(self).__name__

    def to_string(self):
        lines = [f"{type(self).__name__}["]
        for name, tex in self._textures().items():
            lines.append(f"  {name} = " + str(tex).replace("\n", "\n  ") + ",")
        lines += [f"  {k} = {v}," for k, v in self._options().items()]
        lines.append("]")
        return "\n".join(lines)


class LambertDiffuseModel(TwoLobeModel):
    """A two-lobe model whose diffuse lobe is kd / pi: its ``Point`` holds ``kd`` (the diffuse
    colour) and ``ks`` (the specular colour, which the albedo AOV shows where kd is black)."""

    def _diffuse_f(self, p, wi, wo):
        return lambert_f(p.kd, wo)

    def _diffuse_albedo(self, p, wi):
        return channel_mean(p.kd)

    def _diffuse_colour(self, p):
        return p.kd

    def _specular_colour(self, p):
        return p.ks
