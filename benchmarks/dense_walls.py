"""Dense Fog (multiply scattered light) beside surfaces on nine demo scenes, against Cycles path-traced references
(docs/measurements/2026-11-30-dense-walls.md; the slow test tests/test_dense_surplus.py measures two of them so).

Each scene (``CASES``: scene, density 1/m, the reference's samples per pixel) at 128x72 (``shafts.SHAFT_RESOLUTION``):

* the reference: ``shafts.render_ms_reference``, 32 volume bounces, white fog, surfaces black to the scattered light,
  one seed; the committed tests/references/*_ms32.exr for hooded_lamp and street_lamps, else
  benchmarks/out/dense_walls/<scene>_<density>_ms32.exr, rendered only if missing (30-200 s each);
* ours: Compositor, 16 spp, cast shadows, light shafts on, ``--explain``, twice: the file's defaults (Dense Fog on,
  its scales beside surfaces in effect) and ``--multiple-scattering off`` (both kept beside the references);
* the metric: the relative RMSE of 4x4 block means (``dense_surfaces.block_means``) with the reference's fireflies
  clipped and the lamps' 3x3 pixels left out (``shafts.lamp_pixel_mask``), as the test measures it.

Writes benchmarks/out/dense_walls.csv, one row per scene: the blocks error with Dense Fog on and off, the predicted
error (``--explain``), the per-light scales the render used (``--explain``'s "multiple scattering scaled for the
surfaces near ..." line, which names at most three lights, those whose scale may miss most; empty where it prints
none), and the true share: sum(reference - single-scattering reference) / sum(ours on - ours off) over the masked
picture's RGB (the single-scattering reference is ``shafts.shaft_reference_path``'s), with the reference's
fireflies clipped (``true_share``) and not (``true_share_unclipped``).  A failed scene is a row with its error in
``notes``; the run goes on.

    .venv/bin/python benchmarks/dense_walls.py          (about 2 minutes on 2 cores with the references made,
                                                         20-30 minutes rendering the seven missing ones)
"""
import pathlib
import re
import sys
import tempfile
import time
import traceback

import numpy as np

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "benchmarks"))

import csv_rows  # noqa: E402
import smoke  # noqa: E402
from fog_addon import imageio  # noqa: E402
from fog_scenes import dense_surfaces as ds  # noqa: E402
from fog_scenes import render_harness as h  # noqa: E402
from fog_scenes import shafts as fs  # noqa: E402

# (scene, density 1/m, the reference's samples per pixel)
CASES = smoke.pick([("hooded_lamp", 0.08, 2048), ("street_lamps", 0.08, 1024), ("stairwell", 0.1, 1024),
                    ("bus_shelter", 0.07, 1024), ("pergola", 0.08, 1024), ("window_room", 0.1, 1024),
                    ("colonnade", 0.08, 1024), ("fence", 0.05, 1024), ("forest", 0.06, 1024)],
                   [("fence", 0.05, 2)])
# the committed references (tests/test_dense_surplus.py's); the others are rendered into OUT_DIR when missing
COMMITTED = {("hooded_lamp", 0.08): "hooded_lamp_0.08_ms32.exr",
             ("street_lamps", 0.08): "street_lamps_0.08_shadows_ms32.exr"}
SAMPLES = smoke.pick(16, 1)   # ours
OUT = smoke.out(ROOT / "benchmarks" / "out" / "dense_walls.csv")
OUT_DIR = smoke.out(ROOT / "benchmarks" / "out" / "dense_walls")
FIELDS = ["scene", "density", "reference", "blocks_on", "blocks_off", "predicted", "dense_scales", "true_share",
          "true_share_unclipped", "seconds", "notes"]
SCALES_LINE = re.compile(r"multiple scattering scaled for the surfaces near (\d+) light\(s\) \((.*?)\): the scale")


def reference_for(scene, density, samples, blend):
    """The 32-bounce reference's path: the committed one (``COMMITTED``, not in smoke mode), else OUT_DIR's,
    rendered if missing."""
    committed = COMMITTED.get((scene, density))
    if committed and not smoke.ON and (h.REFERENCES / committed).is_file():
        return h.REFERENCES / committed
    path = OUT_DIR / f"{scene}_{h.density_tag(density)}_ms32.exr"
    if not path.is_file():
        t = time.perf_counter()
        fs.render_ms_reference(scene, density, path, samples, blend=blend)
        print(f"  {scene}: reference rendered, {samples} spp, {time.perf_counter() - t:.0f} s", flush=True)
    return path


