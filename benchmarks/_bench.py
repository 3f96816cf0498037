"""Machinery shared by the benchmark scripts: interleaved timing, the report, machine facts.

The scripts run as ``python benchmarks/bench_x.py`` from the repository root and import
this module from their own folder (not a package, hence the leading underscore).
"""

from __future__ import annotations

import importlib
import os
import platform
import statistics
import time
from dataclasses import dataclass


# --------------------------------------------------------------------------- timing
@dataclass(frozen=True)
class Timing:
    seconds: float   # wall time (time.perf_counter) of the chosen statistic: best or median
    cores: float     # process CPU time / wall time in that round: cores actually used
    best: float      # best wall time (context)
    result: object   # the callable's return value (last round)


def interleaved(fns: dict, repeats: int, statistic: str = "best") -> dict[str, Timing]:
    """Wall time of each callable over ``repeats`` rounds, the callables interleaved round
    by round so that a change of machine load affects all of them alike.

    ``statistic`` is "best" (the fastest round) or "median" (the median wall time; its
    ``cores`` is the lower median round's, an actual round)."""
    if statistic not in ("best", "median"):
        raise ValueError(f"statistic must be 'best' or 'median', not {statistic!r}")
    rounds = {name: [] for name in fns}
    result = {}
    for _ in range(repeats):
        for name, fn in fns.items():
            c0, t0 = time.process_time(), time.perf_counter()
            result[name] = fn()
            wall, cpu = time.perf_counter() - t0, time.process_time() - c0
            rounds[name].append((wall, cpu / wall if wall > 0 else 0.0))
    out = {}
    for name, r in rounds.items():
        r.sort()
        if statistic == "best":
            seconds, cores = r[0]
        else:
            seconds, cores = statistics.median(w for w, _ in r), r[(len(r) - 1) // 2][1]
        out[name] = Timing(seconds, cores, r[0][0], result[name])
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
def load_average() -> str:
    return ", ".join(f"{x:.2f}" for x in os.getloadavg()) if hasattr(os, "getloadavg") else "n/a"


def machine_facts(*libraries: str):
    """Print the "== Machine" heading, the usable cores, the load average, and the versions
    of python, numpy, scipy, the named ``libraries`` and vobscure (already importable)."""
    try:
        cores = len(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover - non-Linux
        cores = os.cpu_count()
    print("== Machine")
    print(f"  cores usable (sched_getaffinity): {cores}   os.cpu_count: {os.cpu_count()}   "
          f"load average: {load_average()}")
    versions = [f"python {platform.python_version()}"]
    for name in ("numpy", "scipy", *libraries, "vobscure"):
        versions.append(f"{name} {getattr(importlib.import_module(name), '__version__', '?')}")
    print("  " + "   ".join(versions))
