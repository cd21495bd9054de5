# flatstep: `make demo` reproduces the paper's figures, `make test` runs every test. Each sets up its own venv.
PY ?= python3
VENV ?= .venv
BIN := $(VENV)/bin
OUT ?= out
STAMP := $(VENV)/.installed-flatstep

.PHONY: demo test venv clean

venv: $(STAMP)

$(STAMP): pyproject.toml $(wildcard setup.py) $(wildcard src/flatstep/*.py src/flatstep/*/*.py)
	test -x $(BIN)/python || $(PY) -m venv $(VENV)
	$(BIN)/python -m pip install -q --upgrade pip
	$(BIN)/python -m pip install -q -e '.[test]'
	touch $@

demo: venv
	$(BIN)/flatstep reproduce --out $(OUT)

test: venv
	$(BIN)/python -m pytest -q

clean:
	rm -rf $(VENV) build $(OUT) src/*.egg-info
include mk/embedded.mk
