"""Does the distance haze fade to Blender's own Sky Texture at the horizon? (issue 29 item 4)

Renders Blender 5.0's Sky Texture World alone (Cycles CPU, one Blender process, renders one at a time, cached under
benchmarks/out/sky_texture/): an equirectangular panorama with the sun disc on and off (the horizon's radiance, the
upper hemisphere's mean as ``sunsky.probe_sky`` takes it) and a narrow perspective view centred on the sun, disc
on and off (the disc's irradiance on a surface facing the sun: the difference of the two, integrated over the
view's pixels).  Then evaluates the add-on's daylight (``precompute/physics/daylight/sunlight.py``, numpy) with that sun
and sky at the same directions: the horizon colour ray_glow(d, UNBOUNDED), distant black and white surfaces, the sky
pixel World(d) sky_seen(d) + ray_glow(d, UNBOUNDED) against the Sky Texture alone.

    .venv/bin/python benchmarks/sky_texture_match.py [--figure]

Figures to docs/measurements/2026-11-27-sky-texture.md; tables and the chart to
docs/measurements/data/sky_texture_*_2026-11-27.*.  Smoke mode (``FOG_BENCH_SMOKE=1``, benchmarks/smoke.py): one Sky
Texture (single scattering, no aerosols), two azimuths, a 256x128 panorama and a 16 px zoom at 1 spp, 64 steps
for the converged sky, the figure drawn, every output in the smoke folder.
"""
import argparse
import csv
import json
import math
import pathlib
import subprocess
import sys

import numpy as np

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import smoke  # noqa: E402

OUT = smoke.out(ROOT / "benchmarks" / "out" / "sky_texture")
DATA = smoke.out(ROOT / "docs" / "measurements" / "data")
DATE = "2026-11-27"

SUN_ELEVATION = 40.0            # degrees; the Sky Texture's sun_rotation 0 puts the sun towards +Y
PANO = smoke.pick((512, 256), (256, 128))   # px: 0.703 degrees a pixel
PANO_SPP = smoke.pick(64, 1)
ZOOM = smoke.pick(128, 16)      # px square, centred on the sun
ZOOM_FOV = 1.5                  # degrees (the disc's diameter is the Sky Texture's sun_size, 0.545 degrees)
ZOOM_SPP = smoke.pick(64, 1)
# (sky_type, aerosol_density, ozone_density); air density 1, altitude 0, sun intensity 1, World strength 1
# aerosol 4.4: the clear_day preset's haze (extinction 9.78e-5 /m at the ground, albedo 0.9, scale height 1.2 km)
# in Blender's units (Mie scattering 2e-5 /m x density, extinction 1.11 x scattering, scale height 1.2 km)
CLEAR_DAY_AEROSOL = 4.4
CONFIGS = [("SINGLE_SCATTERING", 1.0, 1.0), ("SINGLE_SCATTERING", 0.0, 1.0), ("SINGLE_SCATTERING", 0.0, 0.0),
           ("SINGLE_SCATTERING", CLEAR_DAY_AEROSOL, 1.0),
           ("MULTIPLE_SCATTERING", 1.0, 1.0), ("MULTIPLE_SCATTERING", 0.0, 1.0), ("MULTIPLE_SCATTERING", 0.0, 0.0),
           ("MULTIPLE_SCATTERING", CLEAR_DAY_AEROSOL, 1.0)]
CONFIGS = smoke.pick(CONFIGS, CONFIGS[1:2])
AZIMUTHS = smoke.pick((0.0, 45.0, 90.0, 135.0, 180.0), (0.0, 90.0))   # degrees from the sun's azimuth
CONVERGED_STEPS = smoke.pick(4096, 64)       # the single-scattering sky's steps taken as converged
HORIZON_ROWS = 3                             # the rows from the horizon up: 0 - 2.11 degrees
ELEVATIONS = (5.0, 10.0, 20.0)               # degrees, single rows (the one containing it)
AZ_HALF = 1.5                                # degrees: columns within this of +-azimuth are averaged
CAMERA_HEIGHTS = (1.6, 300.0)                # m
DISTANCES = (5e3, 20e3, 50e3)                # m: distant surfaces
WHITE = 0.8                                  # the white-ish surface's albedo (a vertical face towards the camera)


