"""The participating medium: one value for the fog's extinction, colour and phase function.

Homogeneous fog as in Sun et al. 2005 section 3: extinction coefficient
beta = scattering coefficient (no absorption; Sun's beta), 1/m; single-scattering
albedo per RGB channel (the fog's colour, a fraction of the scattered light);
Henyey-Greenstein anisotropy g (0: isotropic, Sun's phase function 1/(4 pi)).
Kernels take the fields they need; shader backends hold sockets in them, numpy
holds floats or arrays.
"""
import math
from typing import Any, NamedTuple

from . import presets, tables


# Clear air (Bruneton & Neyret 2008 section 2.1; Dobashi et al. 2002 appendix A.1): Rayleigh scattering at sea
# level for lambda = 680, 550, 440 nm and its scale height; the air's kernels are ``physics/daylight/aerial.py``'s
RAYLEIGH_RGB = (5.8e-6, 13.5e-6, 33.1e-6)   # 1/m
RAYLEIGH_HEIGHT = 8000.0                     # m (Dobashi et al. 2002 appendix A.1: 7994 m)


class Medium(NamedTuple):
    beta: Any                       # extinction = scattering coefficient, 1/m
    albedo: Any = (1.0, 1.0, 1.0)   # single-scattering albedo (RGB, dimensionless)
    g: float = 0.0                  # Henyey-Greenstein anisotropy (a Python float: folded into the kernels)


def validate_anisotropy(g):
    """g as a float in [-MAX_ANISOTROPY, MAX_ANISOTROPY], or ValueError with a message a user understands."""
    try:
        g = float(g)
    except (TypeError, ValueError):
        raise ValueError(f"anisotropy must be a number, got {g!r}") from None
    if not (math.isfinite(g) and abs(g) <= tables.MAX_ANISOTROPY):
        raise ValueError(f"anisotropy (Henyey-Greenstein g) must be between {-tables.MAX_ANISOTROPY} and "
                         f"{tables.MAX_ANISOTROPY}, got {g}")
    return g


def medium(beta, albedo=(1.0, 1.0, 1.0), g=0.0, scene_scale=1.0):
    """A validated Medium from user settings; raises ValueError with a message a user understands.

    beta: 1/m (real metres); scene_scale: real metres per scene unit, so the
    medium's beta is per scene unit (beta * scene_scale).
    """
    beta = presets.validate_density(beta)
    try:
        scene_scale = float(scene_scale)
        albedo = tuple(float(a) for a in albedo)
    except (TypeError, ValueError):
        raise ValueError("scene scale and colour must be numbers") from None
    if not (math.isfinite(scene_scale) and scene_scale > 0.0):
        raise ValueError(f"scene scale must be a positive number of metres per unit, got {scene_scale}")
    if len(albedo) != 3 or not all(math.isfinite(a) and 0.0 <= a <= 1.0 for a in albedo):
        raise ValueError(f"the fog colour (albedo) needs three values in [0, 1], got {albedo}")
    return Medium(beta * scene_scale, albedo, validate_anisotropy(g))
