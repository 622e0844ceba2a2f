"""Forest: a lantern among thin trunks, so the fog around it is cut into dozens of narrow dark wedges.

A scene for light shafts that the shafts were not tuned on (issue 46): 64 trunks 14-30 cm thick and 9 m tall stand
at random (a fixed seed) over a 24 x 24 m floor; a 1.5 kW lantern hangs 2.5 m up among them, so each trunk near it
casts a thin wedge of shadow through the fog, and the far ones cut the ground into stripes.  The camera, at eye
height 7 m from the lantern, looks at it past a few trunks.  At the default density 0.06/m the optical thickness to
the lantern is about 0.4.

    python demo_scenes/forest.py OUT.blend
"""
import os
import random
import sys

if __name__ == "__main__":
    sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

from demo_scenes import add_box, add_camera, add_cylinder, add_point_light, main, material, render_settings, set_world

DEFAULT_DENSITY = 0.06    # 1/m
TRUNKS = 64
AREA = 12.0               # m: the trunks stand within +-AREA of the centre
RADIUS = (0.07, 0.15)     # m
TRUNK_HEIGHT = 9.0        # m
LANTERN = ((0.0, 0.0, 2.5), 1500.0)   # (position m, power W)
CAMERA = ((1.5, -7.0, 1.7), (0.0, 0.0, 2.0))
CLEAR = 0.8               # m: no trunk this near the lantern or the camera's line to it


def trunk_positions(seed=3):
    """(x, y, radius) of the trunks: uniform over the area, none within CLEAR of the lantern or the camera."""
    rng = random.Random(seed)
    (lx, ly, _), _ = LANTERN
    (cx, cy, _), _ = CAMERA
    out = []
    while len(out) < TRUNKS:
        x, y = rng.uniform(-AREA, AREA), rng.uniform(-AREA, AREA)
        # distance to the segment from the camera to the lantern (in plan)
        ax, ay = lx - cx, ly - cy
        s = max(0.0, min(1.0, ((x - cx) * ax + (y - cy) * ay) / (ax * ax + ay * ay)))
        if ((x - cx - s * ax) ** 2 + (y - cy - s * ay) ** 2) ** 0.5 < CLEAR:
            continue
        out.append((x, y, rng.uniform(*RADIUS)))
    return out


def build(scene):
    render_settings(scene)
    set_world(scene)
    soil = material("Soil", (0.3, 0.27, 0.22), roughness=0.9)
    bark = material("Bark", (0.28, 0.22, 0.17), roughness=0.9)
    add_box(scene, "Floor", (0.0, 0.0, -0.1), (AREA + 4.0, AREA + 4.0, 0.1), soil)
    for i, (x, y, r) in enumerate(trunk_positions()):
        add_cylinder(scene, f"Trunk {i + 1}", (x, y, 0.0), r, TRUNK_HEIGHT, bark, segments=12)
    (pos, power) = LANTERN
    add_point_light(scene, "Lantern", pos, power)
    add_camera(scene, *CAMERA, lens=24.0)
    return scene


if __name__ == "__main__":
    sys.exit(main(build))
