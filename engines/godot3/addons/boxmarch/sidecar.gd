tool
extends Reference
# A sidecar NAME.boxmarch.json read as every boxmarch helper reads it (docs/FORMAT.md, "How a
# helper reads the sidecar"): at most MAX_BYTES, UTF-8 (one byte order mark skipped), brackets
# nested at most MAX_DEPTH deep, counted before JSON.parse runs (Godot 3.2's parser recurses: about
# 100,000 nested brackets crash the editor), strict JSON (RFC 8259), an object whose
# format_version, preset, layout, skinned and box_count have the schema's types and the values the
# plug-in reads. Godot's own checks are looser than the format's, so this script makes them on the
# bytes: String.get_string_from_utf8 takes surrogates (CESU-8) and JSON.parse takes text after the
# value, 01, trailing commas and raw control characters in strings.

const MAX_BYTES = 16777216
const MAX_DEPTH = 32


# Why the sidecar at ``path`` does not describe a model the plug-in of ``preset`` reads in one of
# ``layouts_read``, as one line naming the file ("boxmarch: PATH: why"), or "" when it does.
static func refusal(path, format_version, preset, layouts_read):
	var why = file_refusal(path, format_version, preset, layouts_read)
	return "" if why == "" else "boxmarch: %s: %s" % [path, one_line(why)]


static func file_refusal(path, format_version, preset, layouts_read):
	var f = File.new()
	if f.open(path, File.READ) != OK:
		return "cannot be read"
	if f.get_len() > MAX_BYTES:
		f.close()
		return "larger than %d bytes, not a boxmarch sidecar" % MAX_BYTES
	var data = f.get_buffer(f.get_len())
	f.close()
	if data.size() >= 3 and data[0] == 0xEF and data[1] == 0xBB and data[2] == 0xBF:
		data = data.subarray(3, data.size() - 1) if data.size() > 3 else PoolByteArray()  # a byte order mark: skipped
	if not utf8_valid(data):
		return "not UTF-8 text"
	if nesting(data) > MAX_DEPTH:
		return "brackets nested more than %d deep" % MAX_DEPTH
	var syntax = json_syntax_refusal(data)
	if syntax != "":
		return "not JSON (%s)" % syntax
	var parsed = JSON.parse(data.get_string_from_utf8())
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


# The value at ``key`` as JSON, cut to 40 characters, or "missing"; a number beyond a double's
# range (1e400, parsed as an infinity) in words.
static func shown(sidecar, key):
	if not sidecar.has(key):
		return "missing"
	if typeof(sidecar[key]) == TYPE_REAL and is_inf(sidecar[key]):
		return "a number beyond the range of a double"
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

# ``why`` on one line: each control character and line or paragraph separator (what a JSON string
# may hold) written as its JSON escape.
static func one_line(why):
	var out = ""
	for i in range(why.length()):
		var c = why.ord_at(i)
		if c < 0x20 or (c >= 0x7F and c <= 0x9F) or c == 0x2028 or c == 0x2029:
			out += "\\u%04x" % c
		else:
			out += why[i]
	return out


# True when ``data`` is UTF-8 as RFC 3629 defines it: no overlong forms, no surrogates (U+D800 to
# U+DFFF, which CESU-8 writes as ED A0..BF ..), nothing above U+10FFFF.
static func utf8_valid(data):
	var n = data.size()
	var i = 0
	while i < n:
		var c = data[i]
		if c < 0x80:
			i += 1
			continue
		var more = 0
		var lo = 0x80
		var hi = 0xBF
		if c >= 0xC2 and c <= 0xDF:
			more = 1
		elif c >= 0xE0 and c <= 0xEF:
			more = 2
			if c == 0xE0:
				lo = 0xA0
			elif c == 0xED:
				hi = 0x9F
		elif c >= 0xF0 and c <= 0xF4:
			more = 3
			if c == 0xF0:
				lo = 0x90
			elif c == 0xF4:
				hi = 0x8F
		else:
			return false
		if i + more >= n or data[i + 1] < lo or data[i + 1] > hi:
			return false
		for k in range(2, more + 1):
			if data[i + k] < 0x80 or data[i + k] > 0xBF:
				return false
		i += more + 1
	return true


