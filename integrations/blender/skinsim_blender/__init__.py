"""skinsim for Blender: an abrasion-healing timeline (or procedural skin
textures) on the selected mesh.

What it does: for the active mesh object, runs the `skinsim abrasion`
command (seed 000's texture timeline) for a wound painted as a circle (or
strokes from a CSV file) in the mesh's UV space, at a list of days, and
builds a Principled BSDF material from the texture sets: base colour (sRGB),
roughness (1 - 0.8 x reflection, as skinsim's glTF output), specular
(reflection), normal (a Normal Map node, tangent space, Non-Color images)
and height (a Displacement node into the material output; Cycles uses it as
bump by default). Time: the material gets a `skinsim_day` property keyed on
Blender's timeline (frame = start + day x frames per day), and every map's
chain of Mix nodes is driven by it, so between two sampled days the maps are
blended linearly -- the timeline's own blend between key positions (seed
000 §3.2) when the sampled days include the key days, as the default list
does. Retiming the healing is editing the `skinsim_day` curve.

Why the command line rather than the Python package: the CLI is the one
interface every Blender build can use (Blender bundles its own Python, which
may lack numpy or not match the installed package), it writes the PNGs the
material needs anyway, and its error messages are the ones users already
see. A failing run is reported with the command's own message and leaves the
scene untouched.

The "Skin textures" source runs `skinsim skin` over the whole UV square and
wires its base colour, roughness, specular, normal and height (scaled by
skin.json's height range) into a static material; "Procedural skin around
the wound" gives that skin's colour to the abrasion as its healthy skin.

Gave up: the maturation phase (after the scab falls off) is re-rendered by
skinsim at every time; here it is sampled at the listed days and blended
linearly in between. The "Healing simulation" source runs `skinsim wound`
(seed 001's healing turned into textures) on a block of block_mm around the
wound and places its timeline inside the UV square with a Mapping node,
blended over the outer tenth of the block into `skinsim skin`'s textures;
the block's base skin is the same procedural skin made at the block's scale
(skinsim wound --skin).

Settings live on each object (Object.skinsim), so two meshes keep their own
wound, days and folder. From the UI the build runs as a modal job: the
skinsim commands run one after another as child processes while Blender
stays responsive, with a progress bar and the step in the status bar; Esc
cancels (the running command is stopped, nothing in the scene changes).
Called from a script (bpy.ops.skinsim.build_material()) or in background
mode it runs to the end before returning. Every failure -- a bad day list,
an output folder that cannot be made, a command that exits non-zero -- is
reported with report() and kept in the object's last_error.

The same file is a legacy add-on (bl_info, Blender 3.x-4.1) and, with
blender_manifest.toml beside it, a Blender 4.2+ extension (`make
blender-extension` zips the two).
"""

bl_info = {
    "name": "skinsim",
    "author": "skinsim contributors",
    "version": (0, 1, 0),
    "blender": (3, 4, 0),
    "location": "Properties > Material > skinsim",
    "description": "Abrasion-healing texture timelines from skinsim on the selected mesh",
    "category": "Material",
}

import math
import os
import shutil
import subprocess
import tempfile

import bpy

DEFAULT_DAYS = "0,0.007,0.02,0.5,1,3,10,10.01,15,20,30"
DEFAULT_HEAL_DAYS = "0,1,2,3,5,7,10,14,21"
MAPS = ("color", "reflection", "height", "normal")


# ---- settings ------------------------------------------------------------------


class SkinsimPreferences(bpy.types.AddonPreferences):
    bl_idname = __name__
    cli: bpy.props.StringProperty(
        name="skinsim command",
        description="Path of the skinsim program (empty: $SKINSIM_CLI, else skinsim on PATH)",
        subtype="FILE_PATH",
        default="",
    )

    def draw(self, context):
        self.layout.prop(self, "cli")


