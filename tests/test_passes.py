"""Fog passes (shader AOVs) and the compositor set-up that keeps Cycles' denoiser off the fog.

Scenes: tests/scenes/passes_probe.py (its docstring describes them), each run in its own process;
the renders are multilayer EXRs read here.

* Denoising: the one-lamp scene (Cycles 64x48, 16 spp, Gaussian 0.01 px) with the scene's own
  denoiser settings LEFT ON.  With the fog's set-up the composite at the glow's peak, and at every
  pixel where the fog light is more than half the pixel, is within 0.5 % of the undenoised analytic
  value, the airlight by quadrature of Sun et al. 2005 Eq. 5 (``airlight(..., quadrature=True)``) at
  the pixel centre's camera ray; without it (the set-up taken off: Cycles' denoiser back on) the peak
  comes out 65 % too dark.  A grey sphere lit by the World is the noisy part: it must be denoised.
* The passes equal the fog's part: Fog Light = the Combined of the same scene with the lamps lighting
  no surface (so it is the fog's light alone), Fog Transmittance = e^{-beta D_vp} (0 on the background),
  in Cycles and in a tiny EEVEE render.
* Remove restores the scene exactly (denoiser flag, Compositing, view layer AOVs and Denoising Data
  passes, the compositor tree, the scene's and view layers' custom properties), for a scene without a
  compositor, one with the user's (spliced), one whose user's compositor must be left alone, one
  switched from EEVEE to Cycles and one with the OSL method; each is saved and reopened before Remove.
* A saved file renders the same composite in a fresh process without the add-on
  (tests/scenes/farm_render.py, as in test_farm.py).
"""
import concurrent.futures
import json
import math
import os
import subprocess
import sys

import numpy as np
import pytest

from conftest import ROOT
from fog_addon import imageio
from fog_addon.precompute.physics.point import airlight

pytestmark = pytest.mark.render   # every test here starts Blender (bpy) in a subprocess

SCENES = ROOT / "tests" / "scenes"
PROBE = SCENES / "passes_probe.py"
FARM_RENDER = SCENES / "farm_render.py"

# The glow against the undenoised analytic value, per pixel: the bound.  Measured with the
# set-up: +0.31 % at the peak (the 16 samples' 0.015 px jitter on the glow's 1/h profile), median
# 1e-5; without it -65 % at the peak.
MAX_REL = 5e-3
# Without the set-up the peak must be off by at least this (it is off by 65 %): the test can fail.
MIN_SMEAR = 0.1
# About 0.15 % of Cycles' samples with the 0.01 px Gaussian land up to 0.5 px from the pixel centre
# (passes_probe.strays); a pixel with such a sample (mean squared offset above this, in px^2; the
# others stay below 3e-5) is off its centre's value by up to 0.8 % on this steep glow in every render,
# denoised or not.  Those pixels are compared with the undenoised render instead.
STRAY = 1e-3
# The sphere's silhouette: pixel-centre sampling leaves it aliased, and OIDN smooths such an edge as
# if it were noise, moving the sphere's own (denoised) light up to a pixel onto the background (by up
# to half the airlight of the first pixel out, 0.5 % of the second; Cycles' own denoiser does the same
# to that edge).  That is the denoiser working on what is noisy, not on the fog: those pixels are only
# checked for losing none of the fog's light.
RING = 2
# The sphere (a noisy surface lit by the World): the composite's high frequencies (RMS of the
# Laplacian) must drop below this fraction of the raw render's (measured 0.26).
MAX_NOISE_LEFT = 0.5
# The Compositor method's Fog Light against the node groups' pass (the same tables and pixel centres; the
# compositor evaluates each pixel once, in 32-bit nodes): the largest difference over the peak.
COMPOSITOR_FOG_LIGHT = 1e-3   # (measured 9.3e-5)
COMPOSITOR_FOG_LIGHT_EEVEE = 5e-3   # (measured 4.7e-4: half-float AOVs)


def _json(stdout):
    lines = [ln for ln in stdout.splitlines() if ln.startswith("{")]
    assert lines, f"no JSON line in:\n{stdout[-3000:]}"
    return json.loads(lines[-1])


