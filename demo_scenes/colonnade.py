"""Colonnade: a low spot light rakes through a row of square columns, so the fog has lit and dark slabs.

Tests light shafts (issue 27): seven 0.4 m square columns, 4 m high and 1.5 m apart (1.1 m gaps), stand in a
row on a floor; a spot 1.2 m above the floor and 3 m to one side shines through the row, so past the columns
the fog is cut into wedge-shaped slabs, lit where the light passes between two columns and dark in each
column's shadow.  The camera, on the far side of the row and off its end, sees the slabs obliquely, with the
striped floor under them.  At the default density 0.08/m the optical thickness from the camera to the spot is
about 0.8, and 1.0 to the farthest lit floor.

    python demo_scenes/colonnade.py OUT.blend
"""
import os
import sys

if __name__ == "__main__":
    sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

from demo_scenes import add_box, add_camera, add_spot_light, main, material, render_settings, set_world

DEFAULT_DENSITY = 0.08    # 1/m
COLUMNS = 7
COLUMN_SPACING = 1.5      # m, centre to centre along x
COLUMN_HALF = 0.2         # m: 0.4 m square columns
COLUMN_HEIGHT = 4.0       # m
SPOT = ((-0.5, -3.0, 1.2), (0.5, 4.0, 1.0), 8000.0)   # (position m, target m, power W)
SPOT_SIZE, SPOT_BLEND = 100.0, 0.2                    # degrees


def build(scene):
    render_settings(scene)
    set_world(scene)
    stone = material("Stone", (0.55, 0.52, 0.48), roughness=0.8)
    # The floor: a slab 0.2 m thick whose top is at z = 0.
    add_box(scene, "Floor", (0.0, 2.0, -0.1), (10.0, 10.0, 0.1), stone)
    x0 = -0.5 * (COLUMNS - 1) * COLUMN_SPACING
    for i in range(COLUMNS):
        add_box(scene, f"Column {i + 1}", (x0 + i * COLUMN_SPACING, 0.0, 0.5 * COLUMN_HEIGHT),
                (COLUMN_HALF, COLUMN_HALF, 0.5 * COLUMN_HEIGHT), stone)
    pos, target, power = SPOT
    add_spot_light(scene, "Raking Spot", pos, target, power, SPOT_SIZE, SPOT_BLEND)
    add_camera(scene, (6.0, 8.0, 3.0), (-1.0, 1.5, 0.8), lens=24.0)
    return scene


if __name__ == "__main__":
    sys.exit(main(build))
