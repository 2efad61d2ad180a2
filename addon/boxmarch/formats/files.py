"""Files that appear only complete: written under a temporary name in the same folder, then
renamed over the target (one rename on one filesystem, so a reader never sees half a file); a
path that is a symbolic link is written through: its target is replaced and the link kept, as
shell redirection and most tools do (written_path); and the signals that would end the process
meanwhile, turned into an interrupt the writers clean up after (interrupts_recorded)."""
from __future__ import annotations

import contextlib
import errno
import os
import secrets
import signal
import threading

NAME_MAX = 255  # bytes of one file name (Linux and macOS file systems)
# Room left in a temporary name for what a writer adds to it (Blender saves a .blend as NAME@ first).
WRITER_SUFFIX_ROOM = 8
_LONGEST_KEPT_EXTENSION = 16  # the exporters need .glb/.fbx/.blend; a longer one is dropped


# Signals that end a process unless handled, sent from outside (a terminal closing, a job
# control, a service manager, a CPU-time limit): interrupts_recorded makes each stop the work as
# Ctrl-C does, so the temporary files are removed. Synchronous faults (SIGSEGV, SIGBUS, ...) and
# SIGKILL cannot be handled.
TERMINATING_SIGNALS = tuple(getattr(signal, name) for name in (
    "SIGINT", "SIGTERM", "SIGHUP", "SIGQUIT", "SIGUSR1", "SIGUSR2", "SIGALRM", "SIGVTALRM", "SIGPROF",
    "SIGXCPU", "SIGPWR", "SIGIO") if hasattr(signal, name))


def written_path(path: str) -> str:
    """The file a write to ``path`` replaces: its absolute path with every symbolic link resolved
    (a link to a file that does not exist yet names the file it would make). Renaming a file onto
    the link itself would replace the link with a regular file and leave its target as it was.
    Raises OSError (ELOOP) for links that loop."""
    resolved = os.path.realpath(os.path.abspath(path))
    if os.path.islink(resolved):  # realpath stops at a loop and returns a link in it
        raise OSError(errno.ELOOP, "its symbolic links loop", path)
    return resolved


def partial_path(path: str) -> str:
    """A temporary name to write ``path`` under: hidden, beside it, with its extension, unique to
    this call (runs writing the same file at once each write their own), and short enough for
    NAME_MAX with room for a writer's own suffix: a long name is cut (at a character boundary)."""
    folder, name = os.path.split(os.path.abspath(path))
    root, ext = os.path.splitext(name)
    if len(ext.encode()) > _LONGEST_KEPT_EXTENSION:
        ext = ""
    tag = f".{os.getpid()}-{secrets.token_hex(4)}.boxmarch-partial{ext}"
    room = NAME_MAX - WRITER_SUFFIX_ROOM - 1 - len(tag.encode())
    root = root.encode()[:room].decode(errors="ignore")
    return os.path.join(folder, f".{root}{tag}")


def write_together(paths, write) -> list:
    """Call write({path: temporary path}) for the absolute ``paths``, then rename each temporary
    file onto the file its path names (written_path: through symbolic links; the temporary file
    is named after the path, whose extension the writer may need, in the target's folder, on its
    filesystem). On failure (an interrupt included) every temporary file is removed and each path
    is left as it was. Returns what write returned. Each folder must exist (FileNotFoundError
    names it otherwise). Runs writing the same paths at once each write their own temporary
    files: the last rename wins."""
    paths = [os.path.abspath(p) for p in paths]
    finals = {p: written_path(p) for p in paths}
    for folder in dict.fromkeys(os.path.dirname(p) for p in finals.values()):
        if not os.path.isdir(folder):
            raise FileNotFoundError(f"folder '{folder}' does not exist")
    temps = {p: partial_path(os.path.join(os.path.dirname(finals[p]), os.path.basename(p))) for p in paths}
    try:
        result = write(temps)
        for path, temp in temps.items():
            os.replace(temp, finals[path])
    finally:
        for temp in temps.values():
            if os.path.exists(temp):
                os.remove(temp)
    return result


def write_atomically(path: str, write) -> str:
    """Call write(temporary path), then rename it onto ``path`` (write_together of one file).
    Returns the absolute path written."""
    path = os.path.abspath(path)
    write_together([path], lambda temps: write(temps[path]))
    return path



def write_bytes(path: str, data) -> None:
    """Write ``data`` (bytes or str) to ``path`` in place: the body of a write_atomically or
    write_together callback, given its temporary path."""
    with open(path, "wb" if isinstance(data, (bytes, bytearray, memoryview)) else "w") as f:
        f.write(data)


@contextlib.contextmanager
def interrupts_recorded(interrupts: list):
    """While the body runs (in the main thread), a terminating signal (TERMINATING_SIGNALS) is
    appended to ``interrupts`` and raises KeyboardInterrupt, as Python's own SIGINT handler does,
    so write_together removes its temporary files; Blender's operators turn an exception inside
    them into a RuntimeError, and ``interrupts`` still tells the caller the run was stopped."""
    def on_signal(signum, _frame):
        interrupts.append(signum)
        raise KeyboardInterrupt

    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = {signum: signal.signal(signum, on_signal) for signum in TERMINATING_SIGNALS}
    try:
        yield
    finally:
        # None: the Blender program's own C handler, which Python cannot put back; the default
        # (end the process) is what a background Blender does on such a signal.
        for signum, handler in previous.items():
            signal.signal(signum, signal.SIG_DFL if handler is None else handler)