def _run(out, *args, env=None, cwd=None, script=PROBE):
    r = subprocess.run([sys.executable, *map(str, (["-s"] if env else []) + [script, out, *args])],
                       capture_output=True, text=True, timeout=600, env=env, cwd=cwd)
    assert r.returncode == 0, f"{script.name} {args} exited {r.returncode}:\n{r.stderr[-3000:]}\n{r.stdout[-2000:]}"
    return _json(r.stdout)


def _farm_env(base):
    """Nothing inherited but PATH (as test_farm.py): fog_addon is not importable there."""
    env = {"PATH": os.environ.get("PATH", "/usr/bin:/bin"), "PYTHONDONTWRITEBYTECODE": "1"}
    for key, sub in (("HOME", "home"), ("BLENDER_USER_RESOURCES", "user_resources"), ("TMPDIR", "tmp")):
        (base / sub).mkdir(parents=True, exist_ok=True)
        env[key] = str(base / sub)
    return env


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    out = tmp_path_factory.mktemp("passes")
    jobs = {"denoise": ("denoise",), "nosetup": ("nosetup",), "strays": ("strays",),
            "cycles": ("passes", "CYCLES"), "eevee": ("passes", "BLENDER_EEVEE"), "remove": ("remove",)}
    with concurrent.futures.ThreadPoolExecutor(max_workers=2) as ex:
        futures = {k: ex.submit(_run, out, *a) for k, a in jobs.items()}
        res = {k: f.result() for k, f in futures.items()}
    farm = out / "farm"
    farm.mkdir()
    job = json.dumps([{"out": "farm_denoise.exr"}])
    res["farm"] = _run(out / "denoise.blend", farm, job, env=_farm_env(out / "farm_env"), cwd=farm,
                       script=FARM_RENDER)
    res["dir"] = out
    return res


# --- the one-lamp scene ------------------------------------------------------------------------

def _rays(info):
    """Unit camera-ray directions (H, W, 3) through the pixel centres of camera ``info``."""
    w, h, sw, f = info["width"], info["height"], info["sensor"], info["lens"]
    ys, xs = np.mgrid[0:h, 0:w]
    d = np.stack([((xs + 0.5) / w - 0.5) * sw, (0.5 - (ys + 0.5) / h) * sw * h / w, -np.full(xs.shape, f)], -1)
    d /= np.linalg.norm(d, axis=-1, keepdims=True)
    return d @ np.array(info["rotation"]).T


def _plane_distance(info, d, half):
    """Distance along each ray to the plane z = 0 (|x|, |y| <= half), inf where it misses."""
    c = np.array(info["camera"])
    t = np.where(d[..., 2] < 0, -c[2] / np.minimum(d[..., 2], -1e-12), np.inf)
    hit = c[:2] + d[..., :2] * np.where(np.isfinite(t), t, 0.0)[..., None]
    return np.where(np.all(np.abs(hit) <= half, axis=-1), t, np.inf)


def _grow(mask, n):
    for _ in range(n):
        p = np.pad(mask, 1)
        mask = mask | p[:-2, 1:-1] | p[2:, 1:-1] | p[1:-1, :-2] | p[1:-1, 2:]
    return mask


def _shrink(mask, n):
    return ~_grow(~mask, n)


@pytest.fixture(scope="module")
def scene(runs):
    return load_scene(runs["denoise"], runs["dir"])


