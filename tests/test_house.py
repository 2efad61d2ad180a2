"""The house rules CI enforces (CONTRIBUTING.md): ruff's lint over the Python trees, the layer
contracts of docs/ARCHITECTURE.md (import-linter, configured in pyproject.toml) over the add-on,
the cpp/ style of .clang-format over the files already written in it, and the docs that name the
code (docs/ARCHITECTURE.md, CONTRIBUTING.md) naming only what exists, with the layer diagram
equal to the contract's layers. scripts/setup.sh installs the three tools; a missing tool fails
here rather than skipping the check."""
import ast
import fnmatch
import os
import re
import shutil
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

from tests.helpers.tools import need

ROOT = Path(__file__).resolve().parent.parent
PYTHON_TREES = ["addon", "tests", "bench", "scripts", "shaders"]
# Every cpp/ and bindings/ source keeps the .clang-format layout, except shader_library.h, which
# shaders/generate.py writes in the generator's layout.
FORMATTED_CPP = sorted(str(path.relative_to(ROOT)) for tree in ("cpp", "bindings") for pattern in ("*.cpp", "*.h")
                       for path in (ROOT / tree).rglob(pattern) if path.name != "shader_library.h")


def run(command):
    return subprocess.run(command, cwd=ROOT, capture_output=True, text=True, timeout=300)


def test_ruff_finds_nothing():
    proc = run([sys.executable, "-m", "ruff", "check", "--no-cache", *PYTHON_TREES])
    assert proc.returncode == 0, proc.stdout[-5000:] + proc.stderr[-2000:]


def test_ruff_catches_an_unused_import(tmp_path):
    """Negative control: the configuration in pyproject.toml does report a planted finding."""
    planted = tmp_path / "planted.py"
    planted.write_text("import os\n")
    proc = run([sys.executable, "-m", "ruff", "check", "--no-cache", "--config", str(ROOT / "pyproject.toml"),
                str(planted)])
    assert proc.returncode == 1 and "F401" in proc.stdout, proc.stdout + proc.stderr


def lint_imports(package_parent):
    """import-linter over the boxmarch package found in ``package_parent``."""
    command = [sys.executable, "-c", "from importlinter.cli import lint_imports_command; lint_imports_command()",
               "--no-cache", str(ROOT / "pyproject.toml")]
    return subprocess.run(command, cwd=package_parent, env=dict(os.environ, PYTHONPATH=str(package_parent)),
                          capture_output=True, text=True, timeout=300)


def test_imports_keep_the_layer_contracts():
    proc = lint_imports(ROOT / "addon")
    assert proc.returncode == 0, proc.stdout[-5000:] + proc.stderr[-2000:]
    assert "3 kept, 0 broken" in proc.stdout, proc.stdout[-2000:]


@pytest.mark.parametrize("module, planted, contract", [
    ("core.py", "from . import mesh_io", "Layers"),      # the core reaching up to the Blender door
    ("formats/layouts.py", "import bpy", "never import Blender"),  # a format-facing module importing Blender
    ("formats/fbx_container.py", "from io_scene_fbx import parse_fbx", "never import Blender"),  # Blender's add-on
    ("core_boxes.py", "from . import core", "No circle"),  # two modules of one layer importing each other
])
def test_lint_imports_catches_a_planted_import(tmp_path, module, planted, contract):
    """Negative control: a copy of the package with one forbidden import breaks its contract."""
    shutil.copytree(ROOT / "addon" / "boxmarch", tmp_path / "boxmarch", ignore=shutil.ignore_patterns("*.so"))
    with open(tmp_path / "boxmarch" / module, "a") as f:
        f.write(f"\n{planted}  # planted\n")
    proc = lint_imports(tmp_path)
    broken = [line for line in proc.stdout.splitlines() if " BROKEN" in line]
    assert proc.returncode == 1 and any(contract in line for line in broken), proc.stdout[-3000:] + proc.stderr[-2000:]


# Tests use the add-on's public names only (CONTRIBUTING.md): a name with a leading underscore may
# change with no test saying so. One exception: `_core`, the compiled module (its name is the
# build's), whose own argument checks and loaded file the tests look at.
PRIVATE_NAMES_READ_BY_TESTS = {"_core"}


