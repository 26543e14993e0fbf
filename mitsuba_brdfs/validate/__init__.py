"""Checks of a BSDF plugin that the tests and a command line can share.

Every ``check_*`` function raises ``AssertionError`` (with the numbers that failed) when the
property does not hold and returns what it measured otherwise, so a test calls it as it is
and a command can report PASS or FAIL with the numbers. None of them needs pytest.

- ``probe``: calling a BSDF on NumPy directions (interactions, eval, pdf, samples);
- ``directions``: direction sets: random, mirror pairs, hard cases, quadrature;
- ``sampling``: the chi-square test of the sampler against the pdf, sample weight = eval / pdf;
- ``energy``: directional albedo (white furnace) and its bounds;
- ``reciprocity``: f(a, b) = f(b, a);
- ``stability``: finite, non-negative values on grids of hard directions and sample corners,
  zero below the horizon, finite gradients.

Directions are local-frame unit vectors, NumPy arrays of shape (N, 3). Nothing in the
library imports this package.
"""
