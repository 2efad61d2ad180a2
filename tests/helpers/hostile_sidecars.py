"""One table of sidecars (NAME.boxmarch.json) that every engine helper must refuse, each with the
words its one-line message must hold, and the helper-independent rule they break
(docs/FORMAT.md, "How a helper reads the sidecar"). Each helper's test runs the whole table in
the helper's own runtime: three.js in Chromium (tests/test_engine_threejs_inputs.py), the Godot 3
plug-in in godot3-server, the Unity postprocessor under mono and the Unreal script under a stub
``unreal`` module (tests/test_engine_sidecars.py).

``cases(preset, layout)`` builds the files from the sidecar the helper reads (``preset``,
``layout``), so one table serves helpers that read different presets. The first case is the
negative control: a sidecar every helper must accept."""
import json

MAX_BYTES = 1 << 24  # the sidecar size every helper refuses above (docs/FORMAT.md)
MAX_DEPTH = 32       # brackets nested deeper than this are refused before any JSON parser runs
ACCEPTED = "valid"   # the name of the negative control
BOM = b"\xef\xbb\xbf"   # U+FEFF in UTF-8
# How every helper shows a number that is valid JSON but beyond a double's range (1e400): the
# parsers make it an infinity, which has no JSON form.
BEYOND_DOUBLE = "a number beyond the range of a double"


def valid(preset, layout):
    """The keys every helper reads first, as an export writes them, plus one it ignores."""
    return {"format_version": 1, "preset": preset, "layout": layout, "skinned": False, "box_count": 3,
            "file": "model.glb"}


