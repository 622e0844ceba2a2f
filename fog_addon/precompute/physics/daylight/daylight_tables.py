"""A fog layer's tables and their bake: the glow along camera rays, the fog light on surfaces, the World's sky.

``sunlight.py`` composes the sun's and the sky's light through a fog layer from ``daylight.py``'s and ``aerial.py``'s
kernels; three of its terms are read from tables baked here (numpy, float64, the kernels the shaders run otherwise):

* the glow along every camera ray of one camera height (``bake_glow_table``; ``sunlight.table_glow`` reads it),
  re-baked in place when the camera moves;
* the fog light on surfaces (``bake_fog_light``; ``sunlight.fog_light`` reads it): the in-scattered radiance field
  depends on height alone (the medium is plane-parallel), so its irradiance is an order-2 spherical-harmonic
  irradiance map per height (Ramamoorthi & Hanrahan 2001: the clamped cosine keeps l <= 2 of the field, the rest is
  below a few per cent of the irradiance), read per pixel from the normal (``sh_basis``);
* the World's radiance over the upper hemisphere when the World is a sky seen through its own air
  (``sky_table_from_probe``; ``sunlight.world_radiance`` reads it).

``TABLE_KINDS`` lists the three for ``registry.py``.
"""
import math
from typing import Any, NamedTuple

import numpy as np

from ...core import tables
from . import aerial, daylight
SKY_ROWS = 32            # elevations 0..90 degrees of the World's radiance table (``world_radiance``), row j at
                         # 90 ((j + 1/2) / SKY_ROWS)^2 degrees: dense at the horizon, where a sky changes fastest
SKY_COLUMNS = 128        # azimuths, from -180 degrees (-Y through -X) to +180, 0 along +Y
SKY_TABLE = "AnalyticFog World Sky"


def sky_row_elevations(rows=SKY_ROWS):
    """(rows,) radians: the elevations of the World's radiance table's rows (``world_radiance``)."""
    return 0.5 * math.pi * ((np.arange(rows) + 0.5) / rows) ** 2


def sky_table_from_probe(pixels, rows=SKY_ROWS):
    """(rows, columns, 4) float32: the World's radiance table from an equirectangular probe ((h, columns, 3), row 0
    at +90 degrees, rows of equal elevation), each row linearly between the probe's rows at its elevation."""
    h = pixels.shape[0]
    centres = (0.5 - (np.arange(h) + 0.5) / h) * math.pi        # the probe's rows' elevations, falling
    el = sky_row_elevations(rows)
    at = np.interp(el, centres[::-1], np.arange(h)[::-1].astype(float))   # fractional probe row of each elevation
    lo = np.floor(at).astype(int)
    hi = np.minimum(lo + 1, h - 1)
    t = (at - lo)[:, None, None]
    rgb = pixels[lo] * (1.0 - t) + pixels[hi] * t
    return np.concatenate([rgb, np.ones(rgb.shape[:2] + (1,))], axis=-1).astype(np.float32)


# --- the glow along camera rays: a table per camera height -----------------------------------------------

GLOW_ELEVATIONS = 128   # rows: the ray's elevation, y = (1 + sign(v_z) sqrt|v_z|) / 2 (dense about the horizon)
GLOW_DISTANCES = 256    # columns: the segment's length, x = L / (L + L0) (the sky at x = 1)
GLOW_NAME = "AnalyticFog Daylight Glow"


class GlowTable(NamedTuple):
    """The glow of ``ray_glow`` along every camera ray of one camera height (``bake_glow_table``)."""
    spec: Any             # tables.TableSpec: GLOW_DISTANCES x (GLOW_ELEVATIONS x blocks) RGBA texels
    length_scale: float   # L0, units: the distance at x = 1/2 (``glow_length_scale``)
    blocks: int           # 1 without air; with air 3, a colour channel each


def glow_length_scale(beta, air=None):
    """L0 (units): one mean free path at the ground, of the layer and the air's mean channel together; half of the
    table's columns lie nearer than that."""
    extinction = float(beta) + (0.0 if air is None else sum(float(b) for b in air) / 3.0)
    return 1.0 / max(extinction, 1e-9)


