"""Fog models as data: the rungs of each term's ladder, and the chooser that gives each light its models.

A light's contribution to the picture has four terms (Sun et al. 2005):

* ``airlight``   — the glow along a camera ray that ends on a surface (Eq. 5, 11);
* ``background`` — the glow along a camera ray to infinity (Eq. 12);
* ``scatter``    — the fog light a surface reflects, per unit albedo (Eq. 15, 17-18);
* ``direct``     — the light's direct light dimmed on its way to the surface (Eq. 14).

A :class:`Rung` is one model of one term: its kernel (a per-pixel formula
written once against the ops of ``ops.ShaderOps``, with the term's uniform
signature below), the backends that can run it, the tables it reads, its
domain of validity and its error predictor.  Numpy runs every kernel (it is
each rung's reference twin); shader nodes run kernels without loops; OSL runs
kernels without tables.  ``ShaderOps.run`` sends a rung to a backend that can
run it (the node builder puts an OSL Script node in the tree for a rung that
only OSL can run).

Term signatures (distances in m, beta in 1/m, results per unit radiant
intensity of the light):

* airlight(m, beta, d_sv, along, h, d_vp) -> 1/m^2
* background(m, beta, d_sv, along, h) -> 1/m^2
* scatter(m, beta, d_sp, cos_theta, level) -> 1/m^2 per unit albedo
* direct(m, beta, d_sp) -> transmittance (dimensionless)

A spot light (``spot.py``) has rungs of its own for the glow (``spot_rungs``: the point light's rung
on the part of the ray inside the inner cone, quadrature on the blend rim), whose kernels take the
ray in the light's space too: airlight(m, beta, d_sv, along, h, d_vp, px, py, pz, dx, dy, dz,
cos_half, blend) and background(... without d_vp); its scatter rung (``spot_scatter_rung``) gives both
lobes at once, scatter(m, beta, d_sp, cos_n, cos_r, level, c_axis, cos_half, blend, cos_n_axis, cos_r_axis)
-> (diffuse, glossy) (``spot.scatter``: they share the spot's table lookups); and ``DIRECT_SPOT``,
whose ``spot`` flag tells the shading (``shading.shade_point``) to follow the cone in the direct light.
"""
from dataclasses import dataclass, replace
import functools
from typing import Callable, NamedTuple

from ..core import tables
from ..physics.area import area
from ..physics.point import model, multiple, surface
from ..physics.spot import spot, spot_multiple
from . import capabilities

TERMS = ("airlight", "background", "scatter", "direct")
BACKENDS = ("numpy", "nodes", "osl")
PREFERENCES = ("nodes", "osl", "compositor")   # the user's Method: node-group tables, OSL quadrature where a
#                                                rung has one, or the node groups' models in the compositor


@dataclass(frozen=True)
class Rung:
    name: str                 # unique, short: names node groups and OSL texts
    term: str                 # one of TERMS
    kernel: Callable          # the term's signature (module docstring)
    backends: frozenset       # where the kernel runs (subset of BACKENDS)
    tables: tuple = ()        # tables.TableSpec it reads
    domain: str = "all inputs"   # where the error bound holds
    max_error: float = 0.0    # max relative error over the domain against adaptive quadrature (measured; see tests)
    evidence: str = ""        # the test that measures max_error
    spot: bool = False        # a spot light's rung (``spot_rungs``, DIRECT_SPOT): the spot kernels' signature
    area: bool = False        # an area light's rung (``area_rungs``, DIRECT_AREA; with the spot kernels' signature)
    pair: Callable = None     # an airlight rung's (airlight, background) of one ray at once, sharing their work
    #                           (``spot.airlight_pair``), for a backend that needs both per pixel (the compositor)
    halo: "Rung" = None       # a glow rung's multiply scattered part alone (``spot_multiple_rungs``), which the
    #                           compositor evaluates at a coarser resolution: then ``single`` is the rest
    single: "Rung" = None
    sampled: bool = False     # a glow rung estimated from one uniform number u a render sample (the kernel's last
    #                           argument, ``shading.Light.u``): its mean over u is the glow
    #                           (``model.airlight_equiangular``)

    def predicted_error(self, *situation):
        """Bound on the relative error this rung makes in any pixel of a situation (camera, light, medium).

        Today every rung's bound is its measured maximum over its whole domain,
        whatever the situation: a conservative predictor.
        """
        return self.max_error


AIRLIGHT_TABLE = Rung(
    "airlight table", "airlight", model.airlight_segment, frozenset({"numpy", "nodes"}), (tables.AIRLIGHT,),
    "T_sv, T_vp in [0.01, 50] and infinity, gamma in (0, pi); exact limits beyond", 1.6e-4,
    "tests/test_airlight.py: 44 000 samples of Eq. 5")
