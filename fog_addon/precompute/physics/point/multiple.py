"""Multiple scattering around point lights: the glow of the light scattered two or more times, numpy only.

The renderer's single scattering is exact (``airlight.py``, ``model.py``); this module adds the orders it
leaves out.  Narasimhan, Ramamoorthi and Nayar (``002``, §2) give the field of an isotropic point source in an
infinite homogeneous medium as a Legendre series (``apsf.py``); as printed it is off by factors of 0.02 to 70
against transport (docs/measurements/2026-11-27-apsf.md), so the field here is the transport's own:

* **The field by order.**  ``point_source_mc.radiance_by_order`` follows photons from the source without
  absorption and tallies the radiance I_k(T, theta) of each scattering order k on spheres of optical radius T
  (extinction 1, Henyey-Greenstein g).  A photon scattered k times carries W0^k, so one run serves every
  albedo: I_{>=2}(W0) = sum_{k>=2} W0^k I_k, the orders past MAX_ORDER extrapolated (``_order_tail``).  It
  depends on g only, and is baked once per g into the table cache (``orders_spec``).
* **The table.**  ln(I_{>=2} / W0) on (T, theta) (``table_spec``, ``bake_table``): divided by W0 because the
  shading multiplies every glow by the albedo afterwards.  Rows at T = T_MAX y^4 (``table_y``), columns at
  theta = 180 deg u^(1 / U_POWER) (``table_x``), so that both the narrow core (0.01 deg) and the whole sphere
  fit in 64 columns; logs, because the field falls by decades along both and log-linear interpolation follows
  an exponential exactly.
* **Segments.**  A camera ray that ends on a surface at distance D receives from its part in front of the
  surface the infinite ray's field less what crosses the surface point along the same line:

      L_ms = beta^2 I0 [ I(beta d_sv, theta_camera) - e^{-beta D} I(beta d_s, theta_surface) ]

  (``multiple_airlight``; d_s and theta_surface: the light seen from the surface point, along the ray).  It is
  exact for the infinite medium's field, as Biri 2006's lit segments are a difference of one primitive; the
  surface's own shadow on the fog behind it is not in it.  A ray to the sky takes the first term alone
  (``multiple_background``).
* **Surfaces** (Narasimhan et al. §7.4: the irradiance from the same field).  A diffuse surface receives
  E_{>=2}(T, psi) = int I_{>=2}(T, theta(omega)) cos dA over its hemisphere, psi its normal's angle from the
  light's direction, baked from the field into the same image (``irradiance_of_field``); a glossy lobe the
  field along its mirrored direction (``multiple_scatter``).  The forward-scattered light that reaches a
  surface through dense fog (the field near the light's direction) is part of it, beside the direct light
  e^{-beta d}.

Units: beta in 1/m, distances in m, results per unit radiant intensity and per unit albedo in 1/m^2 (as the
single-scattering kernels'); table values dimensionless (radiance / (I0 sigma^2)).
"""
import math

import numpy as np

from ...core import tables
from . import point_source_mc

T_MAX = 40.0           # optical distance of the table's last row (beyond: the last row, a bound noted in the docs)
T_MIN = 0.02           # first row (below: clamped; the single scattering outweighs the rest there by far)
ROWS = 48
COLUMNS = 64
U_POWER = 0.35         # theta = 180 u^(1 / U_POWER) deg: column 1 at 0.002 deg, u = 0.1 at 0.25 deg, 0.3 at 6 deg
MAX_ORDER = 200        # orders followed; the rest by ``_order_tail``
TAIL_POWER = 1.5       # I_k ~ k^-1.5 past MAX_ORDER (a random walk's return to a sphere in 3D)
PHOTONS = 100_000      # of a baked field (3-5 % noise a column before smoothing)
WINDOW_FROM = 20       # the orders from which the bake's weight window acts (``window``)
WINDOW_M = 3           # its roulette's 1 / survival beyond 2 r_near, and copies within r_near
WINDOW_SHARE = 0.5     # the share of a flight's sphere crossings tallied from WINDOW_FROM on
R_MAX = T_MAX + 40.0   # photons farther than this are dropped
SEED = 20261127
FLOOR = 1e-30          # ln of the table never below ln FLOOR
SMOOTH = (1.0, 2.0, 3.0, 2.0, 1.0)   # weights of the moving mean over columns of the log table (``_smooth``)
CAP_DEG = 0.25         # the columns within this angle of the light take their cap's mean (``_merge_cap``)