class SkinsimSettings(bpy.types.PropertyGroup):
    source: bpy.props.EnumProperty(
        name="Source",
        items=[("ABRASION", "Abrasion timeline", "skinsim abrasion: a wound healing over days"),
               ("HEAL", "Healing simulation", "skinsim wound: the simulated healing (seed 001) "
                "as textures in a block around the wound, over procedural skin"),
               ("SKIN", "Skin textures", "skinsim skin: procedural skin (moles, freckles, "
                "follicles, wrinkles), no timeline")],
        default="ABRASION")
    skin_under_abrasion: bpy.props.BoolProperty(
        name="Procedural skin around the wound", default=False,
        description="Run skinsim skin first and use its colour as the healthy skin of the "
                    "abrasion (--upper)")
    wound_u: bpy.props.FloatProperty(name="Wound U", min=0.0, max=1.0, default=0.25,
                                     description="Wound centre, U in the mesh's UV map")
    wound_v: bpy.props.FloatProperty(name="Wound V", min=0.0, max=1.0, default=0.38,
                                     description="Wound centre, V in the mesh's UV map (up)")
    wound_radius: bpy.props.FloatProperty(name="Radius", min=0.0, max=0.5, default=0.05,
                                          description="Wound radius in UV units")
    stroke_csv: bpy.props.StringProperty(
        name="Strokes CSV", subtype="FILE_PATH", default="",
        description="Painted strokes (skinsim's u,v[,id] CSV, v down) instead of the circle")
    size: bpy.props.IntProperty(name="Texture size", min=16, max=16384, default=1024)
    world_size_cm: bpy.props.FloatProperty(
        name="UV square (cm)", min=0.1, default=23.0,
        description="Side of the whole UV square on the body, in cm (noise and edge scale)")
    days: bpy.props.StringProperty(name="Days", default=DEFAULT_DAYS,
                                   description="Days since injury to sample, comma separated")
    heal_days: bpy.props.StringProperty(
        name="Healing days", default=DEFAULT_HEAL_DAYS,
        description="Days to simulate and show (whole steps of 0.05 days), comma separated")
    block_mm: bpy.props.FloatProperty(
        name="Block (mm)", min=4.0, max=200.0, default=40.0,
        description="Side of the simulated skin block around the wound, in mm")
    start_frame: bpy.props.IntProperty(name="Start frame", default=1)
    frames_per_day: bpy.props.FloatProperty(name="Frames per day", min=0.001, default=4.0)
    seed: bpy.props.IntProperty(name="Seed", min=0, default=1)
    out_dir: bpy.props.StringProperty(
        name="Output folder", subtype="DIR_PATH", default="",
        description="Where the textures go (empty: //skinsim_<object> next to the .blend, "
                    "or a temporary folder for an unsaved file)")
    last_error: bpy.props.StringProperty(name="Last error", default="")


def find_cli(context):
    prefs = context.preferences.addons.get(__name__)
    path = prefs.preferences.cli if prefs else ""
    path = bpy.path.abspath(path) if path else os.environ.get("SKINSIM_CLI", "")
    if path:
        return path
    return shutil.which("skinsim") or "skinsim"


def parse_days(text):
    """The day list as increasing floats; ValueError naming the bad entry."""
    days = []
    for tok in text.replace(";", ",").split(","):
        tok = tok.strip()
        if not tok:
            continue
        try:
            d = float(tok)
        except ValueError:
            raise ValueError("Days: %r is not a number" % tok)
        if not math.isfinite(d) or d < 0:
            raise ValueError("Days: %r must be a finite number >= 0" % tok)
        days.append(d)
    if len(days) < 2:
        raise ValueError("Days: need at least two days, got %r" % text)
    if any(b <= a for a, b in zip(days, days[1:])):
        raise ValueError("Days: must increase, got %r" % text)
    return days


def circle_strokes(u, v_up, r, n=24):
    """A circle of n points in skinsim's stroke CSV (v down)."""
    lines = ["u,v"]
    for i in range(n):
        a = 2 * math.pi * i / n
        uu = min(max(u + r * math.cos(a), 0.0), 1.0)
        vv = min(max(1.0 - (v_up + r * math.sin(a)), 0.0), 1.0)
        lines.append("%.6f,%.6f" % (uu, vv))
    return "\n".join(lines) + "\n"


def day_label(d):
    """The file stem the CLI writes for day d (printf %g)."""
    s = "%g" % d
    return "t" + s


# ---- running skinsim ---------------------------------------------------------------


def _run(cmd, cli):
    try:
        p = subprocess.run(cmd, capture_output=True, text=True)
    except OSError as e:
        raise RuntimeError("cannot run skinsim (%s): %s; set its path in the add-on's "
                           "preferences or $SKINSIM_CLI" % (cli, e.strerror))
    if p.returncode != 0:
        msg = (p.stderr or p.stdout).strip().splitlines()
        raise RuntimeError(msg[-1] if msg else "skinsim exited with code %d" % p.returncode)


def skin_command(cli, settings, out_dir, world_size_cm=None, size=None):
    """The `skinsim skin` command (default: over the whole UV square)."""
    return [cli, "skin", "--size", str(size or settings.size), "--world-size-cm",
            repr(world_size_cm or settings.world_size_cm), "--seed", str(settings.seed),
            "--quiet", "--out", out_dir]


def run_skin(cli, settings, out_dir, world_size_cm=None, size=None):
    """Runs `skinsim skin`; returns its folder."""
    os.makedirs(os.path.dirname(os.path.abspath(out_dir)) or ".", exist_ok=True)
    _run(skin_command(cli, settings, out_dir, world_size_cm, size), cli)
    return out_dir


def block_uv(settings):
    """Side of the healing block in UV units and its lower-left UV corner."""
    side = settings.block_mm / (10.0 * settings.world_size_cm)
    return side, (settings.wound_u - side / 2, settings.wound_v - side / 2)


