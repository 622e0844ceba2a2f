"""The demo scenes before and after Method Auto (issue 26): what the fog costs and how far it is from path tracing,
with Method Node Groups (the default before) and Method Auto (the default now), at the default Quality.

    .venv/bin/python benchmarks/demo_auto.py [--cases street_lamps_0.08,...] [--repeats N] [--budget S]
                                             [--methods nodes,auto] [--no-timing]
                                             [--engines cycles,eevee] [--chart-only] [--out CSV] [--chart PNG]

Cases: every path-traced reference in tests/references/ (``<scene>_<beta>[_g<G>].exr``).  Per case and method:

* error: the case rendered as tests/test_render.py renders it (fog_scenes/render_harness.py ``render_test``:
  the reference's 64x36, pixel-centre filter, cast shadows and interreflection off, the samples of the test that
  uses the reference: ``SAMPLES``), compared with fog_addon.compare as ``assert_close`` does (``rel_rmse``,
  ``mean_ratio``: all pixels), and again without the 3x3 pixels around each light the camera sees
  (``rel_rmse_nolamps``: a lamp's own pixels hold the glow's peak, where a few pixels weigh most);
  ``auto_choice``: the CLI's ``models: Method Auto: ...`` line.  ``--engines cycles,eevee``: EEVEE too (errors only).
* cost (Cycles): one worker process per (case, method) (this script with ``--worker``, timed as
  benchmarks/overhead.py's worker times: its ``_render`` and ``_warm``) opens the built demo scene, sets
  320x180, 16 spp, Cycles CPU, no denoiser (the scene's own filter and shadows), renders without fog (first,
  then the minimum of ``repeats`` warm renders), adds the fog (``apply_fog``) and renders with it (first,
  warm).  ``ratio_*_cpu`` (process CPU time, all threads) are the figures to read on a shared machine; the
  wall ratios stand beside them, with the 1-minute load average at the worker's start and end.

Outputs: benchmarks/out/demo_auto.csv (copy it to docs/measurements/data/ to keep it) and
docs/figures/demo_auto.png (per case: warm CPU ratio and relative RMSE, before and after).

Smoke mode (``FOG_BENCH_SMOKE=1``, benchmarks/smoke.py): the case street_lamps_0.08, timed at 8x4 px and 1 spp with
one warm render, its error at the reference's 64x36 and 1 spp; a timing worker not "ok" fails the run.
"""
import argparse
import json
import pathlib
import re
import subprocess
import sys
import tempfile
import time

import csv_rows
import overhead as ov   # the timed renders (_render, _warm, BEAT), _emit, load_avg, source_id

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import smoke  # noqa: E402
from fog_scenes import render_harness as h  # noqa: E402

OUT = smoke.out(ROOT / "benchmarks" / "out")
CSV = OUT / "demo_auto.csv"
PNG = smoke.out(ROOT / "docs" / "figures" / "demo_auto.png")
METHODS = ("nodes", "auto")   # before, after
# samples of the render tests using each reference (test_render.py, test_eevee_direct.py); others: the CLI's 16
SAMPLES = {"boulevard": 512, "concert_stage": 256, "headlights": 256, "glossy_lamps": 128}
RESOLUTION, TIMING_SAMPLES = smoke.pick(((320, 180), 16), ((8, 4), 1))
ERROR_SAMPLES = smoke.pick(None, 1)   # None: the samples of the render tests (``SAMPLES``)
BUDGET_S = 600.0
REF = re.compile(r"(?P<scene>[a-z_]+)_(?P<beta>[0-9.]+)(?:_g(?P<g>[0-9.]+))?\.exr$")
FIELDS = ["case", "scene", "beta", "g", "engine", "method", "rel_rmse", "rel_rmse_nolamps", "mean_ratio", "p95_rel",
          "lamp_pixels", "error_samples", "auto_choice", "ratio_warm_cpu", "ratio_first_cpu", "ratio_warm",
          "ratio_first", "nofog_first_cpu_s", "nofog_warm_cpu_s", "fog_apply_cpu_s", "fog_first_cpu_s",
          "fog_warm_cpu_s", "nofog_first_s", "nofog_warm_s", "fog_first_s", "fog_warm_s", "repeats", "timing_choice",
          "status", "load_avg_start", "load_avg_end", "timing_resolution", "timing_samples", "source"]


