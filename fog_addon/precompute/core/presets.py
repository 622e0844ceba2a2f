"""Fog presets from visibility classes of atmospheric optics, and unit conversions.

Koschmieder's law (1924): meteorological visibility V = ln(1/0.02) / beta
= 3.912 / beta, the distance at which a black object's contrast drops to 2 %.
Visibility classes: haze 5-10 km, mist 1-5 km, fog 0.2-1 km, dense fog < 180 m;
each preset takes a representative visibility inside its class.

Each preset also carries the Henyey-Greenstein asymmetry g of its particles at visible wavelengths
(the mean cosine of the scattering angle, from Mie theory): continental haze aerosol (sub-micron
particles) g = 0.6-0.75 (Hess, Koepke, Schult 1998, OPAC; d'Almeida et al. 1991), 0.7 here; mist of
small droplets about 0.8; fog droplets (radii 2-20 um) g = 0.8-0.9 (Deirmendjian 1969's fog models;
Hale and Querry 1973 water), 0.85 here.

Layered presets (``LAYERED``) are fog with a top: the density is constant up to ``fog_top`` metres above
the ground and falls as e^{-(h - top) / H} above it (H = ``height_falloff``; ``daylight.py``); ``air`` adds clear
air's Rayleigh scattering as a multiple of sea-level air (``spec.py``; 0 in the fogs, whose droplets outshine it).
Depths, visibilities and tops below are typical values of each kind of fog, not measurements of one:

* Valley Fog: radiation fog, formed under a ground inversion on clear calm nights and pooled in valleys
  (Gultepe et al. 2007, "Fog research: a review of past achievements and future perspectives", Pure Appl.
  Geophys. 164): typically tens of metres to about 200 m deep, visibility 100-500 m (fog is visibility below
  1 km, WMO).  Here visibility 200 m, a top at 100 m, softened over H = 10 m (the inversion keeps the top
  sharp), fog droplets' g = 0.85 (above), white (water droplets hardly absorb).
* Summer Haze: aerosol mixed through the daytime convective boundary layer, typically 1-2 km deep over land
  in summer (Stull 1988, An Introduction to Boundary Layer Meteorology, chapter 1), visibility typically
  10-20 km.  Above it the aerosol thins with a scale height of 1.2 km (Dobashi et al. 2002 appendix A.1;
  Bruneton & Neyret 2008 section 2.1, H_M = 1.2 km).  Here visibility 15 km, a top at 1.5 km, H = 1.2 km,
  g = 0.7 (continental aerosol, the haze preset's), albedo 0.9 (Bruneton & Neyret 2008: aerosol extinction
  = scattering / 0.9), and a summer day's clear air above and in the haze: air 1, the standard atmosphere
  (Bruneton & Neyret 2008 section 2.1: beta_R = (5.8, 13.5, 33.1) x 10^-6 1/m, scale height 8 km).
* Sea Mist: advection fog over a cold sea, held in the marine layer under its inversion, typically
  100-400 m deep (Koracin et al. 2014, "Marine fog: a review", Atmos. Res. 143), visibility about 1 km (the
  fog/mist boundary).  Here visibility 1 km, a top at 300 m softened over H = 30 m, g = 0.8 (the mist
  preset's), white.
* Clear Day: the thin aerosol haze of a clear day, densest at the ground and thinning with the aerosol's scale
  height 1.2 km (Bruneton & Neyret 2008 section 2.1: H_M = 1.2 km, Mie g = 0.76, albedo 0.9), under the
  standard atmosphere's clear air (air 1, as Summer Haze).  A clear day's visibility is 20-50 km ("very
  clear" in the international visibility code the WMO adopted; Koschmieder's law above).  Here the aerosol's
  visibility 40 km, a top at 0 m (the haze falls off from the ground), H = 1.2 km, g = 0.76, albedo 0.9,
  air 1 (clear air alone would limit the visibility to 3.912 / 13.5e-6 = 290 km at 550 nm; with it 35 km).
"""
import math

KOSCHMIEDER = -math.log(0.02)   # 3.912
MAX_DENSITY = 100.0             # 1/m: a visibility of 3.9 cm; beyond this the fog is a wall
MIN_VISIBILITY_M = KOSCHMIEDER / MAX_DENSITY
VISIBLE_DEPTH = 0.01            # optical depth below which a fog changes the picture by < 1 %

