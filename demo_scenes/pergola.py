"""Pergola: a low spot shines through the slatted roof of a pergola, so the fog under it is cut into thin sheets.

A scene for light shafts that the shafts were not tuned on (issue 46): four 0.15 m posts 2.6 m high hold two beams
and eleven 6 cm slats 0.4 m apart over a 4 x 3 m patio; a spot 5 m up and 4 m off to the side shines down through
the slats at about 35 degrees, so under the roof the fog holds eleven lit sheets and the ground a striped patch.
The camera, at eye height beside the patio, looks across the sheets.  At the default density 0.08/m the optical
thickness from the camera to the spot is about 0.9.

    python demo_scenes/pergola.py OUT.blend
"""
import os
import sys

if __name__ == "__main__":
    sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

from demo_scenes import add_box, add_camera, add_spot_light, main, material, render_settings, set_world

DEFAULT_DENSITY = 0.08    # 1/m
PATIO = (2.0, 1.5)        # m: half of the pergola's length (x) and width (y)
POST_HALF = 0.075         # m: 0.15 m square posts
HEIGHT = 2.6              # m: the slats' underside
SLATS = 11
SLAT_HALF = (0.03, 0.06)  # m: half of a slat's width (x) and depth (z)
SPOT = ((-4.5, 1.0, 5.0), (0.5, 0.0, 0.0), 20000.0)   # (position m, target m, power W)
SPOT_SIZE, SPOT_BLEND = 50.0, 0.15                    # degrees


def build(scene):
    render_settings(scene)
    set_world(scene)
    paving = material("Paving", (0.45, 0.43, 0.40), roughness=0.8)
    wood = material("Wood", (0.35, 0.25, 0.18), roughness=0.7)
    add_box(scene, "Ground", (0.0, 0.0, -0.1), (12.0, 12.0, 0.1), paving)
    px, py = PATIO
    for i, (sx, sy) in enumerate(((-1, -1), (1, -1), (-1, 1), (1, 1))):
        add_box(scene, f"Post {i + 1}", (sx * px, sy * py, 0.5 * HEIGHT), (POST_HALF, POST_HALF, 0.5 * HEIGHT), wood)
    for i, sy in enumerate((-1, 1)):   # the beams along x, under the slats
        add_box(scene, f"Beam {i + 1}", (0.0, sy * py, HEIGHT - 0.1), (px + 0.3, 0.05, 0.1), wood)
    for i in range(SLATS):
        x = -px + 2.0 * px * i / (SLATS - 1)
        add_box(scene, f"Slat {i + 1}", (x, 0.0, HEIGHT + SLAT_HALF[1]), (SLAT_HALF[0], py + 0.3, SLAT_HALF[1]), wood)
    pos, target, power = SPOT
    add_spot_light(scene, "Low Spot", pos, target, power, SPOT_SIZE, SPOT_BLEND)
    add_camera(scene, (3.0, -7.0, 1.6), (-0.3, 0.5, 1.5), lens=28.0)
    return scene


if __name__ == "__main__":
    sys.exit(main(build))