BACKGROUND_TABLE = Rung(
    "background table", "background", model.airlight_background, frozenset({"numpy", "nodes"}), (tables.AIRLIGHT,),
    AIRLIGHT_TABLE.domain, 1.6e-4, AIRLIGHT_TABLE.evidence)
AIRLIGHT_QUADRATURE = Rung(
    "airlight quadrature", "airlight", model.airlight_quadrature, frozenset({"numpy", "osl"}), (),
    "beta h >= 1e-16", 1.1e-6, AIRLIGHT_TABLE.evidence)
BACKGROUND_QUADRATURE = Rung(
    "background quadrature", "background", model.airlight_quadrature_background, frozenset({"numpy", "osl"}), (),
    AIRLIGHT_QUADRATURE.domain, 1.1e-6, AIRLIGHT_TABLE.evidence)
SCATTER_TABLE = Rung(
    "scatter table", "scatter", surface.surface_scatter, frozenset({"numpy", "nodes"}), (tables.SURFACE,),
    "T = beta D_sp in [0, 60] (clamped beyond, where e^-T < 1e-26), Phong n in [1, 1024]", 4.3e-3,
    "tests/test_surface.py: Eq. 15 with Eq. 5 inside")
DIRECT_EXACT = Rung(
    "direct exact", "direct", model.transmittance, frozenset({"numpy", "nodes", "osl"}), (),
    "all inputs", 0.0, "closed form (Eq. 14)")
# A spot's direct light is the point light's times Blender's cone factor at the surface (``spot.falloff_at``).
DIRECT_SPOT = replace(DIRECT_EXACT, name="direct exact, spot cone", spot=True)
# An area light's: the point light's from its centre times Lambert's cosine (``area.lambert_falloff``).
DIRECT_AREA = replace(DIRECT_EXACT, name="direct exact, area light", spot=True, area=True,
                      domain="from the emitter's centre")

# The viewport preview's sampled lights (``nodes/preview_sampled.py``): one point of the ray a render sample, whose
# mean over the samples is Eq. 5 (unbiased: max_error 0; its noise is the preview's, measured in
# docs/measurements/2026-11-29-viewport-preview.md).
AIRLIGHT_SAMPLED = Rung(
    "airlight equiangular", "airlight", model.airlight_equiangular, frozenset({"numpy", "nodes"}), (),
    "beta h >= 0; unbiased over the uniform number", 0.0,
    "tests/test_airlight.py: its mean over u against scipy quadrature of Eq. 5", sampled=True)
BACKGROUND_SAMPLED = replace(AIRLIGHT_SAMPLED, name="background equiangular", term="background",
                             kernel=model.airlight_equiangular_background)


def no_airlight(m, beta, d_sv, along, h, d_vp):
    """The bottom rung of the airlight ladder: left out (0).  Its error is the term itself, which
    ``predict.py`` bounds from the scene; so for the other two below."""
    return m.const(0.0)


def no_background(m, beta, d_sv, along, h):
    return m.const(0.0)


def no_scatter(m, beta, d_sp, cos_theta, level):
    return m.const(0.0)


_OFF = "the whole term (predict.py bounds it from the scene)"
AIRLIGHT_OFF = Rung("airlight off", "airlight", no_airlight, frozenset(BACKENDS), (), _OFF, 1.0,
                    "tests/test_predict.py, tests/test_quality.py")
BACKGROUND_OFF = Rung("background off", "background", no_background, frozenset(BACKENDS), (), _OFF, 1.0,
                      AIRLIGHT_OFF.evidence)
SCATTER_OFF = Rung("scatter off", "scatter", no_scatter, frozenset(BACKENDS), (), _OFF, 1.0, AIRLIGHT_OFF.evidence)

OFF_RUNGS = (AIRLIGHT_OFF, BACKGROUND_OFF, SCATTER_OFF)


def is_off(rung):
    """True for a rung that leaves its term out (OFF_RUNGS: the ladder's bottom)."""
    return any(rung is r for r in OFF_RUNGS)


RUNGS = (AIRLIGHT_TABLE, BACKGROUND_TABLE, AIRLIGHT_QUADRATURE, BACKGROUND_QUADRATURE, SCATTER_TABLE, DIRECT_EXACT,
         DIRECT_SPOT, AIRLIGHT_OFF, BACKGROUND_OFF, SCATTER_OFF)

