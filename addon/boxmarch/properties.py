"""Per-object settings of the raymarch preview: ``ob.boxmarch``."""
import bpy
from bpy.props import BoolProperty, EnumProperty, FloatProperty, IntProperty, PointerProperty, StringProperty

from . import core
from .formats import layouts
from .formats import presets
from .formats.march_ranges import MARCH_RANGES

_SDF_DESCRIPTIONS = {
    "BOX": "The submesh's own box (matches the rasterised mesh)",
    "SPHERE": "Largest sphere inside the box, centred at its origin",
    "ROUNDED_BOX": "The box with edges rounded by a quarter of its smallest half-extent",
    "CAPSULE": "Capsule along the box's longest side, as thick as the box allows",
    "CYLINDER": "Cylinder filling the box: along its longest side for a rod, across its shortest for a disc",
    "TORUS": "Ring around the box's shortest side, as wide as its middle one",
    "LINK": "Chain link along the box's longest side, ring across its middle one, wire along its shortest",
}
SDF_ITEMS = [(name, name.replace("_", " ").title(), _SDF_DESCRIPTIONS[name], i)
             for i, name in enumerate(core.SDF_PRESETS)]
SDF_ITEMS.append(("USER", "Text Block", "GLSL 'float map(vec3 p)' from a text block (box_half = half-extents, "
                  "box_params = the box's shape, material, random, user)", len(core.SDF_PRESETS)))
SDF_ITEMS.append(("PER_BOX", "Per-Box Shape", "Each box the preset its shape id picks (0 box, 1 sphere, 2 rounded box, "
                  "3 capsule, 4 cylinder, 5 torus, 6 link: paint boxmarch_shape and bake)", len(core.SDF_PRESETS) + 1))
SDF_ITEMS.append(("PER_BOX_BLEND", "Per-Box Shape, Blended into Parent", "Each box its shape id's preset, "
                  "joined smoothly to its parent box's shape across their boundary (Blend Radius)",
                  len(core.SDF_PRESETS) + 2))


def _redraw(self, context):
    from . import preview

    preview.settings_changed(self.id_data)


class BoxmarchObjectSettings(bpy.types.PropertyGroup):
    preview: BoolProperty(name="Raymarch Preview", default=False, update=_redraw,
                          description="Draw this baked mesh raymarched in the 3D viewport")
    sdf: EnumProperty(name="SDF", items=SDF_ITEMS, default="BOX", update=_redraw,
                      description="Distance field raymarched inside every submesh's box")
    user_text: StringProperty(name="Text", default="", update=_redraw,
                              description="Text block holding a GLSL 'float map(vec3 p)' (when SDF is Text Block)")
    max_steps: IntProperty(name="Max Steps", default=64, min=MARCH_RANGES["max_steps"][0],
                           max=MARCH_RANGES["max_steps"][1], update=_redraw,
                           description="Most SDF evaluations per pixel")
    epsilon: FloatProperty(name="Hit Epsilon", default=1e-3, min=MARCH_RANGES["epsilon"][0],
                           max=MARCH_RANGES["epsilon"][1], precision=5, step=0.01,
                           update=_redraw, description="A ray hits when the distance falls below this (box-local units)")
    relaxation: FloatProperty(name="Step Relaxation", default=1.0, min=0.05, max=2.0, update=_redraw,
                              description="Each step advances this times the distance (below 1 is safer for inexact SDFs)")
    blend_radius: FloatProperty(name="Blend Radius", default=0.1, min=0.0, soft_max=10.0, subtype="DISTANCE",
                                update=_redraw, description="Per-Box Shape, Blended into Parent: how far the smooth join "
                                "reaches (each box with a parent is drawn grown by it)")
    max_distance: FloatProperty(name="Max Distance", default=1000.0, min=1e-4, update=_redraw,
                                description="Longest march inside a box (box-local units)")
    quality: FloatProperty(name="Quality", default=1.0, min=MARCH_RANGES["quality"][0],
                           max=MARCH_RANGES["quality"][1], update=_redraw,
                           description="One knob for cost against error (docs/PREVIEW.md): below 1 the march takes "
                                       "longer (secant) steps near a surface, small boxes get fewer steps and boxes "
                                       "under a few pixels take one SDF tap")
    colour_by_material: BoolProperty(name="Colour by Material", default=False, update=_redraw,
                                     description="Shade each box in a colour of its own material id (boxmarch_material)")
    show_outline: BoolProperty(name="Box Outline", default=False, update=_redraw,
                               description="Draw the mesh edges over the preview")
    engine: EnumProperty(
        name="Engine View", default="BLENDER", update=_redraw,
        items=[(p.name, p.label, f"The SDF in the local frame {p.label} gives each box (export preset {p.name})")
               for p in presets.PRESETS.values()],
        description="See the SDF as an export preset's engine evaluates it: Unity mirrors every local frame's x, "
                    "so a shape that is not symmetric in local x appears mirrored there (docs/EXPORT.md)")
    layout: EnumProperty(
        name="Layout", default="CLASSIC", update=_redraw,
        items=[(layout.name, layout.label, layout.description) for layout in layouts.LAYOUTS.values()],
        description="Draw from the channels of this engine layout, decoded as that engine's shader decodes them "
                    "(docs/ENGINES.md); with an Armature modifier only the Normal + tangent layouts' frames follow "
                    "the pose, as in every engine")
    show_vectors: BoolProperty(name="Vectors", default=False, update=_redraw,
                               description="Lines from every vertex along the raw offset (blue) and the rotated "
                                           "offset (orange): the orange ones meet at each submesh's origin")


classes = (BoxmarchObjectSettings,)


def register_properties():
    bpy.types.Object.boxmarch = PointerProperty(type=BoxmarchObjectSettings)


def unregister_properties():
    del bpy.types.Object.boxmarch
