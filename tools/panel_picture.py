"""A picture of the Analytic Fog panel, drawn from the panel's own draw code (there is no display to screenshot).

    .venv/bin/python tools/panel_picture.py [OUT.png]      (default docs/figures/panel.png)

Builds the spheres demo scene in Blender (bpy), adds the fog, and calls ``ui.draw_fog`` with a layout that
records every row, property, operator and label the panel draws, with the property's name and value as
Blender shows them; matplotlib then draws those rows in Blender's dark theme.  So the picture follows the
panel's code: a setting added to ``draw_fog`` appears in it the next time this runs.
"""
import pathlib
import sys

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))


ICONS = {"X": "x", "ADD": "+", "REMOVE": "-", "FILE_REFRESH": "", "ERROR": "(!)", "INFO": "(i)",
         "LIGHT_POINT": "", "DOT": "-"}


class Recorder:
    """Stands in for a ``bpy.types.UILayout``: records what ``draw_fog`` puts in the panel, in order; a row's
    items share one line."""

    def __init__(self, rows, depth=0, line=None, heading=""):
        self.rows, self.depth, self.line, self.heading = rows, depth, line, heading
        self.use_property_split = self.active = self.enabled = True

    def column(self, heading="", **_):
        return Recorder(self.rows, self.depth, self.line, heading)

    def row(self, heading="", **_):
        if self.line is not None:
            return Recorder(self.rows, self.depth, self.line)
        line = ["row", [heading] if heading else [], self.depth]
        self.rows.append(line)
        return Recorder(self.rows, self.depth, line)

    def box(self):
        self.rows.append(["box", [], self.depth])
        return Recorder(self.rows, self.depth + 1)

    def _put(self, kind, text):
        if self.line is not None:
            self.line[1].append(text)
            if kind == "button":
                self.line[0] = "button"
        else:
            self.rows.append([kind, [text], self.depth])

    def prop(self, data, name, text=None, **_):
        prop = data.bl_rna.properties[name]
        value = getattr(data, name)
        if prop.type == "ENUM":
            value = next(i.name for i in prop.enum_items if i.identifier == value)
        elif prop.type == "BOOLEAN":
            value = "[x]" if value else "[ ]"
        elif prop.type == "FLOAT" and getattr(prop, "array_length", 0):
            value = "(" + ", ".join(f"{v:.2g}" for v in value) + ")"
        elif prop.type == "FLOAT":
            value = f"{value:.4g}" + (" m" if prop.subtype == "DISTANCE" else "")
        label = prop.name if text is None else text
        self._put("prop", f"{label}: {value}" if label else str(value))

    def operator(self, idname, text=None, icon=None, **_):
        self._put("button", text if text else f"[{ICONS.get(icon, icon or idname)}]")
        return type("Props", (), {})()

    def menu(self, name, text=None, **_):
        self._put("button", f"{text or name} v")

    def label(self, text="", icon=None, **_):
        mark = ICONS.get(icon, "") if icon else ""
        self._put("label", f"{mark} {text}".strip())


def record(**settings):
    """The rows the panel draws for the spheres demo with the fog added (Method Auto, Quality default), the scene's
    fog ``settings`` (``scene.analytic_fog`` properties) set before."""
    import bpy
    import fog_addon
    from demo_scenes import spheres
    from fog_addon import ui
    bpy.ops.wm.read_factory_settings(use_empty=True)
    fog_addon.register()
    scene = bpy.context.scene
    spheres.build(scene)
    scene.render.engine = "CYCLES"
    for key, value in settings.items():
        setattr(scene.analytic_fog, key, value)
    bpy.ops.fog.add(preset="MIST")
    rows = []
    context = type("Context", (), {"scene": scene})()
    ui.draw_fog(Recorder(rows), context)
    return rows


def draw(rows, out):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    line_h, width = 0.32, 7.2
    fig = plt.figure(figsize=(width, line_h * (len(rows) + 2)), dpi=110)
    fig.patch.set_facecolor("#303030")
    ax = fig.add_axes([0, 0, 1, 1])
    ax.set_xlim(0, width)
    ax.set_ylim(-(len(rows) + 1.5) * line_h, 0.2)
    ax.axis("off")
    ax.text(0.15, -0.05, "v  Analytic Fog", color="#e6e6e6", fontsize=10, weight="bold", va="top")
    for k, (kind, parts, depth) in enumerate(rows):
        text = "   ".join(parts)
        y, x = -(k + 1.2) * line_h, 0.3 + 0.25 * depth
        if kind == "box":
            ax.plot([x - 0.1, width - 0.2], [y + 0.05, y + 0.05], color="#505050", lw=1)
            continue
        if kind == "button":
            ax.add_patch(plt.Rectangle((x - 0.05, y - 0.24), width - x - 0.25, 0.26, color="#545454"))
        colour = {"prop": "#e6e6e6", "button": "#ffffff", "label": "#b0b0b0"}.get(kind, "#e6e6e6")
        shown = text if len(text) < 96 else text[:93] + "..."
        ax.text(x, y, shown, color=colour, fontsize=7.5, va="top", family="DejaVu Sans")
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, facecolor=fig.get_facecolor())
    print(f"wrote {out} ({len(rows)} rows)")


if __name__ == "__main__":
    draw(record(), pathlib.Path(sys.argv[1]) if len(sys.argv) > 1 else ROOT / "docs" / "figures" / "panel.png")
