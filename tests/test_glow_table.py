"""The daylight glow's table (``daylight_tables.bake_glow_table`` / ``sunlight.table_glow``): the sun's and the sky's
glow along every camera ray of one camera height, baked from the kernels and read by one bilinear lookup per colour channel.

Expected values: ``sunlight.ray_glow``'s kernels (themselves against scipy in test_daylight.py and
test_air_kernels.py), on random camera rays of the layers the presets and the render tests use.  The bounds are the
table's interpolation error (docs/measurements/2026-11-27-glow-table.md).
"""
import math

import numpy as np
import pytest

from fog_addon.precompute.core import medium
from fog_addon.precompute.physics.daylight import daylight, daylight_tables, sunlight
from fog_addon.precompute.core.ops import NumpyOps

SUN = np.array([0.3, math.cos(math.radians(40.0)), math.sin(math.radians(40.0))])
SUN = SUN / np.linalg.norm(SUN)
AIR = tuple(medium.RAYLEIGH_RGB)

# name: (beta 1/m, top m, H m, g, albedo, air, camera height m, nearest and farthest surface m)
LAYERS = {
    "clear day valley": (3.912 / 40000.0, 0.0, 1200.0, 0.76, (0.9, 0.8, 0.9), AIR, 300.0, 500.0, 60000.0),
    "city, hard top": (0.01, 100.0, 0.0, 0.0, 1.0, None, 1.6, 5.0, 500.0),
    "city, hard top, air": (0.01, 100.0, 0.0, 0.3, 0.9, AIR, 1.6, 5.0, 500.0),
    "falloff, camera above the top": (0.01, 100.0, 50.0, 0.7, 0.9, None, 130.0, 5.0, 500.0),
    "dense sea mist": (0.1, 30.0, 0.0, 0.85, 0.9, None, 1.6, 1.0, 200.0),
}


def _rays(pz, near, far, n=4000, seed=0):
    rng = np.random.default_rng(seed)
    elevation = np.radians(rng.uniform(-30.0, 60.0, n))
    azimuth = rng.uniform(0.0, 2.0 * math.pi, n)
    d = np.stack([np.cos(elevation) * np.cos(azimuth), np.cos(elevation) * np.sin(azimuth), np.sin(elevation)], -1)
    length = np.exp(rng.uniform(math.log(near), math.log(far), n))
    length = np.where((rng.random(n) < 0.2) & (d[:, 2] > 0.0), daylight.UNBOUNDED, length)   # a fifth see the sky
    ground = np.where(d[:, 2] < 0.0, pz / np.maximum(-d[:, 2], 1e-9), np.inf)
    return d, np.minimum(length, ground)


def _day(beta, top, falloff, g, albedo, air):
    return sunlight.Daylight(beta, top, falloff, 0.0, SUN, np.array([3.0, 2.9, 2.7]), np.array([0.3, 0.5, 0.9]), g,
                             np.array(albedo) if isinstance(albedo, tuple) else albedo, air,
                             medium.RAYLEIGH_HEIGHT if air else 0.0)


@pytest.mark.parametrize("name", list(LAYERS))
def test_table_glow_against_the_kernels(name):
    """Within 0.5 % of the kernels' glow on 99 % of the rays (0.05 % but in the dense mist) and 1.5 % on every ray
    (the worst: a ray that leaves a hard top between two rows)."""
    beta, top, falloff, g, albedo, air, pz, near, far = LAYERS[name]
    day = _day(beta, top, falloff, g, albedo, air)
    table = daylight_tables.glow_table(beta, air)
    baked = daylight_tables.bake_glow_table(beta, top, falloff, SUN[2], g, pz, air, day.air_height)
    assert baked.shape == (table.spec.height, table.spec.width, 4) and np.isfinite(baked).all()
    m = NumpyOps({table.spec.name: baked})
    d, length = _rays(pz, near, far)
    origin = np.array([0.0, 0.0, pz])
    want = sunlight.ray_glow(m, day, origin, d, length)
    got = sunlight.ray_glow(m, day._replace(glow_table=table), origin, d, length)
    err = np.abs(got - want).sum(-1) / want.sum(-1)
    print(f"\n{name}: table against the kernels, max {err.max():.2e}, p99 {np.percentile(err, 99):.2e}")
    assert np.percentile(err, 99) < 5e-3 and err.max() < 1.5e-2


def test_sun_below_the_horizon_gives_no_sun_glow():
    """A sun at or below the horizon lights no fog: the table's sun texels are 0 (the sky's are not)."""
    for air in (None, AIR):
        baked = daylight_tables.bake_glow_table(0.01, 100.0, 0.0, -0.1, 0.5, 1.6, air, medium.RAYLEIGH_HEIGHT)
        blocks = baked.reshape(-1, daylight_tables.GLOW_ELEVATIONS, daylight_tables.GLOW_DISTANCES, 4)
        assert np.all(blocks[..., 0] == 0.0) and blocks[..., 1 if air is None else 2].max() > 0.0
        if air is not None:
            assert np.all(blocks[..., 1] == 0.0)