def tag(cfg):
    sky_type, aerosol, ozone = cfg
    return f"{'single' if sky_type.startswith('SINGLE') else 'multiple'}_aer{aerosol:g}_oz{ozone:g}"


def files(cfg):
    t = tag(cfg)
    return {k: OUT / f"{k}_{t}.exr" for k in ("pano_on", "pano_off", "zoom_on", "zoom_off")}


def sun_vector():
    e = math.radians(SUN_ELEVATION)
    return np.array([0.0, math.cos(e), math.sin(e)])


# --- the Blender side (run in its own process: ``--render``) ----------------------------------------------------

def _render_all():
    import bpy
    import mathutils
    jobs = [(cfg, key, path) for cfg in CONFIGS for key, path in files(cfg).items() if not path.exists()]
    if not (OUT / "directions.exr").exists():
        jobs.insert(0, (None, "directions", OUT / "directions.exr"))
    for cfg, key, path in jobs:
        bpy.ops.wm.read_factory_settings(use_empty=True)
        scene = bpy.context.scene
        world = bpy.data.worlds.new("sky")
        scene.world = world
        nt = world.node_tree
        bg = next(n for n in nt.nodes if n.type == "BACKGROUND")
        bg.inputs["Strength"].default_value = 1.0
        if cfg is None:   # the camera's direction per pixel: (d + 1) / 2 from the World's Generated coordinates
            tc = nt.nodes.new("ShaderNodeTexCoord")
            vm = nt.nodes.new("ShaderNodeVectorMath")
            vm.operation = "MULTIPLY_ADD"
            vm.inputs[1].default_value = (0.5, 0.5, 0.5)
            vm.inputs[2].default_value = (0.5, 0.5, 0.5)
            nt.links.new(tc.outputs["Generated"], vm.inputs[0])
            nt.links.new(vm.outputs[0], bg.inputs["Color"])
        else:
            sky = nt.nodes.new("ShaderNodeTexSky")
            sky.sky_type, sky.aerosol_density, sky.ozone_density = cfg
            sky.air_density, sky.altitude = 1.0, 0.0
            sky.sun_elevation, sky.sun_rotation, sky.sun_intensity = math.radians(SUN_ELEVATION), 0.0, 1.0
            sky.sun_disc = key.endswith("_on")
            nt.links.new(sky.outputs["Color"], bg.inputs["Color"])
        cam_data = bpy.data.cameras.new("cam")
        cam = bpy.data.objects.new("cam", cam_data)
        scene.collection.objects.link(cam)
        scene.camera = cam
        r = scene.render
        r.engine = "CYCLES"
        r.resolution_percentage = 100
        if key.startswith("zoom"):
            cam_data.type = "PERSP"
            cam_data.sensor_fit = "HORIZONTAL"
            cam_data.angle = math.radians(ZOOM_FOV)
            cam_data.clip_start = 0.01
            cam.rotation_euler = mathutils.Vector(sun_vector()).to_track_quat("-Z", "Y").to_euler()
            r.resolution_x = r.resolution_y = ZOOM
            scene.cycles.samples = ZOOM_SPP
        else:   # as sunsky._render_equirect: equirectangular, looking along +Y, +Z up
            cam_data.type = "PANO"
            cam_data.panorama_type = "EQUIRECTANGULAR"
            cam.rotation_euler = (math.pi / 2.0, 0.0, 0.0)
            r.resolution_x, r.resolution_y = PANO if cfg is not None else (64, 32)
            scene.cycles.samples = PANO_SPP if cfg is not None else 4
        scene.cycles.device = "CPU"
        scene.cycles.use_denoising = False
        scene.cycles.pixel_filter_type = "BOX"   # a pixel is the mean over its own area
        scene.cycles.filter_width = 1.0 if cfg is not None else 0.01   # the direction map: pixel centres
        scene.view_settings.view_transform = "Standard"
        r.image_settings.file_format = "OPEN_EXR"
        r.image_settings.color_depth = "32"
        r.filepath = str(path)
        bpy.ops.render.render(write_still=True)
        print(f"rendered {path.name}", flush=True)


