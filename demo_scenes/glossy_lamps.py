"""Two lamps over a wet, glossy street: a near lamp and a far one whose highlight lies on the ground.

EEVEE ignores light node trees, so the fog dims each material's direct light
by one average of the lights' e^(-beta D_sp); here the two lamps are 4.6 m and
about 25 m from the ground they light, so how that average is weighted
decides the far highlight's brightness (issue 8's test of EEVEE's direct
light).  At beta = 0.08 1/m the optical thickness to the far lamp is 2.1.

    python demo_scenes/glossy_lamps.py OUT.blend
"""
import os
import sys

if __name__ == "__main__":
    sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

from demo_scenes import add_camera, add_plane, add_point_light, main, material, render_settings, set_world

DEFAULT_DENSITY = 0.08   # 1/m
NEAR_LAMP = ((1.5, 5.0, 3.0), 600.0)     # (position m, power W)
FAR_LAMP = ((-2.0, 25.0, 4.0), 4000.0)


def build(scene):
    render_settings(scene)
    set_world(scene)
    wet = material("Wet Asphalt", (0.25, 0.25, 0.27), roughness=0.35)
    add_plane(scene, "Street", -10.0, 10.0, -2.0, 60.0, 0.0, wet)
    for name, (pos, power) in (("Near Lamp", NEAR_LAMP), ("Far Lamp", FAR_LAMP)):
        add_point_light(scene, name, pos, power)
    add_camera(scene, (0.0, 0.0, 1.7), (0.0, 12.0, 1.2), lens=28.0)
    return scene


if __name__ == "__main__":
    sys.exit(main(build))
