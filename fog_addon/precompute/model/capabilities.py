"""What each method models in each render engine: the one table of capabilities.

Every "only the compositor does X" in the add-on reads this table: Auto's choice and its reasons
(``methods/auto.py``), the notes of the panel, the operator's report and ``render`` (``caveats.py``,
``sunsky.py``, ``ops/report.py``), the models' ladder (``rungs.choose``) and the README's table "What each
engine supports" (``readme_table``; tests/test_capabilities.py holds the README to it).  Adding a method is
a column here; moving a feature to another method is a cell.

A cell is (models, text): ``models`` True where the method models the feature in that engine, ``text`` what
the README says there.  Features without a README row (``Feature.readme`` False) are behaviour the notes
need, such as where the sun's glow is evaluated once per pixel.  Pure data: no Blender.
"""
from typing import NamedTuple, Tuple

CYCLES, EEVEE = "CYCLES", "BLENDER_EEVEE"
COLUMNS = (("nodes", CYCLES), ("osl", CYCLES), ("compositor", CYCLES), ("nodes", EEVEE), ("compositor", EEVEE))
HEADERS = ("Cycles, node groups", "Cycles, OSL", "Cycles, compositor", "EEVEE, node groups", "EEVEE, compositor")
LABELS = {"nodes": "Node Groups", "osl": "OSL", "compositor": "Compositor"}
NO, YES = "—", "✓"


class Feature(NamedTuple):
    key: str
    label: str                            # the README's row; the notes' name of the feature
    cells: Tuple[Tuple[bool, str], ...]   # by COLUMNS
    readme: bool = True


def _row(key, label, *cells, readme=True):
    return Feature(key, label, tuple((c, YES) if isinstance(c, bool) and c else (False, NO) if c is False
                                     else c for c in cells), readme)


FEATURES = (
    _row("glows", "glows, background through fog", (True, "✓ (tables)"), (True, "✓ (quadrature)"),
         (True, "✓ (tables, once per pixel)"), (True, "✓ (tables)"), (True, "✓ (tables, once per pixel)")),
    _row("dimming", "direct light dimmed by the fog", (True, "exact per light, shadows kept"), (True, "same"),
         (True, "same"), (True, "average over lights, weighted by the light each reflects"),
         (True, "same as EEVEE's node groups")),
    _row("fog_light", "fog light on diffuse / glossy surfaces", True, True,
         (True, "✓ (at the pixel's mean surface point)"), True, (True, "✓ (at the point the pixel's centre sees)")),
    _row("strong_backscatter", "anisotropic fog (g)", (False, "g ≥ −0.8"), (True, "−0.95 to 0.95"),
         (False, "g ≥ −0.8"), (False, "g ≥ −0.8"), (False, "g ≥ −0.8")),
    _row("spots", "spot lights", True, True, True, (True, "✓ (about 4 fully modelled)"), (True, "✓ (any number)")),
    _row("areas", "area lights", True, True, True, (True, "✓ (as many as spots)"), (True, "✓ (any number)")),
    _row("dense_point", "Dense Fog around point lights and glowing objects", True, False, True, True, True),
    _row("dense_shaped", "Dense Fog around spot and area lights", False, False, True, False, True),
    _row("emitters", "glowing objects' glow", False, False, True, False, True),
    _row("daylight", "a fog layer: the sun and the sky", (True, "✓ (every sample)"), (True, "✓ (every sample)"),
         (True, "✓ (once per pixel)"), (True, "✓ (every sample)"), (True, "✓ (once per pixel)")),
    _row("layer_ends", "a fog layer: lamps' glows end at its top", (False, "— (lamps glow above it)"),
         (False, "— (same)"), True, (False, "— (lamps glow above it)"), True),
    _row("air_colour", "the air's colour in the distance", (False, "grey (a shader's factor is one number)"),
         (False, "same"), (True, "✓ (blue)"), (False, "grey"), (True, "✓ (blue)")),
    _row("viewport", "live viewport", (True, "rendered view"), (True, "rendered view"),
         (True, "rendered view: a preview (two lights with their shafts, or every lamp sampled)"),
         (True, "material preview and rendered view"), (True, "both views: a preview (no shafts)")),
    _row("many_lights", "lights fully modelled per material",
         (True, "any (cost grows with the square of the lights)"), (True, "any"),
         (True, "any (cost grows with pixels × lights)"), (False, "about 20 in a saved file"), (True, "any")),
    _row("shafts", "light shafts (shadows in the fog), the sun's too", False, False, True, False, True),
    _row("glass", "fog behind glass and in sharp mirrors",
         (True, "✓ (Glass, Refraction and Principled glass, straight through; sharp mirrors)"), False,
         (True, "✓ (the same, of the 8 brightest lights)"), False, False),
    _row("passes", "fog passes", True, (False, "black"), (True, "✓ (a multilayer EXR the compositor writes)"), True,
         (True, "✓ (a multilayer EXR the compositor writes)")),
    _row("denoiser", "denoiser kept off the fog's light", True, True,
         (True, "✓ (the fog is added after the denoiser)"), (False, "— (no denoiser)"), (False, "—")),
    _row("panoramic", "cameras", (True, "perspective, panoramic"), (True, "same"),
         (True, "perspective, panoramic (no glowing objects' glow)"), (True, "perspective, panoramic"),
         (False, "perspective")),
    _row("quadrature", "the glow by quadrature (OSL), not the tables", False, True, False, False, False, readme=False),
    _row("daylight_once", "the sun's and the sky's glow and fog light evaluated once per pixel", False, False, True,
         False, True, readme=False),
    _row("per_pixel_lights", "lights evaluated once per pixel, not per sample", False, False, True, False, True,
         readme=False),
    _row("animated_sky", "an animated World's glow followed on every frame", False, False, True, False, True,
         readme=False),
    _row("depth_pass", "the fog's light from the depth pass (the sky's where EEVEE's depth fails)", False, False, True,
         False, True, readme=False),
)
BY_KEY = {f.key: f for f in FEATURES}