# A light's steps down the ladder, cheapest last: 0 every term modelled; 1 the fog light it scatters onto
# surfaces left out (the glow stays); 2 its glow left out too (its direct light still dims through the fog);
# 3 (LEFT_OUT) as 2, and the light not in the fog's groups at all, taken only to fit a budget (EEVEE's
# uniform block, ``predict.choose_steps``): Cycles dims its direct light in its own node tree as at 2,
# EEVEE by the other lights' shared attenuation instead of its own.
STEPS = ("full", "glow only", "off", "off, not in EEVEE's shared dimming")
OFF = 2
LEFT_OUT = 3


class LightModels(NamedTuple):
    """The rung of each term (TERMS) for one light."""
    airlight: Rung
    background: Rung
    scatter: Rung
    direct: Rung


# What a light's terms hand on to the composition of Eq. 19 and 12 (``shading.py``), one descriptor per
# quantity: the fog's groups derive their sockets from OUTPUTS (``nodes/light_groups.py``: a light's shader groups,
# read by the bundles; ``nodes/comp_lights.py``, ``comp_bundles.py``: the compositor's per-light groups and
# bundles), and ``shading.surface_light`` / ``pixel_light`` compose them by kind.  A new physical term adds its
# descriptor here; no builder lists terms by hand.
GLOW = "glow"             # RGB radiance gathered along the ray up to its end, W/(m^2 sr): added as it is
REFLECTED = "reflected"   # RGB radiance leaving the ray's surface point: dimmed by e^{-beta D_vp} on its way
DIMMING = "dimming"       # grey factor on the light's direct light at the surface (EEVEE's shared dimming)
WEIGHT = "weight"         # grey weight of that dimming in the average over the lights (EEVEE)
GATE = "gate"             # grey 0/1: the glow is worth computing only where it is 1 (a spot's cone, ``shading.Gated``)
SURFACE_POINT, SKY = "surface", "sky"   # where a quantity is taken: a camera ray's surface point, a ray to infinity


class Output(NamedTuple):
    """One quantity of one light that the composition reads (OUTPUTS)."""
    name: str             # its socket on the light's shader group (saved files and farms read it: never rename)
    field: str            # its field of shading.LightTerms (at SURFACE_POINT) or shading.SkyTerms (at SKY)
    at: str               # SURFACE_POINT or SKY
    term: str             # the TERMS entry whose rung computes it
    kind: str             # how shading composes it: GLOW, REFLECTED, DIMMING, WEIGHT or GATE
    per_light: bool = True   # one per light (all today; a term of the whole sky would not be)
    compositor: str = ""     # its socket in the compositor's groups (``nodes/comp_fog.py``), "" if the
    #                          compositor does not evaluate it per pixel (its materials dim direct light)

    @property
    def colour(self):
        """True for an RGB quantity (a colour socket), False for a grey one."""
        return self.kind in (GLOW, REFLECTED)

    def computed(self, models):
        """True if a light with ``models`` (LightModels) computes this quantity: its term's rung is not off."""
        return not is_off(getattr(models, self.term))

    def present(self, models):
        """True if a light with ``models`` (LightModels) has this quantity: a gate only where its term's rung is
        a spot's (``shading.LightTerms.seen``)."""
        return self.kind != GATE or getattr(models, self.term).spot


AIRLIGHT_OUT = Output("Airlight", "airlight", SURFACE_POINT, "airlight", GLOW, compositor="Airlight")
SCATTERED_OUT = Output("Scattered", "scattered", SURFACE_POINT, "scatter", REFLECTED, compositor="Scattered")
BACKGROUND_OUT = Output("Airlight", "background", SKY, "background", GLOW, compositor="Background")
OUTPUTS = (
    AIRLIGHT_OUT, SCATTERED_OUT,
    Output("Attenuation", "attenuation", SURFACE_POINT, "direct", DIMMING),
    Output("Weight", "weight", SURFACE_POINT, "direct", WEIGHT),
    Output("Seen", "seen", SURFACE_POINT, "airlight", GATE),
    BACKGROUND_OUT,
    Output("Seen", "seen", SKY, "background", GATE),
)
SURFACE_OUTPUTS = tuple(o for o in OUTPUTS if o.at == SURFACE_POINT)   # a light's surface group (shade_point)
SKY_OUTPUTS = tuple(o for o in OUTPUTS if o.at == SKY)                 # a light's World group (sky_terms)
COMPOSITOR_OUTPUTS = tuple(o for o in OUTPUTS if o.compositor)         # what the compositor sums per pixel


