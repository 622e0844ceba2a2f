"""Fence: a lamp behind a picket fence, and a thin pole between a second lamp and the camera.

Tests light shafts cast by thin occluders (issue 27): the picket fence (slats 5 cm wide and 3 cm deep with 10 cm
gaps, 1.2 m high, 6 m long; each slat a closed box) stands 5 m in front of the camera with a 2 kW point lamp 1.5 m
behind it, 0.8 m high, so the fog on the camera's side of the fence is combed into thin fans of light.  Farther
off, a 5 cm square pole 4 m high stands 10 m from the camera, 0.3 m beside the line from the camera to a 3 kW lamp
18 m away: its shadow is a thin dark sheet through that lamp's glow, seen nearly edge-on.  The ground is a slab
0.2 m thick.  At the default density 0.05/m the optical thickness from the camera is 0.35 to the fence lamp and
0.9 to the far lamp.

    python demo_scenes/fence.py OUT.blend
"""
import os
import sys

if __name__ == "__main__":
    sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

from demo_scenes import add_box, add_camera, add_point_light, main, material, render_settings, set_world
from mathutils import Vector   # (after bpy, which demo_scenes imports)

DEFAULT_DENSITY = 0.05     # 1/m
CAMERA = (-2.0, 0.0, 1.6)  # m
FENCE_Y = 5.0              # m: the slats' camera-side face
FENCE_X = (-3.0, 3.0)      # m
SLAT_WIDTH, SLAT_GAP, SLAT_DEPTH, SLAT_HEIGHT = 0.05, 0.10, 0.03, 1.2   # m
FENCE_LAMP = ((0.0, 6.5, 0.8), 2000.0)     # (position m, power W)
FAR_LAMP = ((6.0, 16.5, 2.5), 3000.0)
POLE_DISTANCE = 10.0       # m from the camera, along the line to the far lamp
POLE_SIDE = 0.3            # m beside that line (so the lamp itself stays in view)
POLE_WIDTH, POLE_HEIGHT = 0.05, 4.0


def build(scene):
    render_settings(scene)
    set_world(scene)
    ground = material("Ground", (0.3, 0.3, 0.28), roughness=0.9)
    wood = material("Wood", (0.45, 0.35, 0.25), roughness=0.7)
    metal = material("Pole", (0.2, 0.2, 0.2), roughness=0.5)
    add_box(scene, "Ground", (0.0, 10.0, -0.1), (14.0, 14.0, 0.1), ground)
    x0, x1 = FENCE_X
    n = int(round((x1 - x0 + SLAT_GAP) / (SLAT_WIDTH + SLAT_GAP)))
    for i in range(n):
        x = x0 + 0.5 * SLAT_WIDTH + i * (SLAT_WIDTH + SLAT_GAP)
        add_box(scene, f"Slat {i + 1:02d}", (x, FENCE_Y + 0.5 * SLAT_DEPTH, 0.5 * SLAT_HEIGHT),
                (0.5 * SLAT_WIDTH, 0.5 * SLAT_DEPTH, 0.5 * SLAT_HEIGHT), wood)
    add_point_light(scene, "Fence Lamp", *FENCE_LAMP)
    add_point_light(scene, "Far Lamp", *FAR_LAMP)
    cam, lamp = Vector(CAMERA), Vector(FAR_LAMP[0])
    d = (lamp - cam).normalized()
    side = Vector((d.y, -d.x, 0.0)).normalized()
    p = cam + POLE_DISTANCE * d + POLE_SIDE * side
    add_box(scene, "Pole", (p.x, p.y, 0.5 * POLE_HEIGHT), (0.5 * POLE_WIDTH, 0.5 * POLE_WIDTH, 0.5 * POLE_HEIGHT),
            metal)
    add_camera(scene, CAMERA, (1.5, 10.0, 1.4), lens=26.0)
    return scene


if __name__ == "__main__":
    sys.exit(main(build))
