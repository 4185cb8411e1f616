# The README's two commands: `make demo` (the main job) and `make test`.
# Both bootstrap .venv from the package registries on a fresh machine.
PYTHON ?= python3
VENV := .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed

.PHONY: demo test typecheck bench soak venv clean

$(STAMP): setup.py setup.cfg package.xml
	test -x $(PY) || $(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e '.[ros,test,dask]'
	touch $(STAMP)

venv: $(STAMP)

demo: $(STAMP)
	$(PY) -m gyro_noise_ros.cli.demo --out demo_out

test: $(STAMP)
	$(VENV)/bin/mypy
	$(PY) -m pytest -q -rs -p no:cacheprovider

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
