"""docs/TROUBLESHOOTING.md holds every message the bake and the export can give (warnings,
refusals, the operator's reports): each message's literal text, placeholders aside, must appear
there, so a changed or new message fails here until the page says what it means and what to do."""
import ast
import re
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
ADDON = ROOT / "addon" / "boxmarch"
SOURCES = [*sorted((ADDON / "export").glob("*.py")), ADDON / "operators" / "export.py",
           ADDON / "mesh_io" / "baked.py", ADDON / "mesh_io" / "weights.py", ADDON / "bake_job.py"]
PAGE = ROOT / "docs" / "TROUBLESHOOTING.md"
SHORTEST_FRAGMENT = 8  # characters: shorter literal pieces ("object '", ": ") say nothing alone


def _fragments(node) -> list:
    """The literal pieces of a message expression (an f-string's text between its fields)."""
    if isinstance(node, ast.Constant) and isinstance(node.value, str):
        return [node.value]
    if isinstance(node, ast.JoinedStr):
        pieces, current = [], ""
        for value in node.values:
            if isinstance(value, ast.Constant):
                current += value.value
            else:
                pieces.append(current)
                current = ""
        return pieces + [current]
    if isinstance(node, ast.BinOp):
        return _fragments(node.left) + _fragments(node.right)
    if isinstance(node, ast.IfExp):
        return _fragments(node.body) + _fragments(node.orelse)
    return []


def _message_nodes(tree):
    """(line, expression) of every message: warnings.append(...)/out.append(...), raise
    SomethingError(...), operator.report(kind, ...), and what a *_warning function returns."""
    for node in ast.walk(tree):
        if isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute) and node.args:
            receiver = node.func.value
            if node.func.attr == "append" and isinstance(receiver, ast.Name) and receiver.id in ("warnings", "out"):
                yield node.lineno, node.args[0]
            elif node.func.attr == "report" and len(node.args) == 2:
                yield node.lineno, node.args[1]
        elif isinstance(node, ast.Raise) and isinstance(node.exc, ast.Call) and node.exc.args:
            if getattr(node.exc.func, "id", "").endswith("Error"):
                yield node.lineno, node.exc.args[0]
        elif isinstance(node, ast.FunctionDef) and node.name.endswith("_warning"):
            for inner in ast.walk(node):
                if isinstance(inner, ast.Return) and inner.value is not None:
                    yield inner.lineno, inner.value


def _normalized(text) -> str:
    return re.sub(r"\s+", " ", text)


def messages():
    """{"file:line": [literal pieces]} of every message in SOURCES."""
    found = {}
    for source in SOURCES:
        for line, node in _message_nodes(ast.parse(source.read_text())):
            pieces = [_normalized(p).strip(" :;,.'") for p in _fragments(node)]
            pieces = [p for p in pieces if len(p) >= SHORTEST_FRAGMENT]
            if pieces:
                found[f"{source.relative_to(ROOT)}:{line}"] = pieces
    return found


def test_every_message_is_on_the_troubleshooting_page():
    found = messages()
    # Control of the scan itself: it sees the warnings and refusals it is meant to.
    assert len(found) >= 30, found
    text = " ".join(" ".join(pieces) for pieces in found.values())
    for known in ("the file's offsets and frames are stale", "Unity usually stores vertex colours as 8-bit Color32",
                  "uses the base mesh, so the mesh shown with modifiers does not decode", "run Bake Box Frames first",
                  "shows shape key", "deforms by bone envelopes"):
        assert known in text, known
    page = _normalized(PAGE.read_text())
    missing = {where: [p for p in pieces if p not in page] for where, pieces in found.items()}
    missing = {where: pieces for where, pieces in missing.items() if pieces}
    assert not missing, "docs/TROUBLESHOOTING.md lacks these messages' text:\n" + "\n".join(
        f"{where}: {pieces}" for where, pieces in missing.items())
