# Two entry points: `make demo` (the main job) and `make test`. Each creates .venv when missing.
PY ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed

.PHONY: demo test lint bench clean chromium

$(STAMP): pyproject.toml
	test -x $(BIN)/python || $(PY) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e '.[dev]'
	touch $(STAMP)

demo: $(STAMP)
	MUJOCO_GL=$${MUJOCO_GL:-egl} $(BIN)/workcell demo handoff --dt 0.005 --save handoff.rrd --render handoff.png

# the live view's browser tests drive Debian's chromium (never a downloaded browser)
chromium:
	@test -x /usr/bin/chromium || (apt-get update -q && DEBIAN_FRONTEND=noninteractive \
	  apt-get install -y -q chromium) >/dev/null || \
	  echo "chromium could not be installed: the browser tests will skip"

test: $(STAMP) chromium
	$(BIN)/ruff check .
	MUJOCO_GL=$${MUJOCO_GL:-egl} $(BIN)/python -m pytest -n 2 -q

bench: $(STAMP)
	$(BIN)/python scripts/bench_modeller.py
	$(BIN)/python scripts/bench_kinematics.py
	$(BIN)/python scripts/bench_sim.py
	$(BIN)/python scripts/bench_record.py
	$(BIN)/python scripts/bench_server.py
	$(BIN)/python scripts/bench_study.py
	$(BIN)/python scripts/bench_motion.py
	$(BIN)/python scripts/bench_plan.py
	$(BIN)/python scripts/bench_logic.py
	$(BIN)/python scripts/bench_import.py
	$(BIN)/python scripts/bench_view.py

clean:
	rm -rf $(VENV) build *.egg-info
