"""What Blender prints while the command line works, held back: its exporters and its save print
progress naming the temporary files (files.partial_path), and the operators' reports print to
stdout in background mode, between the lines of the command line's result table. And the one
line worth showing of an error an operator raised."""
from __future__ import annotations

import contextlib
import ctypes
import os
import sys
import tempfile


def _flush_c_streams() -> None:
    """Flush the C library's stdio buffers (Blender's printf output)."""
    try:
        ctypes.CDLL(None).fflush(None)
    except (OSError, AttributeError, TypeError):  # no C library to reach (Windows): Python's own flush suffices
        pass


@contextlib.contextmanager
def captured(fd: int):
    """Send everything the process writes to ``fd`` (1 = stdout, 2 = stderr; Python and C alike)
    into a temporary file while the body runs. Yields a list that holds the captured lines once
    the body has left (also when it raised)."""
    stream = sys.stdout if fd == 1 else sys.stderr
    lines = []
    stream.flush()
    _flush_c_streams()
    saved = os.dup(fd)
    with tempfile.TemporaryFile() as sink:
        os.dup2(sink.fileno(), fd)
        try:
            yield lines
        finally:
            stream.flush()
            _flush_c_streams()
            os.dup2(saved, fd)
            os.close(saved)
            sink.seek(0)
            lines.extend(sink.read().decode(errors="replace").splitlines())


# Lines Blender prints as errors on a run that went right. Blender 3.4's glTF exporter looks for its
# optional Draco library each time it starts and prints "ERROR: Draco mesh compression is not
# available ..." where the build has none (Debian's); boxmarch never asks for Draco compression.
NOT_PROBLEMS = ("Draco mesh compression is not available",)


def is_problem(line: str) -> bool:
    """A line of Blender's output worth passing on: a warning or an error (but NOT_PROBLEMS)."""
    return (("WARNING" in line or "ERROR" in line or line.startswith(("Error", "Warning")))
            and not any(text in line for text in NOT_PROBLEMS))


@contextlib.contextmanager
def stdout_held_back(pass_on):
    """Run the body with the process's stdout captured; afterwards (also when the body raised)
    each warning or error line of it goes to ``pass_on(line)``, the rest is dropped."""
    lines = []
    try:
        with captured(1) as lines:
            yield
    finally:
        for line in lines:
            if is_problem(line):
                pass_on(line.strip())


def one_line(error: BaseException) -> str:
    """The error's type and the last line of its text: an operator that failed in Python
    (Blender's exporters) raises RuntimeError holding the whole traceback, ending with the error
    and a 'Location:' line."""
    lines = [line.strip() for line in str(error).splitlines() if line.strip()]
    last = next((line for line in reversed(lines) if not line.startswith("Location:")), "")
    return f"{type(error).__name__}: {last}"[:400]
