"""Multiple scattering around spot lights: the glow of a cone's light scattered two or more times, numpy only.

A point light's multiply scattered glow is a function of two variables (``multiple.py``).  A spot's is not: a
cone's light stays near its beam for a transport mean free path in forward-scattering fog, so its halo runs up
the beam and the light that reaches a viewer beside it has been turned by the fog, not sent towards the viewer
by the lamp (an isotropised halo of the cone's share of power was 4-15x too bright against path tracing:
docs/measurements/2026-11-27-multiple-scattering.md).  Narasimhan et al. (``002``) treat isotropic sources
only.  Here the spot's own transport is tabulated, and a camera ray gathers it by quadrature:

* **The source function.**  The light a camera ray gathers from orders >= 2 is

      L_ms = sigma_s int_0^D e^{-sigma_t t} J(x(t), -d) dt,     J(x, w) = int p(w' . w) L_{>=1}(x, w') dw',

  the order >= 1 radiance at x scattered towards the camera (Chandrasekhar's source function, without the
  albedo of its last scattering, which the shading applies).  By the cone's symmetry J is a function of four
  variables: the optical distance T of x from the lamp, its angle psi from the axis, and the outgoing
  direction's angle theta from the radial direction e_r and azimuth phi about it (from the plane of the axis,
  mirror-symmetric).
* **The table** (``bake_table``): J by Monte Carlo, per anisotropy g, albedo W0 and cone (half-angle, blend),
  extinction 1, per unit on-axis intensity.  Photons leave the lamp with Blender's spot falloff; every
  collision of an already scattered photon adds w p(w_in . w_out) / V to its (T, psi) cell at each tabulated
  outgoing direction (a collision estimator, exact in the directions: no angular binning).  The first
  collision is drawn log-uniformly in distance, weighted, so that the cells near the lamp, where the beam is
  brightest, hold many collisions.  Stored as ln(J T): near the lamp J grows as 1/T (the single-scattered
  field of a point source), so J T is flat there and below the first row the table extrapolates exactly.
* **The bake** (``spot_walk.py``: the photon walk, bounded in time; ``bake_table`` fills the sparse cells and
  smooths the rows; ``estimate_seconds`` says how long it takes before it starts).
* **The quadrature** (``airlight``).  Along the ray, t = a + h sinh v (a: the distance to the ray's closest
  approach to the lamp, h: its distance there), so r = h cosh v and dt = r dv: the integrand
  beta^2 e^{-beta t} (J T) is bounded however close the ray passes to the lamp, and Gauss-Legendre in v
  spends its points evenly in log-distance from it, on each of the ray's pieces before, inside and after
  the cone (NODES), whose edge is sharp near the lamp.  The ray ends at the surface, so a segment
  needs no difference of fields (unlike ``multiple.multiple_airlight``).

The single scattering stays the exact spot kernels' (``spot.py``); J starts from order 1 radiance, so the
table's glow is orders >= 2 only and nothing is counted twice.

Units: beta in 1/m, distances in m, results per unit on-axis radiant intensity and per unit albedo in 1/m^2
(as the single-scattering kernels'); the table dimensionless (J T per I0 at extinction 1).
"""
import functools
import math

import numpy as np

from ...core import tables
from . import spot
from .spot_walk import (PHI_NODES, PHOTONS, PSI_NODES, ROWS, SEED, T_MAX, T_MIN, THETA_NODES, collide,
                        row_distances, walk_counts)

MIN_COUNT = 40         # a cell with fewer collisions takes its neighbours' too (``_fill``)
FLOOR = 1e-30
NODES = (6, 6, 6)      # quadrature points along a camera ray: before, inside and after the cone
REACH = 30.0           # optical depth past the closest approach where a ray to the sky stops counting


def cone_key(cos_half, blend):
    """(half-angle in whole degrees, blend in hundredths): the cone a table is baked for."""
    half = math.degrees(math.acos(min(max(float(cos_half), -1.0), 1.0)))
    return int(round(half)), int(round(100.0 * min(max(float(blend), 0.0), 1.0)))


def table_spec(g, albedo, cos_half, blend):
    """The table of a spot of cone ``cos_half`` = cos(spot size / 2) and ``blend`` in fog of anisotropy g and
    grey albedo W0: 2 PSI_NODES bands of ROWS rows (T) by THETA_NODES columns, PHI_NODES channels."""
    half, hundredths = cone_key(cos_half, blend)
    blend = f"{hundredths / 100:.2f}"
    return _spec(g, albedo, f"cone {half} deg, blend {blend}", math.cos(math.radians(half)), float(blend))


