tool
extends EditorPlugin
# Every .glb of the project with a boxmarch sidecar (NAME.boxmarch.json) beside it: a GODOT3 export
# (layout NORMAL_COLOR) is imported with mesh compression off, which keeps its colour, normal and
# tangent float32 (Godot's default packs them into 8 bits and the decode misses by up to 1.7
# half-extents); any other sidecar is reported, since Godot 3 keeps two UV sets only.
# docs/ENGINES.md, docs/FORMAT.md (the sidecar).

const FORMAT_VERSION = 1
const PRESET = "GODOT3"
const LAYOUTS_READ = ["NORMAL_COLOR"]
const SIDECAR_SUFFIX = ".boxmarch.json"
const PARAMS = {"meshes/compress": false}

var reported = {}


func _enter_tree():
	get_editor_interface().get_resource_filesystem().connect("filesystem_changed", self, "check_project")
	check_project()


func _exit_tree():
	get_editor_interface().get_resource_filesystem().disconnect("filesystem_changed", self, "check_project")


func models_with_sidecars(dir, out):
	for i in range(dir.get_file_count()):
		var path = dir.get_file_path(i)
		if path.get_extension().to_lower() == "glb" and File.new().file_exists(path.get_basename() + SIDECAR_SUFFIX):
			out.append(path)
	for i in range(dir.get_subdir_count()):
		models_with_sidecars(dir.get_subdir(i), out)
	return out


# The sidecar's refusal of ``model`` (one line naming the sidecar), or "" when this plug-in
# reads it: sidecar.gd, the checks every boxmarch helper makes.
func refusal(model):
	return preload("sidecar.gd").refusal(model.get_basename() + SIDECAR_SUFFIX, FORMAT_VERSION, PRESET, LAYOUTS_READ)


# True when ``model`` has been imported with settings other than PARAMS; rewrites them.
func set_params(model):
	var config = ConfigFile.new()
	if config.load(model + ".import") != OK:
		return false  # not imported yet: the next filesystem change comes back to it
	var changed = false
	for key in PARAMS:
		if config.get_value("params", key, null) != PARAMS[key]:
			config.set_value("params", key, PARAMS[key])
			changed = true
	if changed:
		config.save(model + ".import")
		# Godot compares the .import file's time in whole seconds, and the first import has just
		# written it: without its .md5 the next scan re-imports it for certain.
		var imported = config.get_value("remap", "path", "")
		if imported != "":
			Directory.new().remove(imported.get_basename() + ".md5")
	return changed


func check_project():
	var filesystem = get_editor_interface().get_resource_filesystem()
	var stale = []
	for model in models_with_sidecars(filesystem.get_filesystem(), []):
		var why = refusal(model)
		if why != "":
			if not reported.has(model):
				push_error(why)
				reported[model] = true
		elif set_params(model):
			print("boxmarch: re-importing %s with mesh compression off" % model)
			stale.append(model)
	if stale.size() > 0:  # a changed .import file is re-imported by the next scan (not from inside this signal)
		filesystem.call_deferred("scan_sources")
