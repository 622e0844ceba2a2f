"""Shaft wall: a lamp behind a wall with a square window, and a lamp 2 cm under an opaque hood.

Tests light shafts (issue 27): the wall hides the 3 kW lamp 3 m behind it except through its 1 m window,
whose beam crosses the fog towards the camera; the hood (a 4 cm slab, 0.6 m wide) shadows all the fog
above the 500 W lamp under it (contact).  The camera stands 6 m to the side, so it sees the wall, the beam and
the shadowed fog above the hood side-on.  At the default density 0.1/m the optical thickness from the camera
to the wall is about 1.5.

    python demo_scenes/shaft_wall.py OUT.blend
"""
import os
import sys

if __name__ == "__main__":
    sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

from demo_scenes import (add_box, add_camera, add_plane, add_point_light, main, material, render_settings,
                         set_world)

DEFAULT_DENSITY = 0.1   # 1/m
WALL_Y = 8.0            # m: the wall's plane; 4 m high, 0.2 m thick
WINDOW = (0.0, 2.0, 0.5)   # m: the window's centre (x, z) and half side
HOOD_GAP = 0.02         # m between the hooded lamp and the hood's underside


def build(scene):
    render_settings(scene)
    set_world(scene)
    grey = material("Wall", (0.5, 0.5, 0.5), roughness=0.8)
    add_plane(scene, "Ground", -15.0, 15.0, -10.0, 30.0, 0.0, grey)
    x, z, h = WINDOW
    add_box(scene, "Wall Left", (x - 5.0 - h, WALL_Y, 2.0), (5.0, 0.1, 2.0), grey)
    add_box(scene, "Wall Right", (x + 5.0 + h, WALL_Y, 2.0), (5.0, 0.1, 2.0), grey)
    add_box(scene, "Wall Below", (x, WALL_Y, 0.5 * (z - h)), (h, 0.1, 0.5 * (z - h)), grey)
    add_box(scene, "Wall Above", (x, WALL_Y, 0.5 * (z + h + 4.0)), (h, 0.1, 0.5 * (4.0 - z - h)), grey)
    add_point_light(scene, "Behind", (x, WALL_Y + 3.0, z), 3000.0)
    add_box(scene, "Hood", (-4.0, 3.0, 3.01 + HOOD_GAP + 0.02), (0.3, 0.3, 0.02), grey)
    add_point_light(scene, "Hooded", (-4.0, 3.0, 3.01), 500.0)
    add_camera(scene, (6.0, -6.0, 1.7), (0.0, 6.0, 2.0), lens=28.0)
    return scene


if __name__ == "__main__":
    sys.exit(main(build))
