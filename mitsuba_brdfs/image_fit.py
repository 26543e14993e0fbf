"""Recovering Ashikhmin-Shirley parameters from an image by differentiable rendering (what
the ``fit`` command runs).

The brushed metal cylinder of Ashikhmin & Shirley (2000), Fig. 2 (Rd = 0, Rs = 0.9,
nu = 10, nv = 100), in Mitsuba's own cylinder mapping (u runs around the circumference,
so the lobe is wide around the cylinder and narrow along its axis: the second, swapped
panel of ``scenes/fig2_brushed_cylinder.xml``, not the paper's look) is rendered once as
the target. Starting from wrong
values (nu = nv = 50, Rs = 0.5), ``mi.ad.Adam`` minimises the mean squared difference
between a render and the target, differentiating the render with Mitsuba's ``prb``
integrator through ``mi.traverse`` (keys ``mat.nu.value``, ``mat.nv.value``,
``mat.specular_reflectance.value``)::

    python -m mitsuba_brdfs fit [--iterations 200] [--spp 8] [--res 64] [--out DIR]

Exponents span orders of magnitude, so Adam works on log(nu) and log(nv) and each
iteration maps them back with exp (a step is then a relative change, and the exponents
stay positive); Rs is clamped to [0, 1] after every step. The learning rate drops to a
fifth for the last third of the iterations, to settle the noise of the stochastic
gradients. Writes ``loss.png`` (loss and parameters per iteration) and
``before_target_after.png`` into ``--out`` (default ``mitsuba_brdfs-out/fit/``; the three
tiles there are rendered apart, at 256 x 256).

Image size: the highlight covers enough pixels at 64 x 64 for all three values to end
within about 0.1% of the truth from ``START``; at 128 x 128 all three end within about
0.04%, at 3.5 times the cost of a frozen iteration
(``python -m mitsuba_brdfs bench --sections optimisation`` measures both, section 7 of
``docs/performance.md``).

Each iteration's render, loss and backpropagation run in a function frozen with
``@dr.freeze``: the first calls trace it (through the plugin's Python methods) and record
its kernels, the later ones replay them, several times faster (``--no-freeze`` traces every
iteration, for comparison). Everything that reads values back stays outside it: the
scene update (``params.update()`` checks the new values' ranges), the Adam step, the
clamping, the history. The seed is a ``mi.UInt32`` argument, so a new seed replays the
recording instead of tracing again. Python's cycle collector runs once before the fit and
not again until it ends (``collector.paused``): a scene it frees while Dr.Jit records (a
scene of an earlier run, say) aborts the process in Dr.Jit 1.5, and a collection at a
moment set by what else the process did changed the fitted values in their last digits.

Scene (``build_scene``): a vertical cylinder lit by a point light beside the camera. The
highlight's extent around the cylinder measures nu, along the axis nv, and its height Rs;
a dim uniform environment shows the rest of the cylinder. The scene is built here rather
than read from ``scenes/`` because the fit needs the ``prb`` integrator, a light whose
gradients are not drowned in sampling noise, stable parameter keys (the material has the
id ``mat``), and exactly this orientation: u around the circumference with nu = 10.

References: M. Ashikhmin, P. Shirley, "An Anisotropic Phong BRDF Model", Journal of
Graphics Tools 5(2), 25-32, 2000. D. Vicini, S. Speierer, W. Jakob, "Path Replay
Backpropagation", ACM TOG 40(4), 2021 (the ``prb`` integrator).
"""
import math
import os
import time

import numpy as np

from .arguments import default_out
from .collector import paused

__all__ = ["TRUE", "START", "KEYS", "ITERATIONS", "SPP", "RES", "build_scene", "fit",
           "collector_paused", "plot_history", "plot_tiles"]

#: Python's cycle collector off around a call: ``collector.paused``, under the name the
#: docs gave it first
collector_paused = paused

#: the paper's Fig. 2 material, and the wrong values the fit starts from
TRUE = {"nu": 10.0, "nv": 100.0, "rs": 0.9}
START = {"nu": 50.0, "nv": 50.0, "rs": 0.5}
#: mi.traverse keys of the parameters
KEYS = {"nu": "mat.nu.value", "nv": "mat.nv.value", "rs": "mat.specular_reflectance.value"}
#: the defaults: Adam steps, samples per pixel of each render, image width and height
ITERATIONS, SPP, RES = 200, 8, 64


