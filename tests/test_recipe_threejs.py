"""The three.js recipe exactly as the docs write it: docs/GETTING_STARTED.md's chain (the page's
Blender steps, scripts.getting_started_picture.make_chain) exported by that page's headless
command line, then shaders/threejs/README.md's steps 2 to 4 run as written there, read from the
file's text (so an edit of the docs is what runs): its shell commands in a folder holding the
export, its page saved as index.html, its http.server line (only the port changed, to a free one),
and GETTING_STARTED's address loaded in headless Chromium (SwiftShader) at a fixed window size.
The screenshot must show the whole chain, centred, filling the view, with links as wide on screen
as the chain's known proportions (40 links of 0.46 x 0.23 m, 0.36 m apart) make them for the length
it is drawn at. Negative controls: the page with the camera it had before (at (0, 3, 24), no
framing) and the copy of three.js that gave a blank page (three.module.js and the two loaders
copied alone, the old import map) must fail the same checks.

And the page's claim about the Blender program: GETTING_STARTED's `blender ...` line runs on a
chain saved by Debian's Blender 3.4 (without Blender 3.4's Draco line on stderr) and is refused,
as the page says, on one saved by bpy 5.0."""
import os
import re
import shlex
import shutil
import socket
import subprocess
import sys
import textwrap
import time
from pathlib import Path
from typing import NamedTuple

import numpy as np
import pytest

from scripts import getting_started_picture as chain
from tests.conftest import empty_scene
from tests.engines import threejs
from tests.helpers.blender_program import blender_env, module_environment
from tests.helpers.tools import need

pytestmark = pytest.mark.slow  # Blender, Chromium

REPO = Path(__file__).resolve().parent.parent
README = REPO / "shaders" / "threejs" / "README.md"
GETTING_STARTED = REPO / "docs" / "GETTING_STARTED.md"
WIDTH, HEIGHT = 640, 360
CHAIN_LENGTH = (chain.LINKS - 1) * chain.PITCH + chain.LINK_SIZE[0]  # 14.5 m end to end
LINK_WIDTH = chain.LINK_SIZE[1]
EXPORTS = ("chain.glb", "chain.boxmarch.json", "chain.boxes.bin")
OLD_IMPORT_MAP = '{ "imports": { "three": "./three.module.js", "three/addons/": "./addons/" } }'
OLD_COPY = """mkdir -p addons/loaders addons/controls
cp /usr/share/javascript/three/build/three.module.js .
cp /usr/share/javascript/three/examples/jsm/loaders/GLTFLoader.js addons/loaders/
cp /usr/share/javascript/three/examples/jsm/controls/OrbitControls.js addons/controls/
cp "$BOXMARCH/shaders/threejs/boxmarch.module.js" ."""


class Recipe(NamedTuple):
    export: str  # GETTING_STARTED's command line that bakes and exports chain.blend
    blender: str  # the same in the Blender program
    copy: str    # shaders/threejs/README.md step 2: the shell commands
    page: str    # step 3: index.html
    serve: str   # step 4: the command line that serves the folder
    url: str     # GETTING_STARTED's address of the chain's page


def _section(text, heading):
    start = text.index(f"\n## {heading}\n")
    end = text.find("\n## ", start + 1)
    return text[start:end if end > 0 else len(text)]


def _blocks(text, language):
    return [textwrap.dedent(block) for block in re.findall(rf"^ *```{language}\n(.*?)^ *```", text, re.M | re.S)]


def _one(items, what):
    assert len(items) == 1, f"{what}: {len(items)} found"
    return items[0]


def recipe() -> Recipe:
    steps = _section(README.read_text(), "From Blender to a picture")
    shell = _blocks(steps, "sh")
    guide = GETTING_STARTED.read_text()
    headless = _one(_blocks(_section(guide, "The same, headless"), "sh"), "GETTING_STARTED's headless block")
    lines = [line for line in headless.replace("\\\n", " ").splitlines() if line and not line.startswith("#")]
    return Recipe(export=_one([line for line in lines if line.startswith("python3 -m boxmarch")], "module form"),
                  blender=_one([line for line in lines if line.startswith("blender ")], "Blender form"),
                  copy=_one([block for block in shell if "cp " in block], "copy commands"),
                  page=_one(_blocks(steps, "html"), "page"),
                  serve=_one([block.strip() for block in shell if "http.server" in block], "serve command"),
                  url=_one(re.findall(r"`(http://127\.0\.0\.1:\d+/\?model=chain\.glb)`",
                                      _section(guide, "4. Export and draw in three.js")), "chain's address"))