def wound_command(cli, settings, days, out_dir, skin_bio, tmp):
    """The `skinsim wound` command on a block of block_mm around the wound
    (the circle, written into tmp, or the strokes CSV in the block's own 0..1
    coordinates) and its frames folder."""
    side, _ = block_uv(settings)
    if settings.stroke_csv:
        stroke = bpy.path.abspath(settings.stroke_csv)
    else:
        r = settings.wound_radius / side
        if not 0 < r < 0.45:
            raise RuntimeError("Radius: the wound (%.1f mm across) must fit the block of "
                               "%g mm with a margin" % (2 * settings.wound_radius *
                                                        settings.world_size_cm * 10,
                                                        settings.block_mm))
        stroke = os.path.join(tmp, "wound_block.csv")
        with open(stroke, "w") as f:
            f.write(circle_strokes(0.5, 0.5, r))
    b = "%g" % settings.block_mm
    cmd = [cli, "wound", "--stroke", stroke, "--size-mm", "%s,%s,4" % (b, b),
           "--size", str(min(settings.size, 1024)), "--days", ",".join("%g" % d for d in days),
           "--seed", str(settings.seed), "--no-compare", "--quiet", "--out", out_dir]
    if skin_bio:
        cmd += ["--skin", skin_bio]
    return cmd, os.path.join(out_dir, "frames")


def abrasion_command(cli, settings, days, out_dir, upper, tmp):
    """The `skinsim abrasion` command (the circle written into tmp, or the
    strokes CSV) and its frames folder."""
    if settings.stroke_csv:
        stroke = bpy.path.abspath(settings.stroke_csv)
    else:
        if settings.wound_radius <= 0:
            raise RuntimeError("Radius: the wound radius must be > 0")
        stroke = os.path.join(tmp, "wound.csv")
        with open(stroke, "w") as f:
            f.write(circle_strokes(settings.wound_u, settings.wound_v, settings.wound_radius))
    cmd = [cli, "abrasion", "--stroke", stroke, "--size", str(settings.size),
           "--world-size-cm", repr(settings.world_size_cm), "--seed", str(settings.seed),
           "--times", ",".join("%g" % d for d in days), "--out", out_dir, "--quiet"]
    if upper:
        cmd += ["--upper", upper]
    return cmd, os.path.join(out_dir, "frames")


# ---- the material --------------------------------------------------------------------


def _input(node, *names):
    """A node input by the first name that exists (names changed across
    Blender versions, e.g. Principled 'Specular' -> 'Specular IOR Level')."""
    for n in names:
        if n in node.inputs:
            return node.inputs[n]
    raise KeyError("%s has none of the inputs %s" % (node.bl_idname, names))


def _separate(nt):
    """A node that splits a colour (its first output is the red/grey value)."""
    kind = "ShaderNodeSeparateColor" if hasattr(bpy.types, "ShaderNodeSeparateColor") else \
        "ShaderNodeSeparateRGB"
    return nt.nodes.new(kind)


def _load_image(path, non_color):
    img = bpy.data.images.load(path, check_existing=False)
    img.colorspace_settings.name = "Non-Color" if non_color else "sRGB"
    return img


def _day_driver(target, data_path, material, expression):
    fc = target.driver_add(data_path)
    drv = fc.driver
    drv.type = "SCRIPTED"
    var = drv.variables.new()
    var.name = "day"
    var.type = "SINGLE_PROP"
    var.targets[0].id_type = "MATERIAL"
    var.targets[0].id = material
    var.targets[0].data_path = '["skinsim_day"]'
    drv.expression = expression
    return fc


def _new_material(obj, name):
    mat = bpy.data.materials.new(name)
    mat.use_nodes = True
    nt = mat.node_tree
    nt.nodes.clear()
    out = nt.nodes.new("ShaderNodeOutputMaterial")
    out.location = (900, 0)
    bsdf = nt.nodes.new("ShaderNodeBsdfPrincipled")
    bsdf.location = (600, 0)
    nt.links.new(bsdf.outputs["BSDF"], out.inputs["Surface"])
    return mat, nt, bsdf, out


def _key_days(mat, days, settings):
    """The time property, keyed linearly on the timeline."""
    f0 = settings.start_frame + days[0] * settings.frames_per_day
    f1 = settings.start_frame + days[-1] * settings.frames_per_day
    mat["skinsim_day"] = float(days[0])
    mat.keyframe_insert('["skinsim_day"]', frame=f0)
    mat["skinsim_day"] = float(days[-1])
    mat.keyframe_insert('["skinsim_day"]', frame=f1)
    for fc in mat.animation_data.action.fcurves:
        for kp in fc.keyframe_points:
            kp.interpolation = "LINEAR"