def load_scene(info, d):
    """The one-lamp scene's renders (in folder ``d``), analytic airlight and pixel classes."""
    rays = _rays(info)
    c, lamp = np.array(info["camera"]), np.array(info["lamp"])
    to = lamp - c
    gamma = np.arccos(np.clip(rays @ to / np.linalg.norm(to), -1.0, 1.0))
    d_vp = _plane_distance(info, rays, info["plane"] / 2)
    want = info["power"] / (4 * math.pi) * airlight.airlight(info["beta"], np.linalg.norm(to), d_vp, gamma,
                                                              quadrature=True)
    (centre, radius) = info["sphere"]
    oc = c - np.array(centre)
    b = rays @ oc
    sphere = b * b - (oc @ oc - (1.02 * radius) ** 2) > 0   # rays meeting the sphere (2 % margin: facets)
    layers = imageio.read_layers(d / "denoise.exr")
    stray = imageio.read_layers(d / "strays.exr")["ViewLayer.Combined"]
    raw = layers["ViewLayer.Combined"][..., :3].astype(np.float64)
    fog = layers["ViewLayer.Fog Light"][..., :3].astype(np.float64)
    return {"info": info, "want": want, "sphere": sphere, "ring": _grow(sphere, RING) & ~sphere,
            "stray": stray[..., 0] + stray[..., 1] > STRAY, "raw": raw, "fog": fog,
            "composite": layers.get("Composite.Combined", layers["ViewLayer.Combined"]).astype(np.float64),
            "alpha": layers["ViewLayer.Combined"][..., 3],
            "nosetup": imageio.read_layers(d / "nosetup.exr")["ViewLayer.Combined"][..., :3].astype(np.float64),
            "peak": np.unravel_index(np.argmax(np.where(sphere, 0.0, want)), want.shape)}


def test_the_setup_replaces_the_render_denoiser(runs):
    info = runs["denoise"]
    assert info["denoiser_before"], "the scene's own denoiser was not on (new scenes denoise)"
    assert info["set_up"] and not info["denoiser"], info
    assert info["compositor"] == ["Compositor 0 Add", "Compositor 0 Albedo", "Compositor 0 Denoise",
                                  "Compositor 0 Emitted", "Compositor 0 Subtract", "Group Output",
                                  "Render Layers"], info["compositor"]
    assert runs["nosetup"]["denoiser"] is True and runs["nosetup"]["compositor"] is None


def test_glow_is_not_smeared_by_the_denoiser(scene):
    s = scene
    want, comp, raw, fog = s["want"], s["composite"][..., :3], s["raw"], s["fog"]
    assert np.array_equal(s["composite"][..., 3], s["alpha"]), "the composite's alpha is not the render's"
    fog_pixels = (fog[..., 0] > 0.5 * raw[..., 0]) & ~s["sphere"]
    rel = np.abs(comp / want[..., None] - 1.0).max(axis=-1)
    y, x = s["peak"]
    print(f"\npeak {s['peak']}: composite/analytic - 1 = {comp[y, x, 0] / want[y, x] - 1:+.4%}; "
          f"without the set-up {s['nosetup'][y, x, 0] / want[y, x] - 1:+.2%}; "
          f"{fog_pixels.sum()} pixels with the fog light > 50 %, {(fog_pixels & s['stray']).sum()} with a stray "
          f"sample, {(fog_pixels & s['ring']).sum()} on the sphere's silhouette")
    assert rel[y, x] <= MAX_REL, f"peak {s['peak']}: {rel[y, x]:.3%} from the analytic airlight"
    clean = fog_pixels & ~s["stray"] & ~s["ring"]
    worst = np.unravel_index(np.argmax(np.where(clean, rel, 0.0)), rel.shape)
    print(f"max over those (no stray, off the silhouette): {rel[worst]:.3%} at {worst}; median "
          f"{np.median(rel[clean]):.2e}")
    assert rel[clean].max() <= MAX_REL, f"composite vs analytic airlight: {rel[worst]:.3%} at {worst}"
    # pixels with a stray sample: as rendered (the composite adds nothing to them)
    strays = fog_pixels & s["stray"] & ~s["ring"]
    rel_raw = np.abs(comp / np.maximum(raw, 1e-30) - 1.0).max(axis=-1)
    assert rel_raw[strays].max(initial=0.0) <= MAX_REL, rel_raw[strays].max()
    # next to the sphere the denoiser moves its aliased silhouette by up to a pixel (see RING); the fog's
    # light is not taken away there either
    ring = fog_pixels & s["ring"]
    low = comp[..., 0] / want - 1.0
    print(f"sphere's silhouette: {low[ring].min():+.3%} to {low[ring].max():+.2%} from the analytic airlight")
    kept = fog_pixels & ~s["stray"]
    assert low[kept].min() >= -MAX_REL, f"fog light lost: {low[kept].min():.3%}"


