"""Hooded lamp: a street lamp 2 cm under an opaque hood, and a spot shining through a square hole in a wall.

Tests light shafts at contact (issue 27): the 500 W point lamp hangs 2 cm under a hood (a closed box 0.6 x 0.6 m,
4 cm thick) held by a post, so the fog above the hood's plane gets no light from it at all, and the fog
below glows in a cone cut off by the hood's edges.  Beside it, 4 m further back, a wall (a closed box 0.2 m
thick) has a 1 m square hole; a 15 kW spot 3 m behind the wall shines through the hole towards the camera side,
so one square beam crosses the fog in front of the wall while the wall's face around the hole stays dark.
The ground is a slab 0.2 m thick.  At the default density 0.08/m the optical thickness from the camera is 0.6
to the lamp and 1.0 to the hole.

    python demo_scenes/hooded_lamp.py OUT.blend
"""
import os
import sys

if __name__ == "__main__":
    sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

from demo_scenes import (add_box, add_box_between, add_camera, add_point_light, add_spot_light, main, material,
                         render_settings, set_world)

DEFAULT_DENSITY = 0.08     # 1/m
LAMP = ((-1.5, 7.0, 3.0), 500.0)   # (position m, power W)
HOOD_GAP = 0.02            # m between the lamp and the hood's underside
HOOD_HALF = (0.3, 0.3, 0.02)       # m: 0.6 m wide, 4 cm thick
POST_OFFSET = 0.22         # m: the post stands beside the lamp and holds the hood
WALL_Y = 11.0              # m: the wall's camera-side face
WALL_X = (0.5, 8.5)        # m
WALL_HEIGHT = 4.0          # m
HOLE = (3.5, 2.0, 0.5)     # m: the hole's centre (x, z) and half side
SPOT = ((4.5, 14.0, 2.4), (0.5, 4.0, 0.5), 15000.0)   # (position m, target m, power W)
SPOT_SIZE, SPOT_BLEND = 60.0, 0.2                     # degrees: the cone covers the hole with room to spare


def build(scene):
    render_settings(scene)
    set_world(scene)
    ground = material("Asphalt", (0.30, 0.30, 0.30), roughness=0.8)
    brick = material("Wall", (0.5, 0.45, 0.4), roughness=0.8)
    metal = material("Hood", (0.15, 0.15, 0.16), roughness=0.5)
    add_box(scene, "Ground", (0.0, 10.0, -0.1), (12.0, 14.0, 0.1), ground)
    (lx, ly, lz), power = LAMP
    hz = lz + HOOD_GAP + HOOD_HALF[2]
    add_box(scene, "Hood", (lx, ly, hz), HOOD_HALF, metal)
    add_box(scene, "Post", (lx + POST_OFFSET, ly, 0.5 * (hz - HOOD_HALF[2])), (0.04, 0.04, 0.5 * (hz - HOOD_HALF[2])),
            metal)
    add_point_light(scene, "Hooded Lamp", (lx, ly, lz), power)
    x0, x1 = WALL_X
    hx, hzc, s = HOLE
    y0, y1 = WALL_Y, WALL_Y + 0.2
    add_box_between(scene, "Wall Left", x0, hx - s, y0, y1, 0.0, WALL_HEIGHT, brick)
    add_box_between(scene, "Wall Right", hx + s, x1, y0, y1, 0.0, WALL_HEIGHT, brick)
    add_box_between(scene, "Wall Below", hx - s, hx + s, y0, y1, 0.0, hzc - s, brick)
    add_box_between(scene, "Wall Above", hx - s, hx + s, y0, y1, hzc + s, WALL_HEIGHT, brick)
    pos, target, spot_power = SPOT
    add_spot_light(scene, "Spot Behind", pos, target, spot_power, SPOT_SIZE, SPOT_BLEND)
    add_camera(scene, (-2.0, -1.5, 2.2), (1.5, 9.0, 2.4), lens=26.0)
    return scene


if __name__ == "__main__":
    sys.exit(main(build))