def sky_spec():
    """The TableSpec of the World's radiance table (``sky_table_from_probe``; ``world_radiance`` reads it)."""
    return tables.TableSpec(SKY_TABLE, SKY_COLUMNS, SKY_ROWS, channels=4, kind=SKY_KIND.key)


def glow_table(beta, air=None):
    """The ``GlowTable`` of a layer of extinction ``beta`` (1/unit) and ``air`` (three channels' ground extinction,
    1/unit, or None): one image per file, its texels re-baked in place for another camera height."""
    blocks = 1 if air is None else 3
    return GlowTable(tables.TableSpec(GLOW_NAME, GLOW_DISTANCES, GLOW_ELEVATIONS * blocks, channels=4,
                                      kind=GLOW_KIND.key), glow_length_scale(beta, air), blocks)


def glow_coordinates(m, vz, length, length_scale):
    """(x, y) of the glow table for a ray of elevation sine ``vz`` and a segment ``length`` (units; model.FAR or
    more: the sky)."""
    s = m.sqrt(m.abs(vz))
    y = 0.5 + 0.5 * m.select(m.less(vz, 0.0), -1.0 * s, s)
    length = m.minimum(length, daylight.UNBOUNDED)
    return length / (length + length_scale), y


def _glow_grid(length_scale):
    """The table's (v_z (rows,), L (columns,)) at its texel centres (numpy)."""
    s = np.linspace(-1.0, 1.0, GLOW_ELEVATIONS)
    x = np.linspace(0.0, 1.0, GLOW_DISTANCES)
    with np.errstate(divide="ignore"):
        length = np.where(x < 1.0, length_scale * x / np.maximum(1.0 - x, 1e-300), daylight.UNBOUNDED)
    return np.sign(s) * s * s, np.minimum(length, daylight.UNBOUNDED)


def bake_glow_table(beta, top, falloff, mu_s, g, camera_height, air=None, air_height=0.0):
    """(GLOW_ELEVATIONS x blocks, GLOW_DISTANCES, 4) float32: ``ray_glow``'s integrals per unit sun irradiance and
    sky radiance along every camera ray from ``camera_height`` (units above the ground), on the grid of
    ``glow_coordinates``, the same kernels the shaders run otherwise (numpy, float64).  The sun's phase function is
    left out (constant along a ray: ``table_glow`` multiplies it per pixel) and its elevation sine ``mu_s`` baked in.

    Without air one block, texels (I, L_sky, 0, 0): I the phase-free sun integral (``daylight.sun_airlight``
    over its phase), L_sky the layer's sky glow (``daylight.sky_airlight``, of anisotropy g), albedo 1.  With air a
    block per colour channel, texels (sun_l, sun_a, the layer's sky glow times the air's share, sky_a) of
    ``aerial.air_glow``: the albedo stays out (a driven value)."""
    m = _numpy_ops()
    vz, length = _glow_grid(glow_length_scale(beta, air))
    vz, length = np.meshgrid(vz, length, indexing="ij")
    pz = np.full_like(vz, float(camera_height))
    args = (beta, top, falloff)
    sky = daylight.sky_airlight(m, pz, vz, length, *args, albedo=1.0, g=g)
    if air is None:
        sun = daylight.sun_airlight(m, pz, vz, length, mu_s, 1.0, *args, albedo=1.0, g=0.0) * (4.0 * math.pi)
        out = np.stack([sun, sky, 0.0 * sun, 0.0 * sun], axis=-1)
    else:
        lit = 1.0 if mu_s > 0.0 else 0.0
        blocks = [np.stack([lit * sun_l, lit * sun_a, sky * ratio, sky_a], axis=-1)
                  for sun_l, sun_a, sky_a, ratio in aerial.air_glow(m, pz, vz, length, mu_s, *args, tuple(air),
                                                                      air_height, g)]
        out = np.concatenate(blocks, axis=0)
    return out.astype(np.float32)


# --- the fog light on surfaces: an irradiance map per height -------------------------------------------------

