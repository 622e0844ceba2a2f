"""Many lights: 1, 4, 16, 64 and 256 point lights, Cycles (node groups, OSL, compositor) and EEVEE, against the
numpy twin.

Each case runs fog_scenes/many_lights.py in a fresh process (48x27, 1 spp,
pixel centres; a ground plane and matte, glossy and metallic spheres; the
lights on a grid, out of the surfaces' direct light so each pixel is exactly
the fog's emission) with a hard timeout, and

* scans the process's stdout and stderr (``render_harness.log_errors``): any
  line saying a shader is too big (Cycles: "out of SVM stack space, shader ...
  too big"), a uniform block is too big (EEVEE: "Uniform block node_tree too
  big"), a GPU shader error or a shader compile error fails the test;
* checks the picture against the numpy twin (``fog_addon/precompute/model/shading.py``
  per pixel): on every object, and on the background, the median of render /
  twin is within 5 % of 1 (a material that renders black has 0, EEVEE's
  fallback for a shader that failed to link 3-4.5), and the relative RMSE
  over every pixel compared is at most 3 % (Cycles) / 5 % (EEVEE).  With one
  light it is 0.2 % (the rest: spheres are meshes, the twin's are exact).

Today (one ~450-node group per light inlined into every material, its light one
emission closure per light, summed by a balanced tree of Add Shader nodes)
Cycles' node groups and OSL pass up to 64 lights, EEVEE up to 256 (within its budget); 256
lights are too slow for CI everywhere.  The twin takes each light's models from the add-on's
stored choice: in EEVEE the choice must fit its uniform block (64 KiB of node
constants a material, ``budgets.eevee_budget``): 16 lights fit fully modelled since
709fad8 (eight lost their scattered fog light before it, predicted error 15 %), and at
64 most lights step down or leave the groups (reported), and the test checks the
picture renders exactly that choice.  Before the budget, EEVEE at 16 lights
overflowed the block ("Uniform block node_tree too big (78800/65536)") and every
material rendered EEVEE's fallback (median render / twin 3.0-4.5).
The Compositor method (nodes/comp_fog.py) passes at every count, 256 lights included, in 7-15 s a
case (relative RMSE 0.014-0.17 %, median render / twin within 0.07 % of 1; at ff98a1e).  In EEVEE it
passes with every light fully modelled: 1 / 4 / 16 / 64 lights relative RMSE 0.17 / 0.088 / 0.030 /
0.019 %, 256 lights 0.015 % (slow: EEVEE's own lights).
``MEASURED`` holds what each case did on 2 CPU cores (bpy 5.0.1, other jobs
running); failing cases that finish in about 2 minutes are
``xfail(strict=True)``, so they turn into failures the day they pass (then
drop their entry); slower ones are marked ``slow`` with the measured time as the
marker's reason, passing or not: ``scripts/test.sh --all`` (or ``-m slow``) runs
them (timeout ``SLOW_TIMEOUT_S``): use it to re-measure.  ``test_closure_sum_renders_every_closure``
checks the closure sum itself in SVM and OSL up to 256 closures in seconds.
"""
import json
import subprocess

import pytest

from fog_scenes import render_harness as h

SCRIPT = ("-m", "fog_scenes.many_lights")
LIGHTS = (1, 4, 16, 64, 256)
METHODS = {"cycles_nodes": ("CYCLES", "nodes"), "cycles_osl": ("CYCLES", "osl"), "eevee": ("BLENDER_EEVEE", "nodes"),
           "cycles_compositor": ("CYCLES", "compositor"), "eevee_compositor": ("BLENDER_EEVEE", "compositor")}
SAMPLES = 1
TIMEOUT_S = 300              # hard limit of one case's process
SLOW_TIMEOUT_S = 3000        # the cases MEASURED marks slow (256 lights, Cycles nodes: 1 796 s of CPU, beside the other worker)
FAST_LIGHTS = 4              # the default tier: every method x engine at 1 and 4 lights; 16 to 256 in the slow tier
MEDIAN_TOL = 0.05            # |median(render / twin) - 1| per object
REL_RMSE = {"CYCLES": 0.03, "BLENDER_EEVEE": 0.05}
BLACK = 0.1                  # median render / twin below this: the material renders black

