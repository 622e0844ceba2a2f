"""The fog's settings as one validated value: :class:`FogSpec`.

Every decision the add-on makes (which method, which models, which passes, what the groups hold) reads
a ``FogSpec``.  It is built from the scene's ``scene.analytic_fog`` (``FogSpec.from_settings``), or from
the command line's flags over it (``FogSpec.replace``); nothing reads a setting back out of a node group.
The node groups hold a copy (``to_json``) so that a farm without the add-on, or a person reading the
file, can see what the fog was built with.

Units, stated once:

* ``density``: the extinction coefficient beta of the fog in 1/m of the real world (Sun et al. 2005
  section 3: extinction = scattering, no absorption); Koschmieder's visibility is 3.912 / beta.
* ``scene_scale``: real metres per Blender unit, so the shaders' beta is ``beta_per_unit`` =
  density x scene_scale (1/unit).
* ``albedo``: the single-scattering albedo per RGB channel, in [0, 1] (the fog's colour).
* ``anisotropy``: the Henyey-Greenstein g of the phase function, in [-MAX_ANISOTROPY, MAX_ANISOTROPY].
* ``method``: "auto" (``fog_addon/methods/auto.py`` picks per scene), or a method of
  ``METHODS``: "nodes", "osl", "compositor".
* ``quality``: a Quality preset name of ``QUALITY`` ("draft", "final", "exact") or a target
  relative error in (0, 1).
* ``passes``: write the Fog Light and Fog Transmittance render passes.
* ``world_light``: the World keeps lighting surfaces through the fog (an artistic ambient).
* ``shafts``: objects cast shadows into the fog (light shafts, ``shafts.py``), where a light needs them.
* ``fog_top``: the height of the fog layer's top above the ground, real metres (``daylight.py``: the density is
  ``density`` up to it); None for fog that fills all space (the night scenes' default).
* ``height_falloff``: above the top the density falls as e^{-(h - top) / H}, H in real metres; 0 is a hard top.
* ``ground_level``: the ground's z in Blender units (heights are measured from it).
* ``air``: the density of clear air (molecular Rayleigh scattering) as a multiple of sea-level clear air, in
  [0, MAX_AIR]: 1 is the standard atmosphere (Bruneton & Neyret 2008 section 2.1: beta_R = ``medium.RAYLEIGH_RGB``
  1/m at 680, 550, 440 nm at the ground, falling with the scale height ``medium.RAYLEIGH_HEIGHT`` = 8 km), which
  blues and greys the distance of a daylight scene; 0 is none.  It acts only in a layered fog (with a top):
  ``air_per_unit`` is None without one.

"""
import dataclasses
import json
import math

from . import medium, presets
from .medium import RAYLEIGH_HEIGHT, RAYLEIGH_RGB

METHODS = ("nodes", "osl", "compositor")   # the methods a user can pick besides "auto" (``fog_addon/methods``)
AUTO = "auto"
DEFAULT_METHOD = AUTO
MAX_AIR = 100.0   # clear air's density as a multiple of sea level's: beyond this it is no longer air but a wall


def validate_method(method):
    """``method`` lower-cased if it is "auto" or one of METHODS, else ValueError with the choices."""
    m = str(method).lower()
    if m != AUTO and m not in METHODS:
        raise ValueError(f"unknown method {method!r}; use one of {', '.join((AUTO,) + METHODS)}")
    return m


def _finite(value, what):
    """``value`` as a finite float, or ValueError naming ``what``."""
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{what} must be a number, got {value!r}") from None
    if not math.isfinite(v):
        raise ValueError(f"{what} must be finite, got {v}")
    return v


def validate_top(top):
    """The fog layer's top in metres above the ground (>= 0), or None (fog that fills all space)."""
    if top is None:
        return None
    v = _finite(top, "the fog's top (metres above the ground)")
    if v < 0.0:
        raise ValueError(f"the fog's top must be at or above the ground (>= 0 m), got {v}")
    return v


