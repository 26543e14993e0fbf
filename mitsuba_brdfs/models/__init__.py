"""The reflectance models; importing this package declares every plugin."""
from . import ashikhmin_shirley  # noqa: F401

__all__ = ["ashikhmin_shirley"]
