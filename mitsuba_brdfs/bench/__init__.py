"""The performance study: what accuracy costs in time (``python -m mitsuba_brdfs bench``).

``study`` runs the sections and collects every number, ``report`` writes
``docs/performance.md`` and its plots, ``command`` is the command line. The sections:
``error`` (error against time), ``speed`` (against Mitsuba's C++ plugins; optional
effects), ``accuracy`` (the price of accurate formulas), ``memory`` (peak memory of
command-line renders); ``plugins`` holds the plugins only the study uses. Nothing in the
library imports this package.
"""