def lambert_table_spec(g, albedo):
    """The table of a one-sided Lambertian emitter about the axis, f(c) = max(0, c) (an area light far from
    it, per unit normal intensity I_n): as ``table_spec``'s."""
    return _spec(g, albedo, "lambert", 0.0, None)


def _spec(g, albedo, profile, cos_half, blend):
    """The table's spec; its ``args`` (``spec_parameters``) hold g, W0 and the cone as rounded in its name: the
    bake is a function of the name's values alone."""
    g_name, w0 = f"{float(g):+.3f}", f"{round(float(albedo), 3):.3f}"
    return tables.TableSpec(f"AnalyticFog Spot Multiple (g {g_name}, W0 {w0}, {profile})", THETA_NODES,
                            2 * ROWS * PSI_NODES, float(g), channels=PHI_NODES, kind=KIND_KEY,
                            args=(float(g_name), float(w0), cos_half, blend))


def spec_parameters(spec):
    """(g, albedo, cos_half, blend) a ``table_spec`` was made for, as rounded in its name (the cone's half-angle
    to whole degrees); a ``lambert_table_spec``'s: (g, albedo, 0, None)."""
    return spec.args


def _fill(j, count):
    """Cells with fewer than MIN_COUNT collisions take the collision-weighted mean of J T over their 3 x 3
    neighbourhood in (T, psi) (themselves included): the sparse cells beside the cone near the lamp."""
    t = row_distances()[:, None, None, None]
    jt = j * t
    weighted = jt * count[..., None, None]
    pad_w = np.pad(weighted, ((1, 1), (1, 1), (0, 0), (0, 0)))
    pad_c = np.pad(count, 1)
    sum_w = sum(pad_w[1 + a:1 + a + ROWS, 1 + b:1 + b + PSI_NODES] for a in (-1, 0, 1) for b in (-1, 0, 1))
    sum_c = sum(pad_c[1 + a:1 + a + ROWS, 1 + b:1 + b + PSI_NODES] for a in (-1, 0, 1) for b in (-1, 0, 1))
    mean = sum_w / np.maximum(sum_c, 1.0)[..., None, None]
    return np.where((count < MIN_COUNT)[..., None, None], mean, jt)


def _smooth_rows(jt):
    """A [1, 2, 1] / 4 mean of J T over neighbouring rows (T), the first and last rows kept: the rows are
    1.4x apart in T, where J T changes slowly, and the cells' Monte Carlo noise is independent."""
    out = jt.copy()
    out[1:-1] = 0.25 * (jt[:-2] + 2.0 * jt[1:-1] + jt[2:])
    return out


def bake_table(spec, photons=PHOTONS, seed=SEED, progress=None):
    """The float32 image of ``spec`` (``table_spec``), (2 PSI_NODES ROWS, THETA_NODES, PHI_NODES): band k (rows
    k ROWS .. (k + 1) ROWS - 1) holds ln(J T) at the k-th psi, band PSI_NODES + k ln E there (``collide``;
    ``progress(done, total)`` as it calls it)."""
    g, albedo, cos_half, blend = spec_parameters(spec)
    j, count, e = collide(g, albedo, cos_half, blend, photons=photons, seed=seed, progress=progress)
    t = row_distances()[:, None, None, None]
    blocks = (_smooth_rows(_fill(j, count)), _smooth_rows(_fill(e, count)) / t)   # (ROWS, PSI, THETA, PHI)
    log = [np.log(np.maximum(b, FLOOR)).transpose(1, 0, 2, 3).reshape(PSI_NODES * ROWS, THETA_NODES, PHI_NODES)
           for b in blocks]
    return np.ascontiguousarray(np.concatenate(log)).astype(np.float32)



# seconds of a bake (``estimate_seconds``): a fixed part, then per exact tally, per photon step and per loop
# iteration, fitted to bakes on 2 cores (docs/measurements/2026-11-29-bake-time.md; the steps' and the iterations'
# refitted to six 4 000-photon walks: docs/measurements/2026-11-30-test-time.md)
COST = {"fixed": 0.02, "exact": 2.4e-6, "steps": 0.305e-6, "iterations": 0.155e-3}


