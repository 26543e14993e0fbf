"""The figures: the paper's (``paper``) and the model catalog (``catalog``), both made of
panels rendered and composed by ``panels``; ``check`` tests a scene's integrator against a
deeper path tracer; ``command`` is ``python -m mitsuba_brdfs figures``. Nothing in the
library imports this package.
"""
