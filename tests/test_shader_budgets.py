"""The shader budgets against the renderers: for each engine whose size limit the add-on budgets (EEVEE's uniform
block for the Node Groups method, OSL's shader group for the OSL method) and each light kind, at one ladder step,
the largest number of lights the add-on's budget (``budgets.eevee_budget``, ``budgets.osl_budget``) lets one
material hold must render clean, and the measured limit plus one must not.  A budget one light too generous
then fails at its own N; a measurement that no longer holds (the shaders grew or shrank) fails at the limit
plus one; a budget that wastes room fails the arithmetic check that its N is the measured limit (``MARGIN``
below it at most, where the budget keeps one).

Each probe is a fresh Blender process (``benchmarks/shader_budgets.py``, ``tests/scenes/shader_budgets.py``):
N lights of one kind above a ground and a glossy sphere, fog added by the operator with every light forced to
the case's ladder step, g = 0.85; in EEVEE point lights with Dense Fog too (multiple scattering's tables).

* EEVEE: the file saved and reopened (as a farm renders it: Blender does not save the inline marks of the
  fog's constants), rendered at 8 x 8 px; clean = no "Uniform block ... too big (X/65536)" line.
* OSL: Cycles numbers a shader group's layers with a signed 16-bit index; a material past 32 767 layers crashes
  while OSL optimises it.  Every node of a material, its groups inlined, becomes a layer before Cycles' own
  simplification, which removes some: the inlined node count bounds the layers, and the budget holds the
  lights whose count stays within 32 767.  So the OSL cases' verdict is that count (the probe's ``--count``: the
  scene built, no render), which a render cannot give: past the count's limit a render may still pass (9 area
  lights, 34 464 nodes, rendered clean), and the layer count at which it crashes was not measured.  The area
  light case also renders the budget's N (8 area lights, about 90 s); renders of the budget's 153 points or
  48 spots are left out for time.

The measured limits are read from the measurement (benchmarks/shader_budgets/budgets.json, written by
``shader_budgets.py run``; ``+count``: OSL's from the node count).  4 minutes on 2 shared cores with Mesa's
shader cache warm (~/.cache/mesa_shader_cache: EEVEE's shaders compiled before), about 10 with it cold.
"""
import json
import sys

import pytest

from fog_scenes import render_harness as h

sys.path.insert(0, str(h.ROOT / "benchmarks"))
import shader_budgets as sb  # noqa: E402

pytestmark = [pytest.mark.render, pytest.mark.slow]

MEASURED = h.ROOT / "benchmarks" / "shader_budgets" / "budgets.json"
CAP = 1024   # more lights than any budget allows one material (the search below stops there)
MARGIN = {"osl": 0, "eevee": 0}   # how far below the measured limit a budget may stay (lights)

# (engine, kind, step, render the budget's N): one step per kind; OSL's verdicts are node counts (the docstring)
CASES = [
    ("eevee", "point", "full", True),
    ("eevee", "spot", "full", True),
    ("eevee", "area", "full", True),
    ("eevee", "point_dense", "full", True),
    ("osl", "point", "full", False),
    ("osl", "spot", "full", False),
    ("osl", "area", "full", True),
]


def budget_n(engine, kind, step):
    """The largest N of ``kind`` lights at ``step`` the add-on's budget lets one material hold."""
    from fog_addon.nodes import budgets  # noqa: PLC0415 (bpy)
    ltype, dense, _ = sb.KINDS[kind]
    shaped, area = ltype in ("SPOT", "AREA"), ltype == "AREA"
    k = sb.STEPS[step]
    for n in range(CAP):
        spots, areas = [shaped] * (n + 1), [area] * (n + 1)
        budget = (budgets.osl_budget(spots, areas, allowance=0) if engine == "osl"   # the per-light costs alone
                  else budgets.eevee_budget(sb.ANISOTROPY, spots, areas, dense, allowance=0))
        if not budget.fits([k] * (n + 1)):
            return n
    return CAP


def measured_limit(engine, kind, step):
    key = f"{kind}/{step}/{engine}" + ("+count" if engine == "osl" else "")
    case = json.loads(MEASURED.read_text())["cases"].get(key, {})
    assert case.get("limit") is not None, f"no measured limit for {key} in {MEASURED}"
    return case["limit"]


def within_osl(r):
    """The fogged materials' and the World's inlined node counts are within OSL's 32 767 layers."""
    return bool(r["nodes"]) and max(r["nodes"].values()) <= sb.OSL_LAYERS


def _verdict(r):
    return (f"rc {r['rc']}, bytes {r['uniform_bytes']}, nodes {r['nodes']}, black {r['black']}, "
            f"errors {r['errors'][:2]}")


@pytest.mark.parametrize("engine,kind,step,render", CASES, ids=[f"{e}-{k}-{s}" for e, k, s, _ in CASES])
def test_budget_is_the_renderers_limit(engine, kind, step, render):
    limit = measured_limit(engine, kind, step)
    n = budget_n(engine, kind, step)
    assert limit - MARGIN[engine] <= n, (f"the {engine} budget holds {n} {kind} lights at {step}; {limit} were "
                                         f"measured to fit: it wastes room")
    osl = engine == "osl"
    if n >= 1:
        at = sb.run_probe(kind, step, engine, n, render=render)
        assert at["clean"] and (not osl or within_osl(at)), (
            f"the {engine} budget lets {n} {kind} lights at {step} into a material, which do not "
            f"{'render clean' if render else 'stay within 32 767 nodes'}: {_verdict(at)}")
    over = sb.run_probe(kind, step, engine, limit + 1, render=not osl)
    assert not (within_osl(over) if osl else over["clean"]), (
        f"{limit + 1} {kind} lights at {step} fit {engine} ({_verdict(over)}): the measured limit {limit} no longer "
        f"holds; measure again (benchmarks/shader_budgets.py run)")


@pytest.mark.parametrize("n", [1, 3])
def test_spots_with_a_fog_top_and_passes_fit_svm(n):
    """Cycles' SVM: spots with a Fog Top and the Fog Passes render clean (each spot's glow and the rest of its fog
    light are two closures: ``closures.closure_sum``'s ``gates``).  One spot took 255 floats of SVM's stack (out of
    stack space, the material black) when the passes merged them into one closure; 153 since, 191 at 3 spots."""
    r = sb.run_probe("spot", "full", "svm", n, passes=True, top=True)
    assert r["clean"], r