def build_scene(res=RES, spp=SPP, nu=TRUE["nu"], nv=TRUE["nv"], rs=TRUE["rs"]):
    """The brushed cylinder (axis vertical, u around it) under a point light, for ``prb``."""
    import mitsuba as mi
    return mi.load_dict({
        "type": "scene",
        # direct light and one bounce to the environment: the cylinder sees nothing else
        "integrator": {"type": "prb", "max_depth": 2},
        "sensor": {"type": "perspective", "fov": 32,
                   "to_world": mi.ScalarTransform4f().look_at(origin=[0, 0.8, 6],
                                                              target=[0, 0, 0], up=[0, 1, 0]),
                   "film": {"type": "hdrfilm", "width": res, "height": res,
                            "rfilter": {"type": "box"}},
                   "sampler": {"type": "independent", "sample_count": spp}},
        "mat": {"type": "ashikhmin_shirley", "diffuse_reflectance": 0.0,
                "specular_reflectance": rs, "nu": nu, "nv": nv},
        # Mitsuba's cylinder: u = angle around the axis / 2 pi, v along the axis
        "cylinder": {"type": "cylinder", "p0": [0, -1.5, 0], "p1": [0, 1.5, 0], "radius": 1.0,
                     "bsdf": {"type": "ref", "id": "mat"}},
        "light": {"type": "point", "position": [1.5, 0.5, 4.0],
                  "intensity": {"type": "rgb", "value": 6.0}},
        # emitter sampling (one emitter per sample) nearly always picks the point light, so
        # the highlight is estimated at every sample; BSDF samples (MIS) still find the sky
        "env": {"type": "constant", "radiance": {"type": "rgb", "value": 0.05},
                "sampling_weight": 1e-3},
    })


def _set(params, values):
    """Write nu, nv, Rs (Python floats or Dr.Jit Floats) into the scene."""
    import mitsuba as mi
    for name, value in values.items():
        params[KEYS[name]] = value if isinstance(value, mi.Float) else mi.Float(value)
    params.update()


def _mse(a, b):
    return float(np.mean((np.asarray(a, np.float64) - np.asarray(b, np.float64)) ** 2))