def test_without_the_setup_the_denoiser_smears_the_glow(scene):
    """The test above can fail: the same scene with Cycles' own denoiser is far off at the peak."""
    y, x = scene["peak"]
    err = abs(scene["nosetup"][y, x, 0] / scene["want"][y, x] - 1.0)
    assert err > MIN_SMEAR, f"the render denoiser moved the peak by only {err:.2%}"


def test_noisy_surface_is_denoised(scene):
    inner = _shrink(scene["sphere"], 2)
    assert inner.sum() > 50

    def roughness(img):
        a = (img - scene["fog"])[..., 1]
        lap = 4 * a[1:-1, 1:-1] - a[:-2, 1:-1] - a[2:, 1:-1] - a[1:-1, :-2] - a[1:-1, 2:]
        return float(np.sqrt(np.mean(lap[inner[1:-1, 1:-1]] ** 2)))

    raw, comp = roughness(scene["raw"]), roughness(scene["composite"][..., :3])
    print(f"\nsphere noise (RMS Laplacian): raw {raw:.4f}, composite {comp:.4f}")
    assert comp < MAX_NOISE_LEFT * raw, (raw, comp)


# --- the passes equal the fog's part ------------------------------------------------------------

@pytest.mark.parametrize("engine,tol", [("cycles", 1e-6), ("eevee", 1e-3)])   # EEVEE writes half floats
def test_passes_are_the_fogs_part(runs, engine, tol):
    res = runs[engine]
    name = "blender_eevee" if engine == "eevee" else engine
    lit = imageio.read_layers(runs["dir"] / f"passes_{name}_lit.exr")
    unlit = imageio.read_layers(runs["dir"] / f"passes_{name}_unlit.exr")
    fog_only = unlit["ViewLayer.Combined"][..., :3]
    fog = lit["ViewLayer.Fog Light"][..., :3]
    scale = fog_only.max()
    assert np.abs(fog - fog_only).max() <= tol * scale, np.abs(fog - fog_only).max() / scale
    assert np.abs(unlit["ViewLayer.Fog Light"][..., :3] - fog_only).max() <= tol * scale
    # the lamps light the plane in the lit render: Combined - Fog Light is the surface, non-negative
    rest = lit["ViewLayer.Combined"][..., :3] - fog
    assert rest.min() >= -tol * scale and rest.max() > 0.1 * scale
    info = res["renders"][f"passes_{name}_lit"]
    d_vp = _plane_distance(info, _rays(info), 20.0)
    want = np.exp(-res["beta"] * d_vp)
    got = lit["ViewLayer.Fog Transmittance"][..., 0]
    assert np.isinf(d_vp).sum() > 10 and np.all(got[np.isinf(d_vp)] == 0.0)
    err = np.abs(got - want).max()
    print(f"\n{engine}: Fog Light vs the fog alone {np.abs(fog - fog_only).max() / scale:.1e}, "
          f"Fog Transmittance vs e^(-beta D) {err:.1e}")
    assert err <= tol, err


@pytest.fixture(scope="module")
def compositor_passes(runs):
    """The two-lamp scenes rendered by the command line with the Compositor method and ``--passes``, per engine."""
    out = {}
    for engine, flag, size in (("CYCLES", "cycles", "64x48"), ("BLENDER_EEVEE", "eevee", "32x24")):
        d = runs["dir"] / f"compositor_{flag}"
        blends = _run(d, "passes_blend", engine)
        for name, info in blends["renders"].items():
            exr = d / f"{name}.exr"
            r = subprocess.run([sys.executable, "-m", "fog_addon", "render", info["blend"], "--engine", flag,
                                "--method", "compositor", "--passes", "--density", str(runs["cycles"]["beta"]),
                                "--color", "0.9,0.8,0.7", "--samples", "1", "--resolution", size, "--pixel-centre",
                                "--multiple-scattering", "off",   # (the node groups' probe: single scattering)
                                "--out", str(exr)], capture_output=True, text=True, timeout=600, cwd=ROOT)
            assert r.returncode == 0, r.stderr[-3000:] + r.stdout[-2000:]
            out[name] = imageio.read_layers(exr)
    return out


@pytest.mark.parametrize("engine,tol,light_tol", [("cycles", 1e-6, COMPOSITOR_FOG_LIGHT),
                                                  ("eevee", 1e-3, COMPOSITOR_FOG_LIGHT_EEVEE)])