def _timeline_chains(nt, mat, frames_dir, days, maps, srgb_map, vector, extension="REPEAT"):
    """Per map, the images of every day blended by Mix nodes whose factors
    the material's skinsim_day drives; returns {map: output socket}."""
    chains = {}
    for row, m in enumerate(maps):
        y = 600 - row * 420
        prev = None
        for k, d in enumerate(days):
            path = os.path.join(frames_dir, "%s_%s.png" % (day_label(d), m))
            if not os.path.isfile(path):
                raise RuntimeError("%s: missing (skinsim did not write it)" % path)
            tex = nt.nodes.new("ShaderNodeTexImage")
            tex.label = "%s day %g" % (m, d)
            tex.image = _load_image(path, non_color=(m != srgb_map))
            tex.interpolation = "Linear"
            tex.extension = extension
            tex.location = (-1200 + 60 * k, y - 30 * k)
            tex.hide = True
            nt.links.new(vector, tex.inputs["Vector"])
            if prev is None:
                prev = tex.outputs["Color"]
                continue
            mix = nt.nodes.new("ShaderNodeMixRGB")
            mix.blend_type = "MIX"
            mix.label = "%s to day %g" % (m, d)
            mix.location = (-500 + 40 * k, y - 30 * k)
            mix.hide = True
            nt.links.new(prev, mix.inputs["Color1"])
            nt.links.new(tex.outputs["Color"], mix.inputs["Color2"])
            a = days[k - 1]
            _day_driver(mix.inputs["Fac"], "default_value", mat,
                        "clamp((day - %r) / %r, 0.0, 1.0)" % (a, d - a))
            prev = mix.outputs["Color"]
        chains[m] = prev
    return chains


def _normal_map(nt, obj, color_socket, bsdf):
    """Tangent-space normal map (OpenGL +Y up: Blender's convention)."""
    nmap = nt.nodes.new("ShaderNodeNormalMap")
    nmap.space = "TANGENT"
    if obj.data.uv_layers.active:
        nmap.uv_map = obj.data.uv_layers.active.name
    nmap.location = (250, -300)
    nt.links.new(color_socket, nmap.inputs["Color"])
    nt.links.new(nmap.outputs["Normal"], _input(bsdf, "Normal"))
    return nmap


def _assign(obj, mat):
    obj.data.materials.clear()
    obj.data.materials.append(mat)
    for p in obj.data.polygons:
        p.material_index = 0


def build_material(obj, frames_dir, days, settings, name=None):
    """A material on obj showing the abrasion texture sets in frames_dir,
    blended over the timeline. Returns the material."""
    mat, nt, bsdf, out = _new_material(obj, name or "skinsim_" + obj.name)
    _key_days(mat, days, settings)
    uv = nt.nodes.new("ShaderNodeTexCoord")
    uv.location = (-1400, 0)
    chains = _timeline_chains(nt, mat, frames_dir, days, MAPS, "color", uv.outputs["UV"])

    nt.links.new(chains["color"], _input(bsdf, "Base Color"))
    # reflection map -> specular; roughness = 1 - 0.8 x reflection
    refl = _separate(nt)
    refl.location = (0, 200)
    nt.links.new(chains["reflection"], refl.inputs[0])
    nt.links.new(refl.outputs[0], _input(bsdf, "Specular", "Specular IOR Level"))
    rough = nt.nodes.new("ShaderNodeMath")
    rough.operation = "MULTIPLY_ADD"
    rough.label = "roughness = 1 - 0.8 reflection"
    rough.inputs[1].default_value = -0.8
    rough.inputs[2].default_value = 1.0
    rough.location = (250, 150)
    nt.links.new(refl.outputs[0], rough.inputs[0])
    nt.links.new(rough.outputs["Value"], _input(bsdf, "Roughness"))
    _normal_map(nt, obj, chains["normal"], bsdf)
    # height: 0.5 = skin surface, 0..1 spans -0.5..+0.5 mm (skinsim abrasion --help)
    hsep = _separate(nt)
    hsep.location = (250, -600)
    nt.links.new(chains["height"], hsep.inputs[0])
    disp = nt.nodes.new("ShaderNodeDisplacement")
    disp.location = (600, -500)
    disp.inputs["Midlevel"].default_value = 0.5
    disp.inputs["Scale"].default_value = 0.001  # 1 height unit = 1 mm, in metres
    nt.links.new(hsep.outputs[0], disp.inputs["Height"])
    nt.links.new(disp.outputs["Displacement"], out.inputs["Displacement"])
    if hasattr(mat, "cycles"):
        mat.cycles.displacement_method = "BUMP"

    obj.data.materials.clear()
    obj.data.materials.append(mat)
    for p in obj.data.polygons:
        p.material_index = 0
    return mat


def _math(nt, op, a, b=None, c=None, clamp=False, loc=(0, 0)):
    """A Math node; a, b, c: sockets or numbers."""
    n = nt.nodes.new("ShaderNodeMath")
    n.operation = op
    n.use_clamp = clamp
    n.location = loc
    for i, v in enumerate((a, b, c)):
        if v is None:
            continue
        if isinstance(v, (int, float)):
            n.inputs[i].default_value = v
        else:
            nt.links.new(v, n.inputs[i])
    return n.outputs[0]