# Henyey-Greenstein anisotropy g: the glow's rungs integrate 4 pi p_HG along the ray (model.hg_weight), from
# a table baked for g (tables.anisotropic) or by quadrature; the scatter table is baked for g the same way
# (surface.radiance_profile), its bound hg_scatter_error(g) (measured: tests/test_surface.py).  Measured
# against scipy quadrature of Eq. 5 with the phase function (tests/test_airlight.py); the table's
# cancellation between the two tails grows as
# g -> -1 (the back-scatter peak far beyond the light), so tables serve g >= MIN_TABLE_ANISOTROPY.
MIN_TABLE_ANISOTROPY = -0.8
HG_TABLE_ERROR = 1.6e-3      # max relative error of the g != 0 airlight tables over g in [-0.7, 0.95]
HG_BACKSCATTER_TABLE_ERROR = 3.5e-3   # ... over g in [-0.8, -0.7): the tails start to cancel
HG_QUADRATURE_ERROR = 1e-5


def hg_table_error(g):
    """Bound on the relative error of the airlight table baked for g: measured on 40 000 cached samples over
    16 values of g (tests/test_airlight.py: max 8.0e-4 at g = 0.95, 3.6e-4 at -0.65) and, below -0.7, on
    400 000 random samples (3.3e-3 at g = -0.8: thin fog with the surface just before the light)."""
    return HG_BACKSCATTER_TABLE_ERROR if g < -0.7 else HG_TABLE_ERROR


def hg_scatter_error(g):
    """Bound on the relative error of the scatter table baked for g: its maximum against scipy quadrature
    of Eq. 15 with the phase function over the points of tests/test_surface.py (grazing light sharpens
    the table's theta structure as g grows: 0.31 % at g = -0.5, 0.91 % at 0.85, 2.8 % at 0.95)."""
    g = abs(float(g))
    return SCATTER_TABLE.max_error if g == 0.0 else 5e-3 if g <= 0.5 else 1e-2 if g <= 0.85 else 3e-2


@functools.lru_cache(maxsize=None)
def anisotropic_rungs(g):
    """(airlight table, background table, airlight quadrature, background quadrature, scatter table) rungs
    for Henyey-Greenstein anisotropy g (the isotropic rungs themselves at g = 0)."""
    g = float(g)
    if g == 0.0:
        return AIRLIGHT_TABLE, BACKGROUND_TABLE, AIRLIGHT_QUADRATURE, BACKGROUND_QUADRATURE, SCATTER_TABLE
    spec = tables.anisotropic(tables.AIRLIGHT, g)
    tag = f" (g {g:+.3f})"
    table_domain = f"{AIRLIGHT_TABLE.domain}; Henyey-Greenstein g in [{MIN_TABLE_ANISOTROPY}, {tables.MAX_ANISOTROPY}]"
    return tuple(replace(r, name=r.name + tag, kernel=functools.partial(r.kernel, g=g), tables=t, domain=d,
                         max_error=e)
                 for r, t, d, e in ((AIRLIGHT_TABLE, (spec,), table_domain, hg_table_error(g)),
                                    (BACKGROUND_TABLE, (spec,), table_domain, hg_table_error(g)),
                                    (AIRLIGHT_QUADRATURE, (), AIRLIGHT_QUADRATURE.domain, HG_QUADRATURE_ERROR),
                                    (BACKGROUND_QUADRATURE, (), AIRLIGHT_QUADRATURE.domain, HG_QUADRATURE_ERROR),
                                    (SCATTER_TABLE, (tables.anisotropic(tables.SURFACE, g),), SCATTER_TABLE.domain,
                                     hg_scatter_error(g))))


@functools.lru_cache(maxsize=None)
def sampled_rungs(g):
    """(airlight, background) rungs estimated from one uniform number a render sample (AIRLIGHT_SAMPLED), for
    Henyey-Greenstein anisotropy g: unbiased for any g, noisier as the phase function's peak sharpens."""
    g = float(g)
    if g == 0.0:
        return AIRLIGHT_SAMPLED, BACKGROUND_SAMPLED
    return tuple(replace(r, name=f"{r.name} (g {g:+.3f})", kernel=functools.partial(r.kernel, g=g))
                 for r in (AIRLIGHT_SAMPLED, BACKGROUND_SAMPLED))


# The rim's quadrature by its point count (spot.RIM_LADDER): max of the whole glow over random spots, tests/test_spot.py
# (2.0e-3, 1.4e-2, 4.6e-2 measured).  Fewer points than spot.RIM_NODES are chosen per light where the view's
# samples show the glow move little (predict.py), which bounds them in a scene better than these maxima.
SPOT_RIM_ERROR = {10: 3e-3, 6: 2e-2, 4: 6e-2}


