"""Bus shelter: a lit shelter by a street lamp, so the shelter's roof and back panel cast shadows into the fog from
both lights.

A scene for light shafts that the shafts were not tuned on (issue 46): a 3.6 x 1.6 m shelter, its roof 2.4 m up
on four posts, a back panel from 0.3 m to 2.1 m and a side panel; a 200 W lamp under the roof lights the fog
under it (the roof shadows the fog above); a 4 kW street lamp 6 m behind and 5 m up throws the shelter's
shadow forward through the fog and onto the pavement where the camera stands.  At the default density 0.07/m the
optical thickness to the street lamp is about 0.9.

    python demo_scenes/bus_shelter.py OUT.blend
"""
import os
import sys

if __name__ == "__main__":
    sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

from demo_scenes import (add_box, add_box_between, add_camera, add_point_light, main, material, render_settings,
                         set_world)

DEFAULT_DENSITY = 0.07    # 1/m
HALF = (1.8, 0.8)         # m: half the shelter's length (x) and depth (y)
ROOF = 2.4                # m: the roof's underside
PANEL = (0.3, 2.1)        # m: the back panel's bottom and top
INNER_LAMP = ((0.0, 0.1, ROOF - 0.15), 200.0)   # (position m, power W)
STREET_LAMP = ((-1.0, 6.0, 5.0), 4000.0)


def build(scene):
    render_settings(scene)
    set_world(scene)
    pavement = material("Pavement", (0.4, 0.4, 0.4), roughness=0.8)
    steel = material("Steel", (0.25, 0.26, 0.28), roughness=0.5)
    panel = material("Panel", (0.5, 0.5, 0.5), roughness=0.6)
    add_box(scene, "Pavement", (0.0, 0.0, -0.1), (14.0, 14.0, 0.1), pavement)
    hx, hy = HALF
    add_box_between(scene, "Roof", -hx - 0.1, hx + 0.1, -hy - 0.2, hy + 0.1, ROOF, ROOF + 0.08, steel)
    for i, (sx, sy) in enumerate(((-1, -1), (1, -1), (-1, 1), (1, 1))):
        add_box(scene, f"Post {i + 1}", (sx * hx, sy * hy, 0.5 * ROOF), (0.04, 0.04, 0.5 * ROOF), steel)
    add_box_between(scene, "Back Panel", -hx, hx, hy - 0.02, hy + 0.02, PANEL[0], PANEL[1], panel)
    add_box_between(scene, "Side Panel", hx - 0.02, hx + 0.02, -hy + 0.3, hy, PANEL[0], PANEL[1], panel)
    add_box_between(scene, "Bench", -1.2, 1.2, hy - 0.45, hy - 0.05, 0.42, 0.47, steel)
    add_point_light(scene, "Shelter Lamp", *INNER_LAMP)
    add_point_light(scene, "Street Lamp", *STREET_LAMP)
    add_box(scene, "Lamp Post", (STREET_LAMP[0][0] + 0.3, STREET_LAMP[0][1], 0.5 * STREET_LAMP[0][2] - 0.1),
            (0.06, 0.06, 0.5 * STREET_LAMP[0][2] - 0.1), steel)
    add_camera(scene, (3.5, -6.5, 1.6), (-0.3, 1.5, 1.6), lens=26.0)
    return scene


if __name__ == "__main__":
    sys.exit(main(build))
