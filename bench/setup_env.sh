#!/usr/bin/env bash
# Create .bench-venv (git-ignored): a separate environment for bench/shape.py with torch (CPU
# build) and anny 0.6.2, so the product's own .venv never gets torch. From the repository root:
#     bash bench/setup_env.sh && .bench-venv/bin/python bench/shape.py
# anny builds its own cache (~/.cache/anny, or $ANNY_CACHE_DIR) on first use: a few minutes.
set -euo pipefail
cd "$(dirname "$0")/.."
VENV=${BENCH_VENV:-.bench-venv}  # where to create it
TORCH="torch==2.13.0+cpu"  # the CPU wheel by its local version: never a CUDA build

[ -x "$VENV/bin/python" ] || "${PYTHON:-python3}" -m venv "$VENV"
pip=("$VENV/bin/python" -m pip install --disable-pip-version-check)

# 1. torch first, so that anny's "torch>=2.0" is already satisfied by the CPU wheel.
if ! "${pip[@]}" "$TORCH"; then
    echo "setup_env: no $TORCH wheel found; point PIP_FIND_LINKS (or --index-url) at one" >&2
    exit 1
fi

# 2. anny with its dependencies, torch pinned so pip cannot swap it. Should one of them be
#    unavailable (warp-lang, say), take anny alone plus the others: its forward pass needs
#    roma, numpy, trimesh and safetensors; without warp it falls back to torch skinning.
if ! "${pip[@]}" anny==0.6.2 "$TORCH"; then
    echo "setup_env: anny's full dependency set failed; installing it with --no-deps" >&2
    "${pip[@]}" --no-deps anny==0.6.2
    "${pip[@]}" "$TORCH" roma numpy pyyaml pillow requests safetensors trimesh
    "${pip[@]}" warp-lang || echo "setup_env: warp-lang unavailable; anny will use torch LBS" >&2
fi

# 3. Avatar itself (editable, no deps) plus the numpy/scipy its core needs, so the same script
#    times both.
"${pip[@]}" numpy scipy
"${pip[@]}" --no-deps -e .
"$VENV/bin/python" - <<'PY'
import torch, anny, avatar
assert not torch.version.cuda, f"a CUDA torch got installed ({torch.version.cuda})"
print(f"bench env ready: torch {torch.__version__}, anny {anny.__version__}")
PY
