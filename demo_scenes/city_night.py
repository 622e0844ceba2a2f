"""A city at night (issue 47): N street lamps among a dozen buildings on a 120 m square, seen from a roof.

Twelve blocks (4 x 3, 18 x 24 m footprints, 8 to 34 m high) stand on a 120 m ground with 10 m streets between
them; N point lamps (radius 0, 400 W, shadows on) stand 6 m above the streets, spread evenly along them (every
lamp has walls and the ground within its glow's reach, so Auto shafts all of them).  The camera stands on the
south-east corner of the north-west block's roof (the tallest, 34 m), looking south-east down across the city
(24 mm).  Fog: beta ``DEFAULT_DENSITY`` 0.02/m.

    python demo_scenes/city_night.py OUT.blend [LAMPS]
"""
import os
import sys

if __name__ == "__main__":
    sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

from demo_scenes import (add_box_between, add_camera, add_plane, add_point_light, main, material,
                         render_settings, set_world)

HALF = 60.0                       # m: the ground's half side
STREET = 10.0                     # m between blocks
BLOCKS = (4, 3)                   # blocks along x, y
LAMP_HEIGHT = 6.0                 # m
LAMP_POWER = 400.0                # W
HEIGHTS = (14.0, 26.0, 9.0, 20.0, 12.0, 8.0, 22.0, 16.0, 34.0, 11.0, 18.0, 30.0)   # m, the blocks' roofs
DEFAULT_LAMPS = 100
DEFAULT_DENSITY = 0.02            # 1/m


def _spans(count, half):
    """(start, end) m of ``count`` blocks across [-half, half] with a street of STREET at each side of each."""
    width = (2.0 * half - (count + 1) * STREET) / count
    return [(-half + STREET + k * (width + STREET), -half + STREET + k * (width + STREET) + width)
            for k in range(count)]


def blocks():
    """[(x0, x1, y0, y1, height)] m of the buildings."""
    xs, ys = _spans(BLOCKS[0], HALF), _spans(BLOCKS[1], HALF)
    return [(x0, x1, y0, y1, HEIGHTS[(j * BLOCKS[0] + i) % len(HEIGHTS)])
            for j, (y0, y1) in enumerate(ys) for i, (x0, x1) in enumerate(xs)]


def lamp_positions(n):
    """(x, y, z) m of ``n`` lamps spread evenly along the streets' centre lines (street crossings taken once)."""
    xs, ys = _spans(BLOCKS[0], HALF), _spans(BLOCKS[1], HALF)
    lines_x = [-HALF + 0.5 * STREET] + [x1 + 0.5 * STREET for _, x1 in xs]   # streets running along y
    lines_y = [-HALF + 0.5 * STREET] + [y1 + 0.5 * STREET for _, y1 in ys]   # streets running along x
    span = 2.0 * HALF - STREET
    total = span * (len(lines_x) + len(lines_y))
    step = total / n
    points = []
    for k in range(n):
        s = (k + 0.5) * step
        line, t = divmod(s, span)
        t += -HALF + 0.5 * STREET
        if line < len(lines_x):
            points.append((lines_x[int(line)], t, LAMP_HEIGHT))
        else:
            points.append((t, lines_y[int(line) - len(lines_x)], LAMP_HEIGHT))
    return points


def build(scene, lamps=DEFAULT_LAMPS):
    render_settings(scene)
    set_world(scene)
    ground = material("Asphalt", (0.25, 0.25, 0.25), roughness=0.8)
    wall = material("Facade", (0.45, 0.42, 0.38), roughness=0.7)
    add_plane(scene, "Ground", -HALF, HALF, -HALF, HALF, 0.0, ground)
    for k, (x0, x1, y0, y1, h) in enumerate(blocks()):
        add_box_between(scene, f"Block {k:02d}", x0, x1, y0, y1, 0.0, h, wall)
    for k, pos in enumerate(lamp_positions(lamps)):
        add_point_light(scene, f"Lamp {k:04d}", pos, LAMP_POWER)
    x0, x1, y0, y1, h = blocks()[2 * BLOCKS[0]]   # the north-west block
    eye = (x1 - 1.0, y0 + 1.0, h + 1.7)   # its south-east corner, over the first crossing
    add_camera(scene, eye, (eye[0] + 50.0, eye[1] - 50.0, 0.0), lens=24.0)
    return scene


if __name__ == "__main__":
    args = sys.argv[1:]
    n = int(args.pop()) if len(args) == 2 else DEFAULT_LAMPS
    sys.exit(main(lambda scene: build(scene, n), args))
