"""The core runs without Blender: every module outside avatar.blender imports with bpy,
mathutils and bmesh blocked."""

import subprocess
import sys

SCRIPT = """
import sys, pkgutil, importlib
for name in ("bpy", "mathutils", "bmesh"):
    sys.modules[name] = None  # any import of them now raises ImportError
import avatar
for info in pkgutil.walk_packages(avatar.__path__, "avatar."):
    if not info.name.startswith("avatar.blender"):
        importlib.import_module(info.name)
print("ok")
"""


def test_core_imports_without_blender():
    done = subprocess.run([sys.executable, "-c", SCRIPT], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "ok"
