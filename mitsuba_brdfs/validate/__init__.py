"""Checks of a BSDF plugin that the tests and a command line can share.

In a test suite of your own, ``assert_valid(bsdf)`` runs them all and raises an
``AssertionError`` listing every failed check (``suite.assert_valid``).

Every ``check_*`` function raises ``AssertionError`` (with the numbers that failed) when the
property does not hold and returns what it measured otherwise, so a test calls it as it is
and a command can report PASS or FAIL with the numbers. The measurements behind them
(``sampling.chi2``, ``sampling.weight_errors``, ``energy.quadrature``,
``reciprocity.reciprocity_error``, ``stability.hard_cases``) return the numbers whether the
property holds or not, with the verdict where there is one. None of them needs pytest.

- ``probe``: calling a BSDF on NumPy directions (interactions, eval, pdf, samples);
- ``directions``: direction sets: random, mirror pairs, hard cases, quadrature;
- ``sampling``: the chi-square test of the sampler against the pdf, sample weight = eval / pdf;
- ``energy``: directional albedo (white furnace), quadratures of eval and pdf, bounds;
- ``reciprocity``: f(a, b) = f(b, a);
- ``stability``: finite, non-negative values on grids of hard directions and sample corners,
  zero below the horizon, finite gradients;
- ``suite``: all of them on any BSDF, as named checks returning result records: what
  ``python -m mitsuba_brdfs check`` prints, and what the tests run on every model; its
  parts: ``results`` (the records, verdicts and summary line), ``subject`` (the BSDF under
  test, the settings, the samples checks share), ``checks_sampling`` and
  ``checks_structure`` (the checks themselves: each ``<name>_result`` takes a ``Subject``
  and returns a ``Result``, whether the property holds or not);
- ``properties``: the measurements of the property table and of the plugin pages;
- ``report``: ``check --report``'s Markdown page with its plots.

Directions are local-frame unit vectors, NumPy arrays of shape (N, 3). Nothing in ``core/``
or ``models/`` imports this package.
"""

__all__ = ["assert_valid"]


def assert_valid(bsdf, settings="quick", strict=False, only=None, **options):
    """``suite.assert_valid``: the suite on bsdf, an AssertionError listing every failure."""
    __tracebackhide__ = True
    from .suite import assert_valid as run_suite
    return run_suite(bsdf, settings, strict, only, **options)