def private_names_read(source: str) -> list:
    """(line, name) of each private name of the add-on ``source`` reads: ``m._name`` (or
    ``m.sub._name``) where ``m`` was imported from boxmarch, ``from boxmarch... import _name``, or
    ``setattr(m, "_name", ...)`` (monkeypatch's too)."""
    def private(name):
        return name.startswith("_") and not name.endswith("__") and name not in PRIVATE_NAMES_READ_BY_TESTS

    def root(node):
        while isinstance(node, ast.Attribute):
            node = node.value
        return node.id if isinstance(node, ast.Name) else None

    tree, bound, found = ast.parse(source), set(), []
    for node in ast.walk(tree):  # the names bound to the add-on's modules and objects
        if isinstance(node, ast.Import):
            bound.update(alias.asname or "boxmarch" for alias in node.names if alias.name.split(".")[0] == "boxmarch")
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and (node.module or "").split(".")[0] == "boxmarch":
            bound.update(alias.asname or alias.name for alias in node.names)
            found += [(node.lineno, f"{node.module}.{alias.name}") for alias in node.names if private(alias.name)]
    for node in ast.walk(tree):
        if isinstance(node, ast.Attribute) and private(node.attr) and root(node) in bound:
            found.append((node.lineno, ast.unparse(node)))
        elif (isinstance(node, ast.Call) and getattr(node.func, "attr", getattr(node.func, "id", None)) == "setattr"
              and len(node.args) >= 2 and root(node.args[0]) in bound and isinstance(node.args[1], ast.Constant)
              and isinstance(node.args[1].value, str) and private(node.args[1].value)):
            found.append((node.lineno, f"{ast.unparse(node.args[0])}.{node.args[1].value}"))
    return sorted(found)


def test_tests_read_no_private_name_of_the_add_on():
    reads = {str(path.relative_to(ROOT)): found for path in sorted((ROOT / "tests").rglob("*.py"))
             if (found := private_names_read(path.read_text()))}
    assert reads == {}, f"tests reading private names of the add-on (test its public behaviour instead): {reads}"


@pytest.mark.parametrize("planted, name", [
    ("from boxmarch import cli\ncli._table([], [])", "cli._table"),
    ("import boxmarch.preview\nboxmarch.preview._APP_HANDLERS", "boxmarch.preview._APP_HANDLERS"),
    ("from boxmarch.export.scene import _run_exporter", "boxmarch.export.scene._run_exporter"),
    ("from boxmarch.export import scene\nmonkeypatch.setattr(scene, '_run_exporter', print)", "scene._run_exporter"),
])
def test_private_name_scan_catches_a_planted_read(planted, name):
    assert [found for _, found in private_names_read(planted)] == [name]
    # Not the add-on's, or not private: the compiled module, a helper of the tests, a dunder, self.
    assert private_names_read("from boxmarch.native import _core\nfrom boxmarch import core\ncore._core.__file__\n"
                              "from tests import gltf_reader\ngltf_reader._x\ncore.__name__\nself._y\n") == []


def clang_format():
    tool = shutil.which("clang-format-14") or shutil.which("clang-format")
    need(None if tool else "clang-format is missing (apt-get install clang-format-14)")
    return tool


# A missing tool fails the test through tests/helpers/tools.need, on CI and anywhere else: no test
# skips (a check that did not run reads as one that passed).
SKIP_NAMES = {"skip", "skipif", "importorskip", "xfail", "SkipTest", "skipTest", "skipUnless", "skipIf"}


def skip_paths(source: str) -> list:
    """Line numbers of every pytest or unittest skip in ``source``: a call, marker or import of one
    of SKIP_NAMES, or a raised SkipTest."""
    found = []
    for node in ast.walk(ast.parse(source)):
        named = (node.attr if isinstance(node, ast.Attribute) else node.id if isinstance(node, ast.Name) else None)
        if named in SKIP_NAMES:
            found.append(node.lineno)
        if isinstance(node, ast.ImportFrom) and any(alias.name in SKIP_NAMES for alias in node.names):
            found.append(node.lineno)
    return sorted(set(found))


def test_no_test_skips_past_the_missing_tool_helper():
    skipping = {str(path.relative_to(ROOT)): lines for path in sorted((ROOT / "tests").rglob("*.py"))
                if (lines := skip_paths(path.read_text()))}
    assert skipping == {}, f"skips that bypass tests/helpers/tools.need: {skipping}"


@pytest.mark.parametrize("planted", ["pytest.skip('no node')", "pytest.importorskip('jsonschema')",
                                     "@pytest.mark.skipif(True, reason='x')\ndef f(): pass",
                                     "from pytest import skip", "raise unittest.SkipTest('x')",
                                     "pytestmark = pytest.mark.skip"])
def test_skip_scan_catches_a_planted_skip(planted):
    assert skip_paths(f"import pytest\nimport unittest\n{planted}\n") != []
    assert skip_paths("import pytest\npytest.fail('x')\n") == []