# Re-measured with the balanced closure sum: wall time of the whole case (fog added + first render
# + twin) with other jobs running (load 3-5 on the 2 cores; on a quiet machine about 2.5x less; in a
# full-suite run at load 7-8 up to 2.3x more).  Cases not listed pass: median render / twin within
# 0.07 % of 1 per object (64 lights: 0.3 %, since 4348f61's default Quality "final" leaves some
# lights' scattered fog out; 0.02 % with every light), relative RMSE 0.02-0.2 %:
# Cycles nodes 1 / 4 / 16 / 64 lights in 5 / 5 / 9 / 79 s (64: fog added in 16 s, first render 61 s),
# OSL 1 / 4 / 16 in 6 / 12 / 47 s, EEVEE 1 / 4 / 16 / 64 in 9 / 11 / 67-118 / 29 s (relative RMSE
# 0.044 % at 16 and 64 lights against the models it chose; 64 lights then: 48 off and 16 glow only,
# predicted error 78 %; at f900d1a, with the saved-file budget and lights left out of the groups,
# EEVEE 1 / 4 / 16 / 64 pass again, 16 lights fully modelled; before the budget it was skipped, too
# slow and wrong: uniform block 314384/65536).  (Before 85e9c66 Cycles nodes rendered every fogged material black from 4 lights on:
# out of SVM stack space; from 85e9c66 to the balanced sum OSL dropped all but 16 lights' closures:
# 25 lights 25 %, 64 lights 2-7 % of the twin.)
# The 256-light Cycles entries were measured at 8ca53cb; since ada0798 the fog is added in about 25-30 s
# at 256 lights, but Cycles' first render (node groups) was still not done after 2 177 s of CPU
# (benchmarks/overhead.py at 709fad8).
MEASURED = {
    (16, "cycles_osl"): ("slow", "passes (relative RMSE 0.023 %) but slow for CI: 49 s in the full run at 225f330; "
                                 "test_closure_sum_renders_every_closure checks OSL's closure sum up to 256"),
    (256, "cycles_nodes"): ("slow", "too slow: fog added in 221 s, first render not finished at 300 s (killed); "
                                    "with the lights stepped down to 64 full lights' nodes a material (29 full, "
                                    "137 glow only, 90 left out, predicted error 57 %) it passed (relative RMSE "
                                    "8.8e-5) but the first render still took 661 s under load: the time is not "
                                    "in the material's nodes alone, so no such budget is shipped; at 21b9e50, quiet: "
                                    "121 lights (112 full, 9 glow only) pass, relative RMSE 1.5e-4, first render "
                                    "97 s; 256 lights (238 full, 18 glow only) pass too, relative RMSE 1.4e-4, median "
                                    "render / twin within 0.03 % of 1, but the first render takes 1 139 s (fog added "
                                    "in 17 s; 1 796 s of CPU); profiled at 121 lights (bf2080c): 96 % of the first "
                                    "render is Cycles' ShaderGraph::deduplicate_nodes, quadratic in a material's Math "
                                    "nodes (README, Many lights)"),
    (64, "cycles_osl"): ("slow", "passes (relative RMSE 0.019 %, median render / twin 1.0000-1.0002) but too "
                                 "slow for CI: 140-299 s (fog added in 9-19 s, first render 129-277 s; "
                                 "163 s CPU); test_closure_sum_renders_every_closure checks OSL's closure "
                                 "sum in seconds"),
    (256, "cycles_osl"): ("slow", "passes at 17a658d with OSL's shader-group budget (relative RMSE 7.5e-5; 82 "
                                  "full, 153 glow only, 21 left out) but too slow for CI: fog added in 34 s, "
                                  "first render 1 266 s under load; before the budget it crashed (SIGSEGV: "
                                  "OSL's 16-bit layer index overflowed at 53 195 nodes per material)"),
    (256, "eevee_compositor"): ("slow", "passes (relative RMSE 0.015 %, median render / twin 0.9999-1.0003, every "
                                        "light fully modelled) but too slow for CI: 190 s (fog added in 15 s, first "
                                        "render 173 s: EEVEE's own 256 lights)"),
    (256, "eevee"): ("slow", "passes at f900d1a (relative RMSE 0.041 % against the models it chose: most "
                             "lights left out of the groups to fit EEVEE's uniform block, predicted error 91 %) "
                             "but too slow for CI: 561 s (fog added in 34 s, first render 515 s, load 5-11); "
                             "before: fog added in 253 s and the World's uniform block too big (239728/65536)"),
}


