"""Run the command line (``python interrupted_fbx_export.py SIGNAL ARGS``, in a Python with bpy)
with the signal SIGNAL (a name: SIGINT, SIGTERM, ...) arriving while Blender's FBX exporter writes,
as a Ctrl-C, a closed terminal or a service manager's stop would in the middle of an export: the
exporter's save sends the signal to this process, then goes on."""
import importlib
import os
import signal
import sys

import bpy  # noqa: F401  (Blender's add-ons, the FBX exporter among them, load with it)

import boxmarch.cli

fbx_writer = importlib.import_module("io_scene_fbx.export_fbx_bin")
real_save = fbx_writer.save


def save_interrupted(*args, **kwargs):
    os.kill(os.getpid(), getattr(signal, sys.argv[1]))
    return real_save(*args, **kwargs)


fbx_writer.save = save_interrupted
boxmarch.cli.main(sys.argv[2:])