def _mix(nt, fac, a, b, loc=(0, 0)):
    n = nt.nodes.new("ShaderNodeMixRGB")
    n.blend_type = "MIX"
    n.location = loc
    nt.links.new(fac, n.inputs["Fac"])
    for sock, v in ((n.inputs["Color1"], a), (n.inputs["Color2"], b)):
        if isinstance(v, (int, float)):
            sock.default_value = (v, v, v, 1.0)
        else:
            nt.links.new(v, sock)
    return n.outputs["Color"]


def build_heal_material(obj, frames_dir, days, skin_dir, settings, name=None):
    """The simulated healing (skinsim wound's frames, a block around the
    wound) over skinsim skin's textures (the whole UV square), blended at
    the block's edge, the block's maps blended over the timeline."""
    import json

    with open(os.path.join(skin_dir, "skin.json")) as f:
        info = json.load(f)
    lo, hi = info.get("height_min_mm", 0.0), info.get("height_max_mm", 0.0)
    mat, nt, bsdf, out = _new_material(obj, name or "skinsim_heal_" + obj.name)
    _key_days(mat, days, settings)
    uv = nt.nodes.new("ShaderNodeTexCoord")
    uv.location = (-1900, 0)
    # block coordinates: (uv - corner) / side
    side, (u0, v0) = block_uv(settings)
    mapping = nt.nodes.new("ShaderNodeMapping")
    mapping.vector_type = "POINT"
    mapping.location = (-1700, 0)
    mapping.inputs["Scale"].default_value = (1 / side, 1 / side, 1)
    mapping.inputs["Location"].default_value = (-u0 / side, -v0 / side, 0)
    nt.links.new(uv.outputs["UV"], mapping.inputs["Vector"])
    wound = _timeline_chains(nt, mat, frames_dir, days,
                             ("base_color", "roughness", "height", "normal"), "base_color",
                             mapping.outputs["Vector"], extension="CLIP")
    # the block's weight: 1 inside, falling to 0 over the outer tenth of the block
    sep = nt.nodes.new("ShaderNodeSeparateXYZ")
    sep.location = (-1500, -1800)
    nt.links.new(mapping.outputs["Vector"], sep.inputs["Vector"])
    x, y = sep.outputs["X"], sep.outputs["Y"]
    edge = _math(nt, "MINIMUM", _math(nt, "MINIMUM", x, _math(nt, "SUBTRACT", 1.0, x)),
                 _math(nt, "MINIMUM", y, _math(nt, "SUBTRACT", 1.0, y)))
    weight = _math(nt, "DIVIDE", edge, 0.1, clamp=True)

    def skin_tex(fname, non_color, loc):
        n = nt.nodes.new("ShaderNodeTexImage")
        n.image = _load_image(os.path.join(skin_dir, fname), non_color)
        n.label = "skin " + fname
        n.location = loc
        n.hide = True
        nt.links.new(uv.outputs["UV"], n.inputs["Vector"])
        return n.outputs["Color"]

    nt.links.new(_mix(nt, weight, skin_tex("base_color.png", False, (-600, 900)),
                      wound["base_color"]), _input(bsdf, "Base Color"))
    nt.links.new(_mix(nt, weight, skin_tex("roughness.png", True, (-600, 500)),
                      wound["roughness"]), _input(bsdf, "Roughness"))
    # the wound textures have no specular map: the dielectric default 0.5 there
    nt.links.new(_mix(nt, weight, skin_tex("specular.png", True, (-600, 100)), 0.5),
                 _input(bsdf, "Specular", "Specular IOR Level"))
    _normal_map(nt, obj, _mix(nt, weight, skin_tex("normal.png", True, (-600, -300)),
                              wound["normal"]), bsdf)
    # height in mm: skin lo..hi (skin.json); wound 0.5 = surface, 0..1 = -2..+2 mm
    # (skinsim wound's default recipe height_range)
    hs = _math(nt, "MULTIPLY_ADD", _separate_first(nt, skin_tex("height.png", True, (-600, -700))),
               hi - lo, lo)
    hw = _math(nt, "MULTIPLY_ADD", _separate_first(nt, wound["height"]), 4.0, -2.0)
    h = _math(nt, "ADD", _math(nt, "MULTIPLY", hs, _math(nt, "SUBTRACT", 1.0, weight)),
              _math(nt, "MULTIPLY", hw, weight))
    disp = nt.nodes.new("ShaderNodeDisplacement")
    disp.location = (600, -500)
    disp.inputs["Midlevel"].default_value = 0.0
    disp.inputs["Scale"].default_value = 0.001  # mm -> m
    nt.links.new(h, disp.inputs["Height"])
    nt.links.new(disp.outputs["Displacement"], out.inputs["Displacement"])
    _assign(obj, mat)
    return mat


def _separate_first(nt, color_socket):
    n = _separate(nt)
    nt.links.new(color_socket, n.inputs[0])
    return n.outputs[0]


