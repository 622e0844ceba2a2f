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

from . import point_source_mc, spot, tables

T_MIN = 0.005          # the first row's optical distance from the lamp (below: J T held, J ~ 1/T)
T_MAX = 40.0           # the last row's (beyond: held; e^-40 of the light)
ROWS = 28              # rows in T, geometric
PSI_NODES = 37         # bands in psi, 0 .. 180 deg every 5 deg (the cone edge is sharp near the lamp)
THETA_NODES = 32       # columns in theta = pi u^2 (u uniform: dense towards e_r, where J peaks)
PHI_NODES = 4          # channels: phi = 0, 60, 120, 180 deg
PHOTONS = 100_000      # a bake: about 15 s on 2 cores (docs/measurements/2026-11-28-spot-multiple.md)
SEED = 20261128
FIRST_RANGE = (1e-3, 30.0)   # the first collision's distance, drawn log-uniformly in it
R_MAX = T_MAX + 20.0   # photons farther than this are dropped
ROULETTE = 1e-3
MIN_COUNT = 40         # a cell with fewer collisions takes its neighbours' too (``_fill``)
FLOOR = 1e-30
NODES = (6, 6, 6)      # quadrature points along a camera ray: before, inside and after the cone
REACH = 30.0           # optical depth past the closest approach where a ray to the sky stops counting


def row_distances():
    """The rows' optical distances T (ROWS, geometric from T_MIN to T_MAX)."""
    return np.geomspace(T_MIN, T_MAX, ROWS)


def psi_angles():
    """The bands' angles from the axis (rad), PSI_NODES from 0 to pi."""
    return np.linspace(0.0, math.pi, PSI_NODES)


def theta_angles():
    """The columns' angles of the outgoing direction from e_r (rad): pi u^2."""
    return math.pi * np.linspace(0.0, 1.0, THETA_NODES) ** 2


def phi_angles():
    """The channels' azimuths of the outgoing direction about e_r from the axis' plane (rad)."""
    return np.linspace(0.0, math.pi, PHI_NODES)


def cone_key(cos_half, blend):
    """(half-angle in whole degrees, blend in hundredths): the cone a table is baked for."""
    half = math.degrees(math.acos(min(max(float(cos_half), -1.0), 1.0)))
    return int(round(half)), int(round(100.0 * min(max(float(blend), 0.0), 1.0)))


def table_spec(g, albedo, cos_half, blend):
    """The table of a spot of cone ``cos_half`` = cos(spot size / 2) and ``blend`` in fog of anisotropy g and
    grey albedo W0: 2 PSI_NODES bands of ROWS rows (T) by THETA_NODES columns, PHI_NODES channels."""
    half, hundredths = cone_key(cos_half, blend)
    return _spec(g, albedo, f"cone {half} deg, blend {hundredths / 100:.2f}")


def lambert_table_spec(g, albedo):
    """The table of a one-sided Lambertian emitter about the axis, f(c) = max(0, c) (an area light far from
    it, per unit normal intensity I_n): as ``table_spec``'s."""
    return _spec(g, albedo, "lambert")


def _spec(g, albedo, profile):
    return tables.TableSpec(f"AnalyticFog Spot Multiple (g {float(g):+.3f}, W0 {round(float(albedo), 3):.3f}, "
                            f"{profile})", THETA_NODES, 2 * ROWS * PSI_NODES, float(g), channels=PHI_NODES)


def spec_parameters(spec):
    """(g, albedo, cos_half, blend) a ``table_spec`` was named for; a ``lambert_table_spec``'s: (g, albedo,
    0, None)."""
    inside = spec.name.split("(", 1)[1].rstrip(")")
    fields = dict(part.strip().split(" ", 1) if " " in part.strip() else (part.strip(), "")
                  for part in inside.split(","))
    if "lambert" in fields:
        return float(fields["g"]), float(fields["W0"]), 0.0, None
    return (float(fields["g"]), float(fields["W0"]), math.cos(math.radians(float(fields["cone"].split()[0]))),
            float(fields["blend"]))


