"""scripts/cross_compile.sh --compile-only: every core source compiles for Windows x64 and macOS
arm64 (and the bindings for macOS arm64) with zig's clang, warnings as errors, into object files
of the target's format. Nothing is linked or run here (docs/PLATFORMS.md). In the native tier
(compilers, as its other files): scripts/test.sh runs it beside the sanitizer checks."""
import os
import struct
import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parent.parent
CORE_SOURCES = sorted(p.stem for p in (REPO / "cpp" / "src").glob("*.cpp"))
BINDING_SOURCES = sorted(p.stem for p in (REPO / "bindings").glob("*.cpp"))


def coff_machine(path):
    """The machine field of a COFF object file (0x8664: x86-64)."""
    return struct.unpack("<H", path.read_bytes()[:2])[0]


def macho_cpu(path):
    """(magic, cputype) of a Mach-O file (0xfeedfacf: 64-bit; 0x0100000c: arm64)."""
    return struct.unpack("<II", path.read_bytes()[:8])


@pytest.mark.slow
@pytest.mark.native
def test_native_code_compiles_for_windows_and_macos(tmp_path):
    proc = subprocess.run(["bash", str(REPO / "scripts" / "cross_compile.sh"), "--compile-only", str(tmp_path)],
                          cwd=REPO, env=dict(os.environ, PYTHON=sys.executable), capture_output=True, text=True,
                          timeout=1200)
    assert proc.returncode == 0, proc.stdout[-3000:] + proc.stderr[-3000:]
    windows, macos = tmp_path / "x86_64-windows-gnu", tmp_path / "aarch64-macos"
    assert sorted(p.stem for p in windows.glob("*.o")) == CORE_SOURCES
    assert sorted(p.stem for p in macos.glob("*.o")) == sorted(CORE_SOURCES + BINDING_SOURCES)
    assert {coff_machine(p) for p in windows.glob("*.o")} == {0x8664}
    assert {macho_cpu(p) for p in macos.glob("*.o")} == {(0xFEEDFACF, 0x0100000C)}
    for folder in (windows, macos):
        assert (folder / "libboxmarch_core.a").read_bytes()[:8] == b"!<arch>\n"
