# The two commands of README.md. Each one prepares the machine first (LLVM >= 17 runtime,
# the .venv virtual environment with the pinned packages) and is safe to repeat.
PY := .venv/bin/python

.PHONY: setup figures test bench clean

setup:
	@bash scripts/bootstrap.sh dev

figures: setup
	$(PY) -m mitsuba_brdfs figures $(ARGS)

# JOBS: test processes (pytest-xdist; each file stays in one process, so that its tests
# share their compiled kernels); JOBS=0 runs them in this process
JOBS ?= 2
test: setup
	$(PY) -m pytest -n $(JOBS) --dist loadfile $(ARGS)

bench: setup
	$(PY) -m mitsuba_brdfs bench $(ARGS)

clean:
	rm -rf .venv build *.egg-info renders/*.exr