def estimate_seconds(spec, photons=PHOTONS):
    """About how long ``bake_table(spec, photons)`` takes (``walk_counts`` times COST), s."""
    g, albedo, _, _ = spec_parameters(spec)
    counts = walk_counts(g, albedo, photons)
    return COST["fixed"] + sum(COST[k] * v for k, v in counts.items())


def _label(spec):
    """"the spot table (g +0.850, W0 0.900, cone 45 deg, blend 0.15)", or the area light's."""
    return f"the {'area light' if spec.args[3] is None else 'spot'} table ({tables.details(spec)})"


KIND_KEY = "spot_multiple"
KIND = tables.TableKind(KIND_KEY, make=table_spec, bake=bake_table, estimate=estimate_seconds, label=_label)
TABLE_KINDS = (KIND,)   # (``registry.KINDS``; ``lambert_table_spec`` makes this kind's specs too)


def _row_y(m, optical_distance):
    """The row coordinate in [0, 1] within a band of optical distance T (clamped to the table)."""
    return m.clamp01(m.log(m.maximum(optical_distance, T_MIN) * (1.0 / T_MIN)) * (1.0 / math.log(T_MAX / T_MIN)))


def _read(m, spec, block, optical_distance, cos_psi, cos_theta, phi):
    """exp of ``spec``'s ``block`` (0: ln(J T), 1: ln E) at optical distance T from the lamp, cos psi from the
    axis, for the direction at cos theta from e_r and azimuth phi in [0, pi] (linear in psi and phi, bilinear
    in theta and T within a band, in the logarithm)."""
    x = m.sqrt(_acos(m, cos_theta) * (1.0 / math.pi))
    band = _acos(m, cos_psi) * ((PSI_NODES - 1.0) / math.pi)
    b0 = m.minimum(m.floor(band), PSI_NODES - 2.0)
    frac = band - b0
    height = 2.0 * ROWS * PSI_NODES - 1.0
    y0 = ((b0 + block * PSI_NODES) * ROWS + _row_y(m, optical_distance) * (ROWS - 1.0)) * (1.0 / height)
    y1 = y0 + ROWS / height
    slot = phi * ((PHI_NODES - 1.0) / math.pi)
    value = 0.0
    for k in range(PHI_NODES):
        weight = m.maximum(1.0 - m.abs(slot - float(k)), 0.0)
        a = m.table(spec, x, y0, channel=k)
        value = value + weight * (a + frac * (m.table(spec, x, y1, channel=k) - a))
    return m.exp(value)


def source_times_t(m, spec, optical_distance, cos_psi, cos_theta, phi):
    """J T at optical distance T from the lamp, cos psi from the axis, for the outgoing direction at cos theta
    from e_r and azimuth phi in [0, pi] (``spec``'s table)."""
    return _read(m, spec, 0, optical_distance, cos_psi, cos_theta, phi)


def scatter(m, spec, beta, d_sp, cos_n, c_axis, cos_n_axis):
    """The multiply scattered light a diffuse surface reflects, per unit on-axis intensity and albedo, 1/m^2
    (the scatter term's convention): beta^2 E / pi, E the irradiance from orders >= 2 of a surface at
    ``d_sp`` m from the lamp, its point at cos psi = ``c_axis`` from the axis, its normal at ``cos_n`` from
    the direction to the lamp and ``cos_n_axis`` from the axis (``spot.scatter``'s arguments).  In the frame
    (e_r, e_psi, e_phi) of the point, n . e_r = -cos_n and n . e_psi sin psi = -(cos_n c_axis + cos_n_axis)."""
    along_psi = -1.0 * (cos_n * c_axis + cos_n_axis)
    sin2 = 1.0 - c_axis * c_axis
    across = m.sqrt(sin2 * (1.0 - cos_n * cos_n) - along_psi * along_psi)
    phi = m.atan2(across, along_psi)
    e = _read(m, spec, 1, beta * d_sp, c_axis, -1.0 * cos_n, phi)
    return beta * beta * (1.0 / math.pi) * e


def _gauss_legendre(n):
    return np.polynomial.legendre.leggauss(int(n))


def _acos(m, c):
    """arccos c (rad) from the ops at hand: atan2(sqrt(1 - c^2), c)."""
    return m.atan2(m.sqrt(1.0 - c * c), c)


