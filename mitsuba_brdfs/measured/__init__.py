"""Measured reflectance: the file formats, the measured samples a fit reads, and writing any
BSDF or measurement as an RGL file that Mitsuba's ``measured`` plugin renders.

- ``tensor``: Mitsuba's tensor file format (read, write), ``FormatError``;
- ``warp``: the RGL parameterization (Dupuy & Jakob 2018) in NumPy;
- ``rgl``: RGL material files (``load``), their measured samples (``read_samples``);
- ``reader``: ``read(path)``, the measured samples of an RGL or a MERL file;
- ``sources``: what ``to-rgl`` converts (a BSDF, a MERL file, an RGL file) as evaluators;
- ``acquire``: the virtual measurement that writes an RGL file;
- ``roundtrip``: how close a written file comes to its source (albedo, eval);
- ``to_rgl``: the ``to-rgl`` command.

MERL's binary format is read by ``mitsuba_brdfs.merl``.
"""
from .tensor import FormatError
from .rgl import Samples, read_samples
from .reader import read

__all__ = ["FormatError", "Samples", "read_samples", "read"]
