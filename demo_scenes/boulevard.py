"""Boulevard: a real scene's lamp count -- two rows of 22 street lamps down a
road between façades, one lamp behind the camera, and matte, glossy and
metallic objects on the road (issue 8, "Fog for real scenes").

The road runs along +Y (x in [-6, 6]) between two rows of building blocks
(boxes, x beyond +-9 m).  Lamps stand every 5 m from y = 0 to 105 m, 6 m high,
5.5 m either side of the axis, each on a post: mostly warm sodium and white
LED lamps of different powers, every fifth one a dimmer lamp (a failing
sodium or a small LED).  A 45th lamp hangs 4 m behind and above the camera:
its glow fills the foreground but its point is out of frame.  On the road:
a matte sphere (Principled roughness 0.9, dielectric), a glossy sphere
(dielectric, roughness 0.2), a metallic sphere (metallic 1, roughness 0.3)
and a matte and a metallic box.

The camera stands at eye height 1.7 m, 4 m before the first lamps, looking
down the road.  At the default test density beta = 0.015 1/m the optical
thickness to the far end of the rows (111 m away) is 1.7, to the first
façades 0.15-0.5, to the objects 0.15-0.4.

    python demo_scenes/boulevard.py OUT.blend
"""
import os
import sys

if __name__ == "__main__":
    sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

from demo_scenes import (add_box, add_camera, add_cylinder, add_plane, add_point_light, add_sphere,  # noqa: E402
                         main, material, render_settings, set_world)

EYE = (0.0, -4.0, 1.7)           # camera, m
TARGET = (0.0, 60.0, 3.2)        # looking down the road, slightly up
LENS = 24.0                      # mm (36 mm sensor): 74 degrees across
ROAD_HALF_WIDTH = 6.0            # m; pavements beyond, façades from x = +-9 m
FACADE_X = 9.0
ROAD_END = 130.0                 # m along +Y
LAMP_ROWS = (-5.5, 5.5)          # x of the two rows, m
LAMP_SPACING = 5.0               # m
LAMPS_PER_ROW = 22               # y = 0, 5, ..., 105 m
LAMP_HEIGHT = 6.0                # m
POST_OFFSET = 0.35               # m: the post stands beside its lamp (outwards), its top below it
POST_HEIGHT = 5.8
POST_RADIUS = 0.08
BEHIND_LAMP = ((0.0, -8.0, 5.7), 1200.0, (1.0, 0.78, 0.5))   # location, power W, colour
SODIUM = (1.0, 0.58, 0.22)       # low/high-pressure sodium, warm orange
LED = (0.95, 0.97, 1.0)          # white LED, slightly cold
WARM_LED = (1.0, 0.86, 0.68)
# (y of the first block, length, depth, height) per side: simple boxes with gaps (side streets)
BLOCKS = {
    -1: ((-10.0, 24.0, 10.0, 14.0), (17.0, 30.0, 10.0, 20.0), (51.0, 22.0, 10.0, 11.0), (77.0, 35.0, 10.0, 17.0)),
    +1: ((-10.0, 18.0, 10.0, 18.0), (12.0, 26.0, 10.0, 12.0), (42.0, 40.0, 10.0, 22.0), (86.0, 30.0, 10.0, 15.0)),
}
# the objects on the road: name, centre, size (sphere radius / box half extents), material key
SPHERES = (("Matte Sphere", (-2.4, 9.0, 0.9), 0.9, "matte"),
           ("Glossy Sphere", (0.4, 14.0, 1.0), 1.0, "glossy"),
           ("Metal Sphere", (3.0, 19.0, 1.1), 1.1, "metal"))
BOXES = (("Matte Box", (-3.2, 24.0, 0.8), (1.0, 1.4, 0.8), "matte_box"),
         ("Metal Box", (2.6, 30.0, 1.0), (0.9, 0.9, 1.0), "metal"))
DEFAULT_DENSITY = 0.015          # 1/m: optical thickness 1.7 to the far end of the rows


def lamps():
    """[(name, location, power W, colour)]: the two rows, then the lamp behind the camera."""
    out = []
    for side, x in enumerate(LAMP_ROWS):
        for i in range(LAMPS_PER_ROW):
            k = side * LAMPS_PER_ROW + i
            y = i * LAMP_SPACING + (2.5 if side else 0.0)   # the rows are staggered by half a spacing
            if i % 5 == 3:                                   # dimmer: a failing sodium or a small LED
                power, colour = (250.0, SODIUM) if side == 0 else (180.0, WARM_LED)
            elif (i + side) % 3 == 0:
                power, colour = 900.0 + 60.0 * (k % 4), LED
            else:
                power, colour = 1300.0 + 100.0 * (k % 3), SODIUM
            out.append((f"Lamp {'LR'[side]}{i + 1:02d}", (x, y, LAMP_HEIGHT), power, colour))
    loc, power, colour = BEHIND_LAMP
    out.append(("Lamp Behind", loc, power, colour))
    return out


def build(scene):
    render_settings(scene)
    set_world(scene)
    mats = {
        "road": material("Asphalt", (0.12, 0.12, 0.13), roughness=0.7),
        "pavement": material("Pavement", (0.35, 0.33, 0.30), roughness=0.9),
        "facade": material("Facade", (0.45, 0.40, 0.34), roughness=0.9),
        "facade2": material("Facade Plaster", (0.55, 0.52, 0.48), roughness=0.8),
        "post": material("Post", (0.10, 0.11, 0.12), roughness=0.5, metallic=1.0),
        "matte": material("Matte", (0.70, 0.25, 0.18), roughness=0.9),
        "matte_box": material("Matte Box", (0.30, 0.55, 0.30), roughness=0.9),
        "glossy": material("Glossy", (0.15, 0.30, 0.70), roughness=0.2),
        "metal": material("Metal", (0.90, 0.72, 0.45), roughness=0.3, metallic=1.0),
    }
    add_plane(scene, "Road", -ROAD_HALF_WIDTH, ROAD_HALF_WIDTH, -20.0, ROAD_END, 0.0, mats["road"])
    add_plane(scene, "Pavement L", -FACADE_X, -ROAD_HALF_WIDTH, -20.0, ROAD_END, 0.0, mats["pavement"])
    add_plane(scene, "Pavement R", ROAD_HALF_WIDTH, FACADE_X, -20.0, ROAD_END, 0.0, mats["pavement"])
    for side, blocks in BLOCKS.items():
        for j, (y0, length, depth, height) in enumerate(blocks):
            x = side * (FACADE_X + 0.5 * depth)
            add_box(scene, f"Block {'L' if side < 0 else 'R'}{j + 1}", (x, y0 + 0.5 * length, 0.5 * height),
                    (0.5 * depth, 0.5 * length, 0.5 * height), mats["facade" if (j + (side > 0)) % 2 else "facade2"])
    for name, loc, power, colour in lamps():
        ob = add_point_light(scene, name, loc, power)
        ob.data.color = colour
        if name != "Lamp Behind":
            out = POST_OFFSET if loc[0] > 0 else -POST_OFFSET
            add_cylinder(scene, "Post " + name[5:], (loc[0] + out, loc[1], 0.0), POST_RADIUS, POST_HEIGHT,
                         mats["post"], segments=8)
    for name, centre, radius, key in SPHERES:
        add_sphere(scene, name, centre, radius, mats[key], segments=48, rings=24)
    for name, centre, half, key in BOXES:
        add_box(scene, name, centre, half, mats[key])
    add_camera(scene, EYE, TARGET, lens=LENS)
    return scene


if __name__ == "__main__":
    sys.exit(main(build))