def ours(scene, density, blend, dense):
    """Our render (Dense Fog by the file's defaults, or off) and its log."""
    log = []
    out = OUT_DIR / f"{scene}_{h.density_tag(density)}_{'on' if dense else 'off'}.exr"
    h.render_test(scene, density, out, engine="cycles", method="compositor", samples=SAMPLES,
                  resolution=fs.SHAFT_RESOLUTION, cast_shadows=True, log=log, blend=blend,
                  extra=["--shafts", "on", "--explain"], multiple_scattering=None if dense else "off")
    smoke.echo(log[0])
    return imageio.read_rgb(out), log[0]


def measure(scene, density, samples, workdir):
    notes = []
    blend = h.scene_blend(scene, workdir)
    ref_path = reference_for(scene, density, samples, blend)
    raw = np.asarray(imageio.read_rgb(ref_path), np.float64)[..., :3]
    ref, clipped = ds.clip_fireflies(raw)
    on, log = ours(scene, density, blend, True)
    off, _ = ours(scene, density, blend, False)
    mask = fs.lamp_pixel_mask(scene, fs.SHAFT_RESOLUTION, blend)
    row = {"scene": scene, "density": density, "reference": str(ref_path.relative_to(ROOT))
           if ref_path.is_relative_to(ROOT) else str(ref_path),
           "blocks_on": round(ds.rel_rmse(ds.block_means(on, mask), ds.block_means(ref, mask)), 4),
           "blocks_off": round(ds.rel_rmse(ds.block_means(off, mask), ds.block_means(ref, mask)), 4)}
    predicted = re.search(r"predicted error ([0-9.]+)%", log)
    row["predicted"] = round(float(predicted.group(1)) / 100.0, 4) if predicted else ""
    if not predicted:
        notes.append("no predicted error in the log")
    if "multiple scattering is off" in log:
        notes.append("Dense Fog was off in the defaults' render")
    scales = SCALES_LINE.search(log)
    if scales:
        shown = scales.group(2)
        row["dense_scales"] = shown.removesuffix(" and more").replace(", ", "; ")
        if shown.endswith(" and more"):
            notes.append(f"scales of 3 of {scales.group(1)} lights printed")
    else:
        row["dense_scales"] = ""
        notes.append("--explain printed no scales")
    single_path = fs.shaft_reference_path(scene, density)
    single = np.asarray(imageio.read_rgb(single_path), np.float64)[..., :3] if single_path.is_file() else None
    if single is None:
        notes.append(f"no single-scattering reference {single_path.name}: no true share")
    elif single.shape != raw.shape:
        notes.append(f"{single_path.name} is {single.shape[1]}x{single.shape[0]}, the reference "
                     f"{raw.shape[1]}x{raw.shape[0]}: no true share")
    else:
        added = float((on - off)[mask].sum())
        row["true_share"] = round(float((ref - single)[mask].sum()) / added, 4)
        row["true_share_unclipped"] = round(float((raw - single)[mask].sum()) / added, 4)
    if clipped:
        notes.append(f"{clipped} reference pixels clipped")
    row["notes"] = "; ".join(notes)
    return row


def main():
    OUT_DIR.mkdir(parents=True, exist_ok=True)
    rows = []
    with tempfile.TemporaryDirectory(prefix="dense_walls_") as workdir:
        for scene, density, samples in CASES:
            t = time.perf_counter()
            try:
                row = measure(scene, density, samples, pathlib.Path(workdir))
            except Exception as e:   # (a measurement records a failed scene and goes on)
                traceback.print_exc()
                smoke.check(False, f"{scene}: {e}")
                row = {"scene": scene, "density": density, "notes": f"failed: {str(e).splitlines()[0][:300]}"}
            row["seconds"] = round(time.perf_counter() - t, 1)
            rows.append(row)
            print(", ".join(f"{k} {row[k]}" for k in FIELDS if row.get(k) not in (None, "")), flush=True)
            csv_rows.write(OUT, rows, FIELDS)   # (after every scene: a long run keeps what it measured)
    print(f"wrote {OUT}")


if __name__ == "__main__":
    main()