def test_coordinates_reach_the_table_edges():
    """Straight down and straight up are the first and last rows, a zero length the first column and the sky
    (model.FAR and beyond) the last."""
    m = NumpyOps()
    x, y = daylight_tables.glow_coordinates(m, np.array([-1.0, 0.0, 1.0]), np.array([0.0, 1.0, 1e30]), 7.0)
    assert y.tolist() == [0.0, 0.5, 1.0]
    assert x[0] == 0.0 and x[1] == pytest.approx(1.0 / 8.0) and x[2] == pytest.approx(1.0, abs=1e-14)


# --- in Blender: the table is baked at apply, re-baked in place when the camera moves up, dropped when animated --

_FLOW = r"""
import json, math
import bpy, numpy as np
import fog_addon
from fog_addon import sunsky
from fog_addon.nodes import comp_fog, images
from fog_addon.ops import apply
from fog_addon.precompute.physics.daylight import daylight_tables, sunlight
from fog_addon.precompute.core.spec import FogSpec

bpy.ops.wm.read_factory_settings(use_empty=True)
fog_addon.register()
scene = bpy.context.scene
scene.render.engine = "CYCLES"
bpy.ops.mesh.primitive_plane_add(size=200.0)
cam = bpy.data.objects.new("Camera", bpy.data.cameras.new("Camera"))
scene.collection.objects.link(cam)
scene.camera = cam
cam.location = (0.0, -10.0, 1.6)
cam.rotation_euler = (math.radians(85.0), 0.0, 0.0)
sun = bpy.data.objects.new("Sun", bpy.data.lights.new("Sun", "SUN"))
sun.data.energy = 3.0
sun.rotation_euler = (math.radians(50.0), 0.0, 0.0)
scene.collection.objects.link(sun)
scene.world = bpy.data.worlds.new("Sky")
scene.world.use_nodes = True
scene.world.node_tree.nodes["Background"].inputs["Color"].default_value = (0.3, 0.5, 0.9, 1.0)
R = {}
spec = FogSpec(density=0.02, fog_top=50.0, height_falloff=0.0, method="compositor").validated()
apply.apply(scene, spec)
name = daylight_tables.GLOW_NAME

def pixels():
    img = bpy.data.images.get(name)
    if img is None:
        return None
    a = np.empty(len(img.pixels), np.float32)
    img.pixels.foreach_get(a)
    return a.reshape(img.size[1], img.size[0], 4)

def expected():
    return daylight_tables.bake_glow_table(*sunsky._glow_bake_args(scene, apply.spec_of(scene)))

def reads_table():
    trees = [bpy.data.node_groups[comp_fog.FOG_GROUP]]
    seen = set()
    while trees:
        t = trees.pop()
        for n in t.nodes:
            if getattr(n, "image", None) is not None and n.image.name == name:
                return True
            if getattr(n, "node_tree", None) is not None and n.node_tree.name not in seen:
                seen.add(n.node_tree.name)
                trees.append(n.node_tree)
    return False

img = bpy.data.images.get(name)
R["applied"] = dict(exists=img is not None, packed=img is not None and img.packed_file is not None,
                    matches=float(np.abs(pixels() - expected()).max()), reads=reads_table(),
                    uses=sunsky.uses_glow_table(scene, spec))
before = pixels()
cam.location.z = 6.0
bpy.context.view_layer.update()
apply.refresh_lights(scene)
R["moved_up"] = dict(rebuilt=scene.name in apply.rebuilt, changed=float(np.abs(pixels() - before).max()),
                     matches=float(np.abs(pixels() - expected()).max()), same_image=bpy.data.images.get(name) == img)
cam.location.x = 3.0   # sideways: the table holds
bpy.context.view_layer.update()
kept = pixels()
apply.refresh_lights(scene)
R["moved_sideways"] = dict(rebuilt=scene.name in apply.rebuilt, changed=float(np.abs(pixels() - kept).max()))
cam.keyframe_insert("location", frame=1)
cam.location.z = 20.0
cam.keyframe_insert("location", frame=10)
apply.refresh_lights(scene)
R["animated"] = dict(rebuilt=scene.name in apply.rebuilt, exists=bpy.data.images.get(name) is not None,
                     uses=sunsky.uses_glow_table(scene, spec))
print(json.dumps(R))
"""


@pytest.fixture(scope="module")
def flow(tmp_path_factory):
    from fog_scenes import render_harness as h
    return h.bpy_flow(_FLOW, tmp_path_factory.mktemp("glow_table"))


@pytest.mark.render
def test_applied_fog_reads_the_cameras_table(flow):
    """Applying a daylit layer bakes the camera's table, packed (a farm reads it), and the compositor reads it."""
    a = flow["applied"]
    assert a["uses"] and a["exists"] and a["packed"] and a["reads"]
    assert a["matches"] <= 1e-6


@pytest.mark.render
def test_camera_moved_up_rebakes_in_place_without_a_rebuild(flow):
    up = flow["moved_up"]
    assert not up["rebuilt"] and up["same_image"]
    assert up["changed"] > 0.0 and up["matches"] <= 1e-6
    sideways = flow["moved_sideways"]
    assert not sideways["rebuilt"] and sideways["changed"] == 0.0


@pytest.mark.render
def test_animated_camera_takes_the_kernels(flow):
    """A camera whose height may change over the frames keeps the kernels (a farm renders every frame from one
    file): the groups are rebuilt and the table is gone."""
    a = flow["animated"]
    assert a["rebuilt"] and not a["uses"] and not a["exists"]
