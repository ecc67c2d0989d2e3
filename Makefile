# The README's two commands: `make demo` (the main job) and `make test` (the test suite).
# Both set up everything they need on a fresh machine first (scripts/setup.sh); `make test`
# runs the style checks (`make lint`: ruff, mypy) before the tests.
VENV := .venv/bin
OUT ?= out

.PHONY: setup demo test lint bench pictures clean

setup:
	@bash scripts/setup.sh

demo: setup
	mkdir -p $(OUT)
	$(VENV)/avatar create --set gender=0.3 --set age=0.45 --set muscle=0.6 \
		--wear tshirt --wear jeans --wear shoes --wear hair-short --wear eyebrows --wear eyelashes \
		--motion walk -o $(OUT)/demo.glb --render $(OUT)/demo.png
	@echo "wrote $(OUT)/demo.glb and $(OUT)/demo.png"

# The tests start with the style checks (lint): any ruff or mypy finding fails `make test`.
# The video tests run again in .venv-mocap, where MediaPipe is installed (see setup.sh).
test: lint
	$(VENV)/python -m pytest -q -x --timeout=900
	if [ -x .venv-mocap/bin/python ]; then \
		.venv-mocap/bin/python -m pytest -q -x --timeout=900 -p no:cacheprovider tests/mocap/test_video.py; fi

# ruff (rules in pyproject.toml: layering bans bpy outside avatar.blender, no print in the
# library) and mypy (src/avatar, configured in pyproject.toml).
lint: setup
	$(VENV)/ruff check src tests bench addon
	$(VENV)/mypy

bench: setup
	$(VENV)/python bench/shape.py

clean:
	rm -rf $(OUT) .pytest_cache
