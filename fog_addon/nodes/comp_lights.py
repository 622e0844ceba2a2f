"""The compositor's per-light groups, shared by every light with the same models: the light's glows along the
pixel's ray (``build_glow_group``, times the pixel filter's peak where the light is seen in the picture) and the
fog light the pixel's surface reflects (``build_scatter_group``); what each reads of the pixel."""
from ..precompute.model import pixel, rungs, shading
from ..precompute.physics.emitter import emitter_glow
from . import budgets, groups, light_groups, owned
from .comp_ops import CompOps
from .groups import F, V

LIGHT_GROUP = f"{owned.PREFIX} Compositor Light"  # per-light compositor groups: "<LIGHT_GROUP> [models]"
# what a light's glow group reads of the pixel (the same for all lights), and what its scatter group reads
GLOW_SHARED = (("Beta", F), ("Camera", V), ("Incoming", V), ("View Distance", F), ("Direction", V), ("Pixel", V),
               ("Corner", V), ("Across", V), ("Up", V), ("Size", V), ("Glow Origin", V), ("Glow Length", F))
SURFACE_SHARED = (("Beta", F), ("Camera", V), ("Position", V), ("Incoming", V), ("Normal", V), ("Diffuse", V),
                  ("Specular", V), ("Level", F))
SURFACE_IMAGES = tuple(name for name, _ in SURFACE_SHARED[2:])   # per pixel: cropped to the surfaces' window
SURFACE = "Surface "   # a bundle's inputs of SURFACE_IMAGES: "Surface Position", ...
# the quantities the compositor sums per pixel (``rungs.COMPOSITOR_OUTPUTS``, by their compositor sockets): a light's
# glows (rungs.GLOW) in its glow group, over the picture or the light's window; the light its surface reflects
# (the rest) in its scatter group, over the surfaces' window
GLOW_OUTPUTS = tuple(o for o in rungs.COMPOSITOR_OUTPUTS if o.kind == rungs.GLOW)
SCATTER_OUTPUTS = tuple(o for o in rungs.COMPOSITOR_OUTPUTS if o.kind != rungs.GLOW)
GLOW_TERMS = tuple((o.compositor, V) for o in GLOW_OUTPUTS)            # Airlight, Background
SCATTER_TERMS = tuple((o.compositor, V) for o in SCATTER_OUTPUTS)      # Scattered


def glow_group_name(models, peak, far_from=None):
    """``peak``: the pixel filter's table (``pixel.filter_table``) or None; ``far_from``: the far window's pixel
    angle (``build_glow_group``) or None."""
    suffix = "" if peak is None else " Peak" + (" EEVEE" if peak is pixel.EEVEE_FILTER else "")
    far = "" if far_from is None else f" Far {float(far_from):.6g}"
    return f"{LIGHT_GROUP} Glow [{models.airlight.name}, {models.background.name}]" + suffix + far


def pixel_filter(scene):
    """(the pixel filter's type for ``pixel.filter_scale``, the data path of its width) where a peak factor
    applies, else None: Cycles' Blackman-Harris filter, EEVEE's film filter (not at 1 sample, where EEVEE
    takes each pixel's centre), a width above 0."""
    if scene.render.engine == "CYCLES":
        kind, path = scene.cycles.pixel_filter_type, "cycles.filter_width"
    elif scene.render.engine == budgets.EEVEE_ENGINE and scene.eevee.taa_render_samples > 1:
        kind, path = "EEVEE", "render.filter_size"
    else:
        return None
    return (kind, path) if pixel.filter_scale(kind, scene.path_resolve(path)) is not None else None


def scatter_group_name(models):
    return f"{LIGHT_GROUP} Scatter [{models.scatter.name}]"


def _light_group(name, shared, terms, models, images):
    """(group, CompOps, its inputs by name, its output node, its light) of a new per-light group ``name``."""
    inputs = [*shared, ("Light", V), ("Intensity", V), *light_groups.spot_inputs(models)]
    ng, gin, gout = groups.new_group(name, inputs, terms, tree_type="CompositorNodeTree")
    m = CompOps(ng, images)
    g = {s.name: m.wrap(s, vector=s.type in ("VECTOR", "RGBA")) for s in gin.outputs if s.name}
    return ng, m, g, gout, light_groups.light_of(g, models)