def _params():
    out = []
    for n in LIGHTS:
        for method in METHODS:
            kind, why = MEASURED.get((n, method), (None, None))
            marks = []
            if kind == "xfail":
                marks.append(pytest.mark.xfail(strict=True, reason=why))
            elif kind == "slow":
                marks.append(pytest.mark.slow(reason=why))
            elif n > FAST_LIGHTS:
                marks.append(pytest.mark.slow(reason=f"the default tier runs each method at <= {FAST_LIGHTS} lights"))
            out.append(pytest.param(n, method, marks=marks, id=f"{n}-{method}"))
    return out


def run_case(tmp_path, n, method, timeout):
    """Run the scene script for ``n`` lights and ``method``; (result dict or None, log text, problems)."""
    engine, preference = METHODS[method]
    try:
        proc = h.run([*SCRIPT, tmp_path, engine, preference, n, SAMPLES], timeout=timeout, check=False)
    except subprocess.TimeoutExpired as exc:
        out = (exc.stdout or b"") + (exc.stderr or b"")
        text = out.decode(errors="replace") if isinstance(out, bytes) else out
        return None, text, [f"timed out after {timeout} s"] + h.log_errors(text)
    text = proc.stdout + "\n" + proc.stderr
    problems = h.log_errors(text)
    if proc.returncode != 0:
        problems.append(f"exit code {proc.returncode}: {text[-2000:]}")
    line = next((ln for ln in proc.stdout.splitlines() if ln.startswith("MANY_LIGHTS_JSON ")), None)
    if line is None:
        return None, text, problems + ["no result line"]
    return json.loads(line.split(" ", 1)[1]), text, problems


def picture_problems(res):
    engine = res["engine"]
    problems = []
    for name, st in res["objects"].items():
        if not st.get("pixels"):
            continue
        med = st["median_ratio"]
        if med < BLACK:
            problems.append(f"{name} renders black (median render / twin {med:.3g})")
        elif abs(med - 1.0) > MEDIAN_TOL:
            problems.append(f"{name}: median render / twin {med:.4g}")
    if not res["all"]["rel_rmse"] <= REL_RMSE[engine]:
        problems.append(f"relative RMSE {res['all']['rel_rmse']:.4g} > {REL_RMSE[engine]}")
    return problems


@pytest.mark.render
@pytest.mark.parametrize("n,method", _params())
def test_many_lights(tmp_path, n, method):
    slow = MEASURED.get((n, method), (None,))[0] == "slow"
    res, text, problems = run_case(tmp_path, n, method, SLOW_TIMEOUT_S if slow else TIMEOUT_S)
    if res is not None:
        problems += picture_problems(res)
        medians = ", ".join(f"{k} {st['median_ratio']:.5g}" for k, st in res["objects"].items() if st.get("pixels"))
        print(f"{n} lights, {method}: fog added in {res['apply_s']:.1f} s, first render {res['render_s']:.1f} s, "
              f"rel RMSE {res['all']['rel_rmse']:.3g}; median render / twin: {medians}; steps {res['steps']}, "
              f"predicted error {res['predicted_error']:.3g}, limited by {res['limited']}")
    assert not problems, f"{n} lights, {method}:\n  " + "\n  ".join(problems)


def test_log_scan_catches_known_errors():
    """The scan flags the messages seen today and leaves the harmless ones alone."""
    bad = ['00:02.812  cycles           | ERROR Shader graph: out of SVM stack space, shader "ground" too big.',
           '00:14.238  gpu.shader       | ERROR MAground Linking: ',
           '                            |       | Error: Uniform block node_tree too big (76960/65536)',
           'Error: Uniform block node_tree too big (76128/65536)',
           'ERROR: shader compilation failed']
    good = ['EGL Error (0x3009): EGL_BAD_MATCH: Arguments are inconsistent (for example, a valid context requires '
            'buffers not supplied by a valid surface).',
            'Error: Not freed memory blocks: 4, total unfreed memory 0.293579 MB',
            "00:02.964  render           | Saved: '/tmp/out/many_CYCLES_nodes_1.exr'",
            'many_lights: 4 lights, CYCLES nodes: fog added in 2.09 s',
            "note: BLENDER_EEVEE: limited by EEVEE's uniform block (64 KiB of node constants per material): "
            "lights step down beyond the target, predicted error 15.16% (render --explain lists each light's "
            "models)"]
    assert len(h.log_errors("\n".join(bad))) == len(bad)
    assert h.log_errors("\n".join(good)) == []


