"""The World's mean over the sky for the fog layer's sky glow (``sunsky.probe_sky``): a Sky Texture's sun disc is a
sun, not sky, and is left out of the mean (with it a 40-degree sun made the mean 2.6-11 times the sky's:
docs/measurements/2026-11-27-sky-texture.md).  Expected values: the same World rendered by the test with the disc
off (Cycles, the probe's own equirectangular render).  The disc is made 10 degrees wide: the probe's 5.6-degree
pixels and 16 samples see a real 0.5-degree disc by chance, and then it outweighs the whole sky."""
import pytest

from fog_scenes import render_harness as h

pytestmark = pytest.mark.render

_FLOW = r"""
import json, math
import bpy, numpy as np
from fog_addon import sunsky

bpy.ops.wm.read_factory_settings(use_empty=True)
world = bpy.data.worlds.new("Sky")
world.use_nodes = True
nt = world.node_tree
sky = nt.nodes.new("ShaderNodeTexSky")
sky.sun_elevation = math.radians(40.0)
sky.sun_disc = True
sky.sun_size = math.radians(10.0)   # a disc the probe's 64 x 32 pixels always see (a real one, 0.5 deg, by chance)
nt.links.new(sky.outputs["Color"], nt.nodes["Background"].inputs["Color"])

def mean(w):
    p = sunsky._render_equirect(w)
    h = p.shape[0]
    el = (0.5 - (np.arange(h) + 0.5) / h) * math.pi
    wt = np.where(el > 0.0, np.cos(el), 0.0)[:, None]
    return ((p * wt[..., None]).sum(axis=(0, 1)) / (wt.sum() * p.shape[1])).tolist()

R = {"with_disc": mean(world), "probe": list(sunsky.probe_sky(world)), "disc_kept": sky.sun_disc,
     "worlds": len(bpy.data.worlds), "discs": len(sunsky.sun_discs(world))}
sky.sun_disc = False
R["without_disc"] = mean(world)
print(json.dumps(R))
"""


@pytest.fixture(scope="module")
def probe(tmp_path_factory):
    return h.bpy_flow(_FLOW, tmp_path_factory.mktemp("sky_probe"))


def test_sun_disc_is_left_out_of_the_skys_mean(probe):
    """The probe equals the World rendered with its disc off (within the probe's noise), far below the mean with it
    (so the test can fail); the user's World keeps its disc and no copy is left behind."""
    for got, want in zip(probe["probe"], probe["without_disc"]):
        assert got == pytest.approx(want, rel=0.03)
    assert all(d > 2.0 * w for d, w in zip(probe["with_disc"], probe["without_disc"]))
    assert probe["disc_kept"] and probe["discs"] == 1 and probe["worlds"] == 1