def _cell(method, feature, engine):
    try:
        return BY_KEY[feature].cells[COLUMNS.index((method, engine))]
    except ValueError:
        return (False, NO)   # the method does not run in that engine (OSL in EEVEE)


def runs(method, engine):
    """True if ``method`` renders in ``engine`` at all (a column of the table)."""
    return (method, engine) in COLUMNS


ENGINE_LABELS = {CYCLES: "Cycles", EEVEE: "EEVEE"}


def engines_of(method):
    """The engines ``method`` renders in, as the panel names them ("Cycles", "EEVEE")."""
    return [HEADERS[k].split(",")[0] for k, (m, _) in enumerate(COLUMNS) if m == method]


def can(method, feature, engine=CYCLES):
    """True if ``method`` ("nodes", "osl", "compositor") models ``feature`` (a key of FEATURES) in ``engine``."""
    return _cell(method, feature, engine)[0]


def methods_with(feature, engine=CYCLES):
    """The methods that model ``feature`` in ``engine``, in COLUMNS' order."""
    return [m for m, e in COLUMNS if e == engine and can(m, feature, engine)]


def only(feature, engine=CYCLES):
    """The one method that models ``feature`` in ``engine``, or None (none or several do)."""
    names = methods_with(feature, engine)
    return names[0] if len(names) == 1 else None


def suggestion(feature, engine=CYCLES):
    """A phrase naming the methods that model ``feature`` in ``engine``: "Method Compositor (Auto's choice)"."""
    names = methods_with(feature, engine)
    if not names:
        return "no method"
    listed = " or ".join(f"Method {LABELS[m]}" for m in names)
    return f"{listed} (or Auto)"


def readme_table():
    """The README's table "What each engine supports", as Markdown (the features with ``readme``)."""
    lines = ["| | " + " | ".join(HEADERS) + " |", "|---" * (len(HEADERS) + 1) + "|"]
    lines += [f"| {f.label} | " + " | ".join(text for _, text in f.cells) + " |" for f in FEATURES if f.readme]
    return "\n".join(lines)
