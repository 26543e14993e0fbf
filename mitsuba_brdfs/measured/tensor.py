"""Mitsuba's tensor file format (``.bsdf`` files of the RGL material database).

A tensor file holds named arrays ("fields"), as Mitsuba 3's ``TensorFile``
(``src/core/tensor.cpp``) reads them and its ``mitsuba.tensor_io`` writes them, all
little-endian:

==========  =====================================================================
bytes       content
==========  =====================================================================
12          the identifier ``tensor_file\\0``
2           the format version, major 1 and minor 0
4           uint32: the number of fields
per field   uint16 name length, the name (UTF-8), uint16 rank, uint8 type code,
            uint64 offset of the data from the file's start, rank x uint64 shape
data        each field's values in C order at its offset (8-byte aligned here)
==========  =====================================================================

Type codes: 1 uint8, 2 int8, 3 uint16, 4 int16, 5 uint32, 6 int32, 7 uint64, 8 int64,
9 float16, 10 float32, 11 float64.

Mitsuba maps the file and trusts its field table: a truncated file is read past its end.
``read`` checks every field against the file's size and raises ``FormatError`` (a
``ValueError`` naming the file and what is wrong, in one line) for a file that is not a
tensor file, is truncated, or has a malformed table. ``write`` writes the file whole
(``output.atomic``), so an interrupted write leaves no partial file.
"""
import os
import struct

import numpy as np

__all__ = ["MAGIC", "DTYPES", "FormatError", "is_tensor_file", "read", "write"]

#: the first 12 bytes of every tensor file
MAGIC = b"tensor_file\0"
#: type code -> NumPy type (little-endian)
DTYPES = {1: "<u1", 2: "<i1", 3: "<u2", 4: "<i2", 5: "<u4", 6: "<i4", 7: "<u8", 8: "<i8",
          9: "<f2", 10: "<f4", 11: "<f8"}
_CODES = {np.dtype(t): c for c, t in DTYPES.items()}
_ALIGN = 8


class FormatError(ValueError):
    """A file that is not what it should be (not a tensor file, truncated, a field missing
    or of the wrong shape): the message names the file and says what is wrong, in one line.
    The commands print it and exit with status 2."""


def is_tensor_file(path):
    """Whether the file starts with the tensor file identifier."""
    try:
        with open(path, "rb") as f:
            return f.read(len(MAGIC)) == MAGIC
    except OSError:
        return False


class _Reader:
    """Reads the header's values in order, refusing to read past its end."""

    def __init__(self, data, path):
        self.data, self.pos, self.path = data, 0, path

    def take(self, fmt, what):
        n = struct.calcsize(fmt)
        if self.pos + n > len(self.data):
            raise FormatError(f"{self.path}: truncated tensor file: it ends ({len(self.data)} "
                              f"bytes) inside its field table ({what})")
        values = struct.unpack_from(fmt, self.data, self.pos)
        self.pos += n
        return values if len(values) > 1 else values[0]

    def bytes(self, n, what):
        if self.pos + n > len(self.data):
            raise FormatError(f"{self.path}: truncated tensor file: it ends ({len(self.data)} "
                              f"bytes) inside its field table ({what})")
        out = self.data[self.pos:self.pos + n]
        self.pos += n
        return out