@pytest.mark.render
def test_closure_sum_renders_every_closure(tmp_path):
    """The fog's per-light closure sum (``closures.closure_sum``, surfaces' Emission and the World's
    Background) renders whole in SVM and OSL, for 1 to 256 closures, in a few seconds.

    Cycles' OSL flattens a closure tree with a 16-entry stack (``flatten_closure_tree``,
    intern/cycles/kernel/osl/osl.h: at an Add it walks the first input with the second pushed) and drops,
    without a word, whatever lies below a full stack: the left-deep chain of Add Shader nodes of 85e9c66
    kept the last 16 closures (64 -> 16/64, 256 -> 16/256), the 64-light scene rendered 2-7 % of the
    twin.  The balanced tree needs ceil(log2 N) entries."""
    proc = h.run([h.ROOT / "tests" / "scenes" / "closure_sum_probe.py", tmp_path, 1, 17, 64, 256], timeout=300)
    line = next(ln for ln in proc.stdout.splitlines() if ln.startswith("CLOSURE_SUM_JSON "))
    res = json.loads(line.split(" ", 1)[1])
    for n, r in res.items():
        assert r["osl_stack_depth"] <= max(0, (int(n) - 1).bit_length()), (n, r)
        for key in ("svm_surface", "svm_world", "osl_surface", "osl_world"):
            assert all(abs(x - 1.0) < 1e-5 for x in r[key]), (n, key, r[key])


@pytest.fixture(scope="module")
def switched():
    """tests/scenes/engine_switch.py's result."""
    proc = h.run([h.ROOT / "tests" / "scenes" / "engine_switch.py"], timeout=300)
    line = next(ln for ln in proc.stdout.splitlines() if ln.startswith("ENGINE_SWITCH_JSON "))
    return json.loads(line.split(" ", 1)[1])


@pytest.mark.render
def test_switching_to_eevee_rechooses_within_its_budget(switched):
    """25 lights fit Cycles fully modelled but not EEVEE's uniform block (16 do since 709fad8): switching the
    engine makes the add-on's handler choose again (EEVEE: within the block, saying it is limited), and back."""
    res = switched
    assert res["cycles"]["engine"] == "CYCLES" and not res["cycles"]["fits_eevee"], res["cycles"]
    assert res["eevee"]["engine"] == "BLENDER_EEVEE" and res["eevee"]["fits_eevee"], res["eevee"]
    assert res["eevee"]["limited"] and res["eevee"]["error"] > 0.0, res["eevee"]
    assert res["cycles_again"]["engine"] == "CYCLES" and res["cycles_again"]["limited"] is None, res["cycles_again"]
    assert res["cycles_again"]["steps"] == res["cycles"]["steps"], res


@pytest.mark.render
def test_many_lights_in_cycles_node_groups_are_told_of_the_compositor(switched):
    """With MANY_LIGHTS or more lights in Cycles, the node groups' report says what each material holds (about
    248 nodes a fully modelled light, ``budgets.material_nodes``) and points to the Compositor method, whose
    report does not (tests/scenes/engine_switch.py: 25 lights)."""
    res = switched
    said = [why for _, why in res["notes"]["nodes"] if "Compositor method" in why]
    assert len(said) == 1 and said[0].startswith("25 lights: each fogged material holds about "), res["notes"]
    nodes = int(said[0].split("about ")[1].split(" ")[0].replace(",", ""))
    assert 25 * 63 <= nodes <= 25 * 248, said   # between every light glow only and every light full
    assert not any("Compositor method" in why for _, why in res["notes"]["compositor"]), res["notes"]
