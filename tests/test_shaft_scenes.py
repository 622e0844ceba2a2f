"""Light shafts in issue 27's kinds of scene against Cycles path tracing with cast shadows: a room lit through
two windows, a colonnade, a lamp under a hood with a spot behind a hole, a fence and a thin pole, and the open
street whose posts shadow the lamps (fog_scenes/shafts.py: the cases, their references and their noise).  Each
render also shows no regular pattern of the interleaved shares (``shafts.interleave_excess``: the difference from
the reference at the patterns' frequencies, over its noise).

Cycles, Method Compositor, 16 spp, default Quality, 128x72; relative RMSE with the 3x3 pixels of each lamp the
camera sees left out (``lamp_pixel_mask``, as the issue allows).  The issue's goals are 5 % (shadowed scenes)
and 3 % (the open street); each bound here is the measured figure with a margin
(docs/measurements/2026-11-26-light-shafts.md), so that a regression fails while the goal stays documented.
The window room runs in the default tier (the hardest case: walls lit only by the beams' fog); the rest are
slow.  ``--regen`` renders the references again (minutes each: SHAFT_SAMPLES).
"""
import re

import numpy as np
import pytest

from fog_addon import compare, imageio
from fog_scenes import render_harness as h
from fog_scenes import shafts as fs

pytestmark = pytest.mark.render

# measured (2026-11-30, a spot's nodes within its cone): window room 4.38 %, colonnade 1.22 %, hooded lamp 2.47 %,
# fence 1.51 % (2026-11-26: 5.00, 1.97, 2.73, 1.49 %), street 0.62 %, pergola 1.51 % (before the cone: 1.75 %),
# stairwell 0.55 % (0.65 % before a surface's rays were weighed as passing the light no nearer than NEAREST_RAY),
# forest 0.76 % (0.74 %), bus shelter 1.01 % (0.99 %); the softbox colonnade (an area light, 2026-12-01) 2.07 %
# (14.9 % with no shafts of area lights, 4.2 % with a point light's weights in its shares)
BOUND = {"window_room": 0.049, "colonnade": 0.015, "hooded_lamp": 0.029, "fence": 0.018, "street_lamps": 0.008,
         "pergola": 0.018, "stairwell": 0.0075, "forest": 0.0095, "bus_shelter": 0.0125, "softbox_colonnade": 0.025}
GOAL = {"street_lamps": 0.03}   # the open street: 3 %; the shadowed scenes: 5 %
DEFAULT_TIER = {"window_room"}
CASES = [c if c[0] in DEFAULT_TIER else pytest.param(*c, marks=pytest.mark.slow)
         for c in fs.SHAFT_CASES + fs.OPEN_CASES]


@pytest.mark.parametrize("scene,density,anisotropy", CASES, ids=[c[0] for c in fs.SHAFT_CASES + fs.OPEN_CASES])
def test_shaft_scene_against_path_tracing(tmp_path, regen, scene, density, anisotropy):
    ref = fs.ensure_shaft_reference(scene, density, regen=regen, anisotropy=anisotropy)
    log = []
    out = h.render_test(scene, density, tmp_path / f"{scene}.exr", engine="cycles", method="compositor",
                        samples=16, resolution=fs.SHAFT_RESOLUTION, cast_shadows=True, log=log,
                        extra=["--shafts", "on"])
    assert not h.log_errors(log[0]), h.log_errors(log[0])
    assert "light shafts are not modelled" not in log[0]
    assert np.isfinite(imageio.read_rgb(out)).all()
    m = h.assert_close(out, ref, name=f"shafts_{scene}", rel_rmse=BOUND[scene],
                       mask=fs.lamp_pixel_mask(scene, fs.SHAFT_RESOLUTION))
    print(f"{scene}: relative RMSE {m['rel_rmse']:.4f} (bound {BOUND[scene]}, goal {GOAL.get(scene, 0.05)})")
    assert BOUND[scene] <= GOAL.get(scene, 0.05) * 1.15   # a bound is never far past the goal
    # no interleaving pattern left (issue 46: "structured grain on lit column faces and walls")
    grain = fs.interleave_excess(imageio.read_rgb(out), imageio.read_rgb(ref),
                                 fs.lamp_pixel_mask(scene, fs.SHAFT_RESOLUTION))
    print(f"{scene}: the interleaving pattern's excess {grain:.2f} (bound {fs.GRAIN_BOUND})")
    assert grain <= fs.GRAIN_BOUND, grain


# Measured (2026-11-29), Light Shafts off, relative RMSE against path tracing / the shadows' predicted share: window
# room 180 % / 317 %, colonnade 19 % / 237 %, hooded lamp 83 % / 307 %, fence 4.6 % / 86 %, street 2.1 % / 21 %.
SHAFTS_OFF_CASES = [c if c[0] in DEFAULT_TIER else pytest.param(*c, marks=pytest.mark.slow)
                    for c in fs.SHAFT_CASES + fs.OPEN_CASES]