VISIBILITY_M = {
    "haze": 8000.0,
    "mist": 2000.0,
    "fog": 500.0,
    "dense_fog": 150.0,
}


def density_from_visibility(visibility_m):
    """Extinction coefficient beta (1/m) for a meteorological visibility in m (Koschmieder)."""
    return KOSCHMIEDER / visibility_m


def visibility_from_density(beta):
    """Meteorological visibility (m) for an extinction coefficient beta (1/m); inf for beta = 0."""
    return math.inf if beta == 0 else KOSCHMIEDER / beta


PRESETS = {name: density_from_visibility(v) for name, v in VISIBILITY_M.items()}
ANISOTROPY = {"haze": 0.7, "mist": 0.8, "fog": 0.85, "dense_fog": 0.85}   # Henyey-Greenstein g (docstring)


def _layer(visibility_m, anisotropy, albedo, fog_top_m, height_falloff_m, air=0.0):
    """A layered preset: density (1/m) from its visibility, g, RGB albedo, top and falloff (m), and the clear
    air's density (a multiple of sea-level air, ``spec.py``)."""
    return dict(density=density_from_visibility(visibility_m), anisotropy=anisotropy, albedo=(albedo,) * 3,
                fog_top=fog_top_m, height_falloff=height_falloff_m, air=air)


LAYERED = {   # fog with a top over the ground (docstring: the kinds of fog and their sources)
    "valley_fog": _layer(200.0, 0.85, 1.0, 100.0, 10.0),
    "summer_haze": _layer(15000.0, 0.7, 0.9, 1500.0, 1200.0, air=1.0),
    "sea_mist": _layer(1000.0, 0.8, 1.0, 300.0, 30.0),
    "clear_day": _layer(40000.0, 0.76, 0.9, 0.0, 1200.0, air=1.0),
}


def validate_density(beta):
    """Return beta as a float, or raise ValueError with a message a user understands."""
    try:
        beta = float(beta)
    except (TypeError, ValueError):
        raise ValueError(f"fog density must be a number in 1/m, got {beta!r}") from None
    if math.isnan(beta):
        raise ValueError(f"fog density must be finite, got {beta}")
    if beta < 0:
        raise ValueError(f"fog density must be >= 0 (1/m; a visibility above 0 m), got {beta:g}")
    if math.isinf(beta) or beta >= 1e38:
        raise ValueError(f"fog density must be finite (a visibility above 0 m); the largest supported density is "
                         f"{MAX_DENSITY:g} 1/m, a visibility of {MIN_VISIBILITY_M * 100:.2g} cm")
    if beta > MAX_DENSITY:
        raise ValueError(f"fog density {beta:g} 1/m means a visibility of {KOSCHMIEDER / beta * 100:.2g} cm; "
                         f"the largest supported density is {MAX_DENSITY:g} 1/m (a visibility of "
                         f"{MIN_VISIBILITY_M * 100:.2g} cm)")
    return beta


OPAQUE_DEPTH = 10.0   # optical depth beyond which a surface is hidden (e^-10: 4.5e-5 of its light comes through)


def opaque_fog_note(beta, nearest_m):
    """A message if fog of ``beta`` (1/m) hides every object, the nearest ``nearest_m`` metres from the camera
    (more than OPAQUE_DEPTH optical depths away), else None."""
    depth = beta * nearest_m
    if not nearest_m > 0.0 or depth <= OPAQUE_DEPTH:
        return None
    return (f"The fog is opaque here: the nearest object is {nearest_m:.3g} m from the camera, {depth:.3g} optical "
            f"depths (visibility {visibility_from_density(beta):.3g} m), so the camera sees only the fog's own light. "
            "Lower the density, or set Scene Scale to the real metres per Blender unit")


def invisible_fog_note(beta, size_m):
    """A message if fog of ``beta`` (1/m) can't be seen across a scene ``size_m`` metres deep, else None.

    Optical depth beta * size below VISIBLE_DEPTH dims and glows by under 1 %.
    """
    depth = beta * size_m
    if size_m <= 0 or depth >= VISIBLE_DEPTH:
        return None
    return (f"This fog is invisible here: optical depth {depth:.2g} across the scene's {size_m:.3g} m "
            f"(visibility {visibility_from_density(beta):.3g} m). Raise the density, or set Scene Scale "
            f"to the real metres per Blender unit")