Z_COUNT = 64            # heights of the fog light's table, from the ground to ``table_height``
SH_COUNT = 9            # real spherical harmonics l <= 2
TABLE_ROWS = 5          # the 2 x 9 coefficients in RGBA texels: coefficient k in row k // 4, channel k % 4
FALLOFF_SPAN = 8.0      # the table spans the top + this many falloff lengths (the column left is e^-8 of it)
BAKE_MU = 32            # Gauss-Legendre nodes in each hemisphere's direction cosine (``bake_fog_light``)
BAKE_PHI = 64           # azimuths
PEAK_TERMS = 400        # Legendre terms of ``peak_irradiance`` (g^400 < 1e-8 for g <= 0.95)
CLAMPED_COSINE = (math.pi, 2.0 * math.pi / 3.0, math.pi / 4.0)   # A_l: the clamped cosine's SH (R & H 2001 Eq. 8)


def sh_basis(m, n):
    """The nine real spherical harmonics Y_lm (l <= 2) of unit vector ``n`` (Ramamoorthi & Hanrahan 2001 Eq. 3's
    constants), in the order (0,0), (1,-1), (1,0), (1,1), (2,-2), (2,-1), (2,0), (2,1), (2,2)."""
    x, y, z = (m.dot(n, axis) for axis in ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0)))
    c1, c2, c3, c4 = 0.488603, 1.092548, 0.315392, 0.546274
    return (0.282095 + 0.0 * x, c1 * y, c1 * z, c1 * x, c2 * (x * y), c2 * (y * z), c3 * (3.0 * (z * z) - 1.0),
            c2 * (x * z), c4 * (x * x - y * y))


def _sh_order(k):
    return 0 if k == 0 else (1 if k < 4 else 2)


def table_height(top, falloff):
    """The highest height the fog light's table holds (units): the top, plus FALLOFF_SPAN falloff lengths.  Above a
    hard top the field is that of the top (the layer below is all a surface there sees: plane-parallel)."""
    return max(float(top) + FALLOFF_SPAN * float(falloff), 1e-6)


def table_spec(beta, top, falloff, sun, g, air=None):
    """The TableSpec of the fog light's irradiance map for a layer (1/unit, units) and sun direction (unit vector);
    ``air``: None, or (one channel's air extinction at the ground 1/unit, its scale height units, the layer's albedo
    in that channel) for that channel's map with air (``bake_fog_light``)."""
    s = ", ".join(f"{float(c):+.4f}" for c in sun)
    a = "" if air is None else ", air " + ", ".join(f"{float(v):.6g}" for v in air)
    return tables.TableSpec(f"AnalyticFog Daylight Fog Light (beta {float(beta):.6g}, top {float(top):.6g}, "
                            f"H {float(falloff):.6g}, sun {s}, g {float(g):+.3f}{a})", Z_COUNT, TABLE_ROWS,
                            g=float(g), channels=4, kind=FOG_LIGHT_KIND_KEY, args=(beta, top, falloff, sun, g, air))


def peak_irradiance(g, cos_ns):
    """C_g(c) / pi: the irradiance over pi that a surface receives from a field p(d.s) (Henyey-Greenstein of
    anisotropy g around the direction s, unit integral) at c = n.s, by Funk-Hecke: sum_l k_l g^l P_l(c), k_l the
    clamped cosine's Legendre coefficients (2l+1)/2 int_0^1 x P_l(x) dx (numpy, float64; l up to PEAK_TERMS)."""
    x, w = np.polynomial.legendre.leggauss(2 * PEAK_TERMS)
    x, w = 0.5 * (x + 1.0), 0.5 * w
    c = np.asarray(cos_ns, float)
    total = np.zeros_like(c)
    # P_l at the nodes and at c by Bonnet's recurrence, (l + 1) P_{l+1} = (2l + 1) x P_l - l P_{l-1}
    p_x, p_x_prev = np.ones_like(x), np.zeros_like(x)
    p_c, p_c_prev = np.ones_like(c), np.zeros_like(c)
    for l in range(PEAK_TERMS):
        k_l = (2 * l + 1) / 2.0 * np.sum(w * x * p_x)
        total = total + k_l * g ** l * p_c
        p_x, p_x_prev = ((2 * l + 1) * x * p_x - l * p_x_prev) / (l + 1), p_x
        p_c, p_c_prev = ((2 * l + 1) * c * p_c - l * p_c_prev) / (l + 1), p_c
    return total / math.pi


