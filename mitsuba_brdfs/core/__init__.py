"""Shared building blocks of the models: numerics, frames, Fresnel, warps, parameters, lobes.

Everything here is variant-agnostic: types come from the inputs or from the active
Mitsuba variant at call time, so the same functions trace into LLVM/CUDA kernels and run
in the scalar variants.
"""
