tool
extends MeshInstance
# The design's "Decode vertex vectors" view (docs/ENGINES.md, *The decode-vectors view*): add a
# MeshInstance as a child of a MeshInstance holding a GODOT3 export and give it this script. From
# every vertex of the parent's mesh it draws the raw baked vector f (COLOR.rgb: box-local numbers
# drawn as if they were object-space, light blue) and f turned by the box's frame (NORMAL,
# TANGENT: orange), decoded on the GPU by decode_vectors.shader with the functions boxmarch.shader
# decodes with. The orange lines of each box meet at the box's origin; where they do not, the
# import changed the data (import the .glb with Meshes > Compress off). The lines are drawn over
# everything (no depth test) and follow the parent's transform; a skinned mesh's stay in its rest
# pose (they are not skinned).
# Call rebuild() after changing the parent's mesh or the settings below from a script.

export var show_raw = true
export var show_corrected = true
export var raw_color = Color(0.55, 0.8, 1.0)
export var corrected_color = Color(1.0, 0.55, 0.1)

const LINE_SHADER = preload("decode_vectors.shader")


func _ready():
	rebuild()


# Replaces this node's mesh with the parent's vectors: per surface of the parent's mesh, one
# surface of lines per kind shown (raw, then corrected). Reports, drawing nothing, a parent that
# is not a MeshInstance or a surface without the NORMAL_COLOR channels.
func rebuild():
	mesh = null
	var source = get_parent()
	if not (source is MeshInstance) or source.mesh == null:
		push_error("boxmarch: decode_vectors.gd draws the mesh of its parent MeshInstance, and " + str(source) + " has none")
		return
	var lines = ArrayMesh.new()
	for s in range(source.mesh.get_surface_count()):
		var arrays = source.mesh.surface_get_arrays(s)
		for k in [Mesh.ARRAY_NORMAL, Mesh.ARRAY_TANGENT, Mesh.ARRAY_COLOR]:
			if arrays[k] == null or arrays[k].size() == 0:
				push_error("boxmarch: surface " + str(s) + " of " + str(source.name) + " has no normals, tangents or colours (export with the GODOT3 preset)")
				return
		var doubled = every_vertex_twice(arrays)
		for kind in [[show_raw, true, raw_color], [show_corrected, false, corrected_color]]:
			if not kind[0]:
				continue
			# compress flags 0: the default packs colours into 8 bits, which clamps f to [0, 1]
			lines.add_surface_from_arrays(Mesh.PRIMITIVE_LINES, doubled, [], 0)
			var material = ShaderMaterial.new()
			material.shader = LINE_SHADER
			material.set_shader_param("raw_vectors", kind[1])
			material.set_shader_param("line_color", kind[2])
			lines.surface_set_material(lines.get_surface_count() - 1, material)
	mesh = lines


# The arrays of one line per vertex: the vertex, its normal, tangent and colour twice, UV.x 0 at
# the first end and 1 at the second.
func every_vertex_twice(arrays):
	var vertex = arrays[Mesh.ARRAY_VERTEX]
	var normal = arrays[Mesh.ARRAY_NORMAL]
	var tangent = arrays[Mesh.ARRAY_TANGENT]
	var color = arrays[Mesh.ARRAY_COLOR]
	var out_vertex = PoolVector3Array()
	var out_normal = PoolVector3Array()
	var out_tangent = PoolRealArray()
	var out_color = PoolColorArray()
	var out_uv = PoolVector2Array()
	for i in range(vertex.size()):
		for end in [0.0, 1.0]:
			out_vertex.append(vertex[i])
			out_normal.append(normal[i])
			for k in range(4):
				out_tangent.append(tangent[4 * i + k])
			out_color.append(color[i])
			out_uv.append(Vector2(end, 0.0))
	var out = []
	out.resize(Mesh.ARRAY_MAX)
	out[Mesh.ARRAY_VERTEX] = out_vertex
	out[Mesh.ARRAY_NORMAL] = out_normal
	out[Mesh.ARRAY_TANGENT] = out_tangent
	out[Mesh.ARRAY_COLOR] = out_color
	out[Mesh.ARRAY_TEX_UV] = out_uv
	return out