_Y_MIN = (T_MIN / T_MAX) ** 0.25


def row_distances():
    """The table rows' optical distances T (ROWS of them, T_MIN .. T_MAX)."""
    y = np.linspace(_Y_MIN, 1.0, ROWS)
    return T_MAX * y ** 4


def column_angles_deg():
    """The table columns' angles from the light (deg): COLUMNS, 0 .. 180."""
    return 180.0 * np.linspace(0.0, 1.0, COLUMNS) ** (1.0 / U_POWER)


def column_edges_deg():
    """Bin edges around the columns (midpoints in u), 0 and 180 at the ends: the Monte Carlo's bins."""
    u = np.linspace(0.0, 1.0, COLUMNS)
    mid = 0.5 * (u[1:] + u[:-1])
    return 180.0 * np.concatenate([[0.0], mid, [1.0]]) ** (1.0 / U_POWER)


def orders_spec(g):
    """The cached array of I_k (``bake_orders``): ROWS x MAX_ORDER rows of COLUMNS (not an image)."""
    return tables.TableSpec(f"AnalyticFog Multiple Orders (g {float(g):+.3f})", COLUMNS, ROWS * MAX_ORDER, float(g),
                            kind=ORDERS_KIND_KEY, args=(float(g),))


def window(g):
    """``point_source_mc.radiance_by_order``'s weight window for anisotropy g: (WINDOW_FROM, r_near, WINDOW_M,
    WINDOW_SHARE), r_near = 3.1 / sqrt(1 - g) (at least 2): about where a walk's WINDOW_FROM-th collision
    lies (a diffusion's sqrt(2 k / (1 - g)) / 2).  The photons past it far from the source, where the spheres are
    large and the field smooth, are followed one in WINDOW_M; those near it all."""
    return WINDOW_FROM, max(2.0, 3.1 / math.sqrt(max(1.0 - float(g), 1e-3))), WINDOW_M, WINDOW_SHARE


def bake_orders(spec, progress=None):
    """I_k(T, theta) for k = 1 .. MAX_ORDER at the rows and columns, float64 (ROWS * MAX_ORDER, COLUMNS).
    ``progress(done, total)``: as ``point_source_mc.radiance_by_order`` calls it."""
    arr = point_source_mc.radiance_by_order(row_distances(), spec.g, MAX_ORDER, photons=PHOTONS,
                                            edges_deg=column_edges_deg(), r_max=R_MAX, seed=SEED,
                                            window=window(spec.g), progress=progress)
    return arr.reshape(ROWS * MAX_ORDER, COLUMNS)


# seconds of ``bake_orders`` (one core): ORDERS_SECONDS[0] + ORDERS_SECONDS[1] (1 - g) (its walks stay nearer
# the source at low g, where they cross more of the spheres), and of a table from cached orders (the same for
# every albedo): TABLE_SECONDS (docs/measurements/2026-11-29-bake-time.md, 2026-11-30-test-time.md)
ORDERS_SECONDS = (6.0, 4.2)
TABLE_SECONDS = 0.8


def estimate_seconds(spec, orders_cached=False):
    """About how long ``bake_table(spec)`` takes, s: its orders' bake unless ``orders_cached``, then the
    table's."""
    return (0.0 if orders_cached else orders_seconds(spec)) + TABLE_SECONDS


def orders_seconds(spec):
    """About how long ``bake_orders`` takes for ``spec``'s g (a table's or its ``orders_spec``), s."""
    return ORDERS_SECONDS[0] + ORDERS_SECONDS[1] * (1.0 - float(spec.g))


def table_spec(g, albedo):
    """The image for anisotropy g and grey albedo W0 (rounded to 3 decimals): rows 0 .. ROWS-1 hold
    ln(I_{>=2} / W0) (``field``), rows ROWS .. 2 ROWS-1 ln(E_{>=2} / (pi W0)) (``irradiance``)."""
    w0 = f"{round(float(albedo), 3):.3f}"
    return tables.TableSpec(f"AnalyticFog Multiple (g {float(g):+.3f}, W0 {w0})", COLUMNS, 2 * ROWS, float(g),
                            kind=KIND_KEY, args=(float(g), float(w0)))


def albedo_of(spec):
    """The albedo a ``table_spec`` was made for (rounded to 3 decimals, as its name shows it)."""
    return spec.args[1]