def build_glow_group(models, images, peak, far_from=None):
    """One light's glows at a pixel (compositor group), shared by every light with these models: Airlight
    (the glow along the pixel's ray up to the surface, Sun et al. 2005 Eq. 11) and Background (the glow of
    the ray to the sky, Eq. 12), from ``shading.glow_pair``.  ``peak``: the pixel filter's table or None;
    with one, times the peak factor (``pixel.peak_factor``) where the ray passes the light, seen in the picture
    at ``pixel.picture_position`` (Corner, Across, Up: the image plane, ``comp_fog.camera_frame``; Size: the
    picture's, in the filter table's pixels).  The glows are the kernels' from Glow Origin over
    Glow Length (the camera and the view distance, or in a fog layer the part of the ray in it:
    ``sunlight.lamp_glow_span``); the peak takes the camera's.  Reads GLOW_SHARED (Incoming and Pixel only with
    ``peak``).  ``far_from``: a pixel angle (rad/px), or None: a glowing object's point's glows far from it, times
    the far window s(gamma) of the point's angle gamma off the pixel's ray (``emitter_glow.far_window``): the
    part of its kernel the ladder of blurs leaves out (``comp_fog.emitter_far_glows``)."""
    name = glow_group_name(models, peak, far_from)
    if (ng := groups.up_to_date(name)) is not None:
        return ng
    ng, m, g, gout, light = _light_group(name, GLOW_SHARED, GLOW_TERMS, models, images)
    glows = shading.light_glows(m, g["Glow Origin"], g["Direction"], g["Glow Length"], light,
                                light_groups.medium(m, g["Beta"]), models)
    if peak is not None:   # the sky's rays pass every light before the end of the world: its factor is 1 + excess
        to_light = g["Light"] - g["Camera"]
        seen_at = pixel.picture_position(m, to_light, g["Corner"], g["Across"], g["Up"], g["Size"])
        excess = pixel.peak_excess(m, g["Pixel"], seen_at, peak)
        along = m.dot(to_light, -1.0 * g["Incoming"])
        factors = {rungs.SURFACE_POINT: pixel.peak_factor(m, excess, along, g["View Distance"]),
                   rungs.SKY: 1.0 + excess}
        glows = {o: m.scale(v, factors[o.at]) for o, v in glows.items()}
    if far_from is not None:
        to_point = g["Light"] - g["Camera"]
        gamma = m.atan2(m.length(m.cross(g["Direction"], to_point)), m.dot(g["Direction"], to_point))
        far = emitter_glow.far_window(m, gamma, far_from)
        glows = {o: m.scale(v, far) for o, v in glows.items()}
    for o in GLOW_OUTPUTS:
        m.feed(gout.inputs[o.compositor], glows[o])
    ng[owned.BUILT] = groups.code_fingerprint()
    m.place()
    return groups.install(ng, name)


def build_scatter_group(models, images):
    """One light's fog light reflected by the pixel's surface (compositor group: Scattered, Sun et al. 2005
    Eq. 17-18 through ``shading.shade_point``), shared by every light with these models.  Reads
    SURFACE_SHARED."""
    name = scatter_group_name(models)
    if (ng := groups.up_to_date(name)) is not None:
        return ng
    ng, m, g, gout, light = _light_group(name, SURFACE_SHARED, SCATTER_TERMS, models, images)
    geo = shading.Geometry(g["Camera"], g["Position"], g["Incoming"], m.wrap(0.0), g["Normal"])
    material = shading.Material(g["Diffuse"], g["Specular"], g["Level"])
    terms = shading.shade_point(m, geo, material, light, light_groups.medium(m, g["Beta"]), models,
                                air=m.wrap(0.0))
    for o in SCATTER_OUTPUTS:
        m.feed(gout.inputs[o.compositor], m.wrap(getattr(terms, o.field)))
    ng[owned.BUILT] = groups.code_fingerprint()
    m.place()
    return groups.install(ng, name)