def validate_falloff(falloff):
    """The height falloff H in metres (>= 0; 0 is a hard top)."""
    v = _finite(falloff, "the height falloff (metres)")
    if v < 0.0:
        raise ValueError(f"the height falloff must be >= 0 m (0 is a hard top), got {v}")
    return v


def validate_air(air):
    """The clear air's density as a multiple of sea-level clear air (0 <= air <= MAX_AIR; 1 the standard one)."""
    v = _finite(air, "the clear air's density (a multiple of sea-level air)")
    if v < 0.0:
        raise ValueError(f"the clear air's density must be >= 0 (0 is no air, 1 is sea-level air), got {v}")
    if v > MAX_AIR:
        raise ValueError(f"the clear air's density must be at most {MAX_AIR:g} times sea-level air "
                         f"(1 is the standard atmosphere), got {v:g}")
    return v


def validate_quality(quality):
    """The stored form of a Quality: a preset name ("draft", "final", "exact") or a float; raises ValueError."""
    if quality is None:
        return "exact"
    if isinstance(quality, str):
        q = quality.strip().lower()
        target_error(q)
        return q
    target_error(quality)
    return float(quality)


QUALITY = {"draft": 0.05, "final": 0.01, "exact": None}   # Quality presets: target relative error (None: no step)
DEFAULT_QUALITY = "final"


def target_error(quality):
    """Target relative error from a Quality preset name or a number (None or "exact": no step taken)."""
    if quality is None:
        return None
    if isinstance(quality, str):
        key = quality.strip().lower()
        if key not in QUALITY:
            raise ValueError(f"unknown quality {quality!r}: use {', '.join(QUALITY)} or a relative error "
                             "such as 0.01")
        return QUALITY[key]
    value = float(quality)
    if not (math.isfinite(value) and 0.0 < value < 1.0):
        raise ValueError(f"the target error must be a fraction in (0, 1), such as 0.01 for 1 %, got {quality!r}")
    return value

