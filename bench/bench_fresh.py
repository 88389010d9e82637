"""Benchmark: fresh ``rpr3-gwr`` processes against the eigenvalue baseline.

Run on demand, after ``source ros2_ws/env.sh``:

    python bench/bench_fresh.py [--repeat 3] [--rounds 1]

Each command is a new process (imports, cache load and kernels included),
timed by its wall time, median of ``--repeat`` runs; the plans read the
roadmap cache ($RPR3_GWR_CACHE, else the default; the roadmaps are built
first if missing), the 401 x 401 roadmap starts from an empty cache folder.
The eigenvalue baseline of bench_roadmap.py is measured before and after
each round, on a shared machine the times drift with its load: each round's
ratios are over the mean of its two baselines.  The processor time of each
(user and system, over the baseline's own) is printed beside: on a machine
busy with other work it drifts less than the wall time.

Prints JSON lines: per round the baselines, each command's median seconds
and ratio, then each target with the median ratio over the rounds, its
threshold and whether it is met.
"""

import argparse
import json
import resource
import shutil
import statistics
import subprocess
import tempfile
import time

from bench_roadmap import eigenvalue_baseline  # bench/ is the script's folder

# The README's full-roadmap example and the paper's first example.
FULL_PLAN = ["plan", "--full", "--start", "27.5", "31.67154934", "2.14117832", "-101",
             "--goal", "27.5", "31.67154934", "2.14117832", "158.048263"]
PAPER_PLAN = ["plan", "--rho1", "17", "--start", "12", "18", "122.82",
              "--goal", "10", "25", "-24.24", "--smooth"]
# Command name, its arguments, whether it starts from an empty cache, and its
# bound as a share of the baseline.
COMMANDS = (("plan --full (cached roadmap)", FULL_PLAN, False, 0.6),
            ("plan, paper's first example (cached roadmap)", PAPER_PLAN, False, 0.4),
            ("--help", ["--help"], False, 0.1),
            ("roadmap 401 x 401 (empty cache)", ["roadmap"], True, 0.6))


def _processor_seconds(who):
    usage = resource.getrusage(who)
    return usage.ru_utime + usage.ru_stime


def wall(args, cache_dir=None):
    """Wall and processor seconds of one fresh ``rpr3-gwr`` process."""
    command = [shutil.which("rpr3-gwr"), *args]
    if cache_dir is not None:
        command += ["--cache-dir", cache_dir]
    used = _processor_seconds(resource.RUSAGE_CHILDREN)
    begin = time.perf_counter()
    subprocess.run(command, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, check=True)
    return (time.perf_counter() - begin,
            _processor_seconds(resource.RUSAGE_CHILDREN) - used)


def fresh_processes(repeat):
    """Median wall and processor seconds of each command of :data:`COMMANDS`,
    by name."""
    wall(FULL_PLAN)  # the cached roadmaps these plans load, built now if missing
    wall(PAPER_PLAN)
    medians = {}
    for name, args, empty, _ in COMMANDS:
        times = []
        for _ in range(repeat):
            if empty:
                with tempfile.TemporaryDirectory() as folder:
                    times.append(wall(args, cache_dir=folder))
            else:
                times.append(wall(args))
        medians[name] = tuple(statistics.median(t) for t in zip(*times))
    return medians


def _baseline():
    """Wall and processor seconds of the eigenvalue baseline (median of 5)."""
    used = _processor_seconds(resource.RUSAGE_SELF)
    seconds = eigenvalue_baseline(5)
    # Five runs and the matrices' set-up (a few per cent): a fifth per run.
    return seconds, (_processor_seconds(resource.RUSAGE_SELF) - used) / 5


def _emit(line):
    print(json.dumps(line), flush=True)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=3, help="runs of each command (median)")
    parser.add_argument("--rounds", type=int, default=1,
                        help="rounds of baseline, commands, baseline")
    args = parser.parse_args()
    ratios = {name: [] for name, *_ in COMMANDS}
    for round_ in range(args.rounds):
        before = _baseline()
        medians = fresh_processes(args.repeat)
        after = _baseline()
        baseline, processor = ((a + b) / 2 for a, b in zip(before, after))
        _emit({"round": round_, "baseline_before_s": round(before[0], 3),
               "baseline_after_s": round(after[0], 3),
               "baseline_processor_s": round(processor, 3)})
        for name, (seconds, used) in medians.items():
            ratios[name].append(seconds / baseline)
            _emit({"round": round_, "fresh_process": f"rpr3-gwr {name}",
                   "repeat": args.repeat, "median_s": round(seconds, 3),
                   "over_baseline": round(seconds / baseline, 3),
                   "processor_s": round(used, 3),
                   "processor_over_baseline": round(used / processor, 3)})
    for name, _, _, bound in COMMANDS:
        measured = statistics.median(ratios[name])
        _emit({"target": f"4 rpr3-gwr {name} / baseline", "measured": round(measured, 4),
               "threshold": bound, "met": measured <= bound})


if __name__ == "__main__":
    main()
