# Two targets do all the set-up on a fresh machine (see README.md): both create and use the project's own
# virtual environment .venv (scripts/setup-env), so Debian's system Python works as it is.
VENV ?= .venv
PY := $(VENV)/bin/python

.PHONY: demo test bench install

install:
	bash scripts/setup-env --test

demo:
	bash scripts/setup-env
	$(PY) -m hapmotion demo -o out
	@echo "hapmotion is installed in $(VENV): '. $(VENV)/bin/activate' puts the hapmotion command on PATH in this shell (see the first lines of README.md)"

test:
	bash scripts/setup-env --test
	$(PY) -m pytest -q

bench: install
	for b in render readers audio live viewer metrics; do $(PY) -m benchmarks.bench_$$b || exit 1; done