def render_missing():
    OUT.mkdir(parents=True, exist_ok=True)
    needed = [p for cfg in CONFIGS for p in files(cfg).values()] + [OUT / "directions.exr"]
    if all(p.exists() for p in needed):
        return
    proc = subprocess.run([sys.executable, __file__, "--render"], cwd=ROOT, capture_output=True, text=True)
    print(proc.stdout[-3000:] if not smoke.ON else proc.stdout, proc.stderr if smoke.ON else "", flush=True)
    proc.check_returncode()


# --- reading the renders ------------------------------------------------------------------------------------------

def pano_grid(w, h):
    """(elevation (h,), azimuth from +Y towards +X (w,)) of the panorama's pixel centres, radians (row 0 on top)."""
    elevation = (0.5 - (np.arange(h) + 0.5) / h) * math.pi
    azimuth = ((np.arange(w) + 0.5) / w - 0.5) * 2.0 * math.pi
    return elevation, azimuth


def directions(elevation, azimuth):
    ce = np.cos(elevation)
    return np.stack([ce * np.sin(azimuth), ce * np.cos(azimuth), np.sin(elevation) * np.ones_like(azimuth)], -1)


def check_mapping(read):
    """The mapping ``pano_grid`` assumes against the rendered direction map (64 x 32, 4 samples a pixel): the
    largest angle between them in pixel widths (5.6 degrees; under 1/2: no offset of a pixel or more)."""
    p = read(OUT / "directions.exr") * 2.0 - 1.0
    e, a = pano_grid(p.shape[1], p.shape[0])
    want = directions(e[:, None], a[None, :])
    got = p / np.linalg.norm(p, axis=-1, keepdims=True)
    return float(np.degrees(np.arccos(np.clip((want * got).sum(-1), -1, 1))).max()) / (360.0 / p.shape[1])


def hemisphere_mean(pixels):
    """``sunsky.probe_sky``'s mean over the upper hemisphere (solid-angle weighted)."""
    h = pixels.shape[0]
    elevation = (0.5 - (np.arange(h) + 0.5) / h) * math.pi
    weight = np.where(elevation > 0.0, np.cos(elevation), 0.0)[:, None]
    return (pixels * weight[..., None]).sum(axis=(0, 1)) / (weight.sum() * pixels.shape[1])


def zoom_irradiance(on, off):
    """The sun disc's irradiance on a surface facing the sun (RGB): sum over the view of (disc on - off) x the
    pixel's solid angle x its cosine to the view's axis (a pinhole: dOmega = p^2 cos^3)."""
    n = on.shape[0]
    p = 2.0 * math.tan(math.radians(ZOOM_FOV) / 2.0) / n
    x = (np.arange(n) + 0.5 - n / 2.0) * p
    cos = 1.0 / np.sqrt(1.0 + x[:, None] ** 2 + x[None, :] ** 2)
    weight = p * p * cos ** 4
    diff = on - off
    edge = np.concatenate([diff[:2].ravel(), diff[-2:].ravel(), diff[:, :2].ravel(), diff[:, -2:].ravel()])
    return (diff * weight[..., None]).sum(axis=(0, 1)), float(np.abs(edge).max())


