"""A saved file with the compositor's fog light, driven, rendered on another frame without the add-on.

    .venv/bin/python benchmarks/compositor_fog/farm_check.py OUT_DIR

The many-lights scene (4 lights, 160x90, 16 spp) with the camera moving and turning and a lamp moving and
brightening between frames 1 and 2.  (a) The fog is added at frame 1 with ``to_compositor(drive=True)``
and the file saved; a fresh process that only opens it renders frame 2.  (b) The same scene is set to
frame 2 and the fog added there with constants.  Prints (a)'s relative RMSE against (b), and against (b)'s
frame-1 twin (what (a) would show if its drivers did not follow).
"""
import json
import pathlib
import subprocess
import sys

HERE = pathlib.Path(__file__).resolve().parent
ROOT = HERE.parents[1]
sys.path[:0] = [str(ROOT), str(ROOT / "tests" / "scenes"), str(HERE)]


def scene_at(frame):
    """The animated scene, fogged and moved to the compositor at ``frame`` (constants unless frame is 0:
    then frame 1, driven)."""
    import bpy
    import build
    import many_lights
    from fog_addon import measure
    from fog_addon.ops import apply
    scene, cam = many_lights.build_scene(4, direct_light=True)
    scene.render.engine = "CYCLES"
    measure.set_resolution(scene, 160, 90)
    measure.set_samples(scene, 16)
    measure.set_cycles_cpu(scene)
    scene.cycles.use_denoising = False
    lamp = next(o for o in scene.objects if o.type == "LIGHT")
    for f, (dx, turn, lift, watts) in ((1, (0.0, 0.0, 0.0, 1.0)), (2, (0.8, 0.05, 0.6, 2.5))):
        scene.frame_set(f)
        cam.location.x += dx
        cam.rotation_euler.z += turn
        cam.keyframe_insert("location", frame=f)
        cam.keyframe_insert("rotation_euler", frame=f)
        lamp.location.z += lift
        lamp.keyframe_insert("location", frame=f)
        lamp.data.energy *= watts
        lamp.data.keyframe_insert("energy", frame=f)
        lamp.location.z -= lift
        lamp.data.energy /= watts
        cam.location.x -= dx
        cam.rotation_euler.z -= turn
    scene.frame_set(frame or 1)
    bpy.context.view_layer.update()
    apply.apply_fog(scene, many_lights.BETA, albedo=many_lights.ALBEDO)
    build.to_compositor(scene, drive=frame == 0)
    return scene


def make(blend):
    import bpy
    scene_at(0)
    bpy.ops.wm.save_as_mainfile(filepath=blend)


def render_frame(frame, out):
    import bpy
    from fog_addon import measure
    scene = scene_at(frame)
    measure.render_to_file(scene, out)


def main(out_dir):
    out = pathlib.Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    blend = str(out / "farm_check.blend")
    run = [sys.executable, __file__]
    subprocess.run(run + ["--make", blend], check=True, capture_output=True)
    farm = (f"import bpy; bpy.ops.wm.open_mainfile(filepath={blend!r}); s = bpy.context.scene; "
            f"s.frame_set(2); s.render.filepath = {str(out / 'farm_2.exr')!r}; "
            "s.render.image_settings.file_format = 'OPEN_EXR'; bpy.ops.render.render(write_still=True)")
    subprocess.run([sys.executable, "-c", farm], check=True, capture_output=True)
    for f in (1, 2):
        subprocess.run(run + ["--frame", str(f), str(out / f"const_{f}.exr")], check=True, capture_output=True)
    from fog_addon import compare
    print(json.dumps({f"farm frame 2 against constants at frame {f}":
                      compare.compare_files(out / "farm_2.exr", out / f"const_{f}.exr")["rel_rmse"] for f in (2, 1)}))


if __name__ == "__main__":
    if sys.argv[1] == "--make":
        make(sys.argv[2])
    elif sys.argv[1] == "--frame":
        render_frame(int(sys.argv[2]), sys.argv[3])
    else:
        main(sys.argv[1])