def _falloff(c, cos_half, blend):
    """Blender's spot factor at cosine c to the axis (``spot.spot_falloff`` on numpy arrays)."""
    if blend <= 0.0:
        return (c > cos_half).astype(np.float64)
    x = np.clip((c - cos_half) / ((1.0 - cos_half) * blend), 0.0, 1.0)
    return np.where(c > cos_half, x * x * (3.0 - 2.0 * x), 0.0)


def cone_power(cos_half, blend):
    """int f dOmega over the sphere (sr) of Blender's spot factor: 2 pi (1 - cos_half)(1 - blend / 2), the
    smoothstep's mean over its ramp being 1/2; ``blend`` None: Lambert's, pi."""
    if blend is None:
        return math.pi
    return 2.0 * math.pi * (1.0 - cos_half) * (1.0 - 0.5 * blend)


def _emit(rng, n, cos_half, blend):
    """n unit directions about +z distributed as the spot factor (rejection in the cosine)."""
    if blend is None:   # Lambert: c = sqrt(u) has density 2c on [0, 1]
        c = np.sqrt(rng.random(n))
        phi = rng.uniform(0.0, 2.0 * math.pi, n)
        s = np.sqrt(np.maximum(1.0 - c * c, 0.0))
        return np.stack([s * np.cos(phi), s * np.sin(phi), c], axis=1)
    out, have = [], 0
    while have < n:
        c = rng.uniform(cos_half, 1.0, 2 * n)
        c = c[rng.random(2 * n) < _falloff(c, cos_half, blend)]
        out.append(c)
        have += len(c)
    c = np.concatenate(out)[:n]
    phi = rng.uniform(0.0, 2.0 * math.pi, n)
    s = np.sqrt(np.maximum(1.0 - c * c, 0.0))
    return np.stack([s * np.cos(phi), s * np.sin(phi), c], axis=1)


def _hg(g, c):
    """Henyey-Greenstein phase function per steradian."""
    return (1.0 - g * g) / (4.0 * math.pi * (1.0 + g * g - 2.0 * g * c) ** 1.5)


def _edges(nodes, log):
    """Cell edges about ``nodes``: midpoints (geometric if ``log``), the ends half a step out."""
    x = np.log(nodes) if log else nodes
    mid = 0.5 * (x[1:] + x[:-1])
    e = np.concatenate([[x[0] - (mid[0] - x[0])], mid, [x[-1] + (x[-1] - mid[-1])]])
    return np.exp(e) if log else e


def _out_directions():
    """(THETA_NODES * PHI_NODES, 3) outgoing directions in the local frame (e_r, e_psi, e_phi)."""
    th, ph = np.meshgrid(theta_angles(), phi_angles(), indexing="ij")
    th, ph = th.ravel(), ph.ravel()
    return np.stack([np.cos(th), np.sin(th) * np.cos(ph), np.sin(th) * np.sin(ph)], axis=1)