def sky_texture_figures(cfg, read):
    f = {k: read(v) for k, v in files(cfg).items()}
    off, on = f["pano_off"], f["pano_on"]
    h, w = off.shape[:2]
    elevation, azimuth = pano_grid(w, h)
    rows_h = np.arange(h // 2 - HORIZON_ROWS, h // 2)             # the rows just above the horizon
    out = {"mean_off": hemisphere_mean(off), "mean_on": hemisphere_mean(on)}
    out["sun"], out["zoom_edge"] = zoom_irradiance(f["zoom_on"], f["zoom_off"])
    out["peak_row"], out["peak_col"] = np.unravel_index(np.argmax(on.sum(-1)), on.shape[:2])

    def columns(az):
        d = np.degrees(np.abs(np.angle(np.exp(1j * (np.abs(azimuth) - math.radians(az))))))
        return np.where(d <= AZ_HALF)[0]

    out["horizon"], out["rows"], out["band"] = {}, {}, {}
    for az in AZIMUTHS:
        cols = columns(az)
        out["horizon"][az] = off[np.ix_(rows_h, cols)].mean(axis=(0, 1))
        out["band"][az] = off[np.ix_(rows_h, cols)].mean(axis=1)        # (rows, 3), horizon row last
        for el in ELEVATIONS:
            row = int(np.argmin(np.abs(np.degrees(elevation) - el)))
            out["rows"][(az, el)] = (float(np.degrees(elevation[row])), off[row, cols].mean(axis=0))
    out["band_elevations"] = np.degrees(elevation[rows_h])
    out["cols"] = {az: azimuth[columns(az)] for az in AZIMUTHS}
    out["row_pitch"] = 180.0 / h
    return out


# --- the add-on's daylight at the same directions -----------------------------------------------------------------

def our_day(kind, sun_irradiance, sky_radiance):
    from fog_addon.precompute.core import medium, presets
    from fog_addon.precompute.physics.daylight import sunlight
    if kind == "air only":
        beta, top, falloff, g, albedo = 1e-9, 0.0, 1200.0, 0.76, 0.9
    else:
        p = presets.LAYERED[kind]
        beta, top, falloff, g, albedo = p["density"], p["fog_top"], p["height_falloff"], p["anisotropy"], p["albedo"][0]
    return sunlight.Daylight(beta, top, falloff, 0.0, sun_vector(), np.asarray(sun_irradiance, float),
                             np.asarray(sky_radiance, float), g, albedo, tuple(medium.RAYLEIGH_RGB),
                             medium.RAYLEIGH_HEIGHT)


def ground_sun_transmittance(day):
    """e^{-(C_layer + C_air)/mu_s} per channel at the ground: what the add-on takes off a Sun light's irradiance
    before it reaches the ground (the Daylight's sun_irradiance is the sun above the air)."""
    from fog_addon.precompute.physics.daylight import aerial, daylight
    from fog_addon.precompute.core.ops import NumpyOps
    m = NumpyOps()
    c_l = daylight.column_depth(m, 0.0, day.beta, day.top, day.falloff)
    c_a = aerial.air_column_depth(m, 0.0, 1.0, day.air_height)
    return np.array([math.exp(-(c_l + b * c_a) / day.sun[2]) for b in day.air])


def band_directions(elevations_deg, pitch_deg, azimuths, sub=8):
    """Directions filling the rows (centres ``elevations_deg``, ``pitch_deg`` tall) and columns (``azimuths``,
    radians) as a box filter does: (rows, cols x sub x sub... flattened, 3) and their cos-elevation weights."""
    t = (np.arange(sub) + 0.5) / sub - 0.5
    dirs, wts = [], []
    for el in elevations_deg:
        e = np.radians(el + t * pitch_deg)
        a = np.concatenate([np.asarray(azimuths) + s * math.radians(360.0 / PANO[0]) for s in t])
        ee, aa = np.meshgrid(e, a, indexing="ij")
        dirs.append(directions(ee, aa).reshape(-1, 3))
        wts.append(np.cos(ee).reshape(-1))
    return np.stack(dirs), np.stack(wts)


def our_figures(day, st, height):
    """Ours at the Sky Texture's directions, per azimuth: the horizon colour (the band's mean), its sun and sky
    parts, black and white surfaces at DISTANCES, and the sky pixel at ELEVATIONS."""
    from fog_addon.precompute.physics.daylight import daylight, sunlight
    from fog_addon.precompute.core.ops import NumpyOps
    m = NumpyOps()
    origin = np.array([0.0, 0.0, height])

    def mean_over(d, w, fn):
        v = np.stack([fn(di) for di in d])                          # (rows, n, 3)
        return (v * w[..., None]).sum(axis=1) / w.sum(axis=1)[:, None]

    def glow(dd, length, day_=day):
        return sunlight.ray_glow(m, day_, origin, dd, np.full(len(dd), length))

    out = {}
    sun_only = day._replace(sky_radiance=np.zeros(3))
    sky_only = day._replace(sun_irradiance=np.zeros(3))
    for az in AZIMUTHS:
        d, w = band_directions(st["band_elevations"], st["row_pitch"], st["cols"][az])
        r = {"horizon_rows": mean_over(d, w, lambda di: glow(di, daylight.UNBOUNDED))}
        r["horizon"] = r["horizon_rows"].mean(axis=0)
        r["sun_part"] = mean_over(d, w, lambda di: glow(di, daylight.UNBOUNDED, sun_only)).mean(axis=0)
        r["sky_part"] = mean_over(d, w, lambda di: glow(di, daylight.UNBOUNDED, sky_only)).mean(axis=0)
        r["seen"] = mean_over(d, w, lambda di: sunlight.sky_seen(m, day, origin, di)).mean(axis=0)
        for L in DISTANCES:
            r[("black", L)] = mean_over(d, w, lambda di: glow(di, L)).mean(axis=0)
            r[("white", L)] = mean_over(d, w, lambda di: white_surface(m, day, origin, di, L)).mean(axis=0)
        for el in ELEVATIONS:
            row_el, st_value = st["rows"][(az, el)]
            de, we = band_directions([row_el], st["row_pitch"], st["cols"][az])
            g_ = mean_over(de, we, lambda di: glow(di, daylight.UNBOUNDED))[0]
            seen = mean_over(de, we, lambda di: sunlight.sky_seen(m, day, origin, di))[0]
            r[("sky", el)] = (st_value * seen + g_, g_, seen)
        out[az] = r
    return out


def white_surface(m, day, origin, d, length):
    """A vertical face of albedo WHITE turned to the camera at ``length`` along ``d``: its Lambertian radiance under
    the sun and half the sky (the black ground below), both dimmed as the add-on dims them (``direct_dimming``),
    without the fog light, seen through view_transmittance, plus the glow in front of it."""
    from fog_addon.precompute.physics.daylight import sunlight
    normal = -d * np.array([1.0, 1.0, 0.0])
    normal /= np.linalg.norm(normal, axis=-1, keepdims=True)
    point = origin + d * length
    free = (day.sun_irradiance[None, :] * np.maximum(normal @ day.sun, 0.0)[:, None]
            + math.pi * 0.5 * day.sky_radiance[None, :])
    dim = sunlight.direct_dimming(m, day, point, normal)
    radiance = WHITE / math.pi * free * dim
    t = sunlight.view_transmittance(m, day, point, -d, np.full(len(d), length))
    return radiance * t + sunlight.ray_glow(m, day, origin, d, np.full(len(d), length))


# --- how far 32 midpoint steps leave a single-scattering sky from converged (an independent re-implementation) ---

EARTH_R, ATMOSPHERE_R = 6360e3, 6420e3        # m: Blender's single-scattering sky (intern/sky, sky_nishita.cpp)
MIE_COEFF, MIE_EXTINCTION, MIE_G = 2e-5, 1.11, 0.76
# (nm, Rayleigh scattering 1/m, ozone absorption 1/m) at three of its 21 wavelengths, for R, G, B
WAVELENGTHS = ((684, 4.711e-6, 4.645e-7), (551, 1.150e-5, 2.090e-6), (437, 3.018e-5, 7.310e-8))


def _densities(h):
    return np.stack([np.exp(-h / 8e3), np.exp(-h / 1.2e3), np.maximum(0.0, 1.0 - np.abs(h - 25e3) / 15e3)], -1)


def _to_top(p, d):
    b = (p * d).sum(-1)
    c = (p * p).sum(-1) - ATMOSPHERE_R ** 2
    return -b + np.sqrt(b * b - c)


def _sun_columns(p, s, n=400):
    """The three species' columns (density x m) from points p to the atmosphere's top along s (graded sum)."""
    x = (np.arange(n) + 0.5) / n
    length = _to_top(p, s)[..., None]
    q = p[..., None, :] + (length * x ** 3)[..., None] * s
    return (_densities(np.linalg.norm(q, axis=-1) - EARTH_R) * (length * 3.0 * x ** 2 / n)[..., None]).sum(-2)


def spherical_single_scattering(d, s, aerosol, ozone, rayleigh, ozone_coeff, steps):
    """Single scattering (relative units) along a view ray d from 1 m above a spherical Earth, the sun along s:
    Rayleigh (8 km) and Cornette-Shanks aerosols (1.2 km) and a tent of ozone, the view ray cut into ``steps``
    equal segments evaluated at their middles with the view's optical depth taken to each segment's end (the
    scheme of Blender's single-scattering sky; ``steps`` large: converged)."""
    cam = np.array([0.0, 0.0, EARTH_R + 1.0])
    ds = _to_top(cam, d) / steps
    p = cam + ((np.arange(steps) + 0.5) * ds)[:, None] * d
    rho = _densities(np.linalg.norm(p, axis=-1) - EARTH_R) * np.array([1.0, aerosol, ozone])
    k = np.array([rayleigh, MIE_EXTINCTION * MIE_COEFF, ozone_coeff])
    depth = np.cumsum(rho * ds, axis=0) + _sun_columns(p, s) * np.array([1.0, aerosol, ozone])
    mu = float(d @ s)
    p_r = 3.0 / (16.0 * math.pi) * (1.0 + mu * mu)
    g2 = MIE_G ** 2
    p_m = 3.0 * (1 - g2) * (1 + mu * mu) / (8 * math.pi * (2 + g2) * (1 + g2 - 2 * MIE_G * mu) ** 1.5)
    source = rho[:, 0] * rayleigh * p_r + rho[:, 1] * MIE_COEFF * p_m
    return float((np.exp(-(depth * k).sum(-1)) * source * ds).sum())


def step_bias():
    """{(aerosol, ozone): {azimuth: (R, G, B)}}: 32 steps over 4096 at the horizon band (0.35, 1.05, 1.76 deg)."""
    out = {}
    for aerosol, ozone in sorted({(c[1], c[2]) for c in CONFIGS}):
        out[(aerosol, ozone)] = {}
        for az in AZIMUTHS:
            ratio = []
            for _, rayleigh, oz in WAVELENGTHS:
                d = [directions(math.radians(el), math.radians(az)) for el in (0.35, 1.05, 1.76)]
                v = [np.mean([spherical_single_scattering(di, sun_vector(), aerosol, ozone, rayleigh, oz, n)
                              for di in d]) for n in (32, CONVERGED_STEPS)]
                ratio.append(v[0] / v[1])
            out[(aerosol, ozone)][az] = np.array(ratio)
        print(f"32-step single scattering over converged, aerosol {aerosol:g}, ozone {ozone:g} (684/551/437 nm): "
              + "; ".join(f"az {az:g} {fmt(v)}" for az, v in out[(aerosol, ozone)].items()))
    return out


# --- the report -----------------------------------------------------------------------------------------------------

def fmt(v, digits=3):
    return " / ".join(f"{x:.{digits}g}" for x in v)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--render", action="store_true", help="(internal) render the missing EXRs in this process")
    ap.add_argument("--figure", action="store_true", default=smoke.ON, help="the horizon ratio against azimuth as a PNG")
    a = ap.parse_args()
    if a.render:
        _render_all()
        return
    render_missing()
    from fog_addon import imageio
    from fog_addon.precompute.core import medium
    read = imageio.read_rgb
    print(f"panorama mapping against the rendered direction map: max {check_mapping(read):.2f} pixel widths")
    bias = step_bias()
    rows_ratio, rows_sky, rows_far, summary, summary_rows = [], [], [], {}, []
    for cfg in CONFIGS:
        st = sky_texture_figures(cfg, read)
        t = tag(cfg)
        peak_el = 90.0 - (st["peak_row"] + 0.5) * st["row_pitch"]
        print(f"\n== Sky Texture {t}: sun disc peak at row {st['peak_row']} (elevation {peak_el:.2f}), "
              f"column {st['peak_col']}")
        print(f"  sun disc irradiance (zoom on - off): {fmt(st['sun'], 4)} W/m^2 (largest |on - off| on the view's "
              f"edge {st['zoom_edge']:.3g})")
        print(f"  hemisphere mean, disc off: {fmt(st['mean_off'], 4)}; disc on: {fmt(st['mean_on'], 4)} "
              f"(difference x 2 pi = {fmt((st['mean_on'] - st['mean_off']) * 2 * math.pi, 4)})")
        for az in AZIMUTHS:
            print(f"  horizon {st['band_elevations'][0]:.2f}-{st['band_elevations'][-1]:.2f} deg rows, azimuth "
                  f"{az:5.1f}: {fmt(st['horizon'][az], 4)}")
        kinds = ["air only", "clear_day"] if cfg[1] == 0.0 else ["clear_day", "air only"]
        summary[t] = {"sun": st["sun"].tolist(), "sky_mean_off": st["mean_off"].tolist(),
                      "sky_mean_on": st["mean_on"].tolist(),
                      "horizon": {str(az): st["horizon"][az].tolist() for az in AZIMUTHS}}
        for kind in kinds:
            day = our_day(kind, st["sun"], st["mean_off"])
            t_sun = ground_sun_transmittance(day)
            print(f"  {kind}: the sun's transmittance to the ground in our model {fmt(t_sun)}")
            for height in CAMERA_HEIGHTS:
                ours = our_figures(day, st, height)
                print(f"  ours, {kind}, camera {height:g} m:")
                for az in AZIMUTHS:
                    o, ref = ours[az], st["horizon"][az]
                    ratio = o["horizon"] / ref
                    print(f"    az {az:5.1f}: horizon {fmt(o['horizon'], 4)} ratio {fmt(ratio)} "
                          f"(sun part {fmt(o['sun_part'] / ref)}, sky part {fmt(o['sky_part'] / ref)}); "
                          f"rows from the top: {'; '.join(fmt(x) for x in (o['horizon_rows'] / st['band'][az]))}")
                    top = o["sun_part"] / t_sun / ref     # the disc's irradiance taken as above the air
                    rows_ratio.append([t, kind, height, az, *ratio, *(o["sun_part"] / ref), *(o["sky_part"] / ref),
                                       *(top + o["sky_part"] / ref), *top, *ref, *o["horizon"]])
                    b = bias[(cfg[1], cfg[2])][az] if cfg[0].startswith("SINGLE") else np.ones(3)
                    probe_on = (o["sun_part"] + o["sky_part"] * st["mean_on"] / st["mean_off"]) / ref
                    summary_rows.append((t, kind, height, az, ratio, top + o["sky_part"] / ref, top, top * b,
                                         probe_on))
                    for L in DISTANCES:
                        b, w_ = o[("black", L)], o[("white", L)]
                        rows_far.append([t, kind, height, az, L, *(b / ref), *(w_ / ref), *(b / o["horizon"]),
                                         *(w_ / o["horizon"])])
                    rows_sky.append([t, kind, height, az, "0-2", *(o["horizon"] + ref * o["seen"]) / ref,
                                     *(o["horizon"] / ref), *o["seen"]])
                    for el in ELEVATIONS:
                        pix, g_, seen = o[("sky", el)]
                        ref_el = st["rows"][(az, el)][1]
                        rows_sky.append([t, kind, height, az, f"{el:g}", *(pix / ref_el), *(g_ / ref_el), *seen])
                far = [f"{L / 1e3:g} km black {fmt(ours[90.0][('black', L)] / st['horizon'][90.0])} white "
                       f"{fmt(ours[90.0][('white', L)] / st['horizon'][90.0])}" for L in DISTANCES]
                print("    at azimuth 90, over the Sky Texture's horizon: " + "; ".join(far))
                sky = [f"{el:g} deg {fmt(ours[90.0][('sky', el)][0] / st['rows'][(90.0, el)][1])}"
                       for el in ELEVATIONS]
                print("    sky pixel over the Sky Texture alone, azimuth 90: " + "; ".join(sky))
    DATA.mkdir(parents=True, exist_ok=True)
    rgb = lambda p: [f"{p}_{c}" for c in "rgb"]   # noqa: E731
    with open(DATA / f"sky_texture_horizon_{DATE}.csv", "w", newline="") as fh:
        cw = csv.writer(fh)
        cw.writerow(["sky_texture", "ours", "camera_m", "azimuth_deg", *rgb("ratio"), *rgb("sun_part"),
                     *rgb("sky_part"), *rgb("ratio_sun_top"), *rgb("ratio_sun_top_no_sky"), *rgb("sky_texture"),
                     *rgb("ours")])
        cw.writerows([r[:4] + [f"{x:.5g}" for x in r[4:]] for r in rows_ratio])
    with open(DATA / f"sky_texture_surfaces_{DATE}.csv", "w", newline="") as fh:
        cw = csv.writer(fh)
        cw.writerow(["sky_texture", "ours", "camera_m", "azimuth_deg", "distance_m", *rgb("black_over_st"),
                     *rgb("white_over_st"), *rgb("black_over_ours"), *rgb("white_over_ours")])
        cw.writerows([r[:5] + [f"{x:.5g}" for x in r[5:]] for r in rows_far])
    with open(DATA / f"sky_texture_sky_pixel_{DATE}.csv", "w", newline="") as fh:
        cw = csv.writer(fh)
        cw.writerow(["sky_texture", "ours", "camera_m", "azimuth_deg", "elevation_deg", *rgb("pixel_over_st"),
                     *rgb("glow_over_st"), *rgb("sky_seen")])
        cw.writerows([r[:5] + [f"{x:.5g}" for x in r[5:]] for r in rows_sky])
    with open(DATA / f"sky_texture_renders_{DATE}.json", "w") as fh:
        json.dump({"sun_elevation_deg": SUN_ELEVATION, "pano": PANO, "pano_spp": PANO_SPP, "zoom": ZOOM,
                   "zoom_fov_deg": ZOOM_FOV, "zoom_spp": ZOOM_SPP, "rayleigh_rgb": medium.RAYLEIGH_RGB,
                   "sky_textures": summary}, fh, indent=1)
    print("\n== horizon (0-2.1 deg) ours / Sky Texture, R / G / B: as set | sun above the air | that, no sky glow"
          " | that over a converged single-scattering Sky Texture | as set, the sky's mean probed with the disc on")
    for t, kind, height, az, r0, r1, r2, r3, r4 in summary_rows:
        print(f"{t:20s} {kind:9s} {height:5g} m az {az:5.1f}: {fmt(r0, 2)} | {fmt(r1, 2)} | {fmt(r2, 2)} | "
              f"{fmt(r3, 2)} | {fmt(r4, 2)}")
    with open(DATA / f"sky_texture_summary_{DATE}.csv", "w", newline="") as fh:
        cw = csv.writer(fh)
        cw.writerow(["sky_texture", "ours", "camera_m", "azimuth_deg", *rgb("as_set"), *rgb("sun_top"),
                     *rgb("sun_top_no_sky"), *rgb("sun_top_no_sky_over_converged"), *rgb("as_set_probe_disc_on")])
        cw.writerows([[t, k, h, az] + [f"{x:.4g}" for v in rest for x in v] for t, k, h, az, *rest in summary_rows])
    if a.figure:
        figure(summary_rows)


def figure(rows):
    """The horizon ratio against azimuth (camera 1.6 m): as set (solid), the sun above the air without the sky glow
    (dotted), and that over a converged single-scattering sky (dashed, single-scattering panels)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    pairs = [("single_aer0_oz1", "air only"), (f"single_aer{CLEAR_DAY_AEROSOL:g}_oz1", "clear_day"),
             ("multiple_aer0_oz1", "air only"), (f"multiple_aer{CLEAR_DAY_AEROSOL:g}_oz1", "clear_day"),
             ("multiple_aer1_oz1", "clear_day")]
    fig, axes = plt.subplots(1, len(pairs), figsize=(3.6 * len(pairs), 3.8))
    for ax, (t, kind) in zip(axes, pairs):
        sel = [r for r in rows if r[0] == t and r[1] == kind and r[2] == CAMERA_HEIGHTS[0]]
        az = [r[3] for r in sel]
        for c, colour in enumerate("rgb"):
            ax.plot(az, [r[4][c] for r in sel], "-", color=colour, marker="o", label=f"{'RGB'[c]} as set")
            ax.plot(az, [r[6][c] for r in sel], ":", color=colour, marker="x",
                    label=f"{'RGB'[c]} sun above the air, no sky glow")
            if t.startswith("single"):
                ax.plot(az, [r[7][c] for r in sel], "--", color=colour, lw=0.8,
                        label=f"{'RGB'[c]} that / converged sky")
        ax.axhline(1.0, color="k", lw=0.5)
        ax.set_ylim(bottom=0.0)
        ax.set_title(f"{kind} / Sky Texture\n{t.replace('_', ', ')}", fontsize=9)
        ax.set_xlabel("azimuth from the sun (degrees)", fontsize=8)
        ax.set_xticks(AZIMUTHS)
    axes[0].set_ylabel(f"horizon (0-2 deg): ours / Sky Texture, camera {CAMERA_HEIGHTS[0]:g} m", fontsize=8)
    axes[0].legend(fontsize=5.5)
    fig.tight_layout()
    path = DATA / f"sky_texture_horizon_{DATE}.png"
    fig.savefig(path, dpi=90)
    print(f"figure: {path}")


if __name__ == "__main__":
    main()
