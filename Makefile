# Two targets do all the set-up on a fresh machine (see README.md).
PY ?= python3

.PHONY: demo test bench install

install:
	$(PY) -m pip install --quiet -e '.[test]'

demo:
	$(PY) -m pip install --quiet -e .
	hapmotion demo -o out

test:
	bash scripts/setup-test-env
	$(PY) -m pytest -q

bench: install
	for b in render readers audio live viewer metrics; do $(PY) benchmarks/bench_$$b.py || exit 1; done