def bake_fog_light(beta, top, falloff, sun, g, air=None):
    """(TABLE_ROWS, Z_COUNT, 4) float32: the fog light's irradiance map (per unit albedo, over pi) at each height
    z_k = k / (Z_COUNT - 1) ``table_height``.  Coefficient k = 4 row + channel:

    * 0..8: the sun's field minus its peak, SH coefficients A_l L_lm / pi per unit sun irradiance;
    * 9..17: the sky's field, the same per unit sky radiance;
    * 18: I_s(z), the sun's integral along the sun's own direction (``sun_airlight`` at cos 1 over the phase there);
    * 19: C_g(c) / pi at c = 2 k / (Z_COUNT - 1) - 1 (``peak_irradiance``; not a function of height).

    The sun's field is I(d_z) p(d.s), I the phase-free integral along d: written I(mu_s) p(d.s) + (I(d_z) -
    I(mu_s)) p(d.s), the first term's irradiance is I_s C_g(n.s) exactly (Funk-Hecke) and the second, which
    vanishes at the phase's peak, is smooth enough for l <= 2 (sum_k c_k Y_k(n)).  L(d) is ``ray_glow``'s per-unit
    sun and sky terms along d from the point, to the ground (the field's own geometry) or to the sky; numerical
    quadrature: BAKE_MU Gauss-Legendre nodes per hemisphere x BAKE_PHI azimuths.

    With ``air`` (b, h_air, a: one colour channel's air extinction at the ground, its scale height, the layer's
    albedo in that channel) the map is that channel's, both species' light, the albedos folded in: the sun's field
    a p_HG I_l(d) + p_R I_a(d) (``aerial.air_glow``; the peak taken out of the layer's part as above, I_s the
    layer's integral along the sun) and the sky's a L_l(d) r(d) + L_a(d) (the layer's exact sky glow times the
    air's share of it, and the air's own)."""
    if air is not None:
        return _bake_fog_light_air(beta, top, falloff, sun, g, *air)
    sun = np.asarray(sun, float) / np.linalg.norm(sun)
    m = _numpy_ops()
    mu_g, d, dw = _bake_grid()
    phase = daylight.hg_phase(m, g, d @ sun)
    args = (beta, top, falloff)

    def fields(z, length):
        i_d = daylight.sun_airlight(m, z, mu_g, length, sun[2], 1.0, *args, albedo=1.0, g=0.0) * (4.0 * math.pi)
        i_s = daylight.sun_airlight(m, z, sun[2], daylight.UNBOUNDED, sun[2], 1.0, *args, albedo=1.0,
                                    g=0.0) * (4.0 * math.pi)
        l_sky = daylight.sky_airlight(m, z, mu_g, length, *args, albedo=1.0, g=g)
        return (i_d - i_s) * phase, l_sky, i_s
    return _bake_map(m, top, falloff, g, mu_g, d, dw, fields)


def bake_fog_light_table(spec, progress=None):
    """``bake_fog_light`` of the arguments ``spec`` was made from (``table_spec``)."""
    return bake_fog_light(*spec.args)


FOG_LIGHT_KIND_KEY = "daylight_fog_light"
FOG_LIGHT_KIND = tables.TableKind(FOG_LIGHT_KIND_KEY, make=table_spec, bake=bake_fog_light_table,
                                  estimate=lambda spec: 0.4)   # s on 2 cores
# the glow's table and the World's sky are baked per scene, in place (``nodes/images.keyed_image``): for a camera's
# height (``bake_glow_table``), from a probe of the World (``sky_table_from_probe``)
GLOW_KIND = tables.TableKind("daylight_glow", make=lambda beta, air=None: glow_table(beta, air).spec)
SKY_KIND = tables.TableKind("world_sky", make=lambda: sky_spec())
TABLE_KINDS = (FOG_LIGHT_KIND, GLOW_KIND, SKY_KIND)   # (``registry.KINDS``)


