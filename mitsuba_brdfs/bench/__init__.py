"""The performance study: what accuracy costs in time (``python -m mitsuba_brdfs bench``).

``sections`` is the table of the study's sections (and, one module each, what they write
into the document), ``study`` runs them and collects every number, ``report`` writes
``docs/performance.md`` and its plots, ``command`` is the command line. The measurements:
``error`` (error against time), ``speed`` (against Mitsuba's C++ plugins; optional
effects), ``accuracy`` (the price of accurate formulas), ``memory`` (peak memory of
command-line renders), ``startup`` (the first image and the ``figures`` command in fresh
processes, with an empty and a filled kernel cache; ``child`` is the script those
processes run), ``optimisation`` (optimisation iterations, traced and frozen); ``plugins``
holds the plugins only the study uses, ``load`` the machine's load around a section.
Nothing in the library imports this package.
"""