def cases():
    """(case name, scene, beta 1/m, g) of every reference in tests/references/."""
    out = []
    for p in sorted(h.REFERENCES.glob("*.exr")):
        m = REF.match(p.name)
        if m and ".tmp" not in p.name:
            out.append((p.stem, m["scene"], float(m["beta"]), float(m["g"] or 0.0)))
    return out


# ---------------------------------------------------------------- worker (inside bpy)

def lamp_uv(scene):
    """Normalised camera coordinates (u, v from the bottom left) of the lights in front of the camera."""
    from bpy_extras.object_utils import world_to_camera_view
    uv = []
    for ob in scene.objects:
        if ob.type == "LIGHT":
            p = world_to_camera_view(scene, scene.camera, ob.matrix_world.translation)
            if p.z > 0 and 0 <= p.x <= 1 and 0 <= p.y <= 1:
                uv.append((p.x, p.y))
    return uv


def worker(spec):
    """Time one (case, method): no fog (first, warm), apply, fog (first, warm); print results as they come."""
    import bpy
    from fog_addon import measure
    from fog_addon.ops import apply
    scene = measure.open_scene(spec["blend"])
    scene.render.engine = "CYCLES"
    measure.set_resolution(scene, *RESOLUTION)
    measure.set_samples(scene, TIMING_SAMPLES)
    measure.set_cycles_cpu(scene)
    scene.cycles.use_denoising = False
    bpy.app.handlers.render_stats.append(ov.BEAT)
    res = {"lamp_uv": lamp_uv(scene)}
    res["nofog_first_s"], res["nofog_first_cpu_s"] = ov._render(scene, "nofog_first")
    res["nofog_warm_s"], res["nofog_warm_cpu_s"], _ = ov._warm(scene, spec["repeats"], "nofog_warm")
    ov._emit(res)
    c, t = time.process_time(), time.perf_counter()
    apply.apply_fog(scene, spec["beta"], anisotropy=spec["g"], method=spec["method"])
    res["fog_apply_s"], res["fog_apply_cpu_s"] = time.perf_counter() - t, time.process_time() - c
    res["timing_choice"] = apply.method_line(apply.stored_choice() or {}) or ""
    scene.cycles.use_denoising = False
    res["fog_first_s"], res["fog_first_cpu_s"] = ov._render(scene, "fog_first")
    ov._emit(res)
    res["fog_warm_s"], res["fog_warm_cpu_s"], res["repeats"] = ov._warm(scene, spec["repeats"], "fog_warm")
    ov._emit(res)


# ---------------------------------------------------------------- driver

def timing(blend, beta, g, method, repeats, budget):
    """The worker's last result for one (case, method), with status and load averages."""
    spec = {"blend": str(blend), "beta": beta, "g": g, "method": method, "repeats": repeats}
    env = dict(h._env(), PYTHONUNBUFFERED="1")
    load0 = ov.load_avg()
    try:
        p = subprocess.run([h.PYTHON, __file__, "--worker", json.dumps(spec)], cwd=str(ROOT), env=env,
                           capture_output=True, text=True, timeout=budget)
        out, status = p.stdout, ("ok" if p.returncode == 0 else f"exit {p.returncode}: {p.stderr.strip()[-300:]}")
        smoke.echo(p.stdout, p.stderr)
    except subprocess.TimeoutExpired as exc:
        out = exc.stdout.decode(errors="replace") if isinstance(exc.stdout, bytes) else (exc.stdout or "")
        status = f"timeout after {budget:.0f} s"
    lines = [ln.split(" ", 1)[1] for ln in out.splitlines() if ln.startswith("OVERHEAD_JSON ")]
    res = json.loads(lines[-1]) if lines else {}
    res.update(status=status, load_avg_start=load0, load_avg_end=ov.load_avg())
    for key, num, den in (("ratio_warm", "fog_warm_s", "nofog_warm_s"), ("ratio_first", "fog_first_s", "nofog_first_s"),
                          ("ratio_warm_cpu", "fog_warm_cpu_s", "nofog_warm_cpu_s"),
                          ("ratio_first_cpu", "fog_first_cpu_s", "nofog_first_cpu_s")):
        if num in res and res.get(den):
            res[key] = res[num] / res[den]
    return res