# Why the UTF-8 bytes ``data`` are not one JSON text (RFC 8259), saying where, or "" when they
# are: read without recursion (the open brackets kept in a list), so any nesting is safe here.
static func json_syntax_refusal(data):
	var n = data.size()
	var at = 0
	var brackets = []  # the brackets open: 123 { or 91 [
	var want = "value"  # what may come next: value, value or ], key, key or }, after (a value)
	while true:
		at = skip_space(data, at)
		if at >= n:
			return "" if want == "after" and brackets.empty() else "unexpected end of the text"
		var c = data[at]
		if want == "after":
			if brackets.empty():
				return "text after the value at byte %d" % at
			if c == 44:  # ,
				want = "key" if brackets.back() == 123 else "value"
			elif (c == 125 and brackets.back() == 123) or (c == 93 and brackets.back() == 91):
				brackets.pop_back()
			else:
				return "expected ',' or a closing bracket at byte %d" % at
			at += 1
		elif want == "key" or want == "key or }":
			if c == 125 and want == "key or }":
				brackets.pop_back()
				want = "after"
				at += 1
				continue
			if c != 34:
				return "expected a name in quotes at byte %d" % at
			var end = string_end(data, at)
			if end < 0:
				return "a control character, a bad escape or no closing quote in the string at byte %d" % at
			at = skip_space(data, end)
			if at >= n or data[at] != 58:  # :
				return "expected ':' at byte %d" % at
			at += 1
			want = "value"
		else:
			if c == 123 or c == 91:
				brackets.push_back(c)
				want = "key or }" if c == 123 else "value or ]"
				at += 1
				continue
			if c == 93 and want == "value or ]":
				brackets.pop_back()
				at += 1
			elif c == 34:
				var end = string_end(data, at)
				if end < 0:
					return "a control character, a bad escape or no closing quote in the string at byte %d" % at
				at = end
			elif c == 45 or (c >= 48 and c <= 57):  # - 0..9
				var end = number_end(data, at)
				if end < 0:
					return "a malformed number at byte %d" % at
				at = end
			else:
				var word = ""
				for literal in ["true", "false", "null"]:
					if at + literal.length() <= n and data.subarray(at, at + literal.length() - 1).get_string_from_ascii() == literal:
						word = literal
				if word == "":
					return "unexpected byte %d at byte %d" % [c, at]
				at += word.length()
			want = "after"
	return ""


static func skip_space(data, at):
	while at < data.size() and (data[at] == 32 or data[at] == 9 or data[at] == 10 or data[at] == 13):
		at += 1
	return at


# Where the string whose opening quote is at ``at`` ends (the byte after its closing quote), or -1
# when it holds a raw control character or a bad escape, or does not close.
static func string_end(data, at):
	var n = data.size()
	var i = at + 1
	while i < n:
		var c = data[i]
		if c == 34:
			return i + 1
		if c < 32:
			return -1
		if c != 92:
			i += 1
			continue
		if i + 1 >= n:
			return -1
		var e = data[i + 1]
		if e in [34, 92, 47, 98, 102, 110, 114, 116]:  # " \ / b f n r t
			i += 2
			continue
		if e != 117 or i + 5 >= n:  # u and four hex digits
			return -1
		for k in range(i + 2, i + 6):
			var h = data[k]
			if not ((h >= 48 and h <= 57) or (h >= 65 and h <= 70) or (h >= 97 and h <= 102)):
				return -1
		i += 6
	return -1


# Where the number starting at ``at`` ends (-?(0|[1-9][0-9]*)(.[0-9]+)?([eE][+-]?[0-9]+)?), or -1.
static func number_end(data, at):
	var n = data.size()
	if data[at] == 45:
		at += 1
	if at < n and data[at] == 48:
		at += 1
	else:
		var start = at
		at = digits_end(data, at)
		if at == start:
			return -1
	if at < n and data[at] == 46:  # .
		var start = at + 1
		at = digits_end(data, start)
		if at == start:
			return -1
	if at < n and (data[at] == 101 or data[at] == 69):  # e E
		at += 1
		if at < n and (data[at] == 43 or data[at] == 45):
			at += 1
		var start = at
		at = digits_end(data, at)
		if at == start:
			return -1
	return at


static func digits_end(data, at):
	while at < data.size() and data[at] >= 48 and data[at] <= 57:
		at += 1
	return at
