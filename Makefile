# The two commands of the README:
#   make demo   set up if needed, then run the main job
#   make test   set up if needed, then run every test
# and, beside them, make docs builds the documentation into docs/_build/html.
SHELL := /bin/bash
.SHELLFLAGS := -eo pipefail -c
ENV := source ros2_ws/env.sh

.PHONY: demo test setup build bench docs clean

setup build:
	bash ros2_ws/setup.sh

demo: build
	$(ENV) && python tools/demo.py

test: build
	$(ENV) && python -m pytest

bench: build
	$(ENV) && python bench/bench_roadmap.py && python bench/bench_planning.py

docs: build
	$(ENV) && sphinx-build -W --keep-going -q docs docs/_build/html && echo "docs in docs/_build/html/index.html"

clean:
	rm -rf .venv ros2_ws/build ros2_ws/install ros2_ws/log ros2_ws/.build-stamp \
	  docs/_build docs/_generated
