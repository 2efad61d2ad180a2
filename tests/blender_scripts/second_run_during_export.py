"""Two runs of the command line at once on the same outputs, made deterministic: run as
``python second_run_during_export.py ARGS`` (a Python with bpy), the command ARGS starts; once its
export has written the .glb under its temporary name, and before that is renamed into place, a
second ``python -m boxmarch ARGS`` runs to its end. Its exit code goes to stderr as
"second run: exit N"."""
import subprocess
import sys

import boxmarch.cli
from boxmarch.formats import glb

real_write = glb.write


def write_then_run_again(*args, **kwargs):
    real_write(*args, **kwargs)
    second = subprocess.run([sys.executable, "-m", "boxmarch", *sys.argv[1:]], capture_output=True, text=True)
    print(f"second run: exit {second.returncode}", second.stderr.strip().splitlines()[-1:], file=sys.stderr)


glb.write = write_then_run_again
boxmarch.cli.main(sys.argv[1:])
