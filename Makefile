# Two entry points do all set-up on a fresh machine:
#   make run    builds the Fig. 13 scene's FMU and runs it (CSV + PNG under out/)
#   make test   runs the whole test suite (FMU build, fmpy, libcosim included)
PYTHON ?= python3
VENV   := .venv
PY     := $(VENV)/bin/python
SCENE  ?= scenarios/fig13.toml

.PHONY: run test test-alt-cpu fuzz lint figures report bench docs venv clean

$(VENV)/.installed: pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e ".[test]"
	touch $@

venv: $(VENV)/.installed

run: venv
	$(VENV)/bin/contact-fmu run $(SCENE)

# The numerical tests a second time on another numpy/OpenBLAS code path: numpy's AVX-512
# dispatch off (X86_V4, AVX512_*) and OpenBLAS's Haswell (AVX2) kernels, as on a CPU
# without AVX-512. An assertion that holds only with this machine's kernels (exact float
# equality, a tolerance below the conditioning) then fails here, not on a user's machine.
# Both variables are ignored where the feature or kernel does not exist.
ALT_CPU := NPY_DISABLE_CPU_FEATURES="X86_V4 AVX512_ICL AVX512_SPR" OPENBLAS_CORETYPE=Haswell
NUMERIC_TESTS := tests/test_layer.py tests/test_layer_vanishing_speed.py \
	tests/test_dynamics.py tests/test_transient.py tests/test_stiff.py tests/test_report.py \
	tests/test_native.py tests/test_native_contact_spin.py tests/test_scenarios_references.py \
	$(wildcard tests/test_halfspace_*.py)

test: venv
	$(PY) -m ruff check .
	$(PY) -m ruff format --check .
	$(PY) -m pytest -q
	$(MAKE) --no-print-directory test-alt-cpu

test-alt-cpu: venv
	$(ALT_CPU) $(PY) -m pytest -q -p no:cacheprovider $(NUMERIC_TESTS)

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

# the benchmarks (benchmarks/__main__.py): BENCH="NAME ... [--write] [--quick]"; with
# --write they rewrite their tables in docs/performance.md and docs/reliability.md
BENCH ?=
bench: venv
	$(PY) -m benchmarks $(BENCH)

# the documentation site from docs/ into site/ (mkdocs.yml)
docs: venv
	NO_MKDOCS_2_WARNING=1 $(PY) -m mkdocs build --strict

clean:
	rm -rf out reports site .pytest_cache .ruff_cache