def _order_tail(last, albedo):
    """sum_{k > MAX_ORDER} W0^(k-1) I_k with I_k = I_K (k / K)^-TAIL_POWER (``last`` = I_K), per unit W0."""
    k = np.arange(MAX_ORDER + 1, 40 * MAX_ORDER + 1, dtype=float)
    weights = albedo ** (k - 1.0) * (k / MAX_ORDER) ** -TAIL_POWER
    return last * float(np.sum(weights))


def field_of_orders(orders, albedo):
    """I_{>=2} / W0 (ROWS, COLUMNS) from I_k (ROWS * MAX_ORDER, COLUMNS): sum_{k>=2} W0^(k-1) I_k + the tail."""
    per = np.asarray(orders, float).reshape(ROWS, MAX_ORDER, COLUMNS)
    weights = float(albedo) ** np.arange(0, MAX_ORDER, dtype=float)   # W0^(k-1) for k = 1 .. K
    field = np.einsum("rkc,k->rc", per[:, 1:], weights[1:])
    return field + _order_tail(per[:, -1], float(albedo))


def _merge_cap(field):
    """Each row's columns within CAP_DEG of the light set to the field's mean over that cap (their bins' solid
    angles hold too few crossings for a value each; the multiply scattered field is flat there)."""
    edges = np.radians(column_edges_deg())
    solid = np.cos(edges[:-1]) - np.cos(edges[1:])
    cap = column_angles_deg() <= CAP_DEG
    out = field.copy()
    out[:, cap] = (field[:, cap] @ solid[cap] / solid[cap].sum())[:, None]
    return out


def _smooth(log_table):
    """A moving mean (SMOOTH) of each row of the log table over its columns (edges: the weights that fit)."""
    w = np.asarray(SMOOTH)
    half = len(w) // 2
    out = np.empty_like(log_table)
    n = log_table.shape[1]
    for c in range(n):
        lo, hi = max(0, c - half), min(n, c + half + 1)
        ww = w[lo - c + half:hi - c + half]
        out[:, c] = log_table[:, lo:hi] @ ww / ww.sum()
    return out


HEMISPHERE = (128, 256)   # polar x azimuth cells of ``irradiance_of_field``'s quadrature


def irradiance_of_field(log_field):
    """ln(E / pi) (ROWS, COLUMNS): E(T, psi) = int over the hemisphere about a normal at psi from the light's
    direction of I(T, theta(omega)) cos dA (midpoint rule, HEMISPHERE cells), psi = pi c / (COLUMNS - 1) at
    column c.  ``log_field``: ln I on the table's grid, interpolated linearly in ln I over ``table_x``."""
    n_polar, n_azimuth = HEMISPHERE
    polar = (np.arange(n_polar) + 0.5) * (0.5 * math.pi / n_polar)
    azimuth = (np.arange(n_azimuth) + 0.5) * (2.0 * math.pi / n_azimuth)
    sp, cp = np.sin(polar)[:, None], np.cos(polar)[:, None]
    weight = (cp * sp * (0.5 * math.pi / n_polar) * (2.0 * math.pi / n_azimuth)) * np.ones((1, n_azimuth))
    psi = np.linspace(0.0, math.pi, COLUMNS)
    cos_theta = (np.sin(psi)[:, None, None] * sp[None] * np.cos(azimuth)[None, None, :]
                 + np.cos(psi)[:, None, None] * cp[None])
    x = (np.arccos(np.clip(cos_theta, -1.0, 1.0)) / math.pi) ** U_POWER
    grid = np.linspace(0.0, 1.0, COLUMNS)
    out = np.empty_like(log_field)
    for r in range(ROWS):
        values = np.exp(np.interp(x, grid, log_field[r]))
        out[r] = np.log(np.maximum(np.einsum("cpa,pa->c", values, weight) / math.pi, FLOOR))
    return out


def bake_table(spec, orders=None, progress=None):
    """The two tables of ``spec`` (``table_spec``), float32 (2 ROWS, COLUMNS); ``orders``: ``bake_orders``'s
    array for spec.g (baked through the table cache if None, reporting to ``progress(done, total)``)."""
    if orders is None:
        from ...core.table_cache import cached_bake
        o_spec = orders_spec(spec.g)
        orders = cached_bake(o_spec, lambda: bake_orders(o_spec, progress))
    field = _merge_cap(field_of_orders(orders, albedo_of(spec)))
    log_field = _smooth(np.log(np.maximum(field, FLOOR)))
    return np.concatenate([log_field, irradiance_of_field(log_field)]).astype(np.float32)