def _bake_grid():
    """The bake's directions: (mu, d (mu, phi, 3), dw (mu, phi) solid-angle weights)."""
    x, w = np.polynomial.legendre.leggauss(BAKE_MU)
    mu = np.concatenate([0.5 * (x - 1.0), 0.5 * (x + 1.0)])
    wmu = np.concatenate([0.5 * w, 0.5 * w])
    phi = (np.arange(BAKE_PHI) + 0.5) * (2.0 * math.pi / BAKE_PHI)
    mu_g, phi_g = np.meshgrid(mu, phi, indexing="ij")
    s = np.sqrt(np.maximum(1.0 - mu_g * mu_g, 0.0))
    d = np.stack([s * np.cos(phi_g), s * np.sin(phi_g), mu_g], axis=-1)
    return mu_g, d, (wmu[:, None] * (2.0 * math.pi / BAKE_PHI)) * np.ones_like(phi_g)


def _bake_map(m, top, falloff, g, mu_g, d, dw, fields):
    """The (TABLE_ROWS, Z_COUNT, 4) map of ``bake_fog_light``: at each height z, ``fields(z, length)`` gives the
    sun's residual field and the sky's field on the grid (d, dw; ``length`` to the ground or the sky) and the peak's
    I_s; their SH irradiance coefficients, I_s and C_g go to the rows."""
    basis = np.stack(sh_basis(m, d), axis=0)                           # (9, mu, phi)
    a_l = np.array([CLAMPED_COSINE[_sh_order(k)] for k in range(SH_COUNT)]) / math.pi
    out = np.zeros((TABLE_ROWS * 4, Z_COUNT))
    for k, z in enumerate(np.linspace(0.0, table_height(top, falloff), Z_COUNT)):
        length = np.where(mu_g < 0.0, z / np.maximum(-mu_g, 1e-12), daylight.UNBOUNDED)
        *maps, i_s = fields(z, length)
        for j, field in enumerate(maps):
            out[j * SH_COUNT:(j + 1) * SH_COUNT, k] = a_l * np.sum(basis * (field * dw), axis=(1, 2))
        out[2 * SH_COUNT, k] = i_s
    out[2 * SH_COUNT + 1] = peak_irradiance(g, np.linspace(-1.0, 1.0, Z_COUNT))
    return out.reshape(TABLE_ROWS, 4, Z_COUNT).transpose(0, 2, 1).astype(np.float32)


def _bake_fog_light_air(beta, top, falloff, sun, g, b, h_air, albedo):
    """``bake_fog_light`` of one colour channel with air (its docstring)."""
    sun = np.asarray(sun, float) / np.linalg.norm(sun)
    m = _numpy_ops()
    mu_g, d, dw = _bake_grid()
    cos = d @ sun
    p_l, p_r = albedo * daylight.hg_phase(m, g, cos), aerial.rayleigh_phase(m, cos)
    args = (beta, top, falloff)
    lit = 1.0 if sun[2] > 0.0 else 0.0

    def fields(z, length):
        sun_l, sun_a, sky_a, ratio = aerial.air_glow(m, z, mu_g, length, sun[2], *args, (b, b, b), h_air, g)[0]
        i_s = float(aerial.air_glow(m, np.float64(z), np.float64(sun[2]), daylight.UNBOUNDED, sun[2], *args,
                                      (b, b, b), h_air, g)[0][0])
        l_sky = daylight.sky_airlight(m, z, mu_g, length, *args, albedo=1.0, g=g)
        return (lit * (p_l * (sun_l - i_s) + p_r * sun_a), albedo * l_sky * ratio + sky_a, lit * albedo * i_s)
    return _bake_map(m, top, falloff, g, mu_g, d, dw, fields)


def _numpy_ops():
    from ...core.ops import NumpyOps
    return NumpyOps()
