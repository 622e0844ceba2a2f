"""Table layouts: the one definition of every table's size and coordinates.

The baker (``bake_*``), the node builder, the OSL generator and the tests all
take sizes and coordinate maps from here.

Convention for every table: a float32 array of shape (height, width); entry
``[j, i]`` holds the function at grid coordinates ``X = i / (width - 1)`` and
``Y = j / (height - 1)``.  In a Blender image row ``j`` is the ``j``-th row from
the bottom, so texel ``(i, j)`` sits at UV ``((i + .5) / width, (j + .5) / height)``.
Lookups are bilinear in (X, Y) with clamping at the edges, identical in numpy
(:func:`fog_addon.precompute.core.ops.NumpyOps.table`) and in the node tree.

Coordinate maps are written against an ``m`` ops namespace (numpy or node
sockets, see ``ops.py``) so the same code runs in both.

**Kinds.**  Every table belongs to one ``TableKind``: the phenomenon it tabulates, with its spec constructor,
its baker, its bake-time estimate and its progress label.  A spec names its kind by key (``TableSpec.kind``,
set by the kind's constructor) and carries the arguments it was made from (``TableSpec.args``), so the one
registry (``registry.py``) finds a table's baker without reading its name.  Neither field is part of a spec's
identity: its name, size, g and channels decide its values, its image and its cache entry (``table_cache``
keys on ``repr(spec)``, which leaves them out).
"""
from dataclasses import dataclass, field
import math
from typing import Any, Callable, NamedTuple, Optional

HALF_PI = 0.5 * math.pi
G_DECIMALS = 6   # a table's anisotropy g is kept to this many decimals (``TableSpec``)


@dataclass(frozen=True)
class TableSpec:
    name: str          # Blender image name
    width: int         # samples along X
    height: int        # samples along Y
    g: float = 0.0     # the Henyey-Greenstein anisotropy the table is baked for (a table per g, Biri 2006)
    channels: int = 1  # values per texel, as RGBA; a one-channel table holds its value in all four
    kind: str = field(default="", compare=False, repr=False)   # its TableKind's key ("": not a registry table)
    args: tuple = field(default=(), compare=False, repr=False)  # what its kind's constructor made it from

    def __post_init__(self):
        # g to 6 decimals: Blender's float32 properties give 0.8500000238 for 0.85, which would otherwise be
        # another cache key and another bake of the same table (``table_cache.cache_path`` hashes the spec)
        object.__setattr__(self, "g", round(float(self.g), G_DECIMALS))


def _no_needs(spec):
    return ()


def _named(spec):
    return f"the table {spec.name}"


def details(spec):
    """What a parameterised table's name holds between its parentheses ("g +0.850, W0 0.800"), for a label."""
    return spec.name.split("(", 1)[1].rstrip(")") if "(" in spec.name else ""


class TableReader(NamedTuple):
    """How a bake reads other tables through the cache (``bakers.READER``), handed to the kinds that read some
    (``TableKind.reads``) so that their modules need not import the bakers that import them."""
    array: Callable[..., Any]    # array(spec, g): one table's float32 array
    per_g: Callable[..., Any]    # per_g(g): {name: array} of every table a fog of anisotropy g reads


@dataclass(frozen=True)
class TableKind:
    """One phenomenon's tables: how they are made, baked, timed and announced (``registry.KINDS`` lists them all).

    ``bake(spec, progress=None)`` returns the float32 array of one of its specs (``progress(done, total)`` is
    called by the long bakes and may raise ``table_cache.BakeCancelled``); None for a table baked per scene by its
    caller (from the scene's camera, World or geometry: not a function of its spec, so never cached on disk).
    ``estimate(spec)``: about how long its own bake takes from a cold cache on 2 cores, s; ``needs(spec)``: the
    tables its bake reads through the cache (their bake time counts too unless they are cached).  ``make``:
    its spec constructor (for the tables every fog reads, ``per_g``: ``make(g)``); ``fixed``: specs of it that
    are constants of another module.  ``image``: packed as an image (False: an intermediate array).  ``reads``:
    its bake reads other tables, through the ``tables=`` (a ``TableReader``) it is then given."""
    key: str
    make: Optional[Callable[..., TableSpec]] = None
    bake: Optional[Callable[..., Any]] = None
    estimate: Callable[[TableSpec], float] = lambda spec: 0.0
    label: Callable[[TableSpec], str] = _named
    needs: Callable[[TableSpec], tuple] = _no_needs
    fixed: tuple = ()
    per_g: bool = False
    image: bool = True
    reads: bool = False


