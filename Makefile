# Two entry points do all set-up on a fresh machine:
#   make run    builds the Fig. 13 scene's FMU and runs it (CSV + PNG under out/)
#   make test   runs the whole test suite (FMU build, fmpy, libcosim included)
PYTHON ?= python3
VENV   := .venv
PY     := $(VENV)/bin/python
SCENE  ?= scenarios/fig13.toml

.PHONY: run test fuzz lint figures report venv clean

$(VENV)/.installed: pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e ".[test]"
	touch $@

venv: $(VENV)/.installed

run: venv
	$(VENV)/bin/contact-fmu run $(SCENE)

test: venv
	$(PY) -m ruff check .
	$(PY) -m ruff format --check .
	$(PY) -m pytest -q

# randomised hostile FMI calls on every kind of FMU (tests/fmu_fuzz): FUZZ_EXAMPLES runs
# per kind, every failure counted; the summary is printed and kept under out/fuzz/long
FUZZ_EXAMPLES ?= 200
fuzz: venv
	CONTACT_FMU_FUZZ_EXAMPLES=$(FUZZ_EXAMPLES) $(PY) -m pytest -q -p no:cacheprovider \
		tests/test_fmu_fuzz.py; status=$$?; cat out/fuzz/long/summary.md; exit $$status

figures: venv
	$(PY) -m contact_fmu.figures

report: venv
	$(VENV)/bin/contact-fmu report

clean:
	rm -rf out reports .pytest_cache .ruff_cache
