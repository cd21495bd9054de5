# flatstep: `make demo` reproduces the paper's figures, `make test` runs every test. Each sets up its own venv.
PY ?= python3
VENV ?= .venv
BIN := $(VENV)/bin
OUT ?= out
STAMP := $(VENV)/.installed-flatstep

.PHONY: demo test venv clean ctest fuzz fuzz-ci lint

venv: $(STAMP)

$(STAMP): pyproject.toml $(wildcard setup.py) $(wildcard src/flatstep/*.py src/flatstep/*/*.py csrc/*.c csrc/*.h)
	test -x $(BIN)/python || $(PY) -m venv $(VENV)
	$(BIN)/python -m pip install -q --upgrade pip
	$(BIN)/python -m pip install -q -e '.[test,bench,lint]'
	touch $@

demo: venv
	$(BIN)/flatstep reproduce --out $(OUT)

# lint (one core) runs beside the C builds and tests; then the Python tests on every core.
test: venv
	$(MAKE) --no-print-directory -j2 lint ctest
	$(BIN)/python -m pytest -q -n auto

# ruff (pyflakes, isort, bugbear, numpydoc docstrings) and mypy on the package; clang-format on the C core.
lint: venv
	$(BIN)/ruff check src/flatstep
	$(BIN)/mypy
	$(BIN)/clang-format --dry-run --Werror csrc/*.c csrc/*.h csrc/tests/*.c csrc/tests/*.h

# The C core's unit tests (ctest), then the same tests under ASan+UBSan.
ctest:
	cmake -S . -B build/c -DCMAKE_BUILD_TYPE=Release
	cmake --build build/c --parallel
	cd build/c && ctest --output-on-failure --parallel 2
	cmake -S . -B build/asan -DCMAKE_BUILD_TYPE=Debug -DFS_SANITIZE=ON
	cmake --build build/asan --parallel
	cd build/asan && ctest --output-on-failure --parallel 2

# Fuzz the C core (smc_step, the sampled loop, the continuous loop, the time-optimal planner, the segment tables,
# the plan and flat maps, the d-q law; libFuzzer + ASan/UBSan, installs clang if missing): 12 s per target in CI
# (fuzz-ci), or FUZZ_SECONDS per target.
FUZZ_SECONDS ?= 300
fuzz-ci:
	./fuzz/run.sh 12

fuzz:
	./fuzz/run.sh $(FUZZ_SECONDS)

clean:
	rm -rf $(VENV) build $(OUT) src/*.egg-info
include mk/embedded.mk