def _asinh(m, x):
    """arsinh x = sign(x) ln(|x| + sqrt(x^2 + 1)), without the cancellation of x + sqrt(x^2 + 1) at x << 0."""
    a = m.abs(x)
    value = m.log(a + m.sqrt(a * a + 1.0))
    return m.select(m.less(x, 0.0), -1.0 * value, value)


def _point(spec, m, beta, along, h, v, oz, ez, side):
    """beta^2 e^{-beta t} (J T) at the ray's point t = a + h sinh v (``airlight``)."""
    up = m.exp(v)
    down = 1.0 / up
    t = along + h * (0.5 * (up - down))
    r = h * (0.5 * (up + down))
    cos_psi = -1.0 * (oz + t * ez) / r
    cos_theta = (along - t) / r                               # omega = -e against e_r = q / r
    phi = m.atan2(m.abs(side), cos_theta * cos_psi * r - ez * r)
    return beta * beta * m.exp(-1.0 * beta * t) * source_times_t(m, spec, beta * r, cos_psi, cos_theta, phi)


def _piece(m, spec, beta, ray, along, h, t0, t1, nodes):
    """int_{t0}^{t1} beta^2 e^{-beta t} J T dv, t = a + h sinh v (``airlight``), by ``nodes``-point Gauss-Legendre;
    each point one shared sub-program (a node group: the compositor builds its nodes once)."""
    oz, ez, side = ray
    v0 = _asinh(m, (t0 - along) / h)
    v1 = _asinh(m, (t1 - along) / h)
    half = 0.5 * (v1 - v0)
    mid = 0.5 * (v1 + v0)
    x_nodes, w_nodes = _gauss_legendre(nodes)
    point = functools.partial(_point, spec)
    total = 0.0
    for xi, wi in zip(x_nodes, w_nodes):
        value = m.group(f"Spot Multiple Point [{spec.name}]", point, beta, along, h, mid + float(xi) * half, oz, ez,
                        side)
        total = total + float(wi) * value
    return half * total


def airlight(m, spec, beta, d_vp, px, py, pz, dx, dy, dz, cos_half, nodes=NODES):
    """The multiply scattered glow of a spot along a camera ray's first ``d_vp`` m (model.FAR: to the sky),
    per unit on-axis intensity and albedo, 1/m^2: beta^3 int e^{-beta t} J dt in v, t = a + h sinh v
    (module docstring).  (px, py, pz, dx, dy, dz): the ray in the light's space (``spot.light_space_ray``;
    any uniform scale), the cone's axis its -Z; ``cos_half`` = cos(spot size / 2).  Near the lamp J drops
    by decades across the cone's edge, so the ray is cut where it crosses the edge (``spot.cone_interval``;
    for a cone wider than a hemisphere, the complement's; a ray that misses it at four closest-approach
    distances h about it) and each piece takes its share of ``nodes`` Gauss-Legendre points (NODES: before,
    inside, after)."""
    inv = 1.0 / m.maximum(m.sqrt(dx * dx + dy * dy + dz * dz), 1e-30)
    ox, oy, oz, ex, ey, ez = px * inv, py * inv, pz * inv, dx * inv, dy * inv, dz * inv
    along = -1.0 * (ox * ex + oy * ey + oz * ez)                 # to the closest approach, m
    h = m.maximum(m.sqrt(ox * ox + oy * oy + oz * oz - along * along), 1e-6)
    t_end = m.minimum(d_vp, m.maximum(along, 0.0) + REACH / m.maximum(beta, 1e-12))
    wide = m.less(cos_half, 0.0)
    flip = 1.0 - 2.0 * wide
    lo, hi = spot.cone_interval(m, (ox, oy, flip * oz), (ex, ey, flip * ez), m.abs(cos_half), t_end)
    # a ray that misses the cone: its middle piece the stretch about the closest approach instead
    miss = 1.0 - m.less(lo, hi)
    lo = m.select(miss, m.maximum(along - 2.0 * h, 0.0), lo)
    hi = m.select(miss, m.maximum(along + 2.0 * h, 0.0), hi)
    lo, hi = m.minimum(lo, t_end), m.minimum(hi, t_end)
    ray = (oz, ez, ex * oy - ey * ox)   # the last: omega . (e_r x axis) r, the same along the ray
    before, inside, after = nodes
    return (_piece(m, spec, beta, ray, along, h, 0.0, lo, before) + _piece(m, spec, beta, ray, along, h, lo, hi, inside)
            + _piece(m, spec, beta, ray, along, h, hi, t_end, after))