@functools.lru_cache(maxsize=None)
def spot_rungs(air, background, g, rim_nodes=spot.RIM_NODES):
    """(airlight, background) rungs of a spot light for the point light's rungs ``air`` and ``background``
    (anisotropy g): ``air``'s kernel on the inner cone's piece of the ray (on the sky's rays too: the piece
    stops at optical depth spot.INNER_DEPTH), the rim by quadrature of ``rim_nodes`` points (``spot.airlight``)."""
    rim = dict(inner=air.kernel, g=float(g), rim_nodes=int(rim_nodes))
    kernels = (functools.partial(spot.airlight, **rim), functools.partial(spot.airlight_background, **rim))
    domain = air.domain + "; spot size 1-180 degrees, blend 0-1, any orientation and scale"
    evidence = "tests/test_spot.py, tests/test_spot_strict.py: Eq. 5 with Blender's spot factor, scipy quadrature"
    pair = functools.partial(spot.airlight_pair, **rim)
    tag = "" if rim_nodes == spot.RIM_NODES else f", {rim_nodes}-point rim"
    return tuple(replace(r, name="spot " + r.name + tag, kernel=k, domain=domain, spot=True, evidence=evidence,
                         max_error=air.max_error + SPOT_RIM_ERROR[rim_nodes], pair=p)
                 for r, k, p in ((air, kernels[0], pair), (background, kernels[1], None)))


# The fog light a spot scatters onto a surface: the point light's at the mean direction of the spot's fog
# light, times the share the cone lights and a correction for its concentration (spot.scatter, tables per
# g), never above the point light's.  Against hemisphere quadrature of the spot's airlight (150 random points
# inside, at the edge of and outside cones of 10-120 degrees, g = 0, 0.7, 0.85, tests/test_spot_scatter.py):
# the diffuse lobe at most 0.11 of the point light's fog light off, Phong lobes (n = 2-128) 0.71 of the larger
# of the point light's and the spot's: narrow lobes see the beam's shape, which a mean direction does not hold.
SPOT_SCATTER_ERROR = 0.75


@functools.lru_cache(maxsize=None)
def spot_scatter_rung(scatter, g):
    """The scatter rung of a spot light for the point light's ``scatter`` rung (anisotropy g)."""
    return replace(scatter, name="spot " + scatter.name, spot=True,
                   kernel=functools.partial(spot.scatter, point=scatter.kernel, g=float(g)),
                   tables=scatter.tables + (tables.anisotropic(tables.SPOT_MOMENTS, g),)
                   + (tables.LOBE_RESPONSE,),
                   domain=scatter.domain + "; relative to the point light's fog light", max_error=SPOT_SCATTER_ERROR,
                   evidence="tests/test_spot_scatter.py: Eq. 15 by hemisphere quadrature of the spot's airlight")


def area_glow_error(g):
    """Bound on an area light's glow error against quadrature over its emitter (``area.py``: the phase and
    extinction of each of its cells' centres) on rays that pass at least two half-diagonals from the emitter
    (tests/test_area.py measures it; nearer, forward-peaked fog's errors grow: ``AREA_NEAR_ERRORS``)."""
    return 0.01 + 0.05 * float(g) * float(g)


# The same nearer the emitter, by the ray's distance to it in half-diagonals (tests/test_area.py, 2000 random
# rays): {g: (within 0.5, 0.5-1, 1-2)}.  The cells' centres miss how the phase function's forward peak
# sees the emitter's face behind a fog point right beside it.
AREA_NEAR_ERRORS = {0.0: (0.07, 0.03, 0.02), 0.5: (0.19, 0.04, 0.02), 0.7: (1.4, 0.07, 0.03), 0.9: (2.0, 0.12, 0.19)}


AREA_SCATTER_ERROR = SPOT_SCATTER_ERROR   # the spot's mean-direction model with a cosine-weighted share


def area_rungs(scatter, g):
    """(airlight, background, scatter, direct) rungs of an area light (anisotropy g): its glow by quadrature
    along the ray of the emitter's solid angle (``area.airlight``, no tables), the point light's ``scatter``
    rung times Lambert's cosine (``area.scatter``) and DIRECT_AREA."""
    kw = dict(g=float(g))
    domain = "outside the emitter; any size, orientation and uniform scale; disks and ellipses as rectangles"
    evidence = "tests/test_area.py: Eq. 5 over the emitter's area, scipy quadrature"
    common = dict(backends=frozenset(BACKENDS), tables=(), domain=domain, max_error=area_glow_error(g),
                  evidence=evidence, spot=True, area=True)
    air = Rung(f"area airlight g{float(g):+.3f}", "airlight", functools.partial(area.airlight, **kw),
               pair=functools.partial(area.airlight_pair, **kw), **common)
    background = Rung(f"area background g{float(g):+.3f}", "background",
                      functools.partial(area.airlight_background, **kw), **common)
    lit = replace(scatter, name="area " + scatter.name, spot=True, area=True,
                  kernel=functools.partial(area.scatter, point=scatter.kernel, g=float(g)),
                  tables=scatter.tables + (tables.anisotropic(tables.SPOT_MOMENTS, g), tables.LOBE_RESPONSE),
                  domain=scatter.domain + "; relative to the point light's fog light", max_error=AREA_SCATTER_ERROR,
                  evidence="tests/test_area.py: Eq. 15 by hemisphere quadrature of the area light's airlight")
    return air, background, lit, DIRECT_AREA


