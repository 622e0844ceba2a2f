"""Shared by the cost benchmarks' workers (inside bpy): a scene set to Cycles on the CPU, and a render timed."""
import time


def cycles_cpu(scene, width, height, samples):
    """``scene`` rendered by Cycles on the CPU at ``width`` x ``height`` and ``samples`` spp, no denoising."""
    from fog_addon import measure
    scene.render.engine = "CYCLES"
    measure.set_resolution(scene, width, height)
    measure.set_samples(scene, samples)
    measure.set_cycles_cpu(scene)
    scene.cycles.use_denoising = False


def timed_render():
    """(wall s, CPU s) of one render of the context's scene."""
    import bpy
    c, t = time.process_time(), time.perf_counter()
    bpy.ops.render.render()
    return time.perf_counter() - t, time.process_time() - c


def warm(repeats):
    """(least wall s, least CPU s) of ``repeats`` renders after a first one (shader compilation, the compositor's
    set-up) that is not counted."""
    timed_render()
    runs = [timed_render() for _ in range(repeats)]
    return min(r[0] for r in runs), min(r[1] for r in runs)


def timed_apply(scene, spec):
    """Wall s of applying the fog ``spec`` (a FogSpec) to ``scene``."""
    from fog_addon.ops import apply
    t = time.perf_counter()
    apply.apply(scene, spec)
    return time.perf_counter() - t