def lamp_mask(shape, uv):
    """True except the 3x3 pixels around each light at normalised camera coordinates ``uv``."""
    import numpy as np
    hgt, w = shape[:2]
    mask = np.ones((hgt, w), bool)
    for u, v in uv:
        x, y = int(u * w), int((1 - v) * hgt)   # image rows from the top
        mask[max(y - 1, 0):y + 2, max(x - 1, 0):x + 2] = False
    return mask


def error(scene, beta, g, engine, method, blend, ref, work, uv):
    """The render test's metrics for one (case, engine, method), and the CLI's Method line."""
    from fog_addon import compare, imageio
    log = []
    samples = ERROR_SAMPLES or (SAMPLES.get(scene) if engine == "cycles" else None)
    out = h.render_test(scene, beta, str(work / f"{ref.stem}_{engine}_{method}.exr"), engine=engine,
                        method=method, samples=samples, blend=blend, log=log, timeout=1800,
                        extra=["--anisotropy", repr(g)] if g else ())
    a, b = imageio.read_rgb(out), imageio.read_rgb(ref)
    m, mask = compare.metrics(a, b), lamp_mask(b.shape, uv)
    smoke.echo(log[0])
    line = next((ln[len("models: "):] for ln in log[0].splitlines() if ln.startswith("models: Method")), "")
    return {"rel_rmse": m["rel_rmse"], "mean_ratio": m["mean_ratio"], "p95_rel": m["p95_rel"],
            "rel_rmse_nolamps": compare.metrics(a, b, mask=mask)["rel_rmse"], "lamp_pixels": int((~mask).sum()),
            "error_samples": samples or 16, "auto_choice": line, "image": str(out)}


