"""Cycles' debug log in a bpy process, for its SVM compilation summary (peak stack use per shader).

Cycles logs, for every shader it compiles to SVM, "Shader name: X" and "Peak stack usage: N" (floats of
its 255-float stack) at its DEBUG level.  The bpy module has no command line to turn that level on
(``--log-level``), so ``enable`` sets Cycles' own level variable (``ccl::LOG_LEVEL``) in the loaded
bpy module: its address is the module's load address (/proc/self/maps) plus the symbol's value in the
module's symbol table (``nm``).  It changes nothing else and returns False (the caller skips what
needs the summary) where any of that is missing: another platform, no ``nm``, a stripped module, a
value that is not a log level.

Levels (``ccl::log_level_to_string`` of bpy 5.0.1): 0 FATAL ... 4 WARNING (the default), 6 INFO,
8 DEBUG, 9 TRACE.
"""
import ctypes
import re
import subprocess

SYMBOL = "_ZN3ccl9LOG_LEVELE"   # ccl::LOG_LEVEL
DEBUG = 8
SUMMARY = re.compile(r"Shader name: (\S.*?)\s*\n(?:.*\n){0,3}?.*Peak stack usage:\s*(\d+)")


def _mappings():
    """[(start, end, perms, file offset)] of the bpy module's mappings in this process, and its path."""
    rows, path = [], None
    with open("/proc/self/maps") as f:
        for line in f:
            parts = line.split()
            if len(parts) >= 6 and parts[5].endswith("bpy/__init__.so"):
                start, end = (int(x, 16) for x in parts[0].split("-"))
                rows.append((start, end, parts[1], int(parts[2], 16)))
                path = parts[5]
    return rows, path


def enable(level=DEBUG):
    """Set Cycles' log level of this process (bpy imported); True if it was set."""
    try:
        rows, path = _mappings()
        if not rows:
            return False
        out = subprocess.run(["nm", "--defined-only", path], capture_output=True, text=True, check=True).stdout
    except (OSError, subprocess.CalledProcessError):
        return False
    value = next((int(p[0], 16) for p in (line.split() for line in out.splitlines())
                  if len(p) == 3 and p[2] == SYMBOL), None)
    base = min((start for start, _, _, offset in rows if offset == 0), default=None)
    if value is None or base is None:
        return False
    address = base + value
    if not any(start <= address < end and perms.startswith("rw") for start, end, perms, _ in rows):
        return False
    current = ctypes.c_int.from_address(address)
    if not 0 <= current.value <= 9:
        return False
    current.value = level
    return True


def peaks(text):
    """{shader name: peak SVM stack use} from a log with Cycles' compilation summaries (the last one of each)."""
    return {name: int(n) for name, n in SUMMARY.findall(text)}
