"""Street lamps (Sun et al. 2005, Fig. 8): three identical point lamps on posts
at different distances down a street, seen from eye height.

Lamps stand 2 m to the right of the street axis, 4 m high, at 6, 12 and 20 m
ahead of the camera.  At the default test density beta = 0.08 1/m the optical
thickness to the farthest lamp is beta * 20.2 m = 1.6; each nearer lamp shows
a brighter, larger glow.

    python demo_scenes/street_lamps.py OUT.blend
"""
import os
import sys

if __name__ == "__main__":
    sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

from demo_scenes import (add_camera, add_cylinder, add_plane, add_point_light, main, material,
                         render_settings, set_world)

EYE_HEIGHT = 1.7                 # m
LAMP_DISTANCES = (6.0, 12.0, 20.0)   # m ahead of the camera along +Y
LAMP_SIDE = 2.0                  # m to the right of the street axis
LAMP_HEIGHT = 4.0                # m
LAMP_POWER = 1000.0              # W (radiant intensity I0 = P / 4 pi = 79.6 W/sr)
POST_OFFSET = 0.3                # m; the post stands beside the lamp, its top below it
POST_HEIGHT = 3.8
POST_RADIUS = 0.06
DEFAULT_DENSITY = 0.08           # 1/m: optical thickness 1.6 to the farthest lamp


def build(scene):
    render_settings(scene)
    set_world(scene)
    ground = material("Asphalt", (0.30, 0.30, 0.30), roughness=0.8)
    metal = material("Post", (0.15, 0.15, 0.16), roughness=0.5)
    add_plane(scene, "Street", -8.0, 8.0, -2.0, 40.0, 0.0, ground)
    for i, y in enumerate(LAMP_DISTANCES, 1):
        add_cylinder(scene, f"Post {i}", (LAMP_SIDE + POST_OFFSET, y, 0.0), POST_RADIUS, POST_HEIGHT, metal)
        add_point_light(scene, f"Lamp {i}", (LAMP_SIDE, y, LAMP_HEIGHT), LAMP_POWER)
    # Looking down the street (+Y), tilted up 6 degrees so all three lamps are in frame.
    add_camera(scene, (0.0, 0.0, EYE_HEIGHT), (0.0, 10.0, EYE_HEIGHT + 10.0 * 0.105), lens=24.0)
    return scene


if __name__ == "__main__":
    sys.exit(main(build))