# Normalised airlight kernel N(rho, xi); see airlight.py.
AIRLIGHT = TableSpec("AnalyticFog Airlight N", 128, 64, kind="airlight")
MAX_ANISOTROPY = 0.95   # |g| up to this: the Henyey-Greenstein range the tables are baked and tested for


# The airlight table of an anisotropic medium: its phase peak adds structure; 256 x 256 keeps bilinear
# interpolation within 1e-3 up to |g| = 0.95 (128 x 64: 1.5e-2).
AIRLIGHT_HG_SIZE = (256, 256)


# A spot's fog light on a surface (spot.scatter): tables of X = surface_x(T) (T = beta D_sp) and rows of the
# angle psi in [0, pi] of the surface point from the cone's axis (SPOT_PSI per slice), stacked in slices of
# the cone's half-angle theta_c in [0, pi/2] (SPOT_CONES, uniform), one slice for the whole sphere (the point
# light) and one last slice for a Lambertian emitter (an area light: ``area.scatter``; the share weighted by
# the cosine to the axis).  Per g, one texel holds four values read by one lookup (``spot.bake_scatter_tables``): the
# share F of the point light's fog light that the cone lights (R), the two components of the first moment of
# the directions it arrives from (G, B), and the point light's first moment (A: the last slice's G at that X,
# in every row).
SPOT_PSI = 65
SPOT_CONES = 19
SPOT_SLICES = SPOT_CONES + 2
SPOT_SPHERE_SLICE, SPOT_LAMBERT_SLICE = SPOT_CONES, SPOT_CONES + 1
SPOT_MOMENTS = TableSpec("AnalyticFog Spot Moments", 64, SPOT_PSI * SPOT_SLICES, channels=4, kind="spot_moments")
SPOT_SHARE, SPOT_MOMENT_LIGHT, SPOT_MOMENT_AXIS, SPOT_MOMENT_POINT = range(4)   # its channels

# The Lambertian response of light arriving from a von Mises-Fisher distribution of directions
# (``spot.lobe_response``): X = (c + 1) / 2, c the cosine between the normal and the mean direction;
# Y = the mean resultant length R in [0, 1].  No g: the distribution's shape only.
LOBE_RESPONSE = TableSpec("AnalyticFog Lobe Response", 129, 65, kind="lobe_response")


# The directional albedo of the Principled BSDF's specular layer (``surface.bake_specular_albedo``):
# Karis' split sum, E(mu, r) = F0 A(mu, r) + F90 B(mu, r), GGX with Smith masking and Schlick's Fresnel
# (metals), and E with the dielectric Fresnel equations of IOR SPECULAR_IOR (dielectrics);
# X = mu = cos(view angle) in [0, 1], Y = roughness r in [0, 1] within each of three slices: A, B, E.
SPECULAR_MU = 33
SPECULAR_ROUGHNESS = 33
SPECULAR_IOR = 1.5
SPECULAR_ALBEDO = TableSpec("AnalyticFog Specular Albedo", SPECULAR_MU, 3 * SPECULAR_ROUGHNESS, kind="specular_albedo")


def anisotropic(spec, g):
    """``spec`` baked for Henyey-Greenstein anisotropy g, under its own name (``spec`` itself at g = 0)."""
    g = float(g)
    if g == 0.0:
        return spec
    width, height = AIRLIGHT_HG_SIZE if spec == AIRLIGHT else (spec.width, spec.height)
    return TableSpec(f"{spec.name} (g {g:+.3f})", width, height, g, spec.channels, kind=spec.kind, args=(g,))


