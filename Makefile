# The two commands of the README:
#   make demo   set up if needed, then run the main job
#   make test   set up if needed, then run every test
# make test-quick runs the tests not marked slow (stress, fuzz, multi-process),
# a few minutes, while working.
# and, beside them, make docs builds the documentation into docs/_build/html.
# The range of supported versions is tested at its floor too (CI runs both):
#   make test-floor        the ROS layer's tests and the figures' not marked slow,
#                          on a stock ROS 2 Jazzy's versions (the core's other
#                          tests run at the floor in test-core-py312)
#   make test-core-py312   the core's tests on Python 3.12, Jazzy's interpreter, and
#                          the nodes' code compiled and its imports checked there
SHELL := /bin/bash
.SHELLFLAGS := -eo pipefail -c
ENV := source ros2_ws/env.sh
FLOOR := RPR3_GWR_PROFILE=floor

.PHONY: demo test test-quick test-floor test-core-py312 setup build bench docs clean

setup build:
	bash ros2_ws/setup.sh

demo: build
	$(ENV) && python tools/demo.py

test: build
	$(ENV) && python -m pytest

test-quick: build
	$(ENV) && python -m pytest -m "not slow"

# The core's tests need no ROS: test-core-py312 runs them on the same floor
# versions, except matplotlib's (3.6.3 has no wheel for 3.12), so the
# figures' tests run here.
test-floor:
	$(FLOOR) bash ros2_ws/setup.sh
	export $(FLOOR) && $(ENV) && python -m pytest -m "not slow" tests src/rpr3_gwr_nodes/test \
	  src/rpr3_gwr_msgs/test \
	  src/rpr3_gwr_core/test/test_figures.py src/rpr3_gwr_core/test/test_cli_figures.py

test-core-py312:
	bash tools/core_env.sh 3.12 .venv-core-py312
	@# The nodes need rclpy, whose wheels are for 3.11: on 3.12 their code is
	@# compiled, and tests/test_dependencies.py checks that every module they
	@# import is in 3.12's standard library or provided by a key.
	PATH="$(CURDIR)/.venv-core-py312/bin:$$PATH" && python -m compileall -q src tests tools bench \
	  && python -m pytest src/rpr3_gwr_core/test tests/test_dependencies.py

bench: build
	$(ENV) && python bench/bench_roadmap.py && python bench/bench_planning.py

docs: build
	$(ENV) && sphinx-build -W --keep-going -q docs docs/_build/html && echo "docs in docs/_build/html/index.html"

clean:
	rm -rf .venv .venv-floor .venv-core-py312 ros2_ws/build ros2_ws/install ros2_ws/log \
	  ros2_ws/floor docs/_build docs/_generated