def fit(iterations=ITERATIONS, spp=SPP, res=RES, out=None, lr=0.05, target_spp=None,
        tile_res=256, progress=print, freeze=True):
    """Run the fit; write the two figures into ``out``; return a summary dict.

    ``progress`` receives one line per iteration (None: silent). ``freeze``: record the
    render-and-loss step once and replay it (``@dr.freeze``), or trace it at every
    iteration. The summary holds the final values, the per-iteration history (seconds of
    each iteration included), the seconds spent in the optimisation loop, how often the
    frozen step was recorded (``recordings``; 0 unfrozen), and the losses of the start and
    end values against the target measured with the same seed and sample count
    (``loss_before``, ``loss_after``).
    """
    import drjit as dr
    import mitsuba as mi

    from .core.warp import MAX_EXPONENT

    if iterations < 1 or spp < 1 or res < 2:
        raise ValueError("fit: --iterations and --spp must be >= 1 and --res >= 2")
    out = out or default_out("fit")
    target_spp = target_spp or 8 * spp
    say = progress or (lambda *_: None)

    # Python's garbage collected first and none until the fit ends: its numbers then do not
    # depend on what the process did before, and no scene is freed while Dr.Jit records
    # the step (``collector``)
    with paused(collect=True):
        scene = build_scene(res, spp)
        params = mi.traverse(scene)
        _set(params, TRUE)
        target = mi.render(scene, params, spp=target_spp, seed=1 << 20)
        target_np = np.array(target)

        opt = mi.ad.Adam(lr=lr)
        opt["log_nu"] = mi.Float(math.log(START["nu"]))
        opt["log_nv"] = mi.Float(math.log(START["nv"]))
        opt["rs"] = mi.Float(START["rs"])

        def current():
            # exp of the clamped log can round above MAX_EXPONENT in float32: clamp again
            return {"nu": dr.minimum(dr.exp(opt["log_nu"]), MAX_EXPONENT),
                    "nv": dr.minimum(dr.exp(opt["log_nv"]), MAX_EXPONENT), "rs": opt["rs"]}

        @dr.freeze(enabled=freeze)
        def step(scene, target, seed):
            """Render, compare with the target and backpropagate: no value is read back here."""
            img = mi.render(scene, mi.traverse(scene), spp=spp, seed=seed)
            loss = dr.mean(dr.square(img - target), axis=None)
            dr.backward(loss)
            return loss

        history = {"loss": [], "nu": [], "nv": [], "rs": [], "seconds": []}
        t0 = time.perf_counter()
        for it in range(iterations):
            t_it = time.perf_counter()
            if it == (2 * iterations) // 3:
                opt.set_learning_rate(lr / 5)
            values = current()
            _set(params, values)  # outside the frozen step: the update reads the values back
            loss = step(scene, target, mi.UInt32(it))
            opt.step()
            # back into the plugin's ranges (an update outside them is refused): a reflectance
            # in [0, 1], exponents up to MAX_EXPONENT (exp keeps them > 0)
            opt["rs"] = dr.clip(opt["rs"], 0.0, 1.0)
            for key in ("log_nu", "log_nv"):
                opt[key] = dr.minimum(opt[key], math.log(MAX_EXPONENT))
            row = {"loss": float(loss.array[0])}
            row.update({k: float(v.array[0]) for k, v in values.items()})
            row["seconds"] = time.perf_counter() - t_it
            for k, v in row.items():
                history[k].append(v)
            say(f"iteration {it + 1:4d}/{iterations}  loss {row['loss']:.4e}  "
                f"nu {row['nu']:8.3f}  nv {row['nv']:8.3f}  Rs {row['rs']:.4f}")
        seconds = time.perf_counter() - t0
        final = {k: float(v.array[0]) for k, v in current().items()}

    # start and end against the target: same seed, same samples
    losses = {}
    for name, values in (("before", START), ("after", final)):
        _set(params, values)
        losses[name] = _mse(mi.render(scene, params, spp=spp, seed=7), target_np)

    # the three tiles, rendered larger for the figure
    tiles = []
    big = build_scene(tile_res, target_spp)
    big_params = mi.traverse(big)
    for values in (START, TRUE, final):
        _set(big_params, values)
        tiles.append(np.array(mi.render(big, big_params, spp=target_spp, seed=3)))

    os.makedirs(out, exist_ok=True)
    loss_png = os.path.join(out, "loss.png")
    tiles_png = os.path.join(out, "before_target_after.png")
    plot_history(history, loss_png)
    plot_tiles(tiles, [START, TRUE, final], ["before", "target", "after"], tiles_png)
    errors = {k: abs(final[k] - TRUE[k]) / TRUE[k] for k in TRUE}
    return {"final": final, "true": dict(TRUE), "start": dict(START), "errors": errors,
            "iterations": iterations, "seconds": seconds, "history": history,
            "frozen": freeze, "recordings": step.n_recordings,
            "loss_before": losses["before"], "loss_after": losses["after"],
            "outputs": [loss_png, tiles_png]}


def _pyplot():
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    return plt


def _save(fig, path):
    """Save a matplotlib figure atomically (a temporary file beside it, then a rename)."""
    from .output import save_figure
    save_figure(fig, path, dpi=100, format="png", bbox_inches="tight")


def plot_history(history, path):
    """Loss (log scale) and each parameter relative to its true value, per iteration."""
    plt = _pyplot()
    its = np.arange(1, len(history["loss"]) + 1)
    fig, (a, b) = plt.subplots(1, 2, figsize=(10, 3.6))
    a.semilogy(its, history["loss"], lw=1)
    a.set_xlabel("iteration")
    a.set_ylabel("loss (mean squared error)")
    a.set_title("loss")
    for k, label in (("nu", "nu / 10"), ("nv", "nv / 100"), ("rs", "Rs / 0.9")):
        b.plot(its, np.asarray(history[k]) / TRUE[k], label=label)
    b.axhspan(0.9, 1.1, color="0.9", label="within 10%")
    b.axhline(1.0, color="k", lw=0.6, ls="--")
    b.set_xlabel("iteration")
    b.set_ylabel("value / true value")
    b.set_title("parameters")
    b.legend(fontsize=8)
    fig.tight_layout()
    _save(fig, path)
    plt.close(fig)


def plot_tiles(images, values, names, path):
    """Tone-mapped renders side by side, each titled with its name and parameters."""
    from .output import tonemap
    plt = _pyplot()
    fig, axes = plt.subplots(1, len(images), figsize=(3.2 * len(images), 3.8))
    for ax, img, v, name in zip(np.atleast_1d(axes), images, values, names):
        ax.imshow(tonemap(img))
        ax.set_title(f"{name}\nnu {v['nu']:.1f}  nv {v['nv']:.1f}  Rs {v['rs']:.2f}", fontsize=10)
        ax.axis("off")
    fig.tight_layout()
    _save(fig, path)
    plt.close(fig)
