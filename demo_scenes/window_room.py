"""Window room: a closed room with two windows in one wall and a spot light outside shining in through both.

Tests light shafts (issue 27): the room (6 x 6 x 3 m inside; walls, floor and ceiling are closed boxes 0.2 m
thick) hides the spot everywhere except through its two 0.8 x 1.0 m windows, so two beams cross the fog of the
room from the window wall down to the floor, and the rest of the room's fog is dark.  The camera stands inside
in a corner and sees both beams side-on, with the window wall and the lit patches on the floor.  Objects must
cast shadows: without them the whole cone glows through the wall.  At the default density 0.1/m the optical
thickness across the room is 0.6, and 1.3 along a beam from the spot to the floor patch.

    python demo_scenes/window_room.py OUT.blend
"""
import os
import sys

if __name__ == "__main__":
    sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

from demo_scenes import (add_box_between, add_camera, add_spot_light, main, material, render_settings,
                         set_world)

DEFAULT_DENSITY = 0.1     # 1/m
HALF = 3.0                # m: the room's inner half width (x and y); inner height 3 m
HEIGHT = 3.0
WALL = 0.2                # m: wall, floor and ceiling thickness
WINDOW_X = (-1.2, 1.2)    # m: the two windows' centres along x, in the wall at y = +HALF
WINDOW_HALF_WIDTH = 0.4   # m
WINDOW_Z = (1.4, 2.4)     # m: sill and lintel
SPOT = ((0.0, 10.0, 5.0), (0.0, -1.0, 0.0), 30000.0)   # (position m, target m, power W)
SPOT_SIZE, SPOT_BLEND = 40.0, 0.2                      # degrees; both windows lie well inside the cone


def build(scene):
    render_settings(scene)
    set_world(scene)
    plaster = material("Plaster", (0.6, 0.6, 0.6), roughness=0.9)
    boards = material("Floor", (0.45, 0.4, 0.35), roughness=0.7)
    h, t, z1 = HALF, WALL, HEIGHT
    add_box_between(scene, "Floor", -h - t, h + t, -h - t, h + t, -t, 0.0, boards)
    add_box_between(scene, "Ceiling", -h - t, h + t, -h - t, h + t, z1, z1 + t, plaster)
    add_box_between(scene, "Wall West", -h - t, -h, -h, h, 0.0, z1, plaster)
    add_box_between(scene, "Wall East", h, h + t, -h, h, 0.0, z1, plaster)
    add_box_between(scene, "Wall South", -h - t, h + t, -h - t, -h, 0.0, z1, plaster)
    # The window wall (y from h to h + t), in pieces around the two holes.
    zs, zl = WINDOW_Z
    add_box_between(scene, "Wall North Below", -h - t, h + t, h, h + t, 0.0, zs, plaster)
    add_box_between(scene, "Wall North Above", -h - t, h + t, h, h + t, zl, z1, plaster)
    edges = [-h - t]
    for x in WINDOW_X:
        edges += [x - WINDOW_HALF_WIDTH, x + WINDOW_HALF_WIDTH]
    edges.append(h + t)
    for i in range(0, len(edges), 2):
        add_box_between(scene, f"Wall North Pier {i // 2 + 1}", edges[i], edges[i + 1], h, h + t, zs, zl, plaster)
    pos, target, power = SPOT
    add_spot_light(scene, "Sun Spot", pos, target, power, SPOT_SIZE, SPOT_BLEND)
    add_camera(scene, (2.7, -2.7, 1.5), (-1.0, 1.2, 1.1), lens=18.0)
    return scene


if __name__ == "__main__":
    sys.exit(main(build))