MULTIPLE_ERROR = 0.07   # the multiply scattered glow against Cycles with 64 bounces: 3.3 % measured, tests bound 7 %


def _scaled(value, scale):
    """``value`` (a kernel's: one value or a tuple) times ``scale``; itself for 1 (no node)."""
    if scale == 1.0:
        return value
    return tuple(v * scale for v in value) if isinstance(value, tuple) else value * scale


def _scale_tag(scale):
    return "" if scale == 1.0 else f" x{scale:.2f}"


def _with_multiple(base, extra, spec, m, *args, scale=1.0, sampled=False):
    """A single-scattering kernel's value plus its multiply scattered twin's (``multiple.py``) times ``scale``,
    same arguments (but a ``sampled`` kernel's last, its uniform number: the twin is exact)."""
    return base(m, *args) + _scaled(extra(m, spec, *(args[:-1] if sampled else args)), scale)


def multiple_rungs(air, background, scatter, g, albedo, scale=1.0):
    """(airlight, background, scatter) rungs of a point light with the multiply scattered light
    (``multiple.py``: the field's table for anisotropy ``g`` and grey albedo ``albedo``) added to the single
    scattering of ``air``, ``background`` and ``scatter``.  They run where the table does (numpy, nodes).
    ``scale``: the share of unbounded fog's field that the scene's surfaces leave (``escape.field_scales``)."""
    spec = multiple.table_spec(g, albedo)
    tag = spec.name.split("(", 1)[1].rstrip(")") + _scale_tag(scale)
    out = []
    for rung, extra in ((air, multiple.multiple_airlight), (background, multiple.multiple_background),
                        (scatter, multiple.multiple_scatter)):
        out.append(replace(rung, name=f"{rung.name} + multiple {tag}",
                           kernel=functools.partial(_with_multiple, rung.kernel, extra, spec, scale=scale,
                                                    sampled=rung.sampled),
                           backends=rung.backends & {"numpy", "nodes"}, tables=rung.tables + (spec,),
                           max_error=max(rung.max_error, MULTIPLE_ERROR),
                           evidence="tests/test_multiple.py; docs/measurements/2026-11-27-apsf.md"))
    return tuple(out)


SPOT_MULTIPLE_ERROR = 0.13   # a spot's glow (single + multiple) against Cycles with 64 bounces: 12.7 % at worst


# The spot kernels' two shape arguments are (cos_half, blend) for a spot and the emitter's half sizes (a, b) for
# an area light; ``edge`` is the cosine where the ray is cut for the multiply scattered glow (None: a spot's
# cos_half; an area light's emitting half-space: 0).

def _edge(edge, shape0):
    return shape0 if edge is None else edge


def _halo_air(spec, m, beta, d_sv, along, h, d_vp, px, py, pz, dx, dy, dz, s0, s1, *, edge=None, scale=1.0):
    """The multiply scattered glow alone of a spot (or an area light) along a ray to a surface, times
    ``scale``."""
    return _scaled(spot_multiple.airlight(m, spec, beta, d_vp, px, py, pz, dx, dy, dz, _edge(edge, s0)), scale)


def _halo_background(spec, m, beta, d_sv, along, h, px, py, pz, dx, dy, dz, s0, s1, *, edge=None, scale=1.0):
    """The multiply scattered glow alone of a spot (or an area light) along a ray to the sky, times ``scale``."""
    return _scaled(spot_multiple.airlight(m, spec, beta, model.FAR, px, py, pz, dx, dy, dz, _edge(edge, s0)), scale)


def _halo_pair(spec, m, beta, d_sv, along, h, d_vp, px, py, pz, dx, dy, dz, s0, s1, *, edge=None, scale=1.0):
    ray = (px, py, pz, dx, dy, dz)
    return _scaled((spot_multiple.airlight(m, spec, beta, d_vp, *ray, _edge(edge, s0)),
                    spot_multiple.airlight(m, spec, beta, model.FAR, *ray, _edge(edge, s0))), scale)


def _plus(single, halo, m, *args):
    """A glow kernel's value: its single scattering (``single``) plus its halo (``halo``), same arguments."""
    return single(m, *args) + halo(m, *args)


def _plus_pair(single, halo, m, *args):
    """A ``pair``'s (to the surface, to the sky): ``single``'s plus ``halo``'s, each."""
    return tuple(a + b for a, b in zip(single(m, *args), halo(m, *args)))


