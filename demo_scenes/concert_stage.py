"""Concert stage (issue 9): three coloured spots raking through haze (g = 0.7) onto a stage.

A stage floor 12 m wide and 8 m deep with a back wall; a lighting truss 6 m above its front edge carries
three spots (amber, magenta, cyan; 24-34 degree cones, blend 0.15-0.3) aimed down and back across the
stage, so their beams cross in the air and land as pools on the floor and the wall.  A glossy sphere
and a metal box stand in the light.  The audience camera sits 10 m in front of the stage at eye height.
At the default density beta = 0.04 1/m the optical thickness to the back wall is about 0.8.

    python demo_scenes/concert_stage.py OUT.blend
"""
import os
import sys

if __name__ == "__main__":
    sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

from demo_scenes import (add_box, add_camera, add_plane, add_sphere, add_spot_light, main, material,
                         render_settings, set_world)

DEFAULT_DENSITY = 0.04           # 1/m
ANISOTROPY = 0.7                 # haze (presets.ANISOTROPY["haze"])
TRUSS_HEIGHT = 6.0               # m
SPOTS = (   # (name, position, target, power W, size deg, blend, colour)
    ("Spot Amber", (-4.0, 0.0, TRUSS_HEIGHT), (1.5, 5.0, 0.0), 3000.0, 28.0, 0.2, (1.0, 0.55, 0.15)),
    ("Spot Magenta", (0.0, 0.5, TRUSS_HEIGHT), (-1.0, 6.5, 0.0), 2500.0, 24.0, 0.3, (0.9, 0.2, 0.8)),
    ("Spot Cyan", (4.0, 0.0, TRUSS_HEIGHT), (-2.0, 4.0, 0.0), 3000.0, 34.0, 0.15, (0.2, 0.8, 1.0)),
)


def build(scene):
    render_settings(scene)
    set_world(scene)
    floor = material("Stage Floor", (0.25, 0.22, 0.2), roughness=0.35)
    wall = material("Back Wall", (0.4, 0.4, 0.42), roughness=0.9, specular_ior_level=0.0)
    gloss = material("Glossy Sphere", (0.6, 0.6, 0.65), roughness=0.15)
    metal = material("Metal Box", (0.8, 0.7, 0.5), roughness=0.3, metallic=1.0)
    add_plane(scene, "Stage", -6.0, 6.0, -1.0, 8.0, 0.0, floor)
    add_plane(scene, "Floor", -20.0, 20.0, -14.0, -1.0, -1.0, floor)
    add_box(scene, "Back Wall", (0.0, 8.1, 4.0), (6.0, 0.1, 4.0), wall)
    add_sphere(scene, "Sphere", (-1.2, 4.5, 0.6), 0.6, gloss)
    add_box(scene, "Box", (1.6, 5.5, 0.5), (0.5, 0.5, 0.5), metal)
    for name, pos, target, power, size, blend, colour in SPOTS:
        add_spot_light(scene, name, pos, target, power, size, blend, colour)
    add_camera(scene, (0.0, -10.0, 1.7), (0.0, 4.0, 3.0), lens=24.0)
    return scene


if __name__ == "__main__":
    sys.exit(main(build))
