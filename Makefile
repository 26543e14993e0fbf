# The two commands of README.md. Each one prepares the machine first (LLVM >= 17 runtime,
# the .venv virtual environment with the pinned packages) and is safe to repeat.
# `make figures` and `make bench` write into mitsuba_brdfs-out/ (not tracked, as every
# command does by default); `make docs` and `make docs-bench` regenerate the repository's
# own tracked docs/ and renders/, on purpose.
PY := .venv/bin/python

.PHONY: setup setup-figures figures test bench docs docs-bench clean

# the package with the test tools, the explorer and Debian's chromium (tests, the study)
setup:
	@bash scripts/bootstrap.sh dev

# the package alone: what the figures and the committed pages need (no test tools, no browser)
setup-figures:
	@bash scripts/bootstrap.sh figures

figures: setup-figures
	$(PY) -m mitsuba_brdfs figures $(ARGS)

# JOBS: test processes (pytest-xdist; each file stays in one process, so that its tests
# share their compiled kernels); JOBS=0 runs them in this process
JOBS ?= 2
# the suite's processes (pytest's and the hundred or so commands it runs) keep the bytecode of
# what they import in __pycache__ folders, as Python does by default: where the environment turns that
# off (PYTHONDONTWRITEBYTECODE), each of them would compile the package again
test: setup
	PYTHONDONTWRITEBYTECODE= $(PY) -m pytest -n $(JOBS) --dist loadfile $(ARGS)

bench: setup
	$(PY) -m mitsuba_brdfs bench $(ARGS)

# the committed figures, property tables, fit and plugin pages (a few minutes)
docs: setup-figures
	$(PY) -m mitsuba_brdfs figures --out renders
	$(PY) -m mitsuba_brdfs properties --out docs
	$(PY) -m mitsuba_brdfs fit --out docs/fit
	$(PY) -m mitsuba_brdfs manual --out docs/plugins

# the committed performance study, docs/performance.md and docs/perf/ (about 20 minutes)
docs-bench: setup
	$(PY) -m mitsuba_brdfs bench --out docs $(ARGS)

clean:
	rm -rf .venv build *.egg-info renders/*.exr mitsuba_brdfs-out