def test_compositor_passes_are_the_fogs_part(runs, compositor_passes, engine, tol, light_tol):
    """The Compositor method's fog passes, written by ``render --passes`` into its multilayer EXR: the composite
    is Fog Transmittance x (the surface as lit through the fog) + Fog Light, Fog Light is the fog's part alone
    (the composite of the scene whose lamps light no surface) and equals the node groups' pass, Fog
    Transmittance is e^{-beta D_vp} (0 on the background).  EEVEE writes its AOVs as half floats."""
    name = "blender_eevee" if engine == "eevee" else engine
    lit, unlit = compositor_passes[f"passes_{name}_lit"], compositor_passes[f"passes_{name}_unlit"]
    nodes = imageio.read_layers(runs["dir"] / f"passes_{name}_unlit.exr")["ViewLayer.Fog Light"][..., :3]
    scale = nodes.max()
    for layers in (lit, unlit):
        composite, fog = layers["Composite.Combined"][..., :3], layers["ViewLayer.Fog Light"][..., :3]
        t = layers["ViewLayer.Fog Transmittance"][..., :1]
        surface = layers["ViewLayer.Combined"][..., :3]   # the render: the materials dimmed it by their T
        assert np.abs(composite - (surface + fog)).max() <= 1e-6 * scale
        assert np.abs(layers["ViewLayer.Fog Transmittance"][..., :3] - t).max() == 0.0   # grey without air
    assert np.abs(unlit["Composite.Combined"][..., :3] - unlit["ViewLayer.Fog Light"][..., :3]).max() <= tol * scale
    rest = lit["Composite.Combined"][..., :3] - lit["ViewLayer.Fog Light"][..., :3]
    assert rest.min() >= -tol * scale and rest.max() > 0.1 * scale
    info = runs[engine]["renders"][f"passes_{name}_lit"]
    d_vp = _plane_distance(info, _rays(info), 20.0)
    got = lit["ViewLayer.Fog Transmittance"][..., 0]
    assert np.isinf(d_vp).sum() > 10 and np.all(got[np.isinf(d_vp)] == 0.0)
    err_t = np.abs(got - np.exp(-runs["cycles"]["beta"] * d_vp)).max()
    err_light = np.abs(unlit["ViewLayer.Fog Light"][..., :3] - nodes).max() / scale
    print(f"\ncompositor, {engine}: Fog Transmittance vs e^(-beta D) {err_t:.1e}, Fog Light vs the node groups' "
          f"{err_light:.1e}")
    assert err_t <= tol, err_t
    assert err_light <= light_tol, err_light


def test_passes_weighted_by_opacity(runs):
    """Where a material lets light through, its passes hold what it adds: the Surface group's passes are
    weighted by the material's opacity (white for an opaque one, left unlinked)."""
    o = runs["remove"]["opacity"]
    assert o["Opaque"] == {"linked": False, "value": [1.0, 1.0, 1.0, 1.0]}, o
    assert o["Alpha"] == {"linked": False, "value": [0.4, 0.4, 0.4, 1.0]}, o   # Principled Alpha 0.4
    assert o["Textured"]["linked"], o


def test_world_pass_reads_its_own_light_groups(runs):
    """Cycles runs whatever an AOV output reads on every evaluation (svm.cpp: AOV dependencies are shared
    by both sides of a Mix Shader).  Read from the World's own light groups, the Fog Light pass would undo
    the World's 0/1 mix: Cycles' importance map and every non-camera ray would run the fog (measured at
    48x27 with an automatic map: 7.5 s per render instead of 1.2 s).  The pass has its own instances."""
    reads = runs["remove"]["opacity"]["world_reads"]
    lights = [n for n in reads["emission"] if n.startswith("Light ")]
    assert lights and [n for n in reads["fog_light_pass"] if n.startswith("Light ")], reads
    assert not set(lights) & set(reads["fog_light_pass"]), reads


# --- Remove restores the scene exactly ------------------------------------------------------------

