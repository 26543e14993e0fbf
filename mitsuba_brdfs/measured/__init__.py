"""Measured reflectance: the file formats, the measured samples a fit reads, and writing any
BSDF or measurement as an RGL file that Mitsuba's ``measured`` plugin renders.

- ``merl``: MERL's binary format (read, write, the bins' directions and measures);
- ``tensor``: Mitsuba's tensor file format (read, write), ``FormatError``;
- ``warp``: the RGL parameterization (Dupuy & Jakob 2018) in NumPy;
- ``rgl``: RGL material files (``load``), their measured samples (``read_samples``);
- ``reader``: ``read(path)``, the measured samples of an RGL or a MERL file;
- ``sources``: what ``to-rgl`` converts (a BSDF, a MERL file, an RGL file) as evaluators;
- ``acquire``: the virtual measurement that writes an RGL file;
- ``roundtrip``: how close a written file comes to its source (albedo, eval);
- ``convert``: a source measured, written as an RGL file and compared with it;
- ``to_rgl``: the ``to-rgl`` command; ``to_merl``: the ``to-merl`` command (any source
  as a MERL file);
- fitting a model to measured samples: ``data`` (a file's samples and the energy term's
  rows), ``plugins`` (the model: loaded, written back as XML), ``variables`` (its
  parameters in boxes), ``fitting`` (the loss, ``fit``), ``optimizers`` (L-BFGS-B,
  Adam), ``quality`` (relative RMS error, held-out loss), ``report`` (``fit_file``: a
  fit with what a user judges it by; tables and plots), ``matrix`` (models fitted to
  one another's materials, each fit judged by its albedo). ``fit-measured``
  (``mitsuba_brdfs.fit_measured``) is the command.
"""
from .tensor import FormatError
from .rgl import Samples, read_samples
from .reader import read

__all__ = ["FormatError", "Samples", "read_samples", "read"]