def chart(rows, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np
    names = sorted({r["case"] for r in rows if r["engine"] == "cycles"}, key=lambda c: c)
    get = (lambda c, m, k, e="cycles": next((float(r[k]) for r in rows if r["case"] == c and r["method"] == m
                                             and r["engine"] == e and r.get(k) not in (None, "")), np.nan))
    engines = ["cycles"] + (["eevee"] if any(r["engine"] == "eevee" for r in rows) else [])
    panels = [("ratio_warm_cpu", "cycles", "fog / no fog, warm CPU time (Cycles 320x180, 16 spp)", True)] + [
        ("rel_rmse", e, f"relative RMSE against path tracing ({e})", False) for e in engines]
    fig, axes = plt.subplots(len(panels), 1, figsize=(10, 3.2 * len(panels)), sharex=True)
    x = np.arange(len(names))
    for ax, (key, eng, title, log) in zip(axes, panels):
        for i, (m, label) in enumerate((("nodes", "before: Node Groups"), ("auto", "after: Auto"))):
            ax.bar(x + (i - 0.5) * 0.38, [get(c, m, key, eng) for c in names], 0.38, label=label)
        ax.set_title(title, fontsize=10)
        if log:
            ax.set_yscale("log")
            ax.axhline(1.0, color="k", lw=0.5)
        else:
            ax.yaxis.set_major_formatter(matplotlib.ticker.PercentFormatter(1.0))
        ax.legend(fontsize=8)
    axes[-1].set_xticks(x, names, rotation=30, ha="right", fontsize=8)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--worker")
    ap.add_argument("--cases", default=smoke.pick(None, "street_lamps_0.08"),
                    help="comma-separated case names (reference stems); default all")
    ap.add_argument("--repeats", type=int, default=smoke.pick(3, 1))
    ap.add_argument("--budget", type=float, default=BUDGET_S, help="s per timing worker")
    ap.add_argument("--methods", default=",".join(METHODS))
    ap.add_argument("--no-timing", action="store_true")
    ap.add_argument("--engines", default="cycles", help="cycles,eevee: EEVEE's errors too (Cycles only is timed)")
    ap.add_argument("--chart-only", action="store_true")
    ap.add_argument("--out", type=pathlib.Path, default=CSV)
    ap.add_argument("--chart", type=pathlib.Path, default=PNG)
    args = ap.parse_args(argv)
    if args.worker:
        return worker(json.loads(args.worker))
    if args.chart_only:
        import csv
        chart(list(csv.DictReader(open(args.out))), args.chart)
        return 0
    wanted = set(args.cases.split(",")) if args.cases else None
    work = pathlib.Path(tempfile.mkdtemp(prefix="demo_auto_", dir=h._scratch()))
    rows, source, lamp_uvs = [], ov.source_id(), {}
    for case, scene, beta, g in cases():
        if wanted and case not in wanted:
            continue
        blend = h.scene_blend(scene, work)
        ref = h.reference_path(scene, beta, g)
        for method in args.methods.split(","):
            for engine in args.engines.split(","):
                row = {"case": case, "scene": scene, "beta": beta, "g": g, "engine": engine, "method": method,
                       "source": source}
                if engine == "cycles" and not args.no_timing:
                    row.update(timing(blend, beta, g, method, args.repeats, args.budget),
                               timing_resolution="{}x{}".format(*RESOLUTION), timing_samples=TIMING_SAMPLES)
                smoke.check(row.get("status", "ok") == "ok", f"{case} {method}: {row.get('status')}")
                uv = row.pop("lamp_uv", None) or lamp_uvs.get(scene) or timing_uv(blend)
                lamp_uvs[scene] = uv
                row.update(error(scene, beta, g, engine, method, blend, ref, work, uv))
                smoke.check(row["auto_choice"], f"{case} {engine} {method}: no 'models: Method' line from the CLI")
                row.setdefault("load_avg_end", ov.load_avg())
                rows.append(row)
                print(f"{case} {engine} {method}: ratio warm CPU {row.get('ratio_warm_cpu', float('nan')):.3g} "
                      f"(first {row.get('ratio_first_cpu', float('nan')):.3g}; {row.get('status', 'not timed')}), "
                      f"rel RMSE {row['rel_rmse']:.4f} (w/o lamps {row['rel_rmse_nolamps']:.4f}) "
                      f"load {row['load_avg_end']}; {row['auto_choice']} / {row.get('timing_choice', '')}",
                      flush=True)
            csv_rows.write(args.out, rows, FIELDS, digits=4)
    if not rows:
        raise SystemExit(f"no case of {args.cases or 'tests/references'} ran")
    chart(rows, args.chart)
    print(f"wrote {args.out}, {args.chart} (scratch {work})")
    return 0


def timing_uv(blend):
    """The lights' camera coordinates without a timing run (a small bpy process)."""
    code = ("import json, sys; sys.path.insert(0, %r); import demo_auto; from fog_addon import measure; "
            "print('UV ' + json.dumps(demo_auto.lamp_uv(measure.open_scene(sys.argv[1]))))" % str(ROOT / "benchmarks"))
    out = h.run_bpy_code(code, blend).stdout
    return json.loads(next(ln for ln in out.splitlines() if ln.startswith("UV "))[3:])


if __name__ == "__main__":
    sys.exit(main())