def _spot_scatter_multiple(scatter, spec, m, beta, d_sp, cos_n, cos_r, level, c_axis, s0, s1, cos_n_axis,
                           cos_r_axis, *, scale=1.0):
    """A spot's (diffuse, glossy) fog light on a surface (``scatter``) plus the multiply scattered light times
    ``scale``: the irradiance over pi of a surface facing the normal, and for the glossy lobe facing the mirrored
    view vector (the field is broad: its radiance from a direction is about the irradiance facing it over pi)."""
    diffuse, glossy = scatter(m, beta, d_sp, cos_n, cos_r, level, c_axis, s0, s1, cos_n_axis, cos_r_axis)
    return (diffuse + _scaled(spot_multiple.scatter(m, spec, beta, d_sp, cos_n, c_axis, cos_n_axis), scale),
            glossy + _scaled(spot_multiple.scatter(m, spec, beta, d_sp, cos_r, c_axis, cos_r_axis), scale))


def spot_multiple_rungs(air, background, scatter, g, albedo, cone, scale=1.0):
    """(airlight, background, scatter) rungs of a spot light with its multiply scattered light
    (``spot_multiple``: the table of anisotropy ``g``, grey albedo ``albedo`` and ``cone`` = (cos_half, blend);
    ``cone`` None: an area light's, Lambert's cosine about its normal) added to the rungs ``air``,
    ``background`` and ``scatter``.  The compositor and numpy run them: a ray's quadrature in every material
    would cost the node groups far more.  ``scale``: as ``multiple_rungs``'."""
    spec = (spot_multiple.table_spec(g, albedo, *cone) if cone is not None
            else spot_multiple.lambert_table_spec(g, albedo))
    edge = ({} if cone is not None else {"edge": 0.0}) | {"scale": scale}
    tag = spec.name.split("(", 1)[1].rstrip(")") + _scale_tag(scale)
    common = dict(backends=air.backends & {"numpy", "nodes"}, max_error=max(air.max_error, SPOT_MULTIPLE_ERROR),
                  evidence="tests/test_spot_multiple.py; docs/measurements/2026-11-28-spot-multiple.md")
    halo_air = replace(air, name=f"halo {tag}", tables=(spec,), kernel=functools.partial(_halo_air, spec, **edge),
                       pair=functools.partial(_halo_pair, spec, **edge), **common)
    halo_background = replace(background, name=f"halo background {tag}", tables=(spec,),
                              kernel=functools.partial(_halo_background, spec, **edge), **common)
    return (replace(air, name=f"{air.name} + multiple {tag}", tables=air.tables + (spec,),
                    kernel=functools.partial(_plus, air.kernel, halo_air.kernel),
                    pair=functools.partial(_plus_pair, air.pair, halo_air.pair), halo=halo_air, single=air, **common),
            replace(background, name=f"{background.name} + multiple {tag}", tables=background.tables + (spec,),
                    kernel=functools.partial(_plus, background.kernel, halo_background.kernel),
                    halo=halo_background, single=background, **common),
            replace(scatter, name=f"{scatter.name} + multiple {tag}", tables=scatter.tables + (spec,),
                    kernel=functools.partial(_spot_scatter_multiple, scatter.kernel, spec, scale=scale),
                    backends=scatter.backends & {"numpy", "nodes"},
                    max_error=max(scatter.max_error, SPOT_MULTIPLE_ERROR),
                    evidence="tests/test_spot_multiple.py (a 360-degree cone against the point light's irradiance)"))


LIGHT_KINDS = ("point", "spot", "area")   # the lights the ladder models (a fog layer's sun is ``sunlight``'s)


def _dense_fog(preference, kind, step, multiple_albedo, cone):
    """True if a light of ``kind`` at ``step`` gets its multiply scattered light (Dense Fog) with ``preference``:
    the method models it for the kind (``capabilities``), the step keeps the glow, and a spot's cone is known."""
    if multiple_albedo is None or step >= 2:
        return False
    if kind == "point":
        return capabilities.can(preference, "dense_point")
    return capabilities.can(preference, "dense_shaped") and (kind == "area" or cone is not None)


