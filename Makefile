# The two commands of the README:
#   make demo   set up if needed, then run the main job
#   make test   set up if needed, then run every test
SHELL := /bin/bash
.SHELLFLAGS := -eo pipefail -c
ENV := source ros2_ws/env.sh

.PHONY: demo test setup build bench clean

setup build:
	bash ros2_ws/setup.sh

demo: build
	$(ENV) && python tools/demo.py

test: build
	$(ENV) && python -m pytest

bench: build
	$(ENV) && python bench/bench_roadmap.py && python bench/bench_planning.py

clean:
	rm -rf .venv ros2_ws/build ros2_ws/install ros2_ws/log ros2_ws/.build-stamp
