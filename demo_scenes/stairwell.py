"""Stairwell: a pendant lamp under a shade hangs in a tall stairwell, so the fog above the shade and the ceiling
over it lie in its shadow while the flights below are lit.

A scene for light shafts that the shafts were not tuned on (issue 46: "a ceiling over a shaded lamp too
bright"): a 3.2 x 3.2 m well, 6 m high, closed by 0.2 m walls and a ceiling; a straight flight of twelve steps
climbs along one wall to a landing; a 300 W lamp hangs 1.6 m under the ceiling, 3 cm under a 0.7 m square shade,
so its light falls in a cone below the shade's rim.  The camera stands in a corner at the foot of the stairs and
looks up past the lamp.  At the default density 0.1/m the optical thickness across the well is about 0.3.

    python demo_scenes/stairwell.py OUT.blend
"""
import os
import sys

if __name__ == "__main__":
    sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

from demo_scenes import (add_box, add_box_between, add_camera, add_point_light, main, material, render_settings,
                         set_world)

DEFAULT_DENSITY = 0.1     # 1/m
HALF = 1.6                # m: the well's inner half width
HEIGHT = 6.0              # m: the ceiling's underside
WALL = 0.2                # m
STEPS = 12
STEP = (0.28, 0.2)        # m: tread and rise
LAMP = ((0.2, 0.3, HEIGHT - 1.6), 300.0)   # (position m, power W)
SHADE_GAP, SHADE_HALF = 0.03, (0.35, 0.35, 0.02)   # m: the shade 3 cm over the lamp, 0.7 m square, 4 cm thick


def build(scene):
    render_settings(scene)
    set_world(scene)
    plaster = material("Plaster", (0.7, 0.7, 0.68), roughness=0.9)
    stone = material("Stone", (0.5, 0.48, 0.45), roughness=0.8)
    metal = material("Shade", (0.2, 0.2, 0.22), roughness=0.5)
    h, t = HALF, WALL
    add_box_between(scene, "Floor", -h - t, h + t, -h - t, h + t, -t, 0.0, stone)
    add_box_between(scene, "Ceiling", -h - t, h + t, -h - t, h + t, HEIGHT, HEIGHT + t, plaster)
    add_box_between(scene, "Wall North", -h - t, h + t, h, h + t, 0.0, HEIGHT, plaster)
    add_box_between(scene, "Wall South", -h - t, h + t, -h - t, -h, 0.0, HEIGHT, plaster)
    add_box_between(scene, "Wall East", h, h + t, -h, h, 0.0, HEIGHT, plaster)
    add_box_between(scene, "Wall West", -h - t, -h, -h, h, 0.0, HEIGHT, plaster)
    tread, rise = STEP
    for i in range(STEPS):   # a flight along the west wall, climbing north, 1 m wide
        y0 = -h + 0.3 + i * tread
        add_box_between(scene, f"Step {i + 1}", -h, -h + 1.0, y0, y0 + tread, 0.0, (i + 1) * rise, stone)
    top = STEPS * rise
    add_box_between(scene, "Landing", -h, h, h - 0.9, h, top - 0.2, top, stone)
    (lx, ly, lz), power = LAMP
    add_box(scene, "Shade", (lx, ly, lz + SHADE_GAP + SHADE_HALF[2]), SHADE_HALF, metal)
    add_box(scene, "Cord", (lx, ly, 0.5 * (lz + SHADE_GAP + 2 * SHADE_HALF[2] + HEIGHT)),
            (0.01, 0.01, 0.5 * (HEIGHT - lz - SHADE_GAP - 2 * SHADE_HALF[2])), metal)
    add_point_light(scene, "Pendant", (lx, ly, lz), power)
    add_camera(scene, (1.3, -1.3, 1.5), (-0.3, 0.6, 4.2), lens=16.0)
    return scene


if __name__ == "__main__":
    sys.exit(main(build))