def _diff(a, b, path=""):
    if isinstance(a, dict) and isinstance(b, dict):
        return [d for k in sorted(set(a) | set(b)) for d in _diff(a.get(k, "<missing>"), b.get(k, "<missing>"),
                                                                  f"{path}/{k}")]
    return [] if a == b else [(path, str(a)[:300], str(b)[:300])]


@pytest.mark.parametrize("case", ["own", "user", "user_compositing_off", "eevee_then_cycles", "osl"])
def test_remove_restores_the_scene(runs, case):
    r = runs["remove"][case]
    before, after = dict(r["before"]), dict(r["after"])
    if case == "eevee_then_cycles":   # the test itself switched the engine
        assert (before.pop("engine"), after.pop("engine")) == ("BLENDER_EEVEE", "CYCLES")
    assert not _diff(before, after), _diff(before, after)
    once = r["follow"]["cycles"] if case == "eevee_then_cycles" else r["during"]   # the last add was on Cycles
    assert not _diff(once, r["twice"]), ("adding twice differs from once", _diff(once, r["twice"]))
    assert not _diff(r["twice"], r["reopened"]), ("changed by save and reopen", _diff(r["twice"], r["reopened"]))
    layer = r["during"]["layers"]["ViewLayer"]
    assert [a for a in layer["aovs"] if a[0].startswith("Fog")] == [["Fog Light", "COLOR"],
                                                                   ["Fog Transmittance", "VALUE"]], layer
    assert layer["active_aov"] == r["before"]["layers"]["ViewLayer"]["active_aov"]


def test_own_compositor_when_the_scene_has_none(runs):
    during = runs["remove"]["own"]["during"]
    tree = during["compositor"]
    assert not during["use_denoising"] and during["layers"]["ViewLayer"]["store_passes"]
    assert during["layers"]["ViewLayer"]["emit_env"] == [True, True]
    assert tree["name"] == "AnalyticFog Compositor" and tree["interface"] == [["Image", "OUTPUT", "NodeSocketColor"]]
    links = {(a, b, c, d) for a, b, c, d, _ in tree["links"]}
    n = "AnalyticFog Compositor 0 "
    assert {("AnalyticFog Render Layers", "Emission", n + "Emitted", "A_Color"),
            ("AnalyticFog Render Layers", "Environment", n + "Emitted", "B_Color"),
            ("AnalyticFog Render Layers", "Image", n + "Subtract", "A_Color"),
            (n + "Emitted", "Result_Color", n + "Subtract", "B_Color"),
            (n + "Subtract", "Result_Color", n + "Denoise", "Image"),
            ("AnalyticFog Render Layers", "Denoising Albedo", n + "Albedo", "A_Color"),
            (n + "Emitted", "Result_Color", n + "Albedo", "B_Color"),
            (n + "Albedo", "Result_Color", n + "Denoise", "Albedo"),
            ("AnalyticFog Render Layers", "Denoising Normal", n + "Denoise", "Normal"),
            (n + "Denoise", "Image", n + "Add", "A_Color"),
            (n + "Emitted", "Result_Color", n + "Add", "B_Color"),
            (n + "Add", "Result_Color", "AnalyticFog Group Output", "Socket_0")} == links, links
    den = tree["nodes"][n + "Denoise"]["inputs"]
    assert (den["HDR"], den["Prefilter"], den["Quality"]) == (True, "Accurate", "High"), den


def test_user_compositor_is_spliced_not_edited(runs):
    r = runs["remove"]["user"]
    before, during = r["before"]["compositor"], r["during"]["compositor"]
    assert not r["during"]["use_denoising"]
    mine = {k: v for k, v in during["nodes"].items() if "analytic_fog" not in v["custom"]}
    assert not _diff(before["nodes"], mine), _diff(before["nodes"], mine)
    assert len(during["nodes"]) == len(before["nodes"]) + 5
    links = {(a, b, c, d) for a, b, c, d, _ in during["links"]}
    n = "AnalyticFog Compositor 0 "
    assert {("My Layers", "Image", n + "Subtract", "A_Color"),
            (n + "Add", "Result_Color", "AnalyticFog Halve", "A_Color"),
            (n + "Add", "Result_Color", "Viewer", "Image")} <= links, links
    assert not [x for x in links if x[0] == "My Layers" and x[1] == "Image" and not x[2].startswith(n)]
    # the user's own AOV named Fog Light is used and kept; only Fog Transmittance is the fog's
    assert r["during"]["layers"]["ViewLayer"]["custom"]["analytic_fog_aovs"]["names"] == ["Fog Transmittance"]