def test_formatted_cpp_files_keep_the_style():
    proc = run([clang_format(), "--dry-run", "-Werror", *FORMATTED_CPP])
    assert proc.returncode == 0, proc.stderr[-5000:]


def test_clang_format_catches_a_style_change(tmp_path):
    """Negative control: a file from the list with one indent changed fails the same check."""
    source = (ROOT / FORMATTED_CPP[0]).read_text()
    drifted = tmp_path / "drifted.cpp"
    drifted.write_text(source.replace("\n    ", "\n  ", 1))
    shutil.copy(ROOT / ".clang-format", tmp_path / ".clang-format")
    proc = run([clang_format(), "--dry-run", "-Werror", str(drifted)])
    assert proc.returncode != 0 and "drifted.cpp" in proc.stderr, proc.stderr


# The docs that name the code's modules, functions and files (docs/ARCHITECTURE.md, CONTRIBUTING.md):
# every backticked path, module.name and identifier in them must exist in the tree.
DOCS_NAMING_THE_CODE = ["docs/ARCHITECTURE.md", "CONTRIBUTING.md"]
PACKAGE = ROOT / "addon" / "boxmarch"
SOURCE_SUFFIXES = (".py", ".cpp", ".h", ".glsl", ".hlsl", ".json", ".toml", ".md", ".sh", ".cs", ".shader", ".js")


def tree_files():
    """Every file of the tree git tracks or would add (repository-relative, "/"-separated)."""
    proc = run(["git", "ls-files", "--cached", "--others", "--exclude-standard"])
    assert proc.returncode == 0, proc.stderr
    return [path for path in proc.stdout.splitlines() if (ROOT / path).is_file()]


def module_names():
    """{module path relative to boxmarch ("formats.layouts", "export"): names defined or imported at
    its top level, and "Class.member" for each class's members}."""
    modules = {}
    for path in PACKAGE.rglob("*.py"):
        parts = path.relative_to(PACKAGE).with_suffix("").parts
        names = set()
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, (ast.FunctionDef, ast.ClassDef)):
                names.add(node.name)
                if isinstance(node, ast.ClassDef):
                    names.update(f"{node.name}.{member.name}" for member in ast.walk(node)
                                 if isinstance(member, (ast.FunctionDef, ast.ClassDef)))
                    names.update(f"{node.name}.{item.target.id}" for item in node.body
                                 if isinstance(item, ast.AnnAssign) and isinstance(item.target, ast.Name))
            elif isinstance(node, ast.Name) and isinstance(node.ctx, ast.Store):
                names.add(node.id)
            elif isinstance(node, (ast.Import, ast.ImportFrom)):
                names.update((alias.asname or alias.name).split(".")[0] for alias in node.names)
        modules[".".join(parts[:-1] if parts[-1] == "__init__" else parts)] = names
    return modules


def made_folders():
    """The folders the commands make inside the checkout, which .gitignore names from the root
    (``/.venv-test/``): the docs may name paths in them (``.venv-test/bin/python``)."""
    return {line.strip("/") for line in (ROOT / ".gitignore").read_text().split()
            if line.startswith("/") and line.endswith("/")}


