"""A shop window seen from a foggy street (Cycles): the fog against path tracing, with cast shadows and a glass pane.

tests/scenes/shop_window.py builds it: a street, a facade 0.3 m thick with a 2.4 x 1.6 m window opening, a closed
shop behind it with an 80 W lamp and a shelf, a Principled glass pane (Transmission 1, roughness 0, IOR 1.5) hidden
from shadow rays, an 800 W street lamp 5 m high just above the picture's top left corner; fog 0.1 /m, isotropic,
albedo 1.  Every other object casts shadows (Cycles' shadow rays in the reference).  The reference is Cycles'
World volume, single scattering, rendered once per module; the fog is the add-on's (``apply_fog``), 64 spp.  No
lamp is in the picture (the street lamp is just out of it, the shop's is hidden by the lintel), so the lamp mask is
empty.

Measured 2026-11-29 (96x54; reference 2048 spp, 25 s on 2 cores; fog 64 spp, 3.8 s nodes, 4.7 s compositor,
wall times of the whole process; relative RMSE, mean ratio in brackets):

| render | whole frame | inside the pane |
|---|---|---|
| Node Groups | 5.5 % (1.063) | 21.8 % (1.213) |
| Compositor, the fog past the pane without shadows | 3.8 % (1.013) | 19.1 % (1.187) |
| **Compositor, the fog past the pane in its lights' shadows** | **1.8 % (0.998)** | **5.9 % (0.996)** |
| no fog (``none``) | 99.3 % (1.254) | 51.7 % (1.325) |

The reference's own noise (a second seed, difference / sqrt 2): 1.9 % over the frame, 2.7 % in the pane.  The Node
Groups have no light shafts: the shop lamp glows through the facade into the street's fog (the frame about +6 %).
Inside the pane both methods are about 20 % too bright: with the street lamp alone the pane reads 1.37 of path
tracing (compositor), with the shop lamp alone 1.05; with no shadow casters at all (the street lamp alone) the pane
matches, 2.8 % (1.017).  The excess (0.016 of a pane mean of 0.044) is about the street lamp's unshadowed glow along
the shop's fog seen through the pane: the fog past the pane (``glass_tails.place_tails``) has no shadows, so the
street lamp lights the shop's fog through the facade (and the fog's light on the shop's surfaces is unoccluded, as
in the model).  An IOR 1.0 pane changes nothing (1.40), so the pane's refraction is not the cause.  The bounds
below are 1.5 x the measured figures, rounded up to a 0.5 % step.

The Compositor's segments past the pane now take their lights' shadows (``glass_tails.build_tail_bundle``: each tail
to infinity times its own lit share; the fog light of the shop's surfaces times the share their shadows leave), and
its pane comes within 5.9 % (the reference's noise there 2.7 %).  The Node Groups have no shadow maps.
"""
import numpy as np
import pytest

from fog_addon import compare, imageio
from fog_scenes import render_harness as h

pytestmark = pytest.mark.render   # every test here starts Blender (bpy) in a subprocess

SCENE = h.ROOT / "tests" / "scenes" / "shop_window.py"
FRAME_LIMITS = {"nodes": 0.085, "compositor": 0.03}   # measured 5.5 %, 1.8 %
PANE_LIMITS = {"nodes": 0.33, "compositor": 0.09}     # measured 21.8 %, 5.9 %


def _render(mode, out, samples, method="compositor"):
    proc = h.run([SCENE, mode, out, samples, method], timeout=1200)
    masks = np.load(out.with_suffix(".npz"))
    return imageio.read_rgb(out), masks["pane"], masks["lamps"], proc.stdout


@pytest.fixture(scope="module")
def reference(regen):
    """The path-traced picture, its pane mask and its lamp mask: committed (``tests/references``), rendered again
    with ``--regen-references``."""
    path = h.cached_reference("shop_window_96x54_2048spp", lambda out: _render("reference", out, 2048), regen)
    masks = np.load(path.with_suffix(".npz"))
    return imageio.read_rgb(path), masks["pane"], masks["lamps"]


@pytest.mark.parametrize("method", [pytest.param("nodes", marks=pytest.mark.slow(
    reason="no light shafts: the default tier's method here is the Compositor, which casts them")), "compositor"])
def test_shop_window_against_path_tracing(method, tmp_path, reference):
    """Against Cycles' path-traced single scattering with cast shadows: the whole frame (lamp pixels left out)
    within FRAME_LIMITS, the pane within PANE_LIMITS; nothing non-finite."""
    ref, pane, lamps = reference
    fog, _, _, log = _render("fog", tmp_path / "fog.exr", 64, method)
    frame = compare.metrics(fog, ref, mask=~lamps)
    inside = compare.metrics(fog, ref, mask=pane & ~lamps)
    print(method, "frame", frame, "pane", inside)
    print("\n".join(line for line in log.splitlines() if line.startswith("NOTE")))
    assert frame["n_nonfinite"] == 0 and inside["n_nonfinite"] == 0
    assert np.isfinite(fog).all()
    assert frame["rel_rmse"] <= FRAME_LIMITS[method], frame
    assert inside["rel_rmse"] <= PANE_LIMITS[method], inside
