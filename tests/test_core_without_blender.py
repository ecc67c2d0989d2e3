"""The core runs without Blender: every module outside avatar.blender imports with bpy,
mathutils, bmesh and bpy_extras blocked. (tests/test_layers.py checks the same from the source,
function-level imports included.)"""

import subprocess
import sys

SCRIPT = """
import sys, pkgutil, importlib
for name in ("bpy", "mathutils", "bmesh", "bpy_extras"):
    sys.modules[name] = None  # any import of them now raises ImportError
import avatar
for info in pkgutil.walk_packages(avatar.__path__, "avatar."):
    # avatar.blender is the bridge; a __main__ module runs its program when imported.
    if not info.name.startswith("avatar.blender") and not info.name.endswith(".__main__"):
        importlib.import_module(info.name)
print("ok")
"""


def test_core_imports_without_blender():
    done = subprocess.run([sys.executable, "-c", SCRIPT], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "ok"
