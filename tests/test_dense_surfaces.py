"""Surfaces in dense fog (issue 28): a grey ground and wall around a 1000 W lamp in fog of T = 3 (0.25/m, g 0.85,
albedo 0.9), our render (Compositor) against Cycles' World volume (``fog_scenes/dense_surfaces.py``): Dense Fog
on against 64 volume bounces, off against 0 (single scattering).

Figures (``dense_surfaces.compare``): the whole picture's relative RMSE with the lamp's pixels left out and
each seed's fireflies clipped (to 20x the 5x5 median luminance), the part of it the reference's own noise does
not account for ("excess"), the same over 4x4 block means, and the ratio ours / reference of the mean over the
ground and over the wall.  Issue goal: relative RMSE <= 10 % against the multiple-scattering reference; the
64-bounce reference's per-pixel noise alone is 25 % (4 seeds of 2048 spp), so the goal is held on the excess
and on the block means.  Measured values: docs/measurements/2026-11-27-dense-surfaces.md; the bounds keep a
margin over them.
"""
import pytest

from fog_addon import imageio
from fog_scenes import dense_surfaces as ds

pytestmark = [pytest.mark.render, pytest.mark.slow]

# (volume bounces, Dense Fog) -> upper bounds on: relative RMSE (fireflies clipped), its excess over the
# reference's noise, the 4x4 block means' relative RMSE, |ground ratio - 1|, |wall ratio - 1|.
# Measured against 64 bounces with the ground and the wall absorbing the scattered light (``ds.ABSORBING_TAG``):
# 0.250 (noise 0.247), 0.039, 0.072, 0.107, 0.008 (on / 64: the ground 11 % bright, the light it stops, which Dense
# Fog's scale beside surfaces would take: here the surfaces cast no shadows, the references' convention, so nothing is
# in the photons' way and the scale is 1; docs/measurements/2026-11-30-dense-walls.md);
# 0.069 (noise 0.069), 0.000, 0.020, 0.010, 0.002 (off / 0).  Against the unbounded medium's field (the references
# before 2026-11-30, surfaces hidden from volume-scatter rays) Dense Fog unscaled gave 0.070 and 0.010 on the ground.
BOUNDS = {
    (64, "on"): dict(rel_rmse=0.30, excess=0.10, blocks=0.10, ground=0.15, wall=0.05),
    (0, "off"): dict(rel_rmse=0.09, excess=0.03, blocks=0.03, ground=0.03, wall=0.03),
}


def _case(volume_bounces):
    return next(c for c in ds.REFERENCE_CASES if c[0] == volume_bounces)


@pytest.fixture(scope="module")
def geometry():
    return ds.geometry()


def test_projection(geometry):
    """The lamp's image is the picture's centre column, 34 px from the top; the ground-wall edge below it."""
    lx, ly = geometry["lamp"]
    assert abs(lx - 60.0) < 1e-3 and abs(ly - 34.0) < 1e-3
    m = ds.masks(geometry)
    assert (~m["picture"]).sum() == 16       # the lamp falls on a pixel corner: 4x4 left out
    assert m["ground"].sum() > 1500 and m["wall"].sum() > 5000


@pytest.mark.parametrize("volume_bounces,ms", [(64, "on"), (0, "off")])
def test_surfaces_against_cycles(tmp_path, geometry, volume_bounces, ms, regen):
    seeds = ds.reference_seeds(*_case(volume_bounces), regen=regen)
    log = []
    out = ds.render_ours(tmp_path / "ours.exr", multiple_scattering=ms, log=log)
    assert not ds.h.log_errors(log[0]), ds.h.log_errors(log[0])
    c = ds.compare(imageio.read_rgb(out), seeds, geometry)
    print(f"Dense Fog {ms} vs {volume_bounces} bounces: {c}")
    b = BOUNDS[(volume_bounces, ms)]
    assert c["rel_rmse_clipped"] <= b["rel_rmse"], c
    assert c["excess_clipped"] <= b["excess"], c
    assert c["rel_rmse_blocks"] <= b["blocks"], c
    assert abs(c["ground_ratio"] - 1.0) <= b["ground"], c
    assert abs(c["wall_ratio"] - 1.0) <= b["wall"], c
