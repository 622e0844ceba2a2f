"""Softbox colonnade: the colonnade's row of columns raked by a low rectangular area light (a softbox) instead of
a spot, so the fog's slabs come from an emitter with a size and a facing side.

Tests area lights' shafts (issue 46): the columns, floor and camera of ``colonnade.py``; a 0.5 x 0.25 m
rectangular area light (long side horizontal) 1.2 m above the floor and 3 m to the row's side, facing the row
along the spot's axis, of 2000 W (its intensity along its normal P / pi = 637 W/sr, the spot's P / 4 pi).  From
the columns 3 m away its 0.5 m width widens each shadow's edge into a penumbra of about 0.5 m at 3 m beyond them.
At the default density 0.08/m the optical thickness from the camera to the light is about 0.8.

    python demo_scenes/softbox_colonnade.py OUT.blend
"""
import math
import os
import sys

if __name__ == "__main__":
    sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

import bpy  # noqa: E402
from mathutils import Vector  # noqa: E402

from demo_scenes import main  # noqa: E402
from demo_scenes import colonnade  # noqa: E402

DEFAULT_DENSITY = colonnade.DEFAULT_DENSITY
SOFTBOX = (colonnade.SPOT[0], colonnade.SPOT[1], 2000.0)   # (position m, target m, power W)
SIZE = (0.5, 0.25)   # m: the rectangle's sides (x: horizontal)


def build(scene):
    colonnade.build(scene)
    spot = scene.objects["Raking Spot"]
    bpy.data.objects.remove(spot)
    pos, target, power = SOFTBOX
    light = bpy.data.lights.new("Softbox", "AREA")
    light.energy = power
    light.shape = "RECTANGLE"
    light.size, light.size_y = SIZE
    light.use_shadow = True
    ob = bpy.data.objects.new("Softbox", light)
    ob.location = pos
    ob.rotation_euler = (Vector(target) - Vector(pos)).to_track_quat("-Z", "Y").to_euler()
    scene.collection.objects.link(ob)
    assert math.isclose(scene.camera.location.x, 6.0)   # (the colonnade's camera, kept)
    return scene


if __name__ == "__main__":
    sys.exit(main(build))
