"""Machinery shared by the benchmark scripts: the timer, the report, the machine facts, the
command line and the run's frame.

The scripts run as ``python benchmarks/bench_x.py`` from the repository root and import
this module from their own folder (not a package, hence the leading underscore).

What comes from the library and what is the benchmarks' own
------------------------------------------------------------
- The machine record is :func:`vobscure.experiments.common.machine` (cores available to
  the process, processor, library versions); :func:`machine_facts` prints it with what a
  *benchmark* reader also needs: ``os.cpu_count()`` beside the usable cores and the load
  average, the two signs of a shared machine.
- The timer is :func:`vobscure.experiments.common.time_calls` (one untimed warm-up call,
  then round-robin rounds, wall and process time per round). :func:`interleaved` keeps a
  layer over it because the benchmarks report something ``time_calls``' ``Timing`` does
  not: the **cores of one actual round** (its process CPU time / its wall time), taken in
  the round whose wall time is reported (the best round, or the lower median round).
  ``Timing.cpu_median / Timing.median`` would divide medians of different rounds, which on
  a shared machine can show 1.6 cores for a round that got 1. The ground-truth benchmark
  also reports the *best* round (the least disturbed one), which ``time_calls`` leaves to
  its caller.
"""

from __future__ import annotations

import argparse
import gc
import os
import platform
import time
import tracemalloc
from collections.abc import Callable
from dataclasses import dataclass

from vobscure.experiments.common import machine, time_calls


# --------------------------------------------------------------------------- timing
@dataclass(frozen=True)
class Timing:
    seconds: float   # wall time (time.perf_counter) of the chosen statistic: best or median
    cores: float     # process CPU time / wall time in that round: cores actually used
    best: float      # best wall time (context)
    result: object   # the callable's return value (the untimed warm-up call's)


def interleaved(fns: dict, repeats: int, statistic: str = "best") -> dict[str, Timing]:
    """Wall time of each callable over ``repeats`` rounds after one warm-up call, the
    callables interleaved round by round (:func:`~vobscure.experiments.common.time_calls`)
    so that a change of machine load affects all of them alike.

    ``statistic`` is "best" (the fastest round) or "median" (the median wall time; its
    ``cores`` is the lower median round's, an actual round)."""
    if statistic not in ("best", "median"):
        raise ValueError(f"statistic must be 'best' or 'median', not {statistic!r}")
    timings, values = time_calls(fns, repeats)
    out = {}
    for name, t in timings.items():
        rounds = sorted((w, c / w if w > 0 else 0.0) for w, c in zip(t.runs, t.cpu_runs))
        if statistic == "best":
            seconds, cores = rounds[0]
        else:
            seconds, cores = t.median, rounds[(len(rounds) - 1) // 2][1]
        out[name] = Timing(seconds, cores, rounds[0][0], values[name])
    return out


# --------------------------------------------------------------------------- report
class Report:
    """Prints table rows as they come and collects the summary lines.

    Subclasses set ``columns`` (the table's column headings), ``summary_title`` (the
    summary's heading, after "== "), ``label_width`` (of the summary labels) and a ``row``
    method that prints one table row in the ``columns`` layout."""

    columns = ""
    summary_title = "Summary"
    label_width = 60

    def __init__(self):
        self.summary = []

    def header(self, title: str):
        print(f"\n== {title}")
        print(f"  {self.columns}")

    def goal(self, label: str, value: float, goal: float, *, at_least: bool, unit: str = "x"):
        ok = value >= goal if at_least else value <= goal
        sign = ">=" if at_least else "<="
        self.summary.append(f"  {label:<{self.label_width}} {value:8.2f}{unit}  "
                            f"(goal {sign} {goal:g}{unit}: {'met' if ok else 'MISSED'})")

    def note(self, label: str, value: float, unit: str = "x"):
        self.summary.append(f"  {label:<{self.label_width}} {value:8.2f}{unit}")

    def print_summary(self):
        print(f"\n== {self.summary_title}")
        print("\n".join(self.summary))


# --------------------------------------------------------------------------- machine
def peak_bytes(fn: Callable) -> int:
    """Peak traced memory (bytes) of one call of ``fn``, tracing started just before it."""
    gc.collect()
    tracemalloc.start()
    try:
        result = fn()
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    del result
    return peak


def load_average() -> str:
    return ", ".join(f"{x:.2f}" for x in os.getloadavg()) if hasattr(os, "getloadavg") else "n/a"


def machine_facts(extra: str = ""):
    """Print the "== Machine" heading, :func:`vobscure.experiments.common.machine` (usable
    cores, processor, versions), ``os.cpu_count()``, the load average and the platform, then
    ``extra`` (a benchmark's own line) when given."""
    m = machine()
    print("== Machine")
    print(f"  cores usable (sched_getaffinity): {m['cores']}   os.cpu_count: {os.cpu_count()}   "
          f"load average: {load_average()}   cpu: {m['cpu']}")
    print("  " + "   ".join(f"{k} {m[k]}" for k in ("python", "numpy", "scipy", "embreex", "vobscure")))
    print(f"  platform: {platform.platform()}")
    if extra:
        print(f"  {extra}")


# --------------------------------------------------------------------------- command line
def parser(doc: str, *, quick: str, statistic: str) -> argparse.ArgumentParser:
    """The options every benchmark has: ``--quick`` (help ``quick``) and ``--repeats``
    (``statistic`` of N rounds, "best" or "median")."""
    p = argparse.ArgumentParser(description=doc.split("\n", 1)[0])
    p.add_argument("--quick", action="store_true", help=quick)
    p.add_argument("--repeats", type=int, default=3, help=f"{statistic} of N rounds (default 3)")
    return p


def parse(p: argparse.ArgumentParser, argv):
    """Parse ``argv`` and check ``--repeats`` >= 1."""
    args = p.parse_args(argv)
    if args.repeats < 1:
        p.error("--repeats must be >= 1")
    return args


def run(body, report: Report) -> int:
    """Call ``body(report)``, print the report's summary and the total time and load: the
    frame of every benchmark's ``main``. Returns the exit code, 0."""
    start = time.perf_counter()
    body(report)
    report.print_summary()
    print(f"\n  total benchmark time {time.perf_counter() - start:.1f} s   "
          f"load average now: {load_average()}")
    return 0
