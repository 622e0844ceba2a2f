"""A shop window seen from a foggy street, fogged (Node Groups or Compositor, Cycles) or path-traced.

    python tests/scenes/shop_window.py MODE OUT.exr [SAMPLES] [METHOD]

MODE: ``reference`` (Cycles' World volume, Volume Scatter white of density BETA, single scattering), ``fog`` (the
add-on's fog, ``apply_fog(scene, BETA, method=METHOD)``; its notes are printed, one ``NOTE`` line each) or ``none``
(no fog at all).  METHOD: the fog's method (default ``compositor``; ``nodes``).  SAMPLES: default 2048 for the
reference, 64 otherwise.  Writes OUT.exr and OUT.npz: ``pane``, the pixels whose centre ray meets the pane first
(``scene.ray_cast`` from the camera), and ``lamps``, the 3x3 pixels about each lamp the camera sees (straight, not
through the pane); the lamps' pixels are printed as ``LAMP name row col``.

The scene (metres, z up, the street at y < 0):

* the street: a plane z = 0, x in [-30, 30], y in [-40, 0], a grey Principled BSDF (0.35, roughness 0.9);
* the facade: a wall 8 m wide (x in [-4, 4]), 4 m high and 0.3 m thick (y in [0, 0.3]), four closed boxes around a
  window opening 2.4 x 1.6 m (x in [-1.2, 1.2], z in [0.8, 2.4]), grey diffuse (0.5);
* the pane: a plane in the middle of the opening (y = 0.15) filling it, normal -y, a Principled BSDF of Transmission
  Weight 1, roughness 0, IOR 1.5, base colour white; hidden from shadow rays in every mode (a thin pane lets the lamps'
  light through both ways);
* the shop: a closed room behind the facade (x in [-3.8, 3.8], y in [0.28, 4.3], z in [0, 3.6]: floor, ceiling, back
  and side walls facing in; its open side is covered by the facade), light diffuse (0.7); a shelf against its back
  wall (a box x in [-2.6, -0.6], y in [3.7, 4.2], z in [0, 1.6], diffuse red-brown) seen through the window, and an
  80 W point lamp at (-1.0, 2.2, 3.0) above and before it, not seen directly through the window;
* the street lamp: a 800 W point lamp at (-3.8, -1.4, 5.0), 1.4 m before the facade's left end, just out of the
  picture (about 8 px, 5 degrees, above its top left corner: at 35 mm and 16:9 a lamp 5 m high this near cannot
  share the picture with the window and the street), its glow filling the picture's top left;
* the camera at (3.0, -7.5, 1.7) (7.5 m from the facade, 3 m to the right of the window's centre, about 22 degrees
  off its normal), looking at (0, 0, 1.9), 35 mm, 96 x 54 px, clip start 1 mm.

Both lamps have radius 0 and their shadows on; every object but the pane casts shadows (Cycles' shadow rays in the
reference, the fog's shadow maps or none in the fog, as the method can).  Bounces, as tests/scenes/glass_mirror.py:
volume 0 (single scattering), diffuse 1 (the fog's light on surfaces), glossy 2, transmission 4 (the paths through
the pane), max_bounces their sum; every mesh hidden from diffuse rays (no light from surface to surface, as in the
model).  The World is black.  Traps of blender-facts.md: Volume Scatter white, lamp shadows on, clip start 1 mm,
Gaussian 0.01 px pixel filter.

The pane is one plane of IOR 1.5, so Cycles refracts the camera's rays once there (as into a block of glass): the
shop is seen bent (about 23 degrees from the pane's normal outside, 15 inside), in every mode alike.
"""
import math
import pathlib
import sys

ROOT = pathlib.Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))

import bpy  # noqa: E402
import numpy as np  # noqa: E402
from mathutils import Vector  # noqa: E402

from fog_addon import measure  # noqa: E402
from fog_scenes import probe_common  # noqa: E402

BETA = 0.1               # 1/m, isotropic, albedo 1
WIDTH, HEIGHT = 96, 54
EYE = (3.0, -7.5, 1.7)
TARGET = (0.0, 0.0, 1.9)
LENS = 35.0
FACADE = (-4.0, 4.0, 0.0, 0.3, 0.0, 4.0)        # x0, x1, y0, y1, z0, z1
WINDOW = (-1.2, 1.2, 0.8, 2.4)                 # x0, x1, z0, z1 of the opening
PANE_Y = 0.15
ROOM = (-3.8, 3.8, 0.28, 4.3, 0.0, 3.6)        # (its front edges sunk 2 cm into the facade: no seams)
SHELF = (-2.6, -0.6, 3.7, 4.2, 0.0, 1.6)
SHOP_LAMP = ((-1.0, 2.2, 3.0), 80.0)           # position, W
STREET_LAMP = ((-3.8, -1.4, 5.0), 800.0)


def _mesh(scene, name, verts, faces, mat):
    me = bpy.data.meshes.new(name)
    me.from_pydata(verts, [], faces)
    me.materials.append(mat)
    ob = bpy.data.objects.new(name, me)
    scene.collection.objects.link(ob)
    return ob


def _box(x0, x1, y0, y1, z0, z1, inward=False):
    """A closed box's vertices and faces, its normals out (``inward``: in)."""
    v = [(x, y, z) for x in (x0, x1) for y in (y0, y1) for z in (z0, z1)]
    faces = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    if inward:
        faces = [f[::-1] for f in faces]
    return v, faces