def build_skin_material(obj, skin_dir, name=None):
    """A static material from `skinsim skin`'s maps (no timeline)."""
    import json

    with open(os.path.join(skin_dir, "skin.json")) as f:
        info = json.load(f)
    lo, hi = info.get("height_min_mm", 0.0), info.get("height_max_mm", 0.0)
    mat = bpy.data.materials.new(name or "skinsim_skin_" + obj.name)
    mat.use_nodes = True
    nt = mat.node_tree
    nt.nodes.clear()
    out = nt.nodes.new("ShaderNodeOutputMaterial")
    out.location = (700, 0)
    bsdf = nt.nodes.new("ShaderNodeBsdfPrincipled")
    bsdf.location = (400, 0)
    nt.links.new(bsdf.outputs["BSDF"], out.inputs["Surface"])

    def tex(fname, non_color, y):
        n = nt.nodes.new("ShaderNodeTexImage")
        n.image = _load_image(os.path.join(skin_dir, fname), non_color)
        n.label = fname
        n.location = (-500, y)
        return n

    nt.links.new(tex("base_color.png", False, 300).outputs["Color"], _input(bsdf, "Base Color"))
    nt.links.new(tex("roughness.png", True, 0).outputs["Color"], _input(bsdf, "Roughness"))
    nt.links.new(tex("specular.png", True, -300).outputs["Color"],
                 _input(bsdf, "Specular", "Specular IOR Level"))
    nmap = nt.nodes.new("ShaderNodeNormalMap")
    nmap.space = "TANGENT"
    if obj.data.uv_layers.active:
        nmap.uv_map = obj.data.uv_layers.active.name
    nmap.location = (100, -350)
    nt.links.new(tex("normal.png", True, -600).outputs["Color"], nmap.inputs["Color"])
    nt.links.new(nmap.outputs["Normal"], _input(bsdf, "Normal"))
    # height.png: 0..1 spans height_min_mm..height_max_mm (skin.json)
    disp = nt.nodes.new("ShaderNodeDisplacement")
    disp.location = (400, -500)
    span = hi - lo
    disp.inputs["Midlevel"].default_value = -lo / span if span > 0 else 0.0
    disp.inputs["Scale"].default_value = span / 1000.0  # mm -> m
    nt.links.new(tex("height.png", True, -900).outputs["Color"], disp.inputs["Height"])
    nt.links.new(disp.outputs["Displacement"], out.inputs["Displacement"])
    obj.data.materials.clear()
    obj.data.materials.append(mat)
    for p in obj.data.polygons:
        p.material_index = 0
    return mat


def _out_dir(obj, st):
    """The output folder, made now (RuntimeError naming it when it cannot be)."""
    out_dir = bpy.path.abspath(st.out_dir) if st.out_dir else ""
    if not out_dir:
        base = (bpy.path.abspath("//") if bpy.data.filepath else
                tempfile.mkdtemp(prefix="skinsim_"))
        out_dir = os.path.join(base, "skinsim_" + bpy.path.clean_name(obj.name))
    try:
        os.makedirs(out_dir, exist_ok=True)
    except OSError as e:
        raise RuntimeError("Output folder %s cannot be made: %s" % (out_dir, e.strerror or e))
    if not os.access(out_dir, os.W_OK | os.X_OK):
        raise RuntimeError("Output folder %s is not writable" % out_dir)
    return out_dir