def collide(g, albedo, cos_half, blend, photons=PHOTONS, seed=SEED, batch=10_000):
    """(J, collisions, E) per cell: J (ROWS, PSI_NODES, THETA_NODES, PHI_NODES) per unit on-axis intensity at
    extinction 1, the axis +z (module docstring); E the same shape: the irradiance from orders >= 2 of a surface
    facing each tabulated direction, per unit albedo (the shading multiplies by it)."""
    t_edges, p_edges = _edges(row_distances(), True), _edges(psi_angles(), False)
    p_edges[0], p_edges[-1] = 0.0, math.pi
    n_cells = ROWS * PSI_NODES
    out = _out_directions()
    mirror = out * np.array([1.0, 1.0, -1.0])
    tally = np.zeros((n_cells, len(out)))
    flux = np.zeros((n_cells, len(out)))      # the irradiance of surfaces facing each direction, orders >= 2
    count = np.zeros(n_cells)
    rng = np.random.default_rng(seed)
    lo, hi = FIRST_RANGE
    axis = np.array([0.0, 0.0, 1.0])
    done = 0
    while done < photons:
        n = min(batch, photons - done)
        done += n
        d = _emit(rng, n, cos_half, blend)
        p = np.zeros((n, 3))
        w = np.ones(n)
        order = 0
        while len(w):
            if order == 0:
                s = lo * (hi / lo) ** rng.random(len(w))
                w = w * np.exp(-s) * s * math.log(hi / lo)
            else:
                s = -np.log(1.0 - rng.random(len(w)))
            p = p + s[:, None] * d
            r = np.linalg.norm(p, axis=1)
            if order >= 1:
                sel = (r > t_edges[0]) & (r < t_edges[-1])
                rr = r[sel]
                er = p[sel] / rr[:, None]
                cz = np.clip(er[:, 2], -1.0, 1.0)
                ep = er * cz[:, None] - axis
                norm = np.linalg.norm(ep, axis=1)
                ep = np.where(norm[:, None] > 1e-9, ep / np.maximum(norm, 1e-12)[:, None], np.array([1.0, 0.0, 0.0]))
                ef = np.cross(er, ep)
                dd = d[sel]
                local = np.stack([np.einsum("ij,ij->i", dd, er), np.einsum("ij,ij->i", dd, ep),
                                  np.einsum("ij,ij->i", dd, ef)], axis=1)
                cell = ((np.searchsorted(t_edges, rr) - 1) * PSI_NODES
                        + np.clip(np.searchsorted(p_edges, np.arccos(cz)) - 1, 0, PSI_NODES - 1))
                value = 0.5 * (_hg(g, local @ out.T) + _hg(g, local @ mirror.T)) * w[sel][:, None]
                order_ = np.argsort(cell, kind="stable")
                cells, starts = np.unique(cell[order_], return_index=True)
                tally[cells] += np.add.reduceat(value[order_], starts, axis=0)
                if order >= 2:   # a surface facing n takes max(0, -w_in . n) of the radiance (per unit albedo)
                    facing = 0.5 * (np.maximum(-(local @ out.T), 0.0) + np.maximum(-(local @ mirror.T), 0.0))
                    flux[cells] += np.add.reduceat((facing * (w[sel] / albedo)[:, None])[order_], starts, axis=0)
                count += np.bincount(cell, minlength=n_cells)
            w = w * albedo
            order += 1
            d = point_source_mc.turn(d, point_source_mc.sample_hg(rng, g, len(w)),
                                     rng.uniform(0.0, 2.0 * math.pi, len(w)))
            low = w < ROULETTE
            if low.any():
                live = rng.random(len(w)) < 0.1
                w = np.where(low, np.where(live, w * 10.0, 0.0), w)
            keep = (w > 0.0) & (r < R_MAX)
            p, d, w = p[keep], d[keep], w[keep]
    volume = ((t_edges[1:, None] ** 3 - t_edges[:-1, None] ** 3) / 3.0 * 2.0 * math.pi
              * (np.cos(p_edges[None, :-1]) - np.cos(p_edges[None, 1:])))
    shape = (ROWS, PSI_NODES, THETA_NODES, PHI_NODES)
    scale = (cone_power(cos_half, blend) / photons) / volume[..., None]
    return (tally.reshape(ROWS, PSI_NODES, -1) * scale).reshape(shape), count.reshape(ROWS, PSI_NODES), (
        flux.reshape(ROWS, PSI_NODES, -1) * scale).reshape(shape)


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


def bake_table(spec, photons=PHOTONS, seed=SEED):
    """The float32 image of ``spec`` (``table_spec``), (2 PSI_NODES ROWS, THETA_NODES, PHI_NODES): band k (rows
    k ROWS .. (k + 1) ROWS - 1) holds ln(J T) at the k-th psi, band PSI_NODES + k ln E there (``collide``)."""
    g, albedo, cos_half, blend = spec_parameters(spec)
    j, count, e = collide(g, albedo, cos_half, blend, photons=photons, seed=seed)
    t = row_distances()[:, None, None, None]
    blocks = (_smooth_rows(_fill(j, count)), _smooth_rows(_fill(e, count)) / t)   # (ROWS, PSI, THETA, PHI)
    log = [np.log(np.maximum(b, FLOOR)).transpose(1, 0, 2, 3).reshape(PSI_NODES * ROWS, THETA_NODES, PHI_NODES)
           for b in blocks]
    return np.ascontiguousarray(np.concatenate(log)).astype(np.float32)


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
