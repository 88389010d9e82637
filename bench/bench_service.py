"""Benchmark: the planner's service as real processes on loopback DDS.

Run on demand (after ``source ros2_ws/env.sh``):
    python bench/bench_service.py [--clients 8] [--requests 100] [--full]

``--full`` has the builder publish the full 3-DOF roadmap (from the roadmap
cache, built there first if needed) and the clients ask for the pocket
example (two modes of the same legs that only a motion of rho1 joins).

Starts roadmap_builder and planner as processes (the localhost Fast DDS
profile; the user's ROS_DOMAIN_ID, else a domain of their own), then:

* publish-to-usable: from the builder's call of ``publish`` (its
  "published" log line minus the publishing time it reports) to the
  planner's "planning on a new roadmap" line (transport of the field and
  roadmap messages plus the planner's rebuild of its state);
* round trips of PlanPath for the paper's two examples (alternating),
  first from one client, then from ``--clients`` concurrent clients, each a
  node of its own called from a thread of its own, all spun by one
  single-threaded executor: p50, p95 and throughput.
"""

import argparse
import json
import math
import os
import pathlib
import random
import re
import signal
import statistics
import subprocess
import tempfile
import threading
import time

ROOT = pathlib.Path(__file__).resolve().parents[1]
LIB = ROOT / "ros2_ws" / "install" / "rpr3_gwr_nodes" / "lib" / "rpr3_gwr_nodes"
PROFILE = ROOT / "ros2_ws" / "fastdds_localhost.xml"
os.environ.update(FASTRTPS_DEFAULT_PROFILES_FILE=str(PROFILE),
                  FASTDDS_DEFAULT_PROFILES_FILE=str(PROFILE),
                  RMW_IMPLEMENTATION="rmw_fastrtps_cpp")
os.environ.pop("ROS_AUTOMATIC_DISCOVERY_RANGE", None)
# A user's ROS_DOMAIN_ID is kept; unset, this run takes one of its own in
# 1..100 (domains above 101 can collide with ephemeral ports).
if not os.environ.get("ROS_DOMAIN_ID"):
    os.environ["ROS_DOMAIN_ID"] = str(random.SystemRandom().randint(1, 100))

import rclpy  # noqa: E402
from rclpy.executors import SingleThreadedExecutor  # noqa: E402
from rclpy.node import Node  # noqa: E402
from rpr3_gwr_msgs.msg import Configuration  # noqa: E402
from rpr3_gwr_msgs.srv import PlanPath  # noqa: E402

D = math.radians
EXAMPLES = [((17.0, 12.0, 18.0, D(122.82)), (17.0, 10.0, 25.0, D(-24.24))),
            ((17.0, 20.0, 25.0, D(29.47)), (17.0, 20.0, 25.0, D(96.13)))]
FULL_EXAMPLES = [((27.5, 31.67154934, 2.14117832, D(-101.0)),
                  (27.5, 31.67154934, 2.14117832, D(158.048263)))]


def _request(k, examples=EXAMPLES):
    start, goal = examples[k % len(examples)]
    return PlanPath.Request(start=Configuration(positions=list(start[:3]), mode=start[3]),
                            goal=Configuration(positions=list(goal[:3]), mode=goal[3]))


def _call(client, request, timeout=60.0):
    done = threading.Event()
    future = client.call_async(request)
    future.add_done_callback(lambda _: done.set())
    begin = time.perf_counter()
    if not done.wait(timeout):
        raise TimeoutError("request lost")
    elapsed = time.perf_counter() - begin
    if not future.result().success:
        raise RuntimeError(future.result().error_msg)
    return elapsed


def _line(path, pattern):
    for line in path.read_text().splitlines():
        if re.search(pattern, line):
            return line
    return None


def _stamp(path, pattern):
    line = _line(path, pattern)
    return None if line is None else float(re.search(r"\[(\d+\.\d+)\]", line).group(1))


