"""A stub of Blender's ``gpu`` module for the create-info the preview builds: GPUShaderCreateInfo
and GPUStageInterfaceInfo record every call (Blender 4+'s API, with ``depth_write``; Blender 3.4's,
without it, when ``depth_write=False``), and gpu.shader.create_from_info records the create-info
it is handed. The recording is turned into GLSL as Blender's OpenGL backend declares it (uniform
block, push constants, samplers, vertex inputs, stage interface, outputs, the gl_FragDepth
layout), so glslangValidator can compile and link what the add-on built. boxmarch.preview.shader
is loaded under the stub as a separate module: the real one (and Blender's gpu) stay untouched."""
import importlib.util
import sys
import types
from pathlib import Path

GLSL_TYPES = {"FLOAT": "float", "INT": "int", "VEC2": "vec2", "VEC3": "vec3", "VEC4": "vec4", "MAT4": "mat4"}
SAMPLER_TYPES = {"FLOAT_2D": "sampler2D"}
# GPUShaderCreateInfo.depth_write's values (Blender 4+) and the gl_FragDepth layout each stands for.
DEPTH_LAYOUTS = {"UNCHANGED": "depth_unchanged", "ANY": "depth_any", "GREATER": "depth_greater", "LESS": "depth_less"}


class StageInterface:
    def __init__(self, name):
        self.name, self.members = name, []

    def smooth(self, type_name, name):
        self.members.append(("", type_name, name))

    def flat(self, type_name, name):
        self.members.append(("flat ", type_name, name))

    def no_perspective(self, type_name, name):
        self.members.append(("noperspective ", type_name, name))


class CreateInfo:
    def __init__(self):
        self.calls = []

    def __getattr__(self, method):
        if method.startswith("_"):
            raise AttributeError(method)
        return lambda *args: self.calls.append((method, args))

    def called(self, method) -> list:
        return [args for name, args in self.calls if name == method]

    def glsl(self, stage: str) -> str:
        """The stage ('vert' or 'frag') as Blender's GL backend would compile it."""
        lines = ["#version 450 core", *(src for (src,) in self.called("typedef_source"))]
        lines += [f"layout(std140) uniform _{name} {{ {type_name} {name}; }};"
                  for _slot, type_name, name in self.called("uniform_buf")]
        # push constants and samplers: plain uniforms, declared in every stage
        lines += [f"uniform {GLSL_TYPES[t]} {name};" for t, name in self.called("push_constant")]
        lines += [f"uniform {SAMPLER_TYPES[t]} {name};" for _slot, t, name in self.called("sampler")]
        if stage == "vert":
            lines += [f"layout(location = {slot}) in {GLSL_TYPES[t]} {name};" for slot, t, name in self.called("vertex_in")]
        direction = "out" if stage == "vert" else "in"
        for (interface,) in self.called("vertex_out"):
            lines += [f"{qualifier}{direction} {GLSL_TYPES[t]} {name};" for qualifier, t, name in interface.members]
        if stage == "frag":
            lines += [f"layout(location = {slot}) out {GLSL_TYPES[t]} {name};" for slot, t, name in self.called("fragment_out")]
            lines += [f"layout({DEPTH_LAYOUTS[d]}) out float gl_FragDepth;" for (d,) in self.called("depth_write")]
        (source,) = self.called("vertex_source" if stage == "vert" else "fragment_source")
        return "\n".join(lines + [source[0]]) + "\n"


class CreateInfo34(CreateInfo):
    """Blender 3.4's create-info: no depth_write."""

    def __getattr__(self, method):
        if method == "depth_write":
            raise AttributeError(method)
        return super().__getattr__(method)


def gpu_module(depth_write=True):
    """A stub ``gpu`` module; its ``built`` list holds every create-info handed to create_from_info."""
    gpu = types.ModuleType("gpu")
    gpu.built = []
    gpu.types = types.SimpleNamespace(GPUShaderCreateInfo=CreateInfo if depth_write else CreateInfo34,
                                      GPUStageInterfaceInfo=StageInterface)

    def create_from_info(info):
        gpu.built.append(info)
        return object()

    gpu.shader = types.SimpleNamespace(create_from_info=create_from_info)
    return gpu


def preview_shader_module(gpu):
    """boxmarch.preview.shader loaded afresh, its ``import gpu`` given ``gpu``."""
    import boxmarch.preview

    path = Path(boxmarch.preview.__file__).parent / "shader.py"
    spec = importlib.util.spec_from_file_location("boxmarch.preview.shader_under_stub", path)
    module = importlib.util.module_from_spec(spec)
    saved = sys.modules.get("gpu")
    sys.modules["gpu"] = gpu
    try:
        spec.loader.exec_module(module)
    finally:
        if saved is None:
            del sys.modules["gpu"]
        else:
            sys.modules["gpu"] = saved
    return module