@pytest.mark.parametrize("scene,density,anisotropy", SHAFTS_OFF_CASES,
                         ids=[c[0] for c in fs.SHAFT_CASES + fs.OPEN_CASES])
def test_shafts_off_predicts_what_the_shadows_take(tmp_path, regen, scene, density, anisotropy):
    """With Light Shafts off the picture lacks the shadows in the fog: the predicted error counts them (issue 46:
    it said 0.00 %), at least half the measured relative RMSE against path tracing with shadows, and the note
    says their share."""
    ref = fs.ensure_shaft_reference(scene, density, regen=regen, anisotropy=anisotropy)
    log = []
    out = h.render_test(scene, density, tmp_path / f"{scene}.exr", engine="cycles", method="compositor",
                        samples=16, resolution=fs.SHAFT_RESOLUTION, cast_shadows=True, log=log,
                        extra=["--shafts", "off", "--explain"])
    found = re.search(r"shadows in the fog left out of \d+ light\(s\) \(.*\): up to ([0-9.]+)% of a pixel's fog",
                      log[0])
    assert found, log[0][-3000:]
    predicted = float(found.group(1)) / 100.0
    note = re.search(r"light shafts are not modelled \(Light Shafts is off\).*up to ([0-9]+)% of a pixel's fog",
                     log[0])
    assert note and abs(float(note.group(1)) / 100.0 - predicted) <= 0.006, log[0][-3000:]
    total = float(re.search(r"predicted error ([0-9.]+)%", log[0]).group(1)) / 100.0
    assert total >= predicted - 1e-4, (total, predicted)   # (in the predicted error)
    measured = compare.metrics(imageio.read_rgb(out), imageio.read_rgb(ref),
                               mask=fs.lamp_pixel_mask(scene, fs.SHAFT_RESOLUTION))["rel_rmse"]
    print(f"{scene}, shafts off: measured {measured:.3f}, the shadows' predicted share {predicted:.3f}")
    assert predicted >= 0.5 * measured, (predicted, measured)


# A picture whose shorter side has comp_shafts.HALF_FROM pixels or more takes the shafts' shares (the glows' and the
# surfaces') at half its resolution, from comp_shafts.QUARTER_FROM at a quarter.  At k times the references' size
# (k = 2, 4), k x k pixels averaged are one reference pixel: the shares then have as many samples over each patch
# of the scene as the references' own resolution gives them.  Averaging pixel centres is not a pixel centre where
# the picture changes within a pixel (glow peaks, edges, thin slats), so the check keeps the pixels where the
# reference itself is smooth (SMOOTH: its 3 x 3 neighbours within 10 %).
SMOOTH = 0.1
# measured (2026-11-28) on those pixels, at k = 2 (256 x 144) and k = 4 (512 x 288): window room 3.63 % and 3.63 %
# (full resolution at 128 x 72: 3.67 %), colonnade 2.39 % and 2.25 % (2.20 %), hooded lamp 2.51 % and 2.41 % (2.58 %)
HALF_BOUND = {"window_room": 0.040, "colonnade": 0.027, "hooded_lamp": 0.028}
HALF_CASES = [pytest.param(*c, k, marks=() if (c[0] in DEFAULT_TIER and k == 2) else pytest.mark.slow,
                           id=f"{c[0]}-{k}") for k in (2, 4) for c in fs.SHAFT_CASES if c[0] in HALF_BOUND]


def smooth_pixels(image, tol=SMOOTH):
    """True where every one of a pixel's 3 x 3 neighbours is within ``tol`` of its grey value."""
    y = image.mean(axis=2)
    p = np.pad(y, 1, mode="edge")
    dev = np.max([np.abs(p[1 + dy:1 + dy + y.shape[0], 1 + dx:1 + dx + y.shape[1]] - y)
                  for dy in (-1, 0, 1) for dx in (-1, 0, 1)], axis=0)
    return dev <= tol * y + 1e-4


@pytest.mark.parametrize("scene,density,anisotropy,k", HALF_CASES)
def test_shares_at_half_resolution_against_path_tracing(tmp_path, regen, scene, density, anisotropy, k):
    from fog_addon.nodes import comp_shafts
    resolution = (fs.SHAFT_RESOLUTION[0] * k, fs.SHAFT_RESOLUTION[1] * k)
    assert min(fs.SHAFT_RESOLUTION) < comp_shafts.HALF_FROM   # the references' size keeps full resolution
    assert {2: comp_shafts.HALF_FROM <= min(resolution) < comp_shafts.QUARTER_FROM,
            4: comp_shafts.QUARTER_FROM <= min(resolution)}[k]   # this render takes a sample every k x k pixels
    ref = imageio.read_rgb(fs.ensure_shaft_reference(scene, density, regen=regen, anisotropy=anisotropy))
    log = []
    out = h.render_test(scene, density, tmp_path / f"{scene}_{k}.exr", engine="cycles", method="compositor",
                        samples=16, resolution=resolution, cast_shadows=True, log=log, extra=["--shafts", "on"])
    assert not h.log_errors(log[0]), h.log_errors(log[0])
    img = imageio.read_rgb(out)
    assert np.isfinite(img).all()
    pooled = sum(img[i::k, j::k] for i in range(k) for j in range(k)) / (k * k)
    mask = fs.lamp_pixel_mask(scene, fs.SHAFT_RESOLUTION) & smooth_pixels(ref)
    m = compare.metrics(pooled, ref, mask=mask)
    print(f"{scene} at {resolution}: relative RMSE {m['rel_rmse']:.4f} on {mask.mean():.0%} of the pixels")
    assert m["rel_rmse"] <= HALF_BOUND[scene]
    assert HALF_BOUND[scene] <= 0.05   # the goal