def stale_references(text, files, modules, identifiers):
    """The backticked names of ``text`` (outside code blocks) that name nothing in the tree: a path
    (relative to the repository or the package, ``...`` and ``*`` as wildcards, ``a/b.name`` a
    module's attribute, or inside a folder of :func:`made_folders`), a file name, ``module.name``
    (the module by its path in the package or its own name: ``layouts.channels``), or an identifier
    found in no source file."""
    paths = set(files) | {str(Path(f).parent) for f in files}
    made = made_folders()
    package_paths = {p[len("addon/boxmarch/"):] for p in paths if p.startswith("addon/boxmarch/")}
    basenames = {Path(f).name for f in files}
    by_own_name = {}
    for name in sorted(modules, key=lambda name: (name.count("."), name)):  # the shallowest first
        by_own_name.setdefault(name.rsplit(".", 1)[-1], name)

    def path_exists(path):
        path = path.rstrip("/").replace("...", "**")
        if "*" in path:
            return any(fnmatch.fnmatch(p, path) or fnmatch.fnmatch(p, path.replace("**", "*/*"))
                       for p in paths | package_paths)
        return path in paths or path in package_paths

    def attribute_exists(dotted):
        parts = dotted.split(".")
        for n in range(len(parts), 0, -1):
            module = ".".join(parts[:n])
            module = module if module in modules else by_own_name.get(module) if n == 1 else None
            if module is not None:
                rest = ".".join(parts[n:])
                return not rest or any(fnmatch.fnmatch(name, rest) for name in modules[module])
        return None  # not a module of the package (bpy.ops..., a class, a variable): not checked here

    stale, in_code_block = [], False
    for line in text.splitlines():
        in_code_block ^= line.startswith("```")
        # `bindings/bind_bake.cpp: bake_py` names the file; a command (`bash scripts/test.sh`) its
        # words that name a path
        quoted = [] if in_code_block else [re.sub(r":\s*\w+$", "", token.strip())
                                           for token in re.findall(r"`([^`\n]+)`", line)]
        words = [word for token in quoted for word in token.split()
                 if " " not in token or "/" in word and "$" not in word]
        for token in words:
            first = token.split("/")[0]
            if token.startswith("."):  # `.cpp`: a kind of file; `.clang-format`: a file; `.venv-test/bin/python`
                ok = token in paths or re.fullmatch(r"\.\w+", token) is not None or first in made
            elif token.endswith(SOURCE_SUFFIXES) or "/" in token and (first in paths or first in package_paths):
                if "/" not in token:
                    ok = token in basenames
                elif path_exists(token):
                    ok = True
                else:  # `export/boxes.box_data`: a module's attribute
                    module, _, name = token.rpartition(".")
                    ok = path_exists(module + ".py") and bool(
                        attribute_exists(module.removeprefix("addon/boxmarch/").replace("/", ".") + "." + name))
            elif re.fullmatch(r"[A-Za-z_]\w*(\.[A-Za-z_*]\w*\*?)+", token):
                ok = attribute_exists(token) is not False
            elif re.fullmatch(r"[A-Za-z_]\w*", token) and re.search(r"\w_\w|[a-z][A-Z]", token):
                ok = token in identifiers  # a name of the code's own (snake_case or CamelCase)
            else:
                continue
            if not ok:
                stale.append(token)
    return stale


@pytest.fixture(scope="module")
def code_names():
    files = tree_files()
    identifiers = set()
    this_file = str(Path(__file__).resolve().relative_to(ROOT))  # it names stale names on purpose
    for path in files:
        if path.endswith(SOURCE_SUFFIXES) and not path.endswith(".md") and path != this_file:
            identifiers.update(re.findall(r"[A-Za-z_]\w*", (ROOT / path).read_text(errors="replace")))
    return files, module_names(), identifiers


@pytest.mark.parametrize("doc", DOCS_NAMING_THE_CODE)
def test_docs_name_only_what_exists(doc, code_names):
    assert stale_references((ROOT / doc).read_text(), *code_names) == []


def test_docs_check_catches_planted_stale_references(code_names):
    """Negative control: names of modules, functions and files that do not exist are reported."""
    planted = ["export/transforms.py", "formats/nowhere.py", "preview/sources", "transforms.PRESETS",
               "files.save_blend_copy", "import_settings.for_preset", "export/boxes.no_such_function",
               "read_tool_meshes", "cpp/src/nowhere.cpp", ".venv-tests/bin/python"]
    text = (ROOT / "docs/ARCHITECTURE.md").read_text() + "\n" + " ".join(f"`{name}`" for name in planted)
    assert stale_references(text, *code_names) == planted


def test_layer_diagram_is_the_import_linter_layers():
    """docs/ARCHITECTURE.md's diagram lists, row by row, the modules of pyproject.toml's layers."""
    assert diagram_layers((ROOT / "docs/ARCHITECTURE.md").read_text()) == contract_layers()


def test_layer_diagram_check_catches_a_moved_module():
    """Negative control: the diagram with edit_mode.py drawn in the jobs row differs from the contract."""
    text = (ROOT / "docs/ARCHITECTURE.md").read_text()
    moved = text.replace("  ·  edit_mode.py", "", 1).replace("bake_job.py ", "bake_job.py edit_mode.py ", 1)
    assert moved != text and diagram_layers(moved) != contract_layers()


def contract_layers():
    config = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["importlinter"]["contracts"]
    layers = next(contract["layers"] for contract in config if contract["type"] == "layers")
    return [{name.strip() for name in layer.split(":")} for layer in layers]


def diagram_layers(text):
    """The package modules of each row of the first code block (a row: a line starting with its
    layer's name, and the indented lines under it): ``name.py`` and ``name/`` of the package."""
    block = text.split("```")[1].splitlines()[1:]
    rows = []
    for line in block:
        if line[:2].strip():
            rows.append("")
        rows[-1] += " " + line
    return [{"boxmarch." + name for name in re.findall(r"(?<![\w/])(\w+)(?:\.py\b|/)", row)
             if (PACKAGE / f"{name}.py").exists() or (PACKAGE / name).is_dir()} for row in rows]