def test_left_alone_with_a_note(runs):
    off = runs["remove"]["user_compositing_off"]
    assert off["during"]["use_denoising"] and off["during"]["compositor"] == off["before"]["compositor"]
    assert any("Compositing is off" in n[1] for n in off["notes"]), off["notes"]
    osl = runs["remove"]["osl"]   # Cycles' own Emission and Environment passes: the set-up works with OSL too
    assert osl["during"]["osl"] and not osl["during"]["use_denoising"] and osl["during"]["compositor"] is not None


def test_setup_follows_the_engine(runs):
    r = runs["remove"]["eevee_then_cycles"]
    assert r["during"]["compositor"] is None and r["during"]["use_denoising"], "set up for EEVEE"
    cycles, eevee = r["follow"]["cycles"], r["follow"]["eevee_again"]
    assert cycles["compositor"]["name"] == "AnalyticFog Compositor" and not cycles["use_denoising"]
    assert eevee["compositor"] is None and eevee["use_denoising"]
    assert "AnalyticFog Compositor" not in eevee["node_groups"]


# --- a saved file renders the same without the add-on ----------------------------------------------

def test_saved_file_renders_the_same_without_the_add_on(runs, scene):
    b = runs["farm"]
    s = b["after_open"]
    assert not s["find_spec_fog_addon"] and not s["fog_modules"] and not s["scene_rna_prop"], s
    assert b["settings"]["denoise"] is False, b["settings"]
    got = imageio.read(runs["dir"] / "farm" / "farm_denoise.exr").astype(np.float64)
    want = scene["composite"]
    d = np.abs(got - want).max() / np.abs(want).max()
    print(f"\nfarm composite vs the add-on's: max |B - A| / max A = {d:.3g}")
    assert d <= 1e-5, d
    # it is the composite (the sphere denoised), not the raw render
    assert np.abs(got[..., :3] - scene["raw"])[scene["sphere"]].max() > 1e-2


def test_compositor_passes_on_a_farm(runs, compositor_passes, tmp_path):
    """A saved file with the Compositor method's fog passes, rendered where the add-on is not installed
    (tests/scenes/farm_render.py): its File Output writes them in the folder of the file's own render output, the
    same Fog Light as the command line's render of that scene."""
    out = tmp_path / "saved"
    res = _run(out, "compositor_farm")
    assert res["directories"] == [str(out / "frames") + "/"], res["directories"]
    farm = tmp_path / "farm"
    farm.mkdir()
    _run(out / "compositor_passes.blend", farm, json.dumps([{"out": "farm_comp.exr"}]),
         env=_farm_env(tmp_path / "farm_env"), cwd=farm, script=FARM_RENDER)
    written = sorted((out / "frames").glob("ViewLayer Fog Passes_0001*"))
    assert len(written) == 1, sorted(p.name for p in (out / "frames").glob("*"))
    layers = imageio.read_layers(written[0])
    cli = compositor_passes["passes_cycles_lit"]["ViewLayer.Fog Light"][..., :3]
    farm_light = layers["Fog Light"][..., :3]
    err = np.abs(farm_light - cli).max() / cli.max()
    print(f"\nfarm's Fog Light against the command line's: {err:.1e}")
    assert err <= 1e-5, err


@pytest.mark.parametrize("output,folder", [("/tmp/", "/tmp/"), ("//render/shot_", "//render/"), ("//", "//"),
                                           ("", "//"), ("/renders/frames/f_####", "/renders/frames/")])
def test_compositor_passes_go_beside_the_render(output, folder):
    """The Compositor method's fog passes are written in the folder of the scene's render output, as the user
    wrote it, or beside the .blend when it names none (``compositor.passes_directory``)."""
    import types
    from fog_addon.nodes import compositor
    scene = types.SimpleNamespace(render=types.SimpleNamespace(filepath=output))
    assert compositor.passes_directory(scene) == folder
