"""Helpers shared by the benchmarks: scenes in Blender, timing, peak memory."""
import time

import numpy as np


def boxes_object(bpy, count, seed=0, name="boxes"):
    """One mesh object of ``count`` random boxes (8 vertices, 6 quads, 12 edges each), selected
    and active. Returns (object, centres, sizes)."""
    from boxmarch import mesh_io, scenes  # here: bench_gpu_frame.py uses table() where boxmarch is absent

    (positions, _edges, face_starts, face_sizes, corner_verts), centres, sizes, _ = scenes.random_boxes(count, seed=seed)
    mesh = mesh_io.new_mesh(name, positions, face_starts, face_sizes, corner_verts)
    ob = bpy.data.objects.new(name, mesh)
    bpy.context.scene.collection.objects.link(ob)
    for other in bpy.context.scene.objects:
        other.select_set(other == ob)
    bpy.context.view_layer.objects.active = ob
    return ob, centres, sizes


def best_of(repeats, fn):
    """Smallest wall time of ``repeats`` calls, in seconds."""
    best = float("inf")
    for _ in range(repeats):
        start = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - start)
    return best


def preview_frame(offscreen, ob, view, projection, read=False):
    """One frame of the raymarch preview of ``ob`` drawn into ``offscreen`` as the viewport draws
    it (depth test LESS_EQUAL, depth writes), then read back as :func:`offscreen_frame` does."""
    from boxmarch.preview import draw

    return offscreen_frame(offscreen, lambda: draw.draw_object(ob, view, projection, True), read)


def offscreen_frame(offscreen, draw_call, read=False, depth=False):
    """``draw_call()`` into ``offscreen`` cleared, with the viewport's depth state (test LESS_EQUAL,
    writes on), then read back: one pixel (so the frame has finished on the GPU) or, with
    ``read``, the whole image as a float32 (height, width, 4) array, row 0 at the bottom (with
    ``depth`` too, (image, window depths (height, width)))."""
    import gpu

    width, height = (offscreen.width, offscreen.height) if read else (1, 1)
    with offscreen.bind():
        fb = gpu.state.active_framebuffer_get()
        fb.clear(color=(0.0, 0.0, 0.0, 0.0), depth=1.0)
        gpu.state.depth_test_set("LESS_EQUAL")
        gpu.state.depth_mask_set(True)
        draw_call()
        buffer = fb.read_color(0, 0, width, height, 4, 0, "FLOAT")
        depths = fb.read_depth(0, 0, width, height) if read and depth else None
        gpu.state.depth_test_set("NONE")
        gpu.state.depth_mask_set(False)
    if read:
        buffer.dimensions = width * height * 4
        image = np.array(buffer, np.float32).reshape(height, width, 4)
        if depths is None:
            return image
        depths.dimensions = width * height
        return image, np.array(depths, np.float32).reshape(height, width)
    return None


def reset_peak_rss():
    """Start a new peak-RSS measurement (Linux: writing 5 to clear_refs resets VmHWM)."""
    with open("/proc/self/clear_refs", "w") as f:
        f.write("5")


def rss_bytes(field="VmRSS"):
    with open("/proc/self/status") as f:
        for line in f:
            if line.startswith(field + ":"):
                return int(line.split()[1]) * 1024
    raise RuntimeError(f"{field} not in /proc/self/status")


def table(headers, rows):
    widths = [max(len(str(h)), *(len(str(r[i])) for r in rows)) for i, h in enumerate(headers)]
    line = lambda cells: "| " + " | ".join(str(c).rjust(w) for c, w in zip(cells, widths)) + " |"
    return "\n".join([line(headers), "|" + "|".join("-" * (w + 2) for w in widths) + "|", *map(line, rows)])


def decode_error(mesh, origins, half_extents, raw_bytes):
    """Worst |decoded origin - origin| / largest half-extent over every vertex, decoding what
    Blender stores with the documented formula in float64. ``origins`` and ``half_extents`` (per
    box) are the bake's own, defined from the float32 vertices Blender stores."""
    corner_verts = np.empty(len(mesh.loops), np.int32)
    mesh.attributes[".corner_vert"].data.foreach_get("value", corner_verts)
    colour = np.empty(len(mesh.vertices) * 4, np.float32)
    mesh.color_attributes["BoxOffset"].data.foreach_get("color_srgb" if raw_bytes else "color", colour)
    colour = colour.reshape(-1, 4).astype(np.float64)
    if raw_bytes:
        colour = np.rint(colour * 255) / 255
    q = np.empty((len(mesh.loops), 4), np.float32)
    for half, name in enumerate(("BoxQuatXY", "BoxQuatZW")):
        uv = np.empty(len(mesh.loops) * 2, np.float32)
        mesh.uv_layers[name].uv.foreach_get("vector", uv)
        q[:, 2 * half:2 * half + 2] = uv.reshape(-1, 2)
    positions = np.empty(len(mesh.vertices) * 3, np.float32)
    mesh.vertices.foreach_get("co", positions)
    # per vertex: every corner of a vertex holds the same quaternion
    first_corner = np.empty(len(mesh.vertices), np.int64)
    first_corner[corner_verts[::-1]] = np.arange(len(corner_verts))[::-1]
    q = q[first_corner].astype(np.float64)
    f = (colour[:, :3] * 2 - 1) / colour[:, 3:4]
    u, w = q[:, :3], q[:, 3:4]
    decoded = positions.reshape(-1, 3) + f + 2 * np.cross(u, np.cross(u, f) + w * f)
    error = np.linalg.norm(decoded - np.repeat(origins, 8, axis=0), axis=1)
    return float((error / np.repeat(half_extents.max(axis=1), 8)).max())