KIND_KEY, ORDERS_KIND_KEY = "multiple", "multiple_orders"
ORDERS_KIND = tables.TableKind(ORDERS_KIND_KEY, make=orders_spec, bake=bake_orders, estimate=orders_seconds,
                               label=lambda spec: f"the point light's orders ({tables.details(spec)})", image=False)
KIND = tables.TableKind(KIND_KEY, make=table_spec, bake=bake_table,
                        estimate=lambda spec: estimate_seconds(spec, orders_cached=True),
                        label=lambda spec: f"the point light table ({tables.details(spec)})",
                        needs=lambda spec: (orders_spec(spec.g),))
TABLE_KINDS = (ORDERS_KIND, KIND)   # (``registry.KINDS``)


# --- the kernel (any backend: ``ops.ShaderOps``) ----------------------------------------------------------

def _angle_over_pi(m, cos_theta):
    """theta / pi in [0, 1] of the angle whose cosine is ``cos_theta`` (clamped to [-1, 1])."""
    c = m.maximum(m.minimum(cos_theta, 1.0), -1.0)
    return m.atan2(m.sqrt(1.0 - c * c), c) * (1.0 / math.pi)


def table_x(m, cos_theta):
    """The column coordinate in [0, 1] of the angle whose cosine is ``cos_theta``: (theta / pi)^U_POWER."""
    return m.power(_angle_over_pi(m, cos_theta), U_POWER)


def table_y(m, optical_distance):
    """The row coordinate in [0, 1] of the optical distance T: ((T / T_MAX)^(1/4) - y_min) / (1 - y_min)."""
    y = m.power(m.maximum(optical_distance * (1.0 / T_MAX), 1e-12), 0.25)
    return (y - _Y_MIN) * (1.0 / (1.0 - _Y_MIN))


def field(m, spec, optical_distance, cos_theta):
    """I_{>=2} / (W0 I0 sigma^2) at optical distance T from the light, theta from its direction (``spec``'s
    table, log-bilinear)."""
    return m.exp(m.table(spec, table_x(m, cos_theta), table_y(m, optical_distance), 0, ROWS))


def irradiance(m, spec, optical_distance, cos_psi):
    """E_{>=2} / (pi W0 I0 sigma^2): the multiply scattered light a surface facing psi from the light's
    direction receives, over pi (``irradiance_of_field``; log-bilinear)."""
    return m.exp(m.table(spec, _angle_over_pi(m, cos_psi), table_y(m, optical_distance), ROWS, ROWS))


def multiple_scatter(m, spec, beta, d_sp, cos_theta, level):
    """The multiply scattered light a surface reflects, per unit intensity and albedo, 1/m^2 (the scatter
    term's signature, ``rungs.py``): a diffuse lobe (``level`` 0) takes the hemisphere's irradiance over pi
    at the normal's angle from the light; a glossy lobe the field along the mirrored direction (the field
    varies over degrees, wider than the lobes a glossy surface shows).  A ``level`` given as a Python number
    (the diffuse lobe's 0.0) reads the one table it needs; a per-material socket reads both and selects."""
    t = beta * d_sp
    if isinstance(level, (int, float)):
        lobe = irradiance(m, spec, t, cos_theta) if level < 0.5 else field(m, spec, t, cos_theta)
        return beta * beta * lobe
    return beta * beta * m.select(m.less(level, 0.5), irradiance(m, spec, t, cos_theta), field(m, spec, t, cos_theta))


def multiple_background(m, spec, beta, d_sv, along, h):
    """The multiply scattered glow along a ray to infinity, per unit intensity and albedo, 1/m^2:
    beta^2 I(beta d_sv, theta) with cos theta = along / d_sv (``model.ray_light_geometry``)."""
    cos_c = along / m.maximum(d_sv, 1e-9)
    return beta * beta * field(m, spec, beta * d_sv, cos_c)


def multiple_airlight(m, spec, beta, d_sv, along, h, d_vp):
    """The multiply scattered glow along the ray's first ``d_vp`` m, per unit intensity and albedo, 1/m^2:
    the ray's field less e^{-beta d_vp} times the field crossing its end point along the same line (module
    docstring)."""
    far = along - d_vp                      # the light's offset along the ray from the end point
    d_s = m.sqrt(far * far + h * h)
    beyond = beta * beta * field(m, spec, beta * d_s, far / m.maximum(d_s, 1e-9))
    return multiple_background(m, spec, beta, d_sv, along, h) - m.exp(-1.0 * beta * d_vp) * beyond
