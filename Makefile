# Two commands on a fresh machine:  `make demo`  and  `make test`.
PYTHON ?= python3
VENV   ?= .venv
PY      = $(VENV)/bin/python
STAMP   = $(VENV)/.installed-$(shell cat pyproject.toml constraints.txt | cksum | cut -d' ' -f1)
# What `make install` / `make test` install: the test stack, Ray (the RLlib tests skip without it; CI
# runs them) and TorchRL (compat; it leaves torch and every other pin unchanged), with the CPU torch
# build pinned by constraints.txt (pyproject only gives torch>=2.3).
EXTRAS ?= test,distributed,compat
# The tests run in TEST_WORKERS processes (pytest-xdist), whole files to a worker (their module fixtures are
# built once); 0 runs them in this process.
TEST_WORKERS ?= 2
OUT    ?=

.PHONY: demo test bench bench-peers verify report clean install

$(VENV)/bin/python:
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip

# Re-install whenever pyproject.toml or constraints.txt changes (the stamp name carries their checksum).
$(STAMP): $(VENV)/bin/python pyproject.toml constraints.txt
	$(PY) -m pip install --quiet -c constraints.txt -e ".[$(EXTRAS)]"
	$(VENV)/bin/formation-env warmup  # compile the kernels now, with progress (about 90 s on 2 idle cores, longer under load; else the first run does it)
	rm -f $(VENV)/.installed-*
	touch $(STAMP)

install: $(STAMP)

demo: $(STAMP)
	$(VENV)/bin/formation-env demo $(if $(OUT),--out $(OUT),)

test: $(STAMP)
	$(PY) -m pytest $(if $(filter 0,$(TEST_WORKERS)),,-n $(TEST_WORKERS) --dist loadfile)

bench: $(STAMP)
	$(VENV)/bin/formation-env bench

# The peers (VMAS, PyFlyt) in a virtual environment of their own (PyFlyt needs numpy < 2), timed in the same run as
# formation-env's cases: `formation-env bench --peers --peer-python PATH` (docs/performance.md is this run's JSON).
PEERS_VENV ?= .venv-peers
$(PEERS_VENV)/bin/python:
	$(PYTHON) -m venv $(PEERS_VENV)
	$(PEERS_VENV)/bin/python -m pip install --quiet -c constraints.txt "numpy<2" torch vmas PyFlyt

bench-peers: $(STAMP) $(PEERS_VENV)/bin/python
	$(VENV)/bin/formation-env bench --json --peers --peer-python $(PEERS_VENV)/bin/python $(if $(OUT),> $(OUT).tmp && mv $(OUT).tmp $(OUT),)

verify: $(STAMP)
	$(VENV)/bin/formation-env verify

report: $(STAMP)
	$(VENV)/bin/formation-env report

clean:
	rm -rf $(VENV) build *.egg-info