def rendered_case(tmp_path, regen, scene):
    """(ours, the reference) of the shaft case ``scene``: the render tests' settings, Blender's log clean."""
    scene, density, anisotropy = next(c for c in fs.SHAFT_CASES if c[0] == scene)
    ref = imageio.read_rgb(fs.ensure_shaft_reference(scene, density, regen=regen, anisotropy=anisotropy))
    log = []
    out = h.render_test(scene, density, tmp_path / f"{scene}.exr", engine="cycles", method="compositor",
                        samples=16, resolution=fs.SHAFT_RESOLUTION, cast_shadows=True, log=log,
                        extra=["--shafts", "on"])
    assert not h.log_errors(log[0]), h.log_errors(log[0])
    return imageio.read_rgb(out), ref


# The fog over the hooded lamp's hood (the rows above the wall: sky, fog lit only by the spot behind the wall, whose
# beam through the hole reaches the camera), by 4 x 4 block means against path tracing.  Measured (2026-11-30):
# 0.962-1.042; with the spot's nodes spread over the whole ray instead of its cone, 0.765-1.159 (a dark blob above
# the lamp and bright wedges beside it: one node held a third of a ray's glow).
HOOD_ROWS = 24
HOOD_BLOCKS = (0.93, 1.07)


def test_fog_over_a_hood_has_no_blobs(tmp_path, regen):
    img, ref = rendered_case(tmp_path, regen, "hooded_lamp")

    def blocks(a):
        y = a[:HOOD_ROWS].mean(axis=2)
        return y.reshape(HOOD_ROWS // 4, 4, y.shape[1] // 4, 4).mean(axis=(1, 3))
    ratio = blocks(img) / blocks(ref)
    print(f"fog over the hood: block ratios {ratio.min():.3f}-{ratio.max():.3f}")
    if not (HOOD_BLOCKS[0] <= ratio.min() and ratio.max() <= HOOD_BLOCKS[1]):
        h.FAILURES.mkdir(parents=True, exist_ok=True)
        compare.write_diff(img, ref, h.FAILURES / "shafts_fog_over_a_hood_diff.png", max_rel=0.2)
    assert HOOD_BLOCKS[0] <= ratio.min() and ratio.max() <= HOOD_BLOCKS[1], (ratio.min(), ratio.max())


# The stairwell's walls (its pixels brighter than BLOB_FLOOR of the picture's: the ceiling over the shade is darker),
# where the reference is smooth: the largest deviation from path tracing of a 5 x 5 mean of our / its pixels.
# Measured (2026-11-30): 1.14 %; 2.74 % with every surface ray weighed at its own distance from the lamp (5 x 5
# bright squares where one of a pixel's hemisphere rays passed the lamp within centimetres: the filter that pools
# 5 x 5 pixels' interleaved directions spread it).
BLOB_FLOOR = 30   # percentile
BLOB_BOUND = 0.018


def test_walls_by_a_shaded_pendant_have_no_blobs(tmp_path, regen):
    img, ref = rendered_case(tmp_path, regen, "stairwell")
    scene = "stairwell"
    y = ref.mean(axis=2)
    mask = (fs.lamp_pixel_mask(scene, fs.SHAFT_RESOLUTION) & smooth_pixels(ref)
            & (y > np.percentile(y, BLOB_FLOOR)))
    ratio = np.where(mask, img.mean(axis=2) / y, np.nan)
    windows = np.lib.stride_tricks.sliding_window_view(ratio, (5, 5))
    means = windows.mean(axis=(2, 3))   # NaN wherever a window holds a pixel left out
    worst = float(np.nanmax(np.abs(means - 1.0)))
    print(f"stairwell walls: largest 5 x 5 deviation {worst:.4f} on {np.isfinite(means).sum()} windows")
    if worst > BLOB_BOUND:
        h.FAILURES.mkdir(parents=True, exist_ok=True)
        compare.write_diff(img, ref, h.FAILURES / "shafts_stairwell_blobs_diff.png", max_rel=0.05)
    assert np.isfinite(means).sum() > 500 and worst <= BLOB_BOUND, worst