def choose(preference="nodes", step=0, g=0.0, kind="point", rim_nodes=spot.RIM_NODES, multiple_albedo=None,
           cone=None, multiple_scale=1.0, sampled_glow=False):
    """The models for one light's terms, honouring the user's ``preference`` (PREFERENCES), ``step``
    (index into STEPS) rungs down the ladder, for Henyey-Greenstein anisotropy ``g``; ``kind`` (LIGHT_KINDS):
    a point light, a spot light (``spot_rungs``, DIRECT_SPOT) whose glow's rim takes ``rim_nodes`` points
    (spot.RIM_LADDER), or an area light (``area_rungs``).

    "nodes": every term from the node groups' tables; "osl": the glow by
    quadrature in OSL (Cycles only), the other terms as "nodes" (they have no
    OSL rung); "compositor": the models of "nodes", evaluated once per pixel in the compositor
    (``nodes/comp_fog.py``).  ``predict.choose_steps`` picks each light's step from the
    error it would make in the camera's view.  Raises ValueError for what no rung
    serves (tables below MIN_TABLE_ANISOTROPY).  ``multiple_albedo``: a grey albedo to add a point light's
    multiply scattered glow with (``multiple_rungs``; the node groups' tables, not OSL's quadrature), or None;
    a spot light's with the compositor when its ``cone`` = (cos_half, blend) is given, an area light's with the
    compositor (``spot_multiple_rungs``).  ``multiple_scale``: the share of that field the scene's surfaces
    leave (``escape.field_scales``; 1: unbounded fog).  ``sampled_glow``: a point light's single-scattered glow
    estimated from one uniform number a render sample (``sampled_rungs``: the viewport preview's sampled lights).
    """
    if preference not in PREFERENCES:
        raise ValueError(f"unknown method {preference!r}; use one of {', '.join(PREFERENCES)}")
    if step not in range(len(STEPS)):
        raise ValueError(f"unknown ladder step {step!r}; use 0 to {len(STEPS) - 1}")
    air_table, bg_table, air_quad, bg_quad, scatter = anisotropic_rungs(g)
    if capabilities.can(preference, "quadrature"):
        models = LightModels(air_quad, bg_quad, scatter, DIRECT_EXACT)
    elif g < MIN_TABLE_ANISOTROPY:
        raise ValueError(f"anisotropy {g:g} is below {MIN_TABLE_ANISOTROPY}: the node groups' tables lose accuracy "
                         "with so much back-scattering; use the OSL method (Cycles)")
    else:
        models = LightModels(air_table, bg_table, scatter, DIRECT_EXACT)
    if kind not in LIGHT_KINDS:
        raise ValueError(f"unknown light kind {kind!r}; use one of {', '.join(LIGHT_KINDS)}")
    if sampled_glow:
        if kind != "point":
            raise ValueError(f"a sampled glow is a point light's, not a {kind} light's")
        models = models._replace(**dict(zip(("airlight", "background"), sampled_rungs(g))))
    if kind == "area":
        models = LightModels(*area_rungs(models.scatter, g))
    elif kind == "spot":
        models = models._replace(direct=DIRECT_SPOT, scatter=spot_scatter_rung(models.scatter, g))._replace(
            **dict(zip(("airlight", "background"), spot_rungs(models.airlight, models.background, g, rim_nodes))))
    if _dense_fog(preference, kind, step, multiple_albedo, cone):
        dense = (multiple_rungs(models.airlight, models.background, models.scatter, g, multiple_albedo,
                                multiple_scale)
                 if kind == "point" else spot_multiple_rungs(models.airlight, models.background, models.scatter, g,
                                                             multiple_albedo, cone if kind == "spot" else None,
                                                             multiple_scale))
        models = models._replace(**dict(zip(("airlight", "background", "scatter"), dense)))
    if step >= 1:
        models = models._replace(scatter=SCATTER_OFF)
    if step >= 2:
        models = models._replace(airlight=AIRLIGHT_OFF, background=BACKGROUND_OFF)
    return models   # LEFT_OUT: the models of "off"; the builders leave the light out


def split_halo(models):
    """(models with their glows' single scattering alone, models with the multiply scattered glows alone) of a
    light whose glow rungs carry a halo (``spot_multiple_rungs``), else None.  The compositor evaluates the
    halo, which varies slowly over the picture, at a coarser resolution (``comp_bundles.build_bundle``)."""
    if models.airlight.halo is None or models.background.halo is None:
        return None
    return (models._replace(airlight=models.airlight.single, background=models.background.single),
            models._replace(airlight=models.airlight.halo, background=models.background.halo))


def is_spot(models):
    """True if ``models`` take the spot kernels' arguments: a spot light's or an area light's (``choose``'s kind
    "spot" or "area")."""
    return models.direct.spot


def is_area(models):
    """True if ``models`` are an area light's (``choose``'s kind "area")."""
    return models.direct.area


def needs_osl(models):
    """True if some rung in ``models`` runs only in OSL (Cycles with Open Shading Language on)."""
    return any("nodes" not in r.backends for r in models)


def tables_of(models):
    """The TableSpecs the rungs of ``models`` read (each once)."""
    return tuple(dict.fromkeys(t for r in models for t in r.tables))