class Job:
    """One build: the skinsim commands it needs, in order, then the
    material. start()/poll()/cancel() run it step by step (the modal
    operator); run() runs it to the end. Nothing in the scene changes until
    every command has succeeded."""

    def __init__(self, obj, st, cli):
        self.obj, self.st, self.cli = obj, st, cli
        if not obj.data.uv_layers:
            raise RuntimeError("%s: the mesh has no UV map" % obj.name)
        self.days = None
        if st.source == "ABRASION":
            self.days = parse_days(st.days)
        elif st.source == "HEAL":
            self.days = parse_days(st.heal_days)
        self.out_dir = _out_dir(obj, st)
        self.tmp = tempfile.mkdtemp(prefix="skinsim_job_")
        self.steps = []  # (label, argv)
        # per step, the label of the command's progress that measures it (a
        # command may report several in turn; the others are not followed)
        self.follow = {}
        self.step = 0
        self.proc = None
        self._log = None
        self._pipe = None  # read end of the command's SKINSIM_PROGRESS_FD
        self._partial = ""
        self.sub = 0.0  # the running command's own progress (0..1)
        o = self.out_dir
        if st.source == "HEAL":
            skin = os.path.join(o, "skin")
            block = os.path.join(o, "skin_block")
            self.steps.append(("skin textures", skin_command(cli, st, skin)))
            # the block's base skin: the same procedural skin at the block's
            # scale (bio maps), so it matches the skin around the block
            self.steps.append(("block skin", skin_command(cli, st, block,
                                                          world_size_cm=st.block_mm / 10.0,
                                                          size=min(st.size, 1024))))
            cmd, frames = wound_command(cli, st, self.days, os.path.join(o, "wound"), block,
                                        self.tmp)
            self.steps.append(("healing simulation", cmd))
            self.follow[len(self.steps) - 1] = "wound"
            self._build = lambda: build_heal_material(obj, frames, self.days, skin, st)
        elif st.source == "SKIN":
            skin = os.path.join(o, "skin")
            self.steps.append(("skin textures", skin_command(cli, st, skin)))
            self._build = lambda: build_skin_material(obj, skin)
        else:
            upper = None
            if st.skin_under_abrasion:
                skin = os.path.join(o, "skin")
                self.steps.append(("skin textures", skin_command(cli, st, skin)))
                upper = os.path.join(skin, "base_color.png")
            cmd, frames = abrasion_command(cli, st, self.days, os.path.join(o, "abrasion"),
                                           upper, self.tmp)
            self.steps.append(("abrasion timeline", cmd))
            self.follow[len(self.steps) - 1] = "frames"
            self._build = lambda: build_material(obj, frames, self.days, st)

    @property
    def label(self):
        """What runs now, for the status bar."""
        k = min(self.step, len(self.steps) - 1)
        within = " %d%%" % int(100 * self.sub) if self.sub > 0 else ""
        return "skinsim: %s%s (%d of %d) -- Esc to cancel" % (self.steps[k][0], within, k + 1,
                                                               len(self.steps))

    def start(self):
        """Starts the current step's command (a child process)."""
        label, cmd = self.steps[self.step]
        self._log = open(os.path.join(self.tmp, "step%d.log" % self.step), "w+")
        # the command reports its progress as lines on a pipe
        # ("skinsim-progress LABEL FRACTION", SKINSIM_PROGRESS_FD), read in poll()
        self.sub, self._partial = 0.0, ""
        r, w = os.pipe()
        os.set_blocking(r, False)
        env = dict(os.environ, SKINSIM_PROGRESS_FD=str(w))
        try:
            self.proc = subprocess.Popen(cmd, stdout=self._log, stderr=subprocess.STDOUT,
                                         env=env, pass_fds=(w,))
        except OSError as e:
            os.close(r)
            os.close(w)
            self._close_log()
            raise RuntimeError("cannot run skinsim (%s): %s; set its path in the add-on's "
                               "preferences or $SKINSIM_CLI" % (self.cli, e.strerror))
        os.close(w)
        self._pipe = r

    def _read_progress(self):
        """Takes the running command's latest progress line, if any."""
        if self._pipe is None:
            return
        while True:
            try:
                chunk = os.read(self._pipe, 4096)
            except BlockingIOError:
                break
            except OSError:
                chunk = b""
            if not chunk:
                os.close(self._pipe)
                self._pipe = None
                break
            self._partial += chunk.decode("utf-8", "replace")
        *lines, self._partial = self._partial.split("\n")
        for line in lines:
            f = line.split()
            if len(f) == 3 and f[0] == "skinsim-progress" and \
                    f[1] == self.follow.get(self.step):
                try:
                    self.sub = min(1.0, max(0.0, float(f[-1])))
                except ValueError:
                    pass

    def _close_pipe(self):
        if self._pipe is not None:
            os.close(self._pipe)
            self._pipe = None

    def _close_log(self):
        text = ""
        if self._log:
            self._log.seek(0)
            text = self._log.read()
            self._log.close()
            self._log = None
        return text

    def poll(self):
        """True once every command has finished (the next one is started
        here); RuntimeError with the command's own message if one failed."""
        if self.proc is None:
            self.start()
        rc = self.proc.poll()
        self._read_progress()
        if rc is None:
            return False
        self.proc = None
        self._close_pipe()
        self.sub = 0.0
        text = self._close_log()
        if rc != 0:
            lines = text.strip().splitlines()
            raise RuntimeError(lines[-1] if lines else "skinsim exited with code %d" % rc)
        self.step += 1
        if self.step == len(self.steps):
            return True
        self.start()
        return False

    def fraction(self):
        """Share of the work done (0..1): the commands finished, and the
        running command's own progress within its share (commands that report
        none count in whole steps)."""
        return min(1.0, (self.step + self.sub) / len(self.steps))

    def cancel(self):
        """Stops the running command and drops the job; the scene is untouched
        (the command's own output discipline leaves no half-written folder)."""
        if self.proc is not None:
            self.proc.terminate()
            try:
                self.proc.wait(timeout=10)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()
            self.proc = None
        self._close_pipe()
        self._close_log()
        self.cleanup()

    def cleanup(self):
        """Removes the job's temporary files."""
        shutil.rmtree(self.tmp, ignore_errors=True)

    def run(self):
        """Runs every command to the end (scripts, background mode)."""
        try:
            while not self.poll():
                try:
                    self.proc.wait(timeout=0.2)
                except subprocess.TimeoutExpired:
                    pass
        except BaseException:
            self.cancel()
            raise
        return self.finish()

    def finish(self):
        """Builds the material; returns it."""
        try:
            return self._build()
        finally:
            self.cleanup()