def _material(name, kind, colour=(0.5, 0.5, 0.5)):
    if kind == "diffuse":
        return probe_common.bsdf_material(name, "ShaderNodeBsdfDiffuse", Color=(*colour, 1.0))
    if kind == "street":
        return probe_common.bsdf_material(name, "ShaderNodeBsdfPrincipled", **{"Base Color": (*colour, 1.0),
                                                                               "Roughness": 0.9})
    return probe_common.bsdf_material(name, "ShaderNodeBsdfPrincipled", **probe_common.PRINCIPLED_GLASS)   # the pane


def build():
    """The scene of the module docstring; returns (scene, camera)."""
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    cam = probe_common.look_at(scene, EYE, TARGET, LENS)
    cam.data.clip_end = 1000.0
    scene.world = bpy.data.worlds.new("World")
    scene.world.use_nodes = True
    scene.world.node_tree.nodes["Background"].inputs["Color"].default_value = (0.0, 0.0, 0.0, 1.0)
    street = _material("Street", "street", (0.35, 0.35, 0.35))
    facade = _material("Facade", "diffuse", (0.5, 0.5, 0.5))
    room = _material("Shop", "diffuse", (0.7, 0.7, 0.7))
    shelf = _material("Shelf", "diffuse", (0.6, 0.35, 0.2))
    glass = _material("Pane", "pane")
    _mesh(scene, "Street", [(-30, -40, 0), (30, -40, 0), (30, 0, 0), (-30, 0, 0)], [(0, 1, 2, 3)], street)
    fx0, fx1, fy0, fy1, fz0, fz1 = FACADE
    wx0, wx1, wz0, wz1 = WINDOW
    for name, (x0, x1, z0, z1) in {"Facade Left": (fx0, wx0, fz0, fz1), "Facade Right": (wx1, fx1, fz0, fz1),
                                   "Facade Below": (wx0, wx1, fz0, wz0), "Facade Above": (wx0, wx1, wz1, fz1)}.items():
        _mesh(scene, name, *_box(x0, x1, fy0, fy1, z0, z1), facade)
    v, faces = _box(*ROOM, inward=True)
    faces = [f for f in faces if f != (0, 4, 5, 1)[::-1]]   # no front (y0) face: the facade closes the room
    _mesh(scene, "Shop", v, faces, room)
    _mesh(scene, "Shelf", *_box(*SHELF), shelf)
    pane = _mesh(scene, "Pane", [(wx0, PANE_Y, wz0), (wx1, PANE_Y, wz0), (wx1, PANE_Y, wz1), (wx0, PANE_Y, wz1)],
                 [(0, 1, 2, 3)], glass)
    pane.visible_shadow = False   # a thin pane: the lamps' light passes it (in every mode)
    probe_common.add_point_lights(scene, [(SHOP_LAMP[0], SHOP_LAMP[1], (1.0, 1.0, 1.0)),
                                          (STREET_LAMP[0], STREET_LAMP[1], (1.0, 1.0, 1.0))], fog_only=False)
    return scene, cam


def _first_hit(scene, origin, direction, max_dist=1e4):
    depsgraph = bpy.context.evaluated_depsgraph_get()
    hit, loc, _n, _i, ob, _m = scene.ray_cast(depsgraph, Vector(origin), Vector(direction), distance=max_dist)
    return (ob.name, (loc - Vector(origin)).length) if hit else (None, math.inf)


def masks(scene, cam):
    """(pane, lamps, seen): the boolean (HEIGHT, WIDTH) masks of the module docstring, and [(lamp name, row, col)]."""
    bpy.context.view_layer.update()
    eye, d = probe_common.camera_rays(cam, WIDTH, HEIGHT)
    pane = np.zeros((HEIGHT, WIDTH), bool)
    for r in range(HEIGHT):
        for c in range(WIDTH):
            pane[r, c] = _first_hit(scene, eye, d[r, c])[0] == "Pane"
    lamps, seen = np.zeros((HEIGHT, WIDTH), bool), []
    for ob in scene.objects:
        if ob.type != "LIGHT":
            continue
        x, y, _ = probe_common.light_pixel(scene, ob)
        col, row = int(math.floor(x)), int(math.floor(HEIGHT - y))
        if not (0 <= col < WIDTH and 0 <= row < HEIGHT):
            continue
        to = np.array(ob.matrix_world.translation) - eye
        dist = float(np.linalg.norm(to))
        name, t = _first_hit(scene, eye, to / dist, dist)
        if name is not None and t < dist:
            print(f"LAMP {ob.name} hidden behind {name}")
            continue
        lamps[max(row - 1, 0):row + 2, max(col - 1, 0):col + 2] = True
        seen.append((ob.name, row, col))
    return pane, lamps, seen


def configure(scene, samples):
    """The bounces and visibility of the module docstring, on the scene as built (cast shadows kept)."""
    probe_common.see_through_bounces(scene, WIDTH, HEIGHT)
    scene.objects["Pane"].visible_shadow = False
    measure.set_samples(scene, samples)


def main(mode, out, samples=None, method="compositor"):
    if mode not in ("reference", "fog", "none"):
        raise SystemExit(f"MODE must be reference, fog or none, not {mode!r}")
    out = pathlib.Path(out)
    scene, cam = build()
    probe_common.set_up_mode(scene, mode, BETA, samples, configure)
    pane, lamps, seen = masks(scene, cam)
    for name, row, col in seen:
        print(f"LAMP {name} row {row} col {col}")
    if mode == "fog":
        for what, note in probe_common.add_fog(scene, BETA, method):
            print(f"NOTE {what}: {note}")
    measure.render_to_file(scene, str(out))
    np.savez(out.with_suffix(".npz"), pane=pane, lamps=lamps)


if __name__ == "__main__":
    main(*sys.argv[1:])
