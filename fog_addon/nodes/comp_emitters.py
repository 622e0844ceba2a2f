"""The glows of glowing objects in the compositor (``precompute/physics/emitter/emitter_glow.py``): the Emission pass,
undimmed and weighted per pixel, blurred by a ladder of Blur nodes, each rung stopped at the surfaces in front of its
sources."""
import math

from ..precompute.physics.emitter import emitter_glow
from . import comp_ops, images as images_

EMITTERS = "Emission"   # the fog group's input of the emitters' light: the Render Layers' Emission pass


def emitter_pixel_angle(scene):
    """rad a pixel at the picture's centre (the emitters' glow kernels are baked for it)."""
    from .. import view
    left, right, _, _ = view.frame_extent(scene, scene.camera)
    return math.atan(float(right - left) / max(view.render_size(scene)[0], 1))


def emitter_table(g, pixel_angle, multiple_albedo=None):
    """{name: image} of the emitters' glow weights for anisotropy ``g``, ``pixel_angle`` and Dense Fog's albedo
    (baked once, cached)."""
    specs = emitter_glow.table_spec(g, pixel_angle, multiple_albedo), emitter_glow.facing_spec(g)
    return {spec.name: images_.table_image(spec) for spec in specs}


def glows(m, p, beta, d_vp, g, pixel_angle, multiple_albedo=None, cover=None, facing=None, lean=None):
    """The glows of the glowing objects the camera sees (``precompute/physics/emitter/emitter_glow.py``): the Emission
    pass made undimmed (times e^{beta D_vp}) and weighted by its glow's total weight N(T)
    (``emitter_glow.source_weight``) and, with ``facing`` (the |cos| of each pixel's surface to the camera), taken as
    the two-sided Lambertian source its surface is (``emitter_glow.facing_factor``: a flat sign sends less light
    sideways than towards the camera); then weighted per pixel by each rung's share a_j(T) / N(T), blurred by each Blur
    node of the ladder and summed (per unit albedo).  Each rung's glow stops at the surfaces in front of its sources
    (``emitter_glow.segment_share`` at the rung's angle, the sources' optical depth taken as the mean over what the
    rung blurs in: a second blur of the weights times T); where the pixel sees the sky (``cover`` 0) or a glowing
    surface it is whole.  With ``lean`` (the picture's unit direction (x, y, 0) of each pixel's normal, taken facing
    the camera) a flat emitter glows more on the side its normal leans to: each rung from DIPOLE_MIN_SIZE up adds
    the cos(phi) term of ``emitter_glow.facing_dipole``, -(sigma^2 / rho) div(B * (D / c) L u) (``dipole_scale``;
    the gradient by +-1 px differences; grey, in the glow's colour where it lands)."""
    spec = emitter_glow.table_spec(g, pixel_angle, multiple_albedo)
    t = beta * d_vp
    x = emitter_glow.table_x(m, t)
    light = m.scale(p[EMITTERS], emitter_glow.source_weight(m, spec, t))
    leaning = None
    if facing is not None and multiple_albedo is None:   # (Dense Fog's kernel keeps the isotropic sources)
        c = m.clamp(facing)
        if lean is not None:
            dipole = emitter_glow.facing_factor(m, facing, m.table(emitter_glow.facing_spec(g), c, 1.0))
            leaning = m.scale(lean, m.dot(light, (1.0 / 3.0, 1.0 / 3.0, 1.0 / 3.0)) * dipole)
        light = m.scale(light, emitter_glow.facing_factor(m, facing, m.table(emitter_glow.facing_spec(g), c, 0.0)))
    grey = m.dot(light, (1.0 / 3.0, 1.0 / 3.0, 1.0 / 3.0))
    t_surface = t if cover is None else m.select(m.less(1e-3, cover), t, 1.0e6)
    # a glowing pixel's own surface is no surface in front of the glow: it takes the whole of it (the light its
    # neighbours send through the fog towards it, single and multiply scattered, lies in front of it)
    glowing = m.less(1e-30, m.dot(p[EMITTERS], (1.0, 1.0, 1.0)))
    t_surface = m.select(glowing, 1.0e6, t_surface)
    total = None
    for j, size in enumerate(emitter_glow.SIZES):
        a = emitter_glow.rung_share(m, spec, x, j)
        sources = [m.scale(light, a), m.combine(grey * a * t, grey * a, 0.0)]
        dipole = leaning is not None and size >= emitter_glow.DIPOLE_MIN_SIZE
        if dipole:
            sources.append(m.scale(leaning, a))
        blurred = []
        for source in sources:
            blur = m.node("CompositorNodeBlur", 5)
            blur.inputs["Size"].default_value = (float(size), float(size))
            blur.inputs["Extend Bounds"].default_value = True   # off, Blender extends the picture's edge pixels
            m.feed(blur.inputs["Image"], source)                # outwards: a sign cut by the frame glows on
            blurred.append(m.wrap(blur.outputs["Image"], vector=True))
        glow, moments = blurred[:2]
        if dipole:   # -(sigma^2 / rho) (d/dx of the x channel + d/dy of the y channel), in the glow's colour
            dx = m.dot(comp_ops.translated(m, blurred[2], -1.0, 0.0) - comp_ops.translated(m, blurred[2], 1.0, 0.0),
                       (1.0, 0.0, 0.0))
            dy = m.dot(comp_ops.translated(m, blurred[2], 0.0, -1.0) - comp_ops.translated(m, blurred[2], 0.0, 1.0),
                       (0.0, 1.0, 0.0))
            lean_grey = (dx + dy) * (-0.5 * emitter_glow.dipole_scale(size))
            glow_grey = m.dot(glow, (1.0 / 3.0, 1.0 / 3.0, 1.0 / 3.0))
            glow = glow + m.scale(glow, lean_grey / m.maximum(glow_grey, 1e-30))
        t_source = m.dot(moments, (1.0, 0.0, 0.0)) / m.maximum(m.dot(moments, (0.0, 1.0, 0.0)), 1e-30)
        share = emitter_glow.segment_share(m, t_surface, t_source, emitter_glow.rung_angle(size, pixel_angle))
        v = m.scale(glow, share)
        total = v if total is None else comp_ops.accumulate(m, total, v)
    return total
