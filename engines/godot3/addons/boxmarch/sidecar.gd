tool
extends Reference
# A sidecar NAME.boxmarch.json read as every boxmarch helper reads it (docs/FORMAT.md, "How a
# helper reads the sidecar"): at most MAX_BYTES, UTF-8, brackets nested at most MAX_DEPTH deep,
# counted before JSON.parse runs (Godot 3.2's parser recurses: about 100,000 nested brackets crash
# the editor), JSON, an object whose format_version, preset, layout, skinned and box_count have the
# schema's types and the values the plug-in reads.

const MAX_BYTES = 16777216
const MAX_DEPTH = 32


# Why the sidecar at ``path`` does not describe a model the plug-in of ``preset`` reads in one of
# ``layouts_read``, as one line naming the file ("boxmarch: PATH: why"), or "" when it does.
static func refusal(path, format_version, preset, layouts_read):
	var why = file_refusal(path, format_version, preset, layouts_read)
	return "" if why == "" else "boxmarch: %s: %s" % [path, why]


static func file_refusal(path, format_version, preset, layouts_read):
	var f = File.new()
	if f.open(path, File.READ) != OK:
		return "cannot be read"
	if f.get_len() > MAX_BYTES:
		f.close()
		return "larger than %d bytes, not a boxmarch sidecar" % MAX_BYTES
	var data = f.get_buffer(f.get_len())
	f.close()
	var text = data.get_string_from_utf8()
	if text.to_utf8() != data:
		return "not UTF-8 text"
	if nesting(data) > MAX_DEPTH:
		return "brackets nested more than %d deep" % MAX_DEPTH
	var parsed = JSON.parse(text)
	if parsed.error != OK:
		return "not JSON (%s at line %d)" % [parsed.error_string if parsed.error_string != "" else "no value", parsed.error_line + 1]
	return value_refusal(parsed.result, format_version, preset, layouts_read)


# The checks on the parsed sidecar, in the order every helper makes them (Godot's JSON numbers
# are all floats).
static func value_refusal(sidecar, format_version, preset, layouts_read):
	if typeof(sidecar) != TYPE_DICTIONARY:
		return "not a JSON object"
	var value = sidecar.get("format_version")
	if typeof(value) != TYPE_REAL or value != float(format_version):
		return "format_version must be %d (the format this plug-in reads), not %s" % [format_version, shown(sidecar, "format_version")]
	value = sidecar.get("preset")
	if typeof(value) != TYPE_STRING or value != preset:
		return "preset must be \"%s\", not %s (layout %s): Godot 3 keeps two UV sets only, export with the %s preset" % [preset, shown(sidecar, "preset"), shown(sidecar, "layout"), preset]
	value = sidecar.get("layout")
	if typeof(value) != TYPE_STRING or not value in layouts_read:
		return "layout must be one of %s (what the plug-in reads), not %s" % [PoolStringArray(layouts_read).join(", "), shown(sidecar, "layout")]
	if typeof(sidecar.get("skinned")) != TYPE_BOOL:
		return "skinned must be true or false, not %s" % shown(sidecar, "skinned")
	value = sidecar.get("box_count")
	if typeof(value) != TYPE_REAL or not (value >= 0.0 and value <= 2147483647.0) or value != floor(value):
		return "box_count must be a whole number from 0 to 2147483647, not %s" % shown(sidecar, "box_count")
	return ""


# The value at ``key`` as JSON, cut to 40 characters, or "missing".
static func shown(sidecar, key):
	if not sidecar.has(key):
		return "missing"
	var text = to_json(sidecar[key])
	return text if text.length() <= 40 else text.substr(0, 40) + "..."


# The deepest nesting of brackets in JSON text (UTF-8 bytes), strings skipped.
static func nesting(data):
	var depth = 0
	var deepest = 0
	var in_string = false
	var escaped = false
	for c in data:
		if in_string:
			if escaped:
				escaped = false
			elif c == 92:  # backslash
				escaped = true
			elif c == 34:  # quote
				in_string = false
		elif c == 34:
			in_string = true
		elif c == 91 or c == 123:  # [ {
			depth += 1
			if depth > deepest:
				deepest = depth
		elif c == 93 or c == 125:  # ] }
			depth -= 1
	return deepest
