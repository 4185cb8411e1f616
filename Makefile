# The README's two commands: `make demo` (the main job) and `make test`.
# Both bootstrap .venv from the package registries on a fresh machine.
PYTHON ?= python3
VENV := .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed
PYTEST := $(PY) -m pytest -q -rs -p no:cacheprovider
# pytest-xdist worker processes of `make test` (TEST_JOBS=0: one process, no workers). Whole
# files go to one worker (--dist loadfile), so a module-scoped fixture is built once.
TEST_JOBS ?= 2

.PHONY: demo test test-slow test-all typecheck bench soak venv clean

$(STAMP): setup.py setup.cfg package.xml
	test -x $(PY) || $(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e '.[ros,test,dask]'
	touch $(STAMP)

venv: $(STAMP)

demo: $(STAMP)
	$(PY) -m gyro_noise_ros.cli.demo --out demo_out --overwrite

# mypy and every test not marked slow (on $(TEST_JOBS) worker processes) side by side: mypy's
# minute on a fresh clone (no .mypy_cache) fills the cores the tests leave idle. mypy's output is
# printed after the tests'; the exit code is mypy's when it failed, else pytest's.
test: $(STAMP)
	$(VENV)/bin/mypy > $(VENV)/mypy.log 2>&1 & types=$$!; \
	$(PYTEST) -m 'not slow' -n $(TEST_JOBS) --dist loadfile; tests=$$?; \
	wait $$types; typed=$$?; echo '== mypy'; cat $(VENV)/mypy.log; \
	if [ $$typed -ne 0 ]; then exit $$typed; fi; exit $$tests

# The tests marked slow (real-time ROS chains, the demo, long statistical sweeps), in one
# process: the real-time ones must not share the cores with a second worker. CI runs both.
test-slow: $(STAMP)
	$(PYTEST) -m slow

test-all: test test-slow

# the static type check `make test` starts with (configuration: setup.cfg [mypy])
typecheck: $(STAMP)
	$(VENV)/bin/mypy

bench: $(STAMP)
	for b in bench/bench_*.py; do [ $$b = bench/bench_soak.py ] && continue; \
		echo "== $$b"; $(PY) $$b || exit 1; done

# The live chain for 30 min with faults (not part of `make bench`: it takes the host's cores).
soak: $(STAMP)
	$(PY) bench/bench_soak.py

clean:
	rm -rf $(VENV) demo_out build *.egg-info