def _free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _with_port(text, port):
    assert ":8000" in text or " 8000" in text, text
    return text.replace(":8000", f":{port}").replace(" 8000", f" {port}")


@pytest.fixture(scope="module")
def chain_export(bpy_module, tmp_path_factory):
    """GETTING_STARTED's chain, saved by this bpy (5.0) as chain.blend and exported by the page's
    command line, in a folder of its own."""
    folder = tmp_path_factory.mktemp("chain")
    empty_scene(bpy_module)
    chain.make_chain(str(folder / "chain.blend"))
    empty_scene(bpy_module)
    argv = shlex.split(recipe().export)
    assert argv[0] == "python3", argv  # a Python with bpy: this one
    proc = subprocess.run([sys.executable, *argv[1:]], cwd=folder, env=module_environment(folder),
                          capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stdout[-2000:] + proc.stderr[-2000:]
    assert all((folder / name).is_file() for name in EXPORTS), os.listdir(folder)
    return folder


def serve_and_shoot(site, steps: Recipe, shot):
    """Runs the recipe's serve command in ``site`` (on a free port) and screenshots the recipe's
    address in headless Chromium, WIDTH x HEIGHT, into ``shot``; returns the (H, W, 3) pixels."""
    from PIL import Image

    port = _free_port()
    argv = shlex.split(_with_port(steps.serve, port))
    assert argv[:3] == ["python3", "-m", "http.server"], argv
    server = subprocess.Popen([sys.executable, *argv[1:]], cwd=site, stdout=subprocess.DEVNULL,
                              stderr=subprocess.PIPE, text=True, start_new_session=True)
    try:
        deadline = time.monotonic() + 30
        while True:
            try:
                socket.create_connection(("127.0.0.1", port), timeout=1).close()
                break
            except OSError:
                assert server.poll() is None and time.monotonic() < deadline, "http.server did not start"
                time.sleep(0.2)
        code, _stdout, stderr = threejs.chromium(_with_port(steps.url, port), f"--screenshot={shot}",
                                                 f"--window-size={WIDTH},{HEIGHT}", budget_ms=8000)
    finally:
        os.killpg(server.pid, 9)
        server.wait()
    assert code == 0 and shot.is_file(), stderr[-3000:]
    return np.asarray(Image.open(shot).convert("RGB"))


def framing_problems(pixels):
    """What is wrong with the chain as drawn in ``pixels`` (an empty list: nothing): the covered
    pixels (the page's clear colour is black) must form the whole chain, centred, filling the view,
    as wide as its known proportions make it for the length it is drawn at."""
    height, width = pixels.shape[:2]
    covered = pixels.max(axis=2) > 24
    if not covered.any() or covered.mean() > 0.5:  # a page whose script never ran is white, with no canvas
        return ["nothing drawn"]
    ys, xs = np.nonzero(covered)
    x0, x1, y0, y1 = xs.min(), xs.max() + 1, ys.min(), ys.max() + 1
    problems = []
    if x0 < 2 or y0 < 2 or x1 > width - 2 or y1 > height - 2:
        problems.append(f"cut by the window's edge: columns {x0}..{x1}, rows {y0}..{y1}")
    centre = ((x0 + x1) / 2 / width - 0.5, (y0 + y1) / 2 / height - 0.5)
    if max(map(abs, centre)) > 0.1:
        problems.append(f"off centre by {centre[0]:+.2f} of the width, {centre[1]:+.2f} of the height")
    span = max((x1 - x0) / width, (y1 - y0) / height)
    if span < 0.6:
        problems.append(f"spans {span:.0%} of the view")
    drawn_length = np.hypot(x1 - x0, y1 - y0)  # px: the chain is straight
    link_px = LINK_WIDTH / CHAIN_LENGTH * drawn_length  # a link's width at that scale
    if link_px < 6:
        problems.append(f"links {link_px:.1f} px wide")
    fill = covered.sum() / (drawn_length * link_px)  # links, with their holes, over the chain's strip
    if not 0.3 <= fill <= 1.0:
        problems.append(f"covers {fill:.2f} of the strip a chain of these proportions would")
    return problems


def site_for(chain_export, tmp_path, copy, page):
    """A folder of the export, after ``copy`` (shell commands) ran in it, with ``page`` as index.html."""
    site = tmp_path / "site"
    site.mkdir()
    for name in EXPORTS:
        shutil.copy(chain_export / name, site / name)
    proc = subprocess.run(["bash", "-euo", "pipefail", "-c", copy], cwd=site, env=dict(os.environ, BOXMARCH=str(REPO)),
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    (site / "index.html").write_text(page)
    return site


def test_the_recipe_as_written_draws_the_chain_framed(chain_export, tmp_path):
    need(threejs.available("r111"))
    steps = recipe()
    site = site_for(chain_export, tmp_path, steps.copy, steps.page)
    pixels = serve_and_shoot(site, steps, tmp_path / "shot.png")
    assert framing_problems(pixels) == []


def test_the_old_camera_fails_the_framing_check(chain_export, tmp_path):
    """Negative control: the page with the camera it had before (at (0, 3, 24), looking down -z, no
    framing): the chain is drawn, but off centre and thin."""
    need(threejs.available("r111"))
    steps = recipe()
    page = steps.page.replace("camera.position.set(0.3, 0.4, 1);", "camera.position.set(0, 3, 24);")
    page = page.replace("frame();", ";")  # `if (box) frame();` stays a statement
    assert page.count("camera.position.set(0, 3, 24);") == 1 and "frame()" not in page.replace("function frame()", "")
    pixels = serve_and_shoot(site_for(chain_export, tmp_path, steps.copy, page), steps, tmp_path / "shot.png")
    problems = framing_problems(pixels)
    assert problems and "nothing drawn" not in problems, problems


def test_three_js_copied_as_two_files_fails(chain_export, tmp_path):
    """Negative control: three.module.js and the loaders copied alone under the old import map:
    GLTFLoader.js asks for ../../../build/three.module.js, a 404, and the page draws nothing."""
    need(threejs.available("r111"))
    steps = recipe()
    page = re.sub(r'\{ "imports": \{[^}]*\} \}', OLD_IMPORT_MAP, steps.page)
    assert OLD_IMPORT_MAP in page
    pixels = serve_and_shoot(site_for(chain_export, tmp_path, OLD_COPY, page), steps, tmp_path / "shot.png")
    assert framing_problems(pixels) == ["nothing drawn"]


@pytest.mark.blender_program
def test_the_blender_program_form_runs_on_a_file_its_release_can_open(chain_export, package_parent, tmp_path):
    """GETTING_STARTED's `blender ...` line in Debian's Blender 3.4: it exports a chain saved by
    3.4, without Blender 3.4's Draco line among the command line's messages, and is refused, as the
    page says, on the chain bpy 5.0 saved (`Failed to read blend file`, exit 1)."""
    blender = shutil.which("blender")
    need(None if blender else "Debian's blender (3.4) is missing")
    env = blender_env(tmp_path)
    made = subprocess.run([blender, "--background", "--factory-startup", "--python-exit-code", "1", "--python-expr",
                           f"import sys; sys.path.insert(0, {str(REPO)!r}); "
                           f"from scripts.getting_started_picture import make_chain; make_chain({str(tmp_path / 'chain.blend')!r})"],
                          cwd=tmp_path, env=env, capture_output=True, text=True, timeout=300)
    assert made.returncode == 0 and (tmp_path / "chain.blend").is_file(), made.stdout[-2000:] + made.stderr[-2000:]
    argv = shlex.split(recipe().blender)
    assert argv[0] == "blender", argv
    env["PYTHONPATH"] = str(package_parent)  # boxmarch on the path (Debian's Blender honours it)
    env["PWD"] = str(tmp_path)  # Blender finds a relative FILE.blend from $PWD, as a shell in that folder sets it
    ran = subprocess.run([blender, *argv[1:]], cwd=tmp_path, env=env, capture_output=True, text=True, timeout=300)
    assert ran.returncode == 0 and (tmp_path / "chain.glb").is_file(), ran.stdout[-2000:] + ran.stderr[-2000:]
    assert "| export " in ran.stdout and "Draco" not in ran.stdout + ran.stderr, ran.stderr
    shutil.copy(chain_export / "chain.blend", tmp_path / "chain.blend")  # saved by this bpy (5.0; 4.x in the matrix)
    (tmp_path / "chain.glb").unlink()
    refused = subprocess.run([blender, *argv[1:]], cwd=tmp_path, env=env, capture_output=True, text=True, timeout=300)
    if sys.modules["bpy"].app.version >= (5, 0, 0):
        assert refused.returncode == 1 and "Failed to read blend file" in refused.stdout + refused.stderr, refused
        assert "Failed to read blend file" in " ".join(GETTING_STARTED.read_text().split())  # what the page says
    else:  # the page: 3.4 cannot open a file saved by 4.2 either (it crashes)
        assert refused.returncode != 0, refused
    assert not (tmp_path / "chain.glb").exists()
