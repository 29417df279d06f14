"""relightnet: relight people in images and videos with spherical-harmonics light."""

__version__ = "0.1.0"
