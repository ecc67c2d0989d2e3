# The README's two commands: `make demo` (the main job) and `make test` (the test suite).
# Both set up everything they need on a fresh machine first (scripts/setup.sh).
VENV := .venv/bin
OUT ?= out

.PHONY: setup demo test lint bench pictures clean

setup:
	@bash scripts/setup.sh

demo: setup
	$(VENV)/avatar create --set gender=0.3 --set age=0.45 --set muscle=0.6 \
		--wear tshirt --wear jeans --wear shoes --wear hair-short --wear eyebrows --wear eyelashes \
		--motion walk -o $(OUT)/demo.glb --render $(OUT)/demo.png
	@echo "wrote $(OUT)/demo.glb and $(OUT)/demo.png"

test: setup
	$(VENV)/python -m pytest -q -x --timeout=900

lint: setup
	$(VENV)/ruff check src tests bench
	$(VENV)/mypy

bench: setup
	$(VENV)/python bench/shape.py

clean:
	rm -rf $(OUT) .pytest_cache
