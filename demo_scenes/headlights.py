"""Headlights (issue 9): a car's two narrow spots shining towards the camera, and a street lamp (g = 0.85).

A road down +Y; a car (a box) 18 m ahead faces the camera with two headlights 0.7 m high and 1.4 m
apart, 30-degree cones (blend 0.4) aimed at the road 40 m ahead of the car, tilted down 1.5 degrees:
the camera, 1.4 m up on the road, stands inside both beams and sees them end-on, while their light
lies on the road.  A street lamp (a point light) stands 5 m high beside the road 10 m ahead.  At the
default density beta = 0.05 1/m the optical thickness to the car is 0.9.

    python demo_scenes/headlights.py OUT.blend
"""
import math
import os
import sys

if __name__ == "__main__":
    sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

from demo_scenes import (add_box, add_camera, add_cylinder, add_plane, add_point_light, add_spot_light, main,
                         material, render_settings, set_world)

DEFAULT_DENSITY = 0.05           # 1/m
ANISOTROPY = 0.85                # fog (presets.ANISOTROPY["fog"])
CAR_DISTANCE = 18.0              # m ahead of the camera
HEADLIGHT_HEIGHT = 0.7           # m
HEADLIGHT_SPACING = 1.4          # m between the two
HEADLIGHT_POWER = 2000.0         # W each
HEADLIGHT_SIZE = 30.0            # degrees
HEADLIGHT_BLEND = 0.4
LAMP_POWER = 500.0               # W


def build(scene):
    render_settings(scene)
    set_world(scene)
    road = material("Road", (0.12, 0.12, 0.12), roughness=0.45)
    paint = material("Car Paint", (0.5, 0.05, 0.05), roughness=0.25)
    metal = material("Post", (0.15, 0.15, 0.16), roughness=0.5)
    add_plane(scene, "Road", -10.0, 10.0, -5.0, 60.0, 0.0, road)
    add_box(scene, "Car", (0.0, CAR_DISTANCE + 2.1, 0.75), (0.9, 2.0, 0.55), paint)
    drop = math.tan(math.radians(1.5)) * 40.0
    for side, x in (("Left", -HEADLIGHT_SPACING / 2), ("Right", HEADLIGHT_SPACING / 2)):
        add_spot_light(scene, f"Headlight {side}", (x, CAR_DISTANCE - 0.02, HEADLIGHT_HEIGHT),
                       (x, CAR_DISTANCE - 40.0, HEADLIGHT_HEIGHT - drop), HEADLIGHT_POWER, HEADLIGHT_SIZE,
                       HEADLIGHT_BLEND, (1.0, 0.95, 0.85))
    add_cylinder(scene, "Lamp Post", (4.3, 10.0, 0.0), 0.06, 4.8, metal)
    add_point_light(scene, "Street Lamp", (4.0, 10.0, 5.0), LAMP_POWER)
    add_camera(scene, (0.4, 0.0, 1.4), (0.0, CAR_DISTANCE, 1.2), lens=28.0)
    return scene


if __name__ == "__main__":
    sys.exit(main(build))
