"""The optimisers of a fit, on a problem's variables (``fitting``): ``lbfgs``, SciPy's
L-BFGS-B in the variables' box from several starts, and ``adam``, Adam projected into the
box. Each takes the problem (``loss_and_grad(y)``, ``bounds``, ``clip``, ``starts``,
``evaluations``), the start y0, the budget of evaluations and ``tick(loss)``, and returns
(its best loss, its best y). L-BFGS-B's small matrix products go through OpenBLAS, whose
threads wait for work by spinning: beside Dr.Jit's they slow the fit, so ``lbfgs`` keeps
BLAS to one thread while it runs (threadpoolctl).

References: R. H. Byrd, P. Lu, J. Nocedal, C. Zhu, "A Limited Memory Algorithm for Bound
Constrained Optimization", SIAM J. Sci. Comput. 16(5), 1995 (L-BFGS-B); D. P. Kingma, J. Ba,
"Adam", ICLR 2015.
"""
import math

import numpy as np

__all__ = ["lbfgs", "adam"]

#: a start's share of the budget before the best one runs on to convergence
_SCOUT = 0.08
#: Adam: the learning rate falls geometrically to this fraction; beta_2 (a short memory)
_DECAY, _BETA2 = 0.3, 0.9


class _Budget(Exception):
    """The budget of evaluations is spent."""


def one_blas_thread():
    """A context in which BLAS (OpenBLAS, MKL) runs on one thread."""
    from threadpoolctl import threadpool_limits
    return threadpool_limits(1, user_api="blas")


def lbfgs(problem, y0, evaluations, tick):
    """L-BFGS-B from each start, then the best one on, within ``evaluations`` more
    evaluations of the problem; returns (best loss, best y)."""
    with one_blas_thread():
        return _lbfgs(problem, y0, evaluations, tick)


def _lbfgs(problem, y0, evaluations, tick):
    from scipy.optimize import minimize
    state = {}
    end = problem.evaluations + evaluations

    def fun(y):
        if problem.evaluations >= state["limit"]:
            raise _Budget
        value, g = problem.loss_and_grad(y)
        tick(value)
        if not math.isfinite(value) or not np.isfinite(g).all():
            return 1e30, np.zeros_like(g)   # NaN from the model: the line search backs off
        if value < state["best"][0]:
            state["best"] = (value, np.array(y))
        return value, g

    def run(y, budget):
        """L-BFGS-B from y for at most ``budget`` evaluations: (its best loss, y)."""
        state.update(limit=min(problem.evaluations + budget, end),
                     best=(math.inf, y))
        try:
            minimize(fun, y, jac=True, method="L-BFGS-B", bounds=problem.bounds,
                     options={"maxfun": budget, "maxiter": budget, "ftol": 1e-13,
                              "gtol": 1e-11, "maxcor": 20})
        except _Budget:
            pass
        return state["best"]

    starts = problem.starts(problem.clip(y0))
    scout = max(int(_SCOUT * evaluations), 10) if len(starts) > 1 else evaluations
    best = min((run(y, scout) for y in starts), key=lambda r: r[0])
    # the best start on to convergence, restarted while it gains (L-BFGS-B stops where
    # float32 noise fails its line search; a restart forgets a stale curvature)
    while problem.evaluations < end:
        r = run(best[1], end - problem.evaluations)
        if not r[0] < best[0] * (1 - 1e-7):
            break
        best = r
    return best


def adam(problem, y0, evaluations, tick, lr):
    """Adam in the box (each step projected into it); returns (best loss, best y)."""
    y = problem.clip(y0)
    best = (math.inf, y)
    m, v = np.zeros_like(y), np.zeros_like(y)
    scale, t = 1.0, 0
    for i in range(evaluations):
        value, g = problem.loss_and_grad(y)
        tick(value)
        if value < best[0]:
            best = (value, y)
            scale = min(1.0, scale * 1.05)
        elif not value <= 2 * best[0]:  # also NaN: back to the best, half the step
            y, m, v, t = best[1], 0 * m, 0 * v, 0
            scale, problem.lr_cuts = scale / 2, problem.lr_cuts + 1
            continue
        t += 1
        m = 0.9 * m + 0.1 * g
        v = _BETA2 * v + (1 - _BETA2) * g * g
        step = scale * lr * _DECAY ** (i / evaluations)
        y = problem.clip(y - step * (m / (1 - 0.9 ** t))
                         / (np.sqrt(v / (1 - _BETA2 ** t)) + 1e-8))
    return best
