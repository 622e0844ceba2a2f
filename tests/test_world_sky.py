"""A World that is a sky seen through its own air (a Sky Texture) with Air on (precompute/physics/daylight/sunlight.py,
"a World that is a sky seen through its own air"): what "matches Blender's own Sky Texture" means, checked against
closed forms that do not use the code under test.

* a pixel of sky is the World itself (its radiance, not dimmed and not glowing twice), with a vanishing layer;
* a black surface far away takes the World's radiance just above it in its direction, times the air's opacity
  e^{-tau} computed here from the exponential air's column (1 - e^{-b H (1 - e^{-L v_z / H}) / v_z});
* the Sun light is the sun at the ground: a surface on the ground with no layer is not dimmed by the air, and one
  h above it gets back the air between, e^{+b H (1 - e^{-h/H}) / mu_s}.
"""
import math

import numpy as np
import pytest

from fog_addon.precompute.core import medium
from fog_addon.precompute.physics.daylight import daylight as dl, daylight_tables, sunlight as sl
from fog_addon.precompute.core.ops import NumpyOps
from fog_addon.precompute.core.tables import TableSpec

AIR = tuple(3.0 * b for b in medium.RAYLEIGH_RGB)   # thicker than sea-level air: the opacities below are not tiny
H = medium.RAYLEIGH_HEIGHT
SPEC = TableSpec(daylight_tables.SKY_TABLE, daylight_tables.SKY_COLUMNS, daylight_tables.SKY_ROWS, channels=4)
SUN = np.array([0.0, math.cos(math.radians(30.0)), math.sin(math.radians(30.0))])


def sky_table():
    """A World whose radiance varies with azimuth and elevation (smoothly, so the table's bilinear lookup is exact
    to well under 1 % at the cells' centres), as (rows, columns, 4)."""
    el = daylight_tables.sky_row_elevations()
    az = ((np.arange(daylight_tables.SKY_COLUMNS) + 0.5) / daylight_tables.SKY_COLUMNS - 0.5) * 2.0 * math.pi
    e, a = np.meshgrid(el, az, indexing="ij")
    rgb = np.stack([1.0 + 0.5 * np.cos(a) - 0.3 * e, 2.0 + 0.2 * np.sin(a) - 0.5 * e, 3.0 - e], axis=-1)
    return np.concatenate([rgb, np.ones(rgb.shape[:2] + (1,))], axis=-1), (el, az, rgb)


def world_at(el, az, cells):
    """The table's own cell value nearest to (el, az) (the test's directions sit at cell centres)."""
    els, azs, rgb = cells
    return rgb[np.argmin(abs(els - el)), np.argmin(abs(azs - az))]


def day(beta=1e-12, irradiance=(0.0, 0.0, 0.0)):
    return sl.Daylight(beta, 50.0, 0.0, 0.0, SUN, np.array(irradiance, float), np.array([0.3, 0.4, 0.6]), 0.0,
                       1.0, AIR, H, None, SPEC)


def direction(el, az):
    return np.array([math.cos(el) * math.sin(az), math.cos(el) * math.cos(az), math.sin(el)])


CELLS = [(3, 17), (0, 64), (10, 100), (25, 5)]


@pytest.mark.parametrize("grey", [False, True])
@pytest.mark.parametrize("cell", CELLS)
def test_a_pixel_of_sky_is_the_world_itself(cell, grey):
    """In colour (the Compositor) and with the node groups' one grey factor on the sky (the World term's opacity is
    grey too)."""
    table, cells = sky_table()
    m = NumpyOps({SPEC.name: table})
    el, az = cells[0][cell[0]], cells[1][cell[1]]
    d, camera = direction(el, az), np.array([0.0, 0.0, 1.6])
    world = world_at(el, az, cells)
    d_ = day()._replace(grey_air=grey)
    seen = sl.sky_seen(m, d_, camera, d)
    pixel = world * (sl.grey(m, seen) if grey else seen) + sl.ray_glow(m, d_, camera, d, dl.UNBOUNDED)
    assert np.allclose(pixel, world, rtol=2e-3), (pixel, world)


@pytest.mark.parametrize("length", [2.0e3, 2.0e4, 1.0e5])
def test_far_terrain_fades_to_the_world_above_it(length):
    table, cells = sky_table()
    m = NumpyOps({SPEC.name: table})
    el, az = cells[0][0], cells[1][40]
    d, camera = direction(el, az), np.array([0.0, 0.0, 1.6])
    glow = sl.ray_glow(m, day(), camera, d, length)
    vz = d[2]
    tau = np.array(AIR) * H * math.exp(-camera[2] / H) * (1.0 - math.exp(-length * vz / H)) / vz
    want = world_at(el, az, cells) * (1.0 - np.exp(-tau))
    assert np.allclose(glow, want, rtol=2e-3), (glow, want)


@pytest.mark.parametrize("height", [0.0, 500.0, 3000.0])
def test_the_sun_light_is_the_sun_at_the_ground(height):
    m = NumpyOps()
    d_ = day(irradiance=(3.0, 3.0, 3.0))._replace(sky_radiance=np.zeros(3))
    factor = sl.direct_dimming(m, d_, np.array([0.0, 0.0, height]), np.array([0.0, 0.0, 1.0]))
    want = np.exp(np.array(AIR) * H * (1.0 - math.exp(-height / H)) / SUN[2])
    assert np.allclose(factor, want, rtol=1e-4), (factor, want)


def test_a_world_of_light_above_the_air_is_unchanged():
    """Without ``world_sky`` the air's glow and dimming are the kernels' (the World is the light above the air)."""
    m = NumpyOps()
    d_ = day(irradiance=(3.0, 3.0, 3.0))._replace(world_sky=None, sky_radiance=np.zeros(3))
    factor = sl.direct_dimming(m, d_, np.array([0.0, 0.0, 0.0]), np.array([0.0, 0.0, 1.0]))
    assert np.allclose(factor, np.exp(-np.array(AIR) * H / SUN[2]), rtol=1e-4)

