"""Run the command line (``python interrupted_fbx_export.py SIGNAL ARGS``, in a Python with bpy)
with the signal SIGNAL (a name: SIGINT, SIGTERM, ...) arriving while Blender's FBX exporter writes,
as a Ctrl-C, a closed terminal or a service manager's stop would in the middle of an export: the
exporter's save writes its file (under the export's temporary name), then sends the signal to this
process, still inside the exporter."""
import importlib
import os
import signal
import sys

import bpy  # noqa: F401  (Blender's add-ons, the FBX exporter among them, load with it)

import boxmarch.cli

fbx_writer = importlib.import_module("io_scene_fbx.export_fbx_bin")
real_save = fbx_writer.save


def save_interrupted(*args, **kwargs):
    result = real_save(*args, **kwargs)
    os.kill(os.getpid(), getattr(signal, sys.argv[1]))
    return result


fbx_writer.save = save_interrupted
boxmarch.cli.main(sys.argv[2:])