def read(path):
    """The fields of a tensor file: {name: NumPy array} in the file's order (copies, native
    byte order). Raises ``FormatError`` for a file that is not a complete tensor file."""
    path = os.fspath(path)
    if os.path.isdir(path):
        raise FormatError(f"{path}: a folder, not a tensor file (RGL material files, "
                          f"*.bsdf, are tensor files)")
    if not os.path.isfile(path):
        raise FormatError(f"{path}: no such file")
    with open(path, "rb") as f:
        data = f.read()
    if data[:len(MAGIC)] != MAGIC:
        raise FormatError(f"{path}: not a tensor file (it does not start with "
                          f"'tensor_file'; RGL material files, *.bsdf, do)")
    r = _Reader(data, path)
    r.pos = len(MAGIC)
    major, minor = r.take("<BB", "version")
    if (major, minor) != (1, 0):
        raise FormatError(f"{path}: tensor file version {major}.{minor}; only 1.0 is known")
    count = r.take("<I", "field count")
    table = []
    for i in range(count):
        name_length = r.take("<H", f"field {i}")
        raw = r.bytes(name_length, f"field {i}'s name")
        try:
            name = raw.decode("utf-8")
        except UnicodeDecodeError:
            raise FormatError(f"{path}: field {i}'s name is not UTF-8 text") from None
        rank, code, offset = r.take("<HBQ", f"field '{name}'")
        if code not in DTYPES:
            raise FormatError(f"{path}: field '{name}' has the unknown type code {code} "
                              f"(known: 1-11)")
        shape = tuple(int(s) for s in np.atleast_1d(r.take("<" + "Q" * rank, f"field "
                                                           f"'{name}''s shape"))) if rank else ()
        table.append((name, code, offset, shape))
    fields = {}
    for name, code, offset, shape in table:
        dtype = np.dtype(DTYPES[code])
        n = int(np.prod(shape, dtype=np.float64)) if shape else 1
        end = offset + n * dtype.itemsize
        if offset < r.pos or end > len(data):
            raise FormatError(f"{path}: truncated or corrupt tensor file: field '{name}' "
                              f"({' x '.join(map(str, shape)) or 'scalar'} {dtype.name}) needs "
                              f"bytes {offset}..{end}, the file has {len(data)}")
        if name in fields:
            raise FormatError(f"{path}: field '{name}' appears twice")
        fields[name] = np.frombuffer(data, dtype, n, offset).reshape(shape).astype(
            dtype.newbyteorder("="))
    return fields


def write(path, fields):
    """Write {name: array or str} as a tensor file (strings as uint8 text), whole: nothing
    is left at ``path`` if the write stops. Returns the file's size in bytes."""
    from ..output import atomic
    arrays = {}
    for name, value in fields.items():
        if isinstance(value, str):
            value = np.frombuffer(value.encode("utf-8"), np.uint8)
        value = np.array(value, order="C")   # a copy; keeps rank 0 (ascontiguousarray: 1)
        if value.ndim == 0:
            raise ValueError(f"tensor field '{name}' is a scalar: give it shape (1,) (Mitsuba's "
                             f"mitsuba.tensor_io cannot read rank 0)")
        if value.dtype.newbyteorder("<") not in _CODES:
            raise ValueError(f"tensor field '{name}': type {value.dtype} has no tensor file code")
        arrays[name] = value.astype(value.dtype.newbyteorder("<"))
    header = len(MAGIC) + 2 + 4 + sum(2 + len(k.encode("utf-8")) + 2 + 1 + 8 + 8 * v.ndim
                                      for k, v in arrays.items())
    offsets, pos = {}, header
    for name, value in arrays.items():
        pos = (pos + _ALIGN - 1) // _ALIGN * _ALIGN
        offsets[name] = pos
        pos += value.nbytes
    out = bytearray(pos)
    table = [MAGIC, struct.pack("<BBI", 1, 0, len(arrays))]
    for name, value in arrays.items():
        label = name.encode("utf-8")
        table.append(struct.pack("<H", len(label)) + label
                     + struct.pack("<HBQ", value.ndim, _CODES[value.dtype], offsets[name])
                     + struct.pack("<" + "Q" * value.ndim, *value.shape))
    head = b"".join(table)
    out[:len(head)] = head
    for name, value in arrays.items():
        out[offsets[name]:offsets[name] + value.nbytes] = value.tobytes()
    with atomic(path) as tmp, open(tmp, "wb") as f:
        f.write(bytes(out))
    return len(out)
