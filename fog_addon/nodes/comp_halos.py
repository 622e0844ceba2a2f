"""The multiply scattered halos (Dense Fog) in the compositor: the field of light scattered more than once varies
slowly over the picture, so each light's halo is evaluated at a coarser resolution (``halo``), summed over a
bundle's lights there and upsampled once (``fine``)."""
from . import comp_lights, comp_ops, comp_shafts
from .comp_lights import GLOW_OUTPUTS, GLOW_SHARED
from .comp_shafts import HALF_FROM, QUARTER_FROM
from .groups import V

HALO_STEP = "Halo Step"   # px between the samples of the multiply scattered halos (a bundle's input): 1, 2 or 4


def coarse_step(m, scene):
    """The step (px) between coarse samples: 1 below HALF_FROM pixels on the picture's shorter side, 2 from it, 4
    from QUARTER_FROM (a driver on the render's size, so a resolution changed later is followed)."""
    size = "min(rx,ry)*p/100"
    variables = [("rx", scene, "render.resolution_x"), ("ry", scene, "render.resolution_y"),
                 ("p", scene, "render.resolution_percentage")]
    return comp_ops.driven_value(m, "Halo Step",
                                 f"1+min(floor({size}/{HALF_FROM}),1)+2*min(floor({size}/{QUARTER_FROM}),1)",
                                 variables)


def halo(m, coarse, g, models, images, label, position):
    """(group node, {rungs.SURFACE_POINT: glow to the surface, rungs.SKY: to the sky}) of a light's multiply
    scattered halo (``rungs.split_halo``'s second models) per unit intensity, at the coarse resolution of
    ``coarse`` (``coarse_inputs``): the halo varies over many pixels (it is the field of light scattered more
    than once), so coarse samples hold it, and its quadrature along each ray costs the compositor a sixteenth at
    a quarter of the resolution.  ``fine`` brings the bundle's sum back."""
    node = m.node("CompositorNodeGroup", 6)
    node.node_tree, node.label = comp_lights.build_glow_group(models, images, None), label
    for socket, _ in GLOW_SHARED:
        m.feed(node.inputs[socket], coarse.get(socket, g[socket]))
    m.feed(node.inputs["Light"], position)
    m.feed(node.inputs["Intensity"], m.wrap((1.0, 1.0, 1.0)))
    return node, {o.at: m.dot(m.wrap(node.outputs[o.compositor], vector=True), (1.0, 0.0, 0.0))
                  for o in GLOW_OUTPUTS}


def coarse_inputs(m, g, per_pixel):
    """A glow group's per-pixel inputs (``per_pixel``, over the whole picture) at 1 / HALO_STEP of the
    resolution, shared by the bundle's halos."""
    kinds = dict(GLOW_SHARED)
    out = {}
    for socket in per_pixel:
        value = comp_ops.scaled(m, g[socket], 1.0 / g[HALO_STEP])
        out[socket] = value if kinds[socket] == V else comp_ops.first(m, value)
    return out


def fine(m, g, coarse, sums):
    """The bundle's coarse halo sums (RGB images, by rungs.SURFACE_POINT / rungs.SKY) at the picture's
    resolution: the depth-aware upsampling (``comp_shafts.upsampled_group``) of each, divided by its weights."""
    step = g[HALO_STEP]
    args = (comp_ops.first(m, comp_ops.scaled(m, coarse["View Distance"], step)), g["View Distance"], step)
    ones = m.less(-1.0, coarse["View Distance"])   # 1 at every coarse sample (an image, not a folded constant)
    weight = comp_ops.first(m, comp_shafts.upsampled_group(m, m.combine(ones, ones, ones), *args))
    inverse = 1.0 / m.maximum(weight, 1e-6)
    return {at: m.scale(comp_shafts.upsampled_group(m, v, *args), inverse) for at, v in sums.items()}
