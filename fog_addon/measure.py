"""Scene I/O shared by the ``render`` and ``reference`` commands (needs bpy).

* :func:`open_scene` opens a .blend and returns its active scene;
* :func:`set_resolution`, :func:`set_samples`, :func:`set_pixel_centre_filter`
  prepare a measurement;
* :func:`render_to_file` renders the scene's camera and writes ``.exr``
  (linear float32, RGBA, the view transform does not touch EXR data) or ``.png``
  (display-referred 8-bit RGBA through the scene's colour management).

See /work/shared/notes/blender-facts.md §0 for why the pixel filter matters:
Cycles' default 1.5 px Blackman-Harris averages a glow's convex peak over the
footprint (up to 20 % off); a Gaussian of width 0.01 px samples pixel centres.
"""
import os

import bpy

from .nodes import compositor

PIXEL_CENTRE_FILTER_WIDTH = 0.01   # px, Cycles Gaussian (BOX always uses width 1)


def open_scene(path):
    """Open ``path`` (a .blend) replacing the current file; return the scene to render."""
    path = os.path.abspath(os.fspath(path))
    if not os.path.isfile(path):
        raise FileNotFoundError(f"no such .blend file: {path}")
    bpy.ops.wm.open_mainfile(filepath=path, load_ui=False)
    scene = bpy.context.scene
    if scene.camera is None:
        raise ValueError(f"{path}: scene {scene.name!r} has no camera")
    return scene


def set_resolution(scene, width, height):
    r = scene.render
    r.resolution_x = int(width)
    r.resolution_y = int(height)
    r.resolution_percentage = 100
    r.pixel_aspect_x = r.pixel_aspect_y = 1.0
    r.use_border = False


def set_samples(scene, samples):
    """Samples per pixel for the scene's engine (Cycles: fixed count, no adaptivity)."""
    samples = int(samples)
    if scene.render.engine == 'CYCLES':
        scene.cycles.samples = samples
        scene.cycles.use_adaptive_sampling = False
    else:
        scene.eevee.taa_render_samples = samples


def set_pixel_centre_filter(scene):
    """Make each pixel a point sample at its centre (both engines)."""
    scene.cycles.pixel_filter_type = 'GAUSSIAN'
    scene.cycles.filter_width = PIXEL_CENTRE_FILTER_WIDTH
    compositor.teardown_denoiser(scene)   # no denoiser at all, not even the fog's compositor set-up
    scene.cycles.use_denoising = False   # on by default; it smears glow peaks at low sample counts
    # EEVEE reconstructs with render.filter_size (px); 0 = no spatial filter.
    scene.render.filter_size = 0.0


def set_cycles_cpu(scene, threads=0):
    """Deterministic CPU Cycles: fixed seed, auto threads (0) unless given."""
    scene.cycles.device = 'CPU'
    scene.cycles.seed = 0
    scene.cycles.use_animated_seed = False
    scene.render.threads_mode = 'AUTO' if not threads else 'FIXED'
    if threads:
        scene.render.threads = int(threads)


def configure_output(scene, out, multilayer=False):
    """Set the image format from the extension of ``out``; return the absolute path.  ``multilayer``: an .exr is
    Blender's multilayer EXR, every pass of every view layer that renders (the fog passes' AOVs among them) beside
    the composite."""
    out = os.path.abspath(os.fspath(out))
    ext = os.path.splitext(out)[1].lower()
    im = scene.render.image_settings
    if ext == '.exr' and multilayer:
        im.media_type = 'MULTI_LAYER_IMAGE'
        im.file_format = 'OPEN_EXR_MULTILAYER'
        im.color_depth = '32'
        im.exr_codec = 'ZIP'
    elif ext == '.exr':
        im.media_type = 'IMAGE'
        im.file_format = 'OPEN_EXR'
        im.color_depth = '32'
        im.exr_codec = 'ZIP'
        im.color_mode = 'RGBA'
    elif ext == '.png':
        im.media_type = 'IMAGE'
        im.file_format = 'PNG'
        im.color_depth = '8'
        im.color_mode = 'RGBA'
        im.compression = 15
    else:
        raise ValueError(f"output must end in .exr or .png, got {out!r}")
    scene.render.filepath = out
    scene.render.use_file_extension = False
    scene.render.film_transparent = False
    return out


def render_to_file(scene, out, multilayer=False):
    """Render ``scene`` through its camera and write ``out`` (.exr or .png; ``multilayer``: see
    ``configure_output``)."""
    out = configure_output(scene, out, multilayer)
    d = os.path.dirname(out)
    if d:
        os.makedirs(d, exist_ok=True)
    if bpy.context.window is not None and bpy.context.window.scene is not scene:
        bpy.context.window.scene = scene
    bpy.ops.render.render(write_still=True, scene=scene.name)
    if not os.path.isfile(out):
        raise RuntimeError(f"render finished but {out} was not written")
    return out