def cases(preset, layout):
    """{name: (file bytes, words the refusal must hold)}; ``ACCEPTED`` holds None: no refusal."""
    good = valid(preset, layout)

    def with_value(key, value):
        return json.dumps({**good, key: value}).encode()

    def without(key):
        return json.dumps({k: v for k, v in good.items() if k != key}).encode()

    text = json.dumps(good)
    return {
        ACCEPTED: (json.dumps(good).encode(), None),
        # Every JSON form a sidecar may hold, laid out as the exports write it (indent 2): read.
        "every JSON form, indented": (json.dumps({**good, "extra": {
            "empty": [[], {}], "numbers": [-0.5, 1e-05, -2e+300, 0, 12.25, -0.0, 1E2], "words": [True, False, None],
            "text": "\u00e9 \U0001f600 \"quoted\" back\\slash /", "deep": {"a": [{"b": [1, {"c": "d"}]}]}}},
            indent=2, ensure_ascii=False).replace(" /\"", " \\/ \\u00e9\\n\\t\"").replace("100.0", "1E2").encode(), None),
        "version 1.0 (the number 1)": (text.replace('"format_version": 1', '"format_version": 1.0').encode(), None),
        "version null": (with_value("format_version", None), "format_version must be 1"),
        "version 1.5": (with_value("format_version", 1.5), "format_version must be 1"),
        "version 1.9999": (with_value("format_version", 1.9999), "format_version must be 1"),
        "version string": (with_value("format_version", "1"), "format_version must be 1"),
        "version true": (with_value("format_version", True), "format_version must be 1"),
        "version 2": (with_value("format_version", 2), "format_version must be 1"),
        "version missing": (without("format_version"), "format_version must be 1"),
        "preset of another engine": (with_value("preset", "BLENDER"), "preset must be"),
        "preset a number": (with_value("preset", 3), "preset must be"),
        "preset of 10,000 characters": (with_value("preset", "GLTF" * 2500), "preset must be"),
        "layout null": (with_value("layout", None), "layout must be one of"),
        "layout unknown": (with_value("layout", "SOMETHING"), "layout must be one of"),
        "layout a list": (with_value("layout", [layout]), "layout must be one of"),
        "skinned a string": (with_value("skinned", "false"), "skinned must be true or false"),
        "skinned 0": (with_value("skinned", 0), "skinned must be true or false"),
        "box_count -1": (with_value("box_count", -1), "box_count must be a whole number"),
        "box_count 2.5": (with_value("box_count", 2.5), "box_count must be a whole number"),
        "box_count 1e300": (with_value("box_count", 1e300), "box_count must be a whole number"),
        "box_count a string": (with_value("box_count", "3"), "box_count must be a whole number"),
        "box_count missing": (without("box_count"), "box_count must be a whole number"),
        "a list": (b"[1, 2, 3]", "not a JSON object"),
        "null": (b"null", "not a JSON object"),
        "not JSON": (text[:-1].encode(), "not JSON"),
        "NaN token": (text.replace('"box_count": 3', '"box_count": NaN').encode(), "not JSON"),
        "empty": (b"", "not JSON"),
        "not UTF-8": (text.replace('"model.glb"', '"mod\\u00e9l.glb"').encode().replace(b"\\u00e9", b"\xe9"),
                      "not UTF-8 text"),
        "100,000 nested brackets": (b"[" * 100_000 + b"]" * 100_000, f"nested more than {MAX_DEPTH} deep"),
        "100,000 nested objects": (b'{"a":' * 100_000 + b"1" + b"}" * 100_000, f"nested more than {MAX_DEPTH} deep"),
        "32 deep in a valid sidecar": (text[:-1].encode() + b', "extra": ' + b"[" * 31 + b"]" * 31 + b"}", None),
        "33 deep in a valid sidecar": (text[:-1].encode() + b', "extra": ' + b"[" * 32 + b"]" * 32 + b"}",
                                       f"nested more than {MAX_DEPTH} deep"),
        "brackets inside a string are text": (with_value("file", "[[[[" * 20 + '"\\' + "{" * 40), None),
        "larger than 16 MiB": (text[:-1].encode() + b" " * MAX_BYTES + b"}", f"larger than {MAX_BYTES} bytes"),
        # Valid JSON whose number no double holds: refused by the key's rule, shown in words.
        "box_count 1e400": (text.replace('"box_count": 3', '"box_count": 1e400').encode(),
                            "box_count must be a whole number from 0 to 2147483647, not " + BEYOND_DOUBLE),
        "version 1e400": (text.replace('"format_version": 1', '"format_version": 1e400').encode(),
                          "not " + BEYOND_DOUBLE),
        "version -1e400": (text.replace('"format_version": 1', '"format_version": -1e400').encode(),
                           "not " + BEYOND_DOUBLE),
        # Strict JSON (RFC 8259): one value, nothing after it but white space.
        "text after the object": (text.encode() + b" x", "not JSON"),
        "two objects back to back": (text.encode() * 2, "not JSON"),
        "a number with a leading zero": (text.replace('"box_count": 3', '"box_count": 03').encode(), "not JSON"),
        "a trailing comma": (text[:-1].encode() + b", }", "not JSON"),
        "a raw newline in a string": (text.replace('"model.glb"', '"model\n.glb"').encode(), "not JSON"),
        "a raw tab in a string": (text.replace('"model.glb"', '"model\t.glb"').encode(), "not JSON"),
        "CESU-8 surrogate bytes": (text.replace('"model.glb"', '"mod?l.glb"').encode().replace(b"?", b"\xed\xa0\x80"),
                                   "not UTF-8 text"),
        # A byte order mark is no part of the JSON text; RFC 8259 lets a parser ignore one, and
        # Windows editors write one: every helper skips one (a second one is text, not JSON).
        "a UTF-8 byte order mark": (BOM + text.encode(), None),
        "two byte order marks": (BOM * 2 + text.encode(), "not JSON"),
        # Every refusal is one line (str.splitlines: no CR, LF, VT, FF, FS..RS, NEL, U+2028/9).
        # (Chromium quotes the text around the error in its message.)
        "a comment first": (b"//\n// exported by boxmarch\n" + text.encode(), "not JSON"),
        "blank lines, then not JSON": (b"\n\n\r\nnot JSON\n", "not JSON"),
        "an HTML page": (b"<html>\n<head><title>404 Not Found</title></head>\n"
                         b"<body>\n<h1>Not Found</h1>\n</body>\n</html>\n", "not JSON"),
        "a vertical tab before a value": (text.replace('"skinned": false', '"skinned":\x0bfalse').encode(), "not JSON"),
        "a line separator before a value": (text.replace('"skinned": false', '"skinned":\u2028false').encode(),
                                            "not JSON"),
        "preset with line breaks": (with_value("preset", "GL\nTF\r\u000b\u000c\u001c\u0085\u2028\u2029"),
                                    "preset must be"),
    }


def check_refusals(messages, preset, layout, path_of):
    """Asserts that ``messages`` ({case name: the helper's message, or None for an accepted
    sidecar}) answers every case of the table: the accepted ones None, each other one line
    starting with "boxmarch: ", naming its file (``path_of(case)``) and holding its words."""
    wrong = {}
    for name, (_data, words) in cases(preset, layout).items():
        message = messages[name]
        if words is None:
            if message is not None:
                wrong[name] = message
        elif not (message and message.startswith("boxmarch: ") and path_of(name) in message and words in message
                  and len(message.splitlines()) == 1 and len(message) < 400):
            wrong[name] = message
    assert not wrong, json.dumps(wrong, indent=1)[:6000]