def hg_stretch(g):
    """s = (1 + g) / (1 - g): the Henyey-Greenstein weight of the airlight integrand depends on s Q / h
    (``model.hg_weight``), so its forward (g > 0) or backward (g < 0) peak is 1/s or s times as wide."""
    return (1.0 + g) / (1.0 - g)

# Surface-scattering factor M_n(T, theta) of surface.py (Sun et al. 2005 Eq. 15-18),
# stored as ln M_n for the Phong exponents below, stacked along Y: level k
# (n = 2^(k / PHONG_LEVELS_PER_OCTAVE)) occupies rows [k * SURFACE_THETA, (k+1) * SURFACE_THETA).
# Columns: optical light-surface distance T (surface_x); rows: lobe angle theta
# (surface_y, graded on the lobe width of each level).  A quarter octave between
# levels keeps the interpolation of ln M in log2 n within 0.2 % (an octave: 3 %).
SURFACE_T = 96
SURFACE_THETA = 65            # odd: theta = pi/2 (the clamped-cosine kink of n = 1) is a grid row
PHONG_LEVELS_PER_OCTAVE = 4
PHONG_EXPONENTS = tuple(2.0 ** (k / PHONG_LEVELS_PER_OCTAVE) for k in range(41))   # 1 ... 1024
SURFACE = TableSpec("AnalyticFog Surface M", SURFACE_T, SURFACE_THETA * len(PHONG_EXPONENTS), kind="surface")

SURFACE_T_MAX = 60.0          # X = 1; beyond it the lookup clamps (exp(-T) < 1e-26 there)
SURFACE_T_SCALE = 1.0         # T0 of surface_x
SURFACE_T_POWER = 0.15        # p of surface_x
_SURFACE_X_NORM = 1.0 / (1.0 - (1.0 + SURFACE_T_MAX / SURFACE_T_SCALE) ** -SURFACE_T_POWER)
SURFACE_UNIFORM_LEVELS = 4    # levels k < 4 (n < 2, the pi/2 kink matters) use theta / pi
SURFACE_THETA_WIDTH = 0.7     # theta0 = 0.7 / sqrt(n) of the graded levels
SURFACE_THETA_POWER = 0.1     # q of the graded levels


def airlight_x(m, rho, g=0.0):
    """Grid X of the airlight table for optical radius rho >= 0: sqrt(rho / (1 + rho)), for a forward
    peak (g > 0) the mean of that and sqrt(rho / (s + rho)) (``hg_stretch``: the far field starts only
    where beta h / s passes 1)."""
    x = m.sqrt(rho / (rho + 1.0))
    if g <= 0.0:
        return x
    return 0.5 * (x + m.sqrt(rho / (rho + hg_stretch(g))))


def airlight_rho(x, g=0.0):
    """Inverse of :func:`airlight_x` (numpy floats); x = 1 maps to a large finite rho."""
    import numpy as np
    x = np.minimum(np.asarray(x, float), 1.0 - 1e-12)
    if g <= 0.0:
        return x * x / (1.0 - x * x)
    lo, hi = np.zeros_like(x), np.full_like(x, 1.0)   # in sqrt(rho / (1 + rho)), increasing with rho
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        rho = mid * mid / (1.0 - mid * mid)
        below = 0.5 * (mid + np.sqrt(rho / (rho + hg_stretch(g)))) < x
        lo, hi = np.where(below, mid, lo), np.where(below, hi, mid)
    mid = 0.5 * (lo + hi)
    return mid * mid / (1.0 - mid * mid)


def airlight_y(m, q, h, g=0.0, xi=None):
    """Grid Y of the airlight table for the point Q = q on a ray at distance h from the light (``xi`` =
    atan2(q, h) if already known): xi / (pi/2), for g != 0 the mean of that and atan2(s q, h) / (pi/2)
    (``hg_stretch``: half the rows graded on the phase function's peak, half uniform)."""
    xi = m.atan2(q, h) if xi is None else xi
    if not g:
        return xi * (1.0 / HALF_PI)
    return (xi + m.atan2(q * hg_stretch(g), h)) * (0.5 / HALF_PI)