def _frames(context, st, days):
    scene = context.scene
    scene.frame_start = st.start_frame
    scene.frame_end = max(scene.frame_end,
                          int(math.ceil(st.start_frame + days[-1] * st.frames_per_day)))
    return scene.frame_start, scene.frame_end


class SKINSIM_OT_build_material(bpy.types.Operator):
    """Run skinsim for the active mesh and build a time-driven skin material"""

    bl_idname = "skinsim.build_material"
    bl_label = "Build skinsim material"
    bl_options = {"REGISTER", "UNDO"}

    _job = None
    _timer = None

    @classmethod
    def poll(cls, context):
        o = context.active_object
        return o is not None and o.type == "MESH"

    def _fail(self, st, e):
        msg = str(e)
        st.last_error = msg
        self.report({"ERROR"}, msg if msg.startswith("skinsim") else "skinsim: " + msg)
        return {"CANCELLED"}

    def _done(self, context, st, job, mat):
        if job.days is None:
            self.report({"INFO"}, "skinsim: material %s (skin textures)" % mat.name)
        else:
            f0, f1 = _frames(context, st, job.days)
            self.report({"INFO"}, "skinsim: material %s, days %g..%g over frames %d..%d" % (
                mat.name, job.days[0], job.days[-1], f0, f1))
        return {"FINISHED"}

    def execute(self, context):
        obj = context.active_object
        st = obj.skinsim
        st.last_error = ""
        try:
            job = Job(obj, st, find_cli(context))
            mat = job.run()
        except (RuntimeError, ValueError, OSError) as e:
            return self._fail(st, e)
        return self._done(context, st, job, mat)

    def invoke(self, context, event):
        if bpy.app.background or context.window is None:
            return self.execute(context)
        obj = context.active_object
        st = obj.skinsim
        st.last_error = ""
        try:
            self._job = Job(obj, st, find_cli(context))
            self._job.start()
        except (RuntimeError, ValueError, OSError) as e:
            return self._fail(st, e)
        self._obj_name = obj.name
        wm = context.window_manager
        self._timer = wm.event_timer_add(0.25, window=context.window)
        wm.progress_begin(0, 100)
        context.workspace.status_text_set(self._job.label)
        wm.modal_handler_add(self)
        return {"RUNNING_MODAL"}

    def _end(self, context):
        wm = context.window_manager
        if self._timer is not None:
            wm.event_timer_remove(self._timer)
            self._timer = None
        wm.progress_end()
        context.workspace.status_text_set(None)

    def modal(self, context, event):
        job = self._job
        st = job.obj.skinsim
        if event.type == "ESC":
            job.cancel()
            self._end(context)
            self.report({"WARNING"}, "skinsim: cancelled; the scene is unchanged")
            return {"CANCELLED"}
        if event.type != "TIMER":
            return {"PASS_THROUGH"}
        try:
            done = job.poll()
            context.window_manager.progress_update(int(100 * job.fraction()))
            if not done:
                context.workspace.status_text_set(job.label)
                return {"RUNNING_MODAL"}
            self._end(context)
            mat = job.finish()
        except (RuntimeError, ValueError, OSError) as e:
            job.cancel()
            self._end(context)
            return self._fail(st, e)
        return self._done(context, st, job, mat)


class SKINSIM_PT_panel(bpy.types.Panel):
    """The active object's skinsim settings (Properties > Material)."""

    bl_label = "skinsim"
    bl_space_type = "PROPERTIES"
    bl_region_type = "WINDOW"
    bl_context = "material"

    @classmethod
    def poll(cls, context):
        o = context.object
        return o is not None and o.type == "MESH"

    def draw(self, context):
        st = context.object.skinsim
        col = self.layout.column()
        col.label(text="Settings of %s" % context.object.name)
        for p in ("source", "skin_under_abrasion", "wound_u", "wound_v", "wound_radius",
                  "stroke_csv", "size", "world_size_cm", "days", "heal_days", "block_mm",
                  "start_frame", "frames_per_day", "seed", "out_dir"):
            col.prop(st, p)
        col.operator(SKINSIM_OT_build_material.bl_idname)
        if st.last_error:
            col.label(text=st.last_error, icon="ERROR")


CLASSES = (SkinsimPreferences, SkinsimSettings, SKINSIM_OT_build_material, SKINSIM_PT_panel)


def register():
    for c in CLASSES:
        bpy.utils.register_class(c)
    bpy.types.Object.skinsim = bpy.props.PointerProperty(type=SkinsimSettings)


def unregister():
    del bpy.types.Object.skinsim
    for c in reversed(CLASSES):
        bpy.utils.unregister_class(c)
