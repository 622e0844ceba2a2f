"""The fog's drivers close no dependency cycle (issue 43, item 6): Blender printed "Detected 6 dependency cycles" on
every depsgraph evaluation of a daylight fog (a Fog Top and a Sun), the fog's World group driven by the World's own
Background, and a driver in a cycle may read a value of the frame before in an animation.

One Blender (bpy) process, no render (tests/scenes/dependency_cycles.py): the fog added in the scenes the tests
build most, Blender's log (stderr, sent into stdout) read case by case, every driver of the fog checked against its
variables on frames 1, 10 and 5 of an animation (a lamp moving, a sun turning, the sky brightening)."""
import json
import re

import pytest

from fog_scenes import render_harness as h

pytestmark = pytest.mark.render   # starts Blender (bpy) in a subprocess

SCRIPT = h.ROOT / "tests" / "scenes" / "dependency_cycles.py"
CORE = ["point_compositor", "daylight_nodes", "daylight_compositor"]   # the default tier's: the defect's cases
REST = ["point_nodes", "dense", "spot", "area"]                       # the slow tier's
PROBES = ["probe_group_world", "probe_tree", "probe_context"]
FOG_CASES = [*CORE, *(pytest.param(c, marks=pytest.mark.slow) for c in REST)]
CYCLE = re.compile(r"(?i)dependency cycle")
_RUNS = {}


@pytest.fixture(scope="module")
def runs():
    """One Blender process for the default tier's cases and the probes, another (slow tier) for the rest."""
    def get(case):
        cases = tuple(REST) if case in REST else (*CORE, *PROBES)
        if cases not in _RUNS:
            _RUNS[cases] = _run(cases)
        return _RUNS[cases]
    return get


@pytest.fixture(scope="module")
def run(runs):
    return runs(CORE[0])


def _run(cases):
    proc = h.run([SCRIPT, *cases], timeout=600)
    # Blender's log, the control probes' deliberate cycles left out (each case's cycles are checked below)
    assert not [e for e in h.log_errors(proc.stdout + proc.stderr) if not CYCLE.search(e)]
    logs, case = {}, None
    for line in proc.stdout.splitlines():
        if line.startswith("=== CASE "):
            case = line.split(" ", 2)[2]
            logs[case] = []
        elif case is not None:
            logs[case].append(line)
    line = next(ln for ln in proc.stdout.splitlines() if ln.startswith("CYCLES_JSON "))
    return logs, json.loads(line.split(" ", 1)[1]), proc.stderr


def test_the_log_is_read_case_by_case(run):
    """Every case printed its marker, and Blender's C log reached stdout (nothing left on stderr to miss)."""
    logs, res, stderr = run
    assert list(logs) == CORE + PROBES + ["end"]
    assert not CYCLE.search(stderr)


@pytest.mark.parametrize("case", PROBES)
def test_a_world_read_into_its_own_shading_is_a_cycle(run, case):
    """The positive control: each way a driver could bring the World's Background into a group of the World's own
    tree (``sunsky._sky``) makes Blender 5.0 print cycles, under its own case.  If one stops doing so, the World
    group's copy of the sky can be driven again."""
    logs, _, _ = run
    assert any(CYCLE.search(line) for line in logs[case]), (case, logs[case])


@pytest.mark.parametrize("case", FOG_CASES)
def test_no_dependency_cycle(runs, case):
    logs, res, _ = runs(case)
    assert res[case]["added"] == ["FINISHED"]
    cycles = [line for line in logs[case] if CYCLE.search(line)]
    assert cycles == [], (case, cycles[:8])


@pytest.mark.parametrize("case", FOG_CASES)
def test_every_driver_follows_the_frame(runs, case):
    """On frames 1, 10 and 5 every driver of the fog holds the value of its variables on that frame (none stale)."""
    _, res, _ = runs(case)
    for frame, f in res[case]["frames"].items():
        assert f["drivers"] >= 10, (case, frame, f["drivers"])
        assert f["n_stale"] == 0, (case, frame, f["stale"])


@pytest.mark.parametrize("case", ["daylight_nodes", "daylight_compositor"])
def test_the_driven_sun_follows_the_sun(run, case):
    """The sun turned between frames 1 and 10: every 'Sun Direction' node holds its direction on frames 1, 10, 5."""
    _, res, _ = run
    frames = res[case]["frames"]
    assert max(abs(a - b) for a, b in zip(frames["1"]["sun"], frames["10"]["sun"])) > 0.3
    for frame, f in frames.items():
        assert len(f["sun_driven"]) >= 2, (case, frame)   # the Surface's (or the compositor's) and the World's
        for driven in f["sun_driven"]:
            assert max(abs(a - b) for a, b in zip(driven, f["sun"])) < 1e-6, (case, frame, driven, f["sun"])
    assert frames["10"]["strength"] == pytest.approx(2.0)   # the World's Background Strength, keyed 1 -> 2


@pytest.mark.parametrize("case", ["daylight_nodes", "daylight_compositor"])
def test_the_world_groups_sky_is_set_from_the_background(run, case):
    """The World group holds a copy of the uniform sky's radiance (not a driver: a cycle), as built and after the
    sky's colour changed (the fog's depsgraph handler sets it again); an animated Background is noted where the
    World group's sky glow reads it (Node Groups, sun and camera still)."""
    _, res, _ = run
    r = res[case]
    for key in ("world_sky_built", "world_sky_refreshed"):
        sky, copies = r[key]["sky"], r[key]["world_group"]
        assert len(copies) == 1, (case, key, copies)
        assert copies[0] == pytest.approx(sky, rel=1e-6, abs=1e-9), (case, key)
    assert r["world_sky_refreshed"]["sky"] != pytest.approx(r["world_sky_built"]["sky"], rel=0.1)
    assert len(r["notes"]["nodes"]) == 1 and "Background is animated" in r["notes"]["nodes"][0][1]
    assert r["notes"]["compositor"] == []