def airlight_xi(y, g=0.0):
    """Inverse of :func:`airlight_y` (numpy floats): xi at grid Y in [0, 1] (bisection for g != 0)."""
    import numpy as np
    y = np.clip(np.asarray(y, float), 0.0, 1.0)
    if not g:
        return y * HALF_PI
    lo, hi = np.zeros_like(y), np.full_like(y, HALF_PI)
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        below = (mid + np.arctan(np.tan(mid) * hg_stretch(g))) * (0.5 / HALF_PI) < y
        lo, hi = np.where(below, mid, lo), np.where(below, hi, mid)
    return 0.5 * (lo + hi)


def surface_x(m, t):
    """Grid X of the surface table for the optical distance T = beta D_sp >= 0.

    X = sqrt((1 - (1 + T/T0)^-p) / (1 - (1 + T_max/T0)^-p)): ~sqrt(T) near 0
    (M_n - M_n(0) ~ T ln T there), ~log-spaced for T of order 1-60.
    """
    return m.sqrt((1.0 - m.power(t * (1.0 / SURFACE_T_SCALE) + 1.0, -SURFACE_T_POWER)) * _SURFACE_X_NORM)


def surface_t(x):
    """Inverse of :func:`surface_x` (numpy floats): T at grid X in [0, 1]."""
    import numpy as np
    s = np.clip(np.asarray(x, float), 0.0, 1.0) ** 2 / _SURFACE_X_NORM
    return SURFACE_T_SCALE * ((1.0 - s) ** (-1.0 / SURFACE_T_POWER) - 1.0)


def surface_y(m, theta, level):
    """Grid Y within the band of level ``level`` for the lobe angle theta in [0, pi].

    ``level`` is a Python int or an ``m`` value holding an integer.  Levels
    k < SURFACE_UNIFORM_LEVELS: Y = theta / pi; others Y = ((theta + t0)^q - t0^q) /
    ((pi + t0)^q - t0^q) with t0 = 0.7 / sqrt(n_k) = 0.7 * 2^(-k / 8), q = 0.1: rows
    graded on the lobe width near theta = 0, ~log-spaced beyond.
    """
    if isinstance(level, int):
        if level < SURFACE_UNIFORM_LEVELS:
            return theta * (1.0 / math.pi)
        t0 = SURFACE_THETA_WIDTH * 2.0 ** (-0.5 * level / PHONG_LEVELS_PER_OCTAVE)
        q = SURFACE_THETA_POWER
        return (m.power(theta + t0, q) - t0 ** q) * (1.0 / ((math.pi + t0) ** q - t0 ** q))
    t0 = SURFACE_THETA_WIDTH * m.power(2.0, level * (-0.5 / PHONG_LEVELS_PER_OCTAVE))
    q = SURFACE_THETA_POWER
    t0q = m.power(t0, q)
    graded = (m.power(theta + t0, q) - t0q) / (m.power(t0 + math.pi, q) - t0q)   # denominator >= 0.2
    return m.select(m.less(level, SURFACE_UNIFORM_LEVELS - 0.5), theta * (1.0 / math.pi), graded)


def surface_theta(y, level):
    """Inverse of :func:`surface_y` (numpy floats, Python int level): theta at grid Y in [0, 1]."""
    import numpy as np
    y = np.clip(np.asarray(y, float), 0.0, 1.0)
    if level < SURFACE_UNIFORM_LEVELS:
        return y * math.pi
    t0 = SURFACE_THETA_WIDTH * 2.0 ** (-0.5 * level / PHONG_LEVELS_PER_OCTAVE)
    q = SURFACE_THETA_POWER
    return np.minimum((y * ((math.pi + t0) ** q - t0 ** q) + t0 ** q) ** (1.0 / q) - t0, math.pi)
