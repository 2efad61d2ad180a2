"""Child of tests/test_fbx_container.py: reads one FBX file with boxmarch.formats.fbx_container
and prints one JSON line: the outcome ("read", "ValueError: ..." or "MemoryError"), the peak
resident memory above what the process held before the read, and the peak address space
reserved above what it had reserved before (VmPeak: memory allocated and never touched counts
here, not in the resident peak), in bytes.

    python fbx_memory_child.py PATH
"""
import json
import resource
import sys

from boxmarch.formats import fbx_container



def address_space_peak():
    with open("/proc/self/status") as f:
        return next(int(line.split()[1]) * 1024 for line in f if line.startswith("VmPeak:"))


with open(sys.argv[1], "rb") as f:
    data = f.read()
before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
address_before = address_space_peak()
try:
    fbx_container.decode(data)
    outcome = "read"
except ValueError as error:
    outcome = f"ValueError: {error}"
except MemoryError:
    outcome = "MemoryError"
peak = (resource.getrusage(resource.RUSAGE_SELF).ru_maxrss - before) * 1024  # Linux: ru_maxrss in KiB
print(json.dumps({"outcome": outcome, "peak_bytes": peak, "peak_address_bytes": address_space_peak() - address_before}))