def _summary(times, wall):
    if not times:
        return {"requests": 0}
    return {"requests": len(times), "p50_ms": round(1e3 * statistics.median(times), 2),
            "p95_ms": round(1e3 * sorted(times)[int(0.95 * (len(times) - 1))], 2),
            "throughput_per_s": round(len(times) / wall, 1)}


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--clients", type=int, default=8)
    parser.add_argument("--requests", type=int, default=100)
    parser.add_argument("--full", action="store_true",
                        help="the full 3-DOF roadmap and the pocket example")
    args = parser.parse_args()
    examples = FULL_EXAMPLES if args.full else EXAMPLES
    logs = pathlib.Path(tempfile.mkdtemp(prefix="rpr3_bench_"))
    processes = []
    for name in ("roadmap_builder", "planner"):
        log = open(logs / f"{name}.log", "w")
        command = [str(LIB / name)]
        if args.full and name == "roadmap_builder":
            command += ["--ros-args", "-p", "full:=true"]
        processes.append(subprocess.Popen(command, stdout=log, stderr=subprocess.STDOUT))
    rclpy.init()
    # All clients share this process's executor, which waits on every
    # entity of every node: parameter services the clients never use would
    # make each response cost the benchmark eight times their upkeep.
    nodes = [Node(f"bench_client_{k}", start_parameter_services=False)
             for k in range(args.clients)]
    clients = [n.create_client(PlanPath, "plan_path") for n in nodes]
    executor = SingleThreadedExecutor()
    for n in nodes:
        executor.add_node(n)
    spinner = threading.Thread(target=executor.spin, daemon=True)
    spinner.start()
    try:
        assert clients[0].wait_for_service(timeout_sec=120.0)
        deadline = time.monotonic() + 120.0
        while time.monotonic() < deadline:
            try:
                _call(clients[0], _request(0, examples))
                break
            except RuntimeError:  # no roadmap yet
                time.sleep(0.2)
        published = _stamp(logs / "roadmap_builder.log", "published the roadmap")
        line = _line(logs / "roadmap_builder.log", "published the roadmap")
        sending = float(re.search(r"published in (\d+\.\d+) s", line).group(1))
        usable = _stamp(logs / "planner.log", "planning on a new roadmap")
        print(json.dumps({"publish_to_usable_s": round(usable - published + sending, 3),
                          "of_which_publish_call_s": sending, "builder": line.split("]: ")[-1]}))
        for k in range(10):  # warm the planner's patch profiles
            _call(clients[0], _request(k, examples))
        begin = time.perf_counter()
        single = [_call(clients[0], _request(k, examples)) for k in range(args.requests)]
        print(json.dumps(dict(_summary(single, time.perf_counter() - begin), clients=1)))
        # Each client's first exchange completes the server's discovery of its
        # response reader (as PlannerClient.wait_until_ready does): not timed.
        for client in clients[1:]:
            for _ in range(3):
                try:
                    _call(client, _request(0, examples), timeout=10.0)
                    break
                except TimeoutError:
                    continue
        results = [[] for _ in clients]
        errors = []

        def run(k):
            for j in range(args.requests):
                try:
                    results[k].append(_call(clients[k], _request(j + k, examples)))
                except (RuntimeError, TimeoutError) as exc:
                    errors.append(str(exc)[:200])

        threads = [threading.Thread(target=run, args=(k,)) for k in range(len(clients))]
        begin = time.perf_counter()
        for t in threads:
            t.start()
        for t in threads:
            t.join()
        wall = time.perf_counter() - begin
        merged = [t for r in results for t in r]
        print(json.dumps(dict(_summary(merged, wall), clients=len(clients),
                              failures=len(clients) * args.requests - len(merged),
                              errors=sorted(set(errors)))))
    finally:
        executor.shutdown(timeout_sec=10.0)
        spinner.join(timeout=10.0)
        for n in nodes:
            n.destroy_node()
        rclpy.try_shutdown()
        for p in processes:
            p.send_signal(signal.SIGINT)
            p.wait(timeout=20)


if __name__ == "__main__":
    main()
