# Every target sets itself up: the first run creates .venv and installs the project.
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed-stamp
SCENARIO ?= slope50
OUT    ?= out/$(SCENARIO)/mission
JOBS   ?= 2
# pytest runs one worker more than JOBS: a test that waits (a campaign's pool starting, a
# timeout, a socket) then leaves its core to the others. The suite is CPU-bound: on two
# cores 2 workers took 15:21 and 3 workers 12:07 for the same 23 min of CPU.
TEST_JOBS ?= $(shell expr $(JOBS) + 1)

.PHONY: demo test test-fast lint bench reference clean help

help:
	@echo "make demo   - the main job: the full simulated mission on '$(SCENARIO)' (outputs in $(OUT))"
	@echo "make test   - run the whole test suite (slow closed-loop tests included)"
	@echo "make test-fast - the suite without tests marked slow"
	@echo "make bench  - print benchmark numbers"
	@echo "make lint   - ruff"
	@echo "make reference - regenerate docs/reference/ (scenario fields, log columns) from the code"

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e '.[dev]'
	@touch $(STAMP)

demo: $(STAMP)
	MPLBACKEND=Agg $(BIN)/tetherland mission $(SCENARIO) --out $(OUT) --overwrite

# The suite starts hundreds of Python processes (pytest's workers, the CLI, campaign
# workers): each reads the sources' bytecode, and pytest's rewritten test modules, from
# __pycache__ instead of compiling them again, even where PYTHONDONTWRITEBYTECODE is set
# (pytest's collection 7.9 s -> 3.7 s per process; the CLI tests 29.8 s -> 28.4 s).
TEST_ENV := PYTHONDONTWRITEBYTECODE= MPLBACKEND=Agg MUJOCO_GL=egl

test: $(STAMP)
	$(TEST_ENV) $(BIN)/python -m tetherland.warmup --jobs $(JOBS)
	$(TEST_ENV) $(BIN)/python -m pytest -n $(TEST_JOBS) --dist worksteal

test-fast: $(STAMP)
	$(TEST_ENV) $(BIN)/python -m tetherland.warmup --jobs $(JOBS)
	$(TEST_ENV) $(BIN)/python -m pytest -n $(TEST_JOBS) --dist worksteal -m "not slow"

lint: $(STAMP)
	$(BIN)/ruff check src tests benchmarks examples

bench: $(STAMP)
	@for b in benchmarks/bench_*.py; do echo "== $$b"; MPLBACKEND=Agg MUJOCO_GL=egl $(BIN)/python $$b || exit 1; done

reference: $(STAMP)
	$(BIN)/python -m tetherland.docs_reference

clean:
	rm -rf $(VENV) out .pytest_cache .ruff_cache .hypothesis
