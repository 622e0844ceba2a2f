"""Does a driver on a compositor group's input follow an animated light in a farm render?

    .venv/bin/python benchmarks/compositor_fog/driver_check.py OUT_DIR

Saves a file whose compositor group multiplies its input by 10, the input driven (simple expression) by
an animated light's world X (1 at frame 1, 5 at frame 2); renders frames 1-2 in a fresh process that
only opens the file (no add-on); prints the composite's value per frame: 10 and 50 if the compositor
evaluates the driver on every frame.
"""
import pathlib
import subprocess
import sys

ROOT = pathlib.Path(__file__).resolve().parents[2]


def make(blend, frames):
    import bpy
    bpy.ops.wm.read_factory_settings(use_empty=True)
    sc = bpy.context.scene
    sc.render.engine = "CYCLES"
    sc.cycles.samples = 1
    sc.render.resolution_x, sc.render.resolution_y = 8, 4
    cam = bpy.data.objects.new("Cam", bpy.data.cameras.new("Cam"))
    sc.collection.objects.link(cam)
    sc.camera = cam
    lamp = bpy.data.objects.new("L", bpy.data.lights.new("L", "POINT"))
    sc.collection.objects.link(lamp)
    for frame, x in ((1, 1.0), (2, 5.0)):
        lamp.location = (x, 0.0, 0.0)
        lamp.keyframe_insert("location", frame=frame)
    group = bpy.data.node_groups.new("G", "CompositorNodeTree")
    group.interface.new_socket("X", in_out="INPUT", socket_type="NodeSocketFloat")
    group.interface.new_socket("O", in_out="OUTPUT", socket_type="NodeSocketFloat")
    gin, gout = group.nodes.new("NodeGroupInput"), group.nodes.new("NodeGroupOutput")
    times = group.nodes.new("ShaderNodeMath")
    times.operation = "MULTIPLY"
    times.inputs[1].default_value = 10.0
    group.links.new(gin.outputs[0], times.inputs[0])
    group.links.new(times.outputs[0], gout.inputs[0])
    tree = bpy.data.node_groups.new("C", "CompositorNodeTree")
    tree.interface.new_socket("Image", in_out="OUTPUT", socket_type="NodeSocketColor")
    tree.nodes.new("CompositorNodeRLayers")
    node = tree.nodes.new("CompositorNodeGroup")
    node.node_tree = group
    driver = node.inputs[0].driver_add("default_value").driver
    driver.type, driver.expression = "SCRIPTED", "x"
    var = driver.variables.new()
    var.name, var.type = "x", "TRANSFORMS"
    var.targets[0].id, var.targets[0].transform_type = lamp, "LOC_X"
    var.targets[0].transform_space = "WORLD_SPACE"
    vec = tree.nodes.new("ShaderNodeCombineXYZ")
    tree.links.new(node.outputs[0], vec.inputs[0])
    tree.links.new(vec.outputs[0], tree.nodes.new("NodeGroupOutput").inputs[0])
    sc.compositing_node_group = tree
    sc.render.use_compositing = True
    sc.render.image_settings.file_format = "OPEN_EXR"
    sc.render.filepath = frames
    sc.frame_start, sc.frame_end = 1, 2
    bpy.ops.wm.save_as_mainfile(filepath=blend)


def main(out_dir):
    out = pathlib.Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    blend, frames = str(out / "driver_check.blend"), str(out / "frame_")
    subprocess.run([sys.executable, __file__, "--make", blend, frames], check=True, capture_output=True)
    render = (f"import bpy; bpy.ops.wm.open_mainfile(filepath={blend!r}); "
              "bpy.ops.render.render(animation=True)")
    subprocess.run([sys.executable, "-c", render], check=True, capture_output=True)
    sys.path.insert(0, str(ROOT))
    from fog_addon import imageio
    for frame in (1, 2):
        print(f"frame {frame}: {float(imageio.read(f'{frames}{frame:04d}.exr')[0, 0, 0]):g}")


if __name__ == "__main__":
    if sys.argv[1] == "--make":
        make(sys.argv[2], sys.argv[3])
    else:
        main(sys.argv[1])
