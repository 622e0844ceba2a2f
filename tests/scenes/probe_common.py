"""What the per-pixel probes share: the tiny render set-up and the camera ray of each pixel centre."""
import numpy as np

from fog_addon import measure


def tiny_render(scene, engine, width, height):
    """1 sample at each pixel centre, no bounces (Cycles), point lights unwindowed (EEVEE)."""
    scene.render.engine = engine
    measure.set_resolution(scene, width, height)
    measure.set_samples(scene, 1)
    measure.set_pixel_centre_filter(scene)
    scene.cycles.max_bounces = 0
    scene.eevee.light_threshold = 1e-4


def camera_rays(cam, width, height):
    """(camera position, unit world direction of each pixel centre's ray (height, width, 3)) of a perspective camera
    with horizontal sensor fit."""
    ys, xs = np.mgrid[0:height, 0:width]
    sw, f = cam.data.sensor_width, cam.data.lens
    d = np.stack([((xs + 0.5) / width - 0.5) * sw, (0.5 - (ys + 0.5) / height) * sw * height / width,
                  -np.full(xs.shape, f)], -1)
    d /= np.linalg.norm(d, axis=-1, keepdims=True)
    return np.array(cam.location), d @ np.array(cam.matrix_world.to_3x3()).T