@dataclasses.dataclass(frozen=True)
class FogSpec:
    """The fog's settings (units: module docstring); construct with :func:`spec` or ``FogSpec(...).validated()``."""
    density: float = presets.PRESETS["fog"]
    scene_scale: float = 1.0
    albedo: tuple = (1.0, 1.0, 1.0)
    anisotropy: float = 0.0
    method: str = DEFAULT_METHOD
    quality: object = DEFAULT_QUALITY
    passes: bool = False
    world_light: bool = False
    shafts: bool = True
    multiple_scattering: bool = True
    fog_top: object = None
    height_falloff: float = 0.0
    ground_level: float = 0.0
    air: float = 0.0

    @property
    def beta_per_unit(self):
        """The shaders' extinction coefficient, 1/(Blender unit): density x scene_scale."""
        return self.density * self.scene_scale

    @property
    def grey_albedo(self):
        """The albedo the multiply scattered glow is modelled with (``multiple.py``): the channels' mean."""
        return sum(self.albedo) / 3.0

    @property
    def multiple_albedo(self):
        """``rungs.choose``'s multiple_albedo: the grey albedo with multiple scattering on, else None."""
        return self.grey_albedo if self.multiple_scattering else None

    @property
    def layered(self):
        """The fog has a top (a layer over the ground, ``daylight.py``) rather than filling all space."""
        return self.fog_top is not None

    def layer_per_unit(self):
        """(top, falloff, ground) of the layer in Blender units (heights above ``ground_level``), or None for fog
        that fills all space."""
        if self.fog_top is None:
            return None
        return (self.fog_top / self.scene_scale, self.height_falloff / self.scene_scale, self.ground_level)

    def air_per_unit(self):
        """(rgb, height) of the clear air's Rayleigh scattering, or None without air or without a top (the air acts
        only in a layered fog): rgb the scattering coefficients at the ground, 1/(Blender unit), RAYLEIGH_RGB x air
        x scene_scale; height its scale height RAYLEIGH_HEIGHT / scene_scale, Blender units (Bruneton & Neyret
        2008 section 2.1)."""
        if not self.layered or self.air <= 0.0:
            return None
        rgb = tuple(beta * self.air * self.scene_scale for beta in RAYLEIGH_RGB)
        return rgb, RAYLEIGH_HEIGHT / self.scene_scale

    @property
    def target_error(self):
        """The Quality as a target relative error, None for Exact (``target_error``)."""
        return target_error(self.quality)

    def validated(self):
        """This spec with every field checked and normalised; raises ValueError with a message a user understands."""
        fog = medium.medium(self.density, self.albedo, self.anisotropy, self.scene_scale)
        return dataclasses.replace(
            self, density=presets.validate_density(self.density), scene_scale=float(self.scene_scale),
            albedo=tuple(float(a) for a in fog.albedo), anisotropy=fog.g, method=validate_method(self.method),
            quality=validate_quality(self.quality), passes=bool(self.passes), world_light=bool(self.world_light),
            shafts=bool(self.shafts), multiple_scattering=bool(self.multiple_scattering),
            fog_top=validate_top(self.fog_top), height_falloff=validate_falloff(self.height_falloff),
            ground_level=_finite(self.ground_level, "the ground level (z, Blender units)"), air=validate_air(self.air))

    def replace(self, **changes):
        """A validated copy with ``changes`` (None values keep this spec's: the command line's unset flags)."""
        return dataclasses.replace(self, **{k: v for k, v in changes.items() if v is not None}).validated()

    def to_json(self):
        return json.dumps(dataclasses.asdict(self), sort_keys=True)

    @classmethod
    def from_json(cls, text):
        data = json.loads(text)
        data["albedo"] = tuple(data["albedo"])
        return cls(**{f.name: data[f.name] for f in dataclasses.fields(cls) if f.name in data}).validated()

    @classmethod
    def from_settings(cls, settings):
        """The spec of a ``scene.analytic_fog`` (``props.AnalyticFogSettings``, or anything with its fields)."""
        quality = settings.target_error if settings.quality == "CUSTOM" else settings.quality.lower()
        return cls(density=settings.density, scene_scale=settings.scene_scale, albedo=tuple(settings.color),
                   anisotropy=settings.anisotropy, method=settings.method.lower(), quality=quality,
                   passes=settings.use_passes, world_light=settings.world_light,
                   shafts=getattr(settings, "use_shafts", True),
                   multiple_scattering=getattr(settings, "use_multiple_scattering", True),
                   fog_top=settings.fog_top if getattr(settings, "use_fog_top", False) else None,
                   height_falloff=getattr(settings, "height_falloff", 0.0),
                   ground_level=getattr(settings, "ground_level", 0.0),
                   air=getattr(settings, "air_density", 0.0)).validated()

    def settings_values(self):
        """{property: value} that store this spec in a ``scene.analytic_fog`` (the inverse of ``from_settings``)."""
        values = dict(density=self.density, scene_scale=self.scene_scale, color=self.albedo,
                      anisotropy=self.anisotropy, method=self.method.upper(), use_passes=self.passes,
                      world_light=self.world_light, use_shafts=self.shafts,
                      use_multiple_scattering=self.multiple_scattering, use_fog_top=self.fog_top is not None,
                      height_falloff=self.height_falloff, ground_level=self.ground_level, air_density=self.air)
        if self.fog_top is not None:
            values["fog_top"] = self.fog_top
        if isinstance(self.quality, str):
            values["quality"] = self.quality.upper()
        else:
            values.update(quality="CUSTOM", target_error=self.quality)
        return values


def spec(**fields):
    """A validated FogSpec (keyword fields as in :class:`FogSpec`); raises ValueError for bad input."""
    return FogSpec(**fields).validated()
