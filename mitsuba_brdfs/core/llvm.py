"""Check, before any kernel is compiled, that Dr.Jit's LLVM backend found a usable LLVM.

Dr.Jit 1.5 loads the system libLLVM at run time. LLVM 16 and older cannot lower the
``llvm.minimum``/``llvm.maximum`` intrinsics it emits on x86, and abort the whole process
("LLVM ERROR: Cannot select ... fminimum") at the first kernel. Raising a Python error here
is the only way to tell the user what to install instead.
"""
import drjit as dr

__all__ = ["MIN_LLVM", "LLVMVersionError", "check_llvm"]

MIN_LLVM = 17


class LLVMVersionError(RuntimeError):
    """Dr.Jit loaded no LLVM, or one too old to compile its kernels."""


_checked = set()


def check_llvm(variant):
    """Raise ``LLVMVersionError`` if ``variant`` needs LLVM and the loaded one is too old."""
    if not variant.startswith("llvm") or variant in _checked:
        return
    try:
        version = tuple(dr.detail.llvm_version())
    except Exception:  # backend failed to initialise: no libLLVM at all
        version = (0, 0, 0)
    if version[0] < MIN_LLVM:
        # Dr.Jit reports (-1, -1, -1) when it found no libLLVM
        found = "no LLVM library" if version[0] <= 0 else "LLVM " + ".".join(map(str, version))
        raise LLVMVersionError(
            f"mitsuba_brdfs: Dr.Jit's LLVM backend found {found}, but variant {variant!r} needs "
            f"LLVM >= {MIN_LLVM} (older releases abort the process with 'LLVM ERROR: Cannot "
            f"select ... fminimum'). On Debian/Ubuntu install it with "
            f"'apt-get install -y libllvm19' (scripts/bootstrap.sh does this), or point "
            f"DRJIT_LIBLLVM_PATH at a libLLVM.so of release {MIN_LLVM} or newer.")
    _checked.add(variant)
