"""The figure scenes: plain Mitsuba XML, installed with the package.

Each scene's comment block says what it shows and why its light, camera and integrator.
``SCENES`` is the folder that holds them, wherever the package is installed.
"""
import os

__all__ = ["SCENES"]

SCENES = os.path.dirname(os.path.abspath(__file__))
